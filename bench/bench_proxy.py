"""Proxy benchmark: round-trip time added by `opentmcl proxy` on loopback (issue 13: target < 1 ms).

    python bench/bench_proxy.py [--quick]

The reference server (`opentmcl serve --tcp`, a TMCM-6212) and the proxy (`opentmcl proxy --to
tcp://... --tcp ... --log FILE`, capture on) each run in their own process, as a user runs them. The
client, in this process, sends GAP 1 (TMCM-6212 manual 3.6.6) and reads the nine-byte reply, once
straight to the server and once through the proxy, in interleaved rounds; each round's median
round trip is taken and the best round of each kept (the least disturbed on a busy machine).
Figures: both medians, the time the proxy adds, and the ratio proxied / direct.
"""
from __future__ import annotations

import argparse
import os
import select
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time

from opentmcl.protocol.frame import Request

GAP_1 = Request(1, 6, 1, 0, 0).encode()


def start(*args: str) -> tuple[subprocess.Popen, str]:
    """A tool process and the tcp:// URL it announced."""
    proc = subprocess.Popen([sys.executable, "-m", "opentmcl", *args], stdout=subprocess.PIPE)
    deadline = time.monotonic() + 30
    buf = b""
    while b"Press Ctrl-C" not in buf:
        ready, _, _ = select.select([proc.stdout], [], [], max(0.0, deadline - time.monotonic()))
        ch = os.read(proc.stdout.fileno(), 1) if ready else b""
        if not ch:
            proc.kill()
            raise RuntimeError(f"{args[0]} did not start: {buf!r}")
        buf += ch
    url = next(line.split()[1] for line in buf.decode().splitlines() if line.strip().startswith("tcp "))
    return proc, url


def stop(proc: subprocess.Popen) -> None:
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def median_round_trip(url: str, n: int) -> float:
    host, port = url.removeprefix("tcp://").rsplit(":", 1)
    with socket.create_connection((host, int(port)), timeout=5) as s:
        s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        times = []
        for i in range(n + 20):
            start_t = time.perf_counter()
            s.sendall(GAP_1)
            got = b""
            while len(got) < 9:
                got += s.recv(9 - len(got))
            if i >= 20:  # warm-up left out
                times.append(time.perf_counter() - start_t)
    return statistics.median(times)


def measure(quick: bool = False) -> dict[str, float]:
    rounds, n = (2, 200) if quick else (5, 1000)
    server, direct_url = start("serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0")
    with tempfile.TemporaryDirectory() as tmp:
        try:
            proxy, proxy_url = start("proxy", "--to", direct_url, "--tcp", "127.0.0.1:0", "--log",
                                     os.path.join(tmp, "bench.jsonl"))
            try:
                direct, proxied = [], []
                for _ in range(rounds):
                    direct.append(median_round_trip(direct_url, n))
                    proxied.append(median_round_trip(proxy_url, n))
            finally:
                stop(proxy)
        finally:
            stop(server)
    d, p = min(direct), min(proxied)
    return {
        "direct round trip, median ms": d * 1000,
        "through the proxy (capture on), median ms": p * 1000,
        "added by the proxy, ms (target < 1)": (p - d) * 1000,
        "ratio proxied / direct": p / d,
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    for key, value in measure(args.quick).items():
        print(f"{key:<45} {value:10.3f}")


if __name__ == "__main__":
    main()
