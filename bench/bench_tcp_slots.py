"""TCP slots under idle clients (issue 11 problem 3): who holds the slots of `--max-clients`, and
for how long.

    python bench/bench_tcp_slots.py [--idle-timeout SECONDS] [--tries N] [--give-up SECONDS]

Starts `opentmcl serve` (default --max-clients 4) on a free loopback port, opens four connections
that send one request (GGP 66, manual 3.6.8) and then nothing, tries `--tries` further clients at
once (counting the refused ones), then tries one client every 0.25 s until one is served or
`--give-up` seconds have passed. `--idle-timeout` is passed to serve only when given, so the same
script measures a server without the option. Prints the figures and the server's log lines.
"""
from __future__ import annotations

import argparse
import os
import re
import select
import socket
import subprocess
import sys
import time

GGP_66 = bytes.fromhex("010A4200000000004D")  # manual 3.6.8 example
REPLY = bytes.fromhex("0201640A0000000172")


def start_server(extra: list[str]) -> tuple[subprocess.Popen, tuple[str, int]]:
    proc = subprocess.Popen([sys.executable, "-m", "opentmcl", "serve", "--module", "TMCM-6212",
                             "--tcp", "127.0.0.1:0", *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    text, deadline = b"", time.monotonic() + 30
    while b"Press Ctrl-C" not in text:
        if time.monotonic() > deadline or proc.poll() is not None:
            proc.kill()
            raise SystemExit(f"server did not start: {text!r} {proc.stderr.read()!r}")
        if select.select([proc.stdout], [], [], 0.5)[0]:
            text += os.read(proc.stdout.fileno(), 4096)
    m = re.search(rb"tcp://([\d.]+):(\d+)", text)
    return proc, (m.group(1).decode(), int(m.group(2)))


def served(address) -> bool:
    """One client: True if GGP 66 is answered, False if the server closed the connection."""
    with socket.create_connection(address, timeout=5) as s:
        s.sendall(GGP_66)
        got = b""
        try:
            while len(got) < 9:
                chunk = s.recv(9 - len(got))
                if not chunk:
                    return False
                got += chunk
        except (ConnectionResetError, TimeoutError):
            return False
        return got == REPLY


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--idle-timeout", type=float, default=None)
    ap.add_argument("--tries", type=int, default=100)
    ap.add_argument("--give-up", type=float, default=30.0)
    args = ap.parse_args()
    extra = [] if args.idle_timeout is None else ["--idle-timeout", str(args.idle_timeout)]
    proc, address = start_server(extra)
    idle = []
    try:
        for _ in range(4):
            s = socket.create_connection(address, timeout=5)
            s.sendall(GGP_66)
            assert s.recv(9) == REPLY
            idle.append(s)
        refused = sum(not served(address) for _ in range(args.tries))
        start = time.monotonic()
        tries, ok = 0, False
        while time.monotonic() - start < args.give_up:
            tries += 1
            if served(address):
                ok = True
                break
            time.sleep(0.25)
        waited = time.monotonic() - start
    finally:
        for s in idle:
            s.close()
        proc.terminate()
        _, err = proc.communicate(timeout=20)
    option = "none" if args.idle_timeout is None else f"{args.idle_timeout:g} s"
    print(f"idle timeout option: {option}; idle clients held: 4 of 4 slots")
    print(f"clients tried while held: {args.tries}, refused: {refused}")
    if ok:
        print(f"a new client was served after {waited:.1f} s ({tries} tries)")
    else:
        print(f"no new client served within {args.give_up:g} s ({tries} tries)")
    lines = err.decode().splitlines()
    print(f"server log: {sum('refused' in line for line in lines)} refused lines, "
          f"{sum('dropped' in line for line in lines)} dropped lines")
    for line in lines[:3]:
        print(f"  {line}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
