"""Robustness figures against real `opentmcl serve` processes on loopback: fuzzed frames, kills.

    python bench/bench_robustness.py [--frames N] [--kills N]

- frames fuzzed: N random 9-byte frames (random bytes: mostly bad checksums, some valid commands)
  streamed over one TCP connection in chunks of random size; afterwards GGP 66 (manual 3.6.8
  example) must still get its exact reply, and the server must still be running;
- kills survived: N times, start `serve --eeprom FILE`, stream auto-stored SGP 75 writes (manual
  5.1) and SIGKILL the server mid-stream; the EEPROM file must load each time, and the next
  start must leave no `.ee.json.*.tmp` file behind.
"""
from __future__ import annotations

import argparse
import os
import random
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

GGP_66 = bytes.fromhex("010A4200000000004D")
REPLY_66 = bytes.fromhex("0201640A0000000172")


def frame(*fields: int) -> bytes:
    addr, cmd, typ, motor, value = fields
    body = bytes([addr, cmd, typ, motor]) + (value & 0xFFFFFFFF).to_bytes(4, "big")
    return body + bytes([sum(body) & 0xFF])


def serve(*extra: str) -> tuple[subprocess.Popen, int]:
    proc = subprocess.Popen([sys.executable, "-m", "opentmcl", "serve", "--module", "TMCM-6212",
                             "--tcp", "127.0.0.1:0", *extra], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                            text=True)
    for line in proc.stdout:
        if "tcp://" in line:
            return proc, int(line.rsplit(":", 1)[1])
    raise RuntimeError("serve printed no TCP address")


def read_until(sock: socket.socket, tail: bytes, limit: float = 20.0) -> bool:
    sock.settimeout(limit)
    data = b""
    while not data.endswith(tail):
        chunk = sock.recv(4096)
        if not chunk:
            return False
        data = data[-64:] + chunk
    return True


def fuzz_frames(n: int, seed: int = 11) -> dict:
    rng = random.Random(seed)
    proc, port = serve("--idle-timeout", "0")
    try:
        with socket.create_connection(("127.0.0.1", port)) as sock:
            data = rng.randbytes(9 * n)
            sock.setblocking(True)
            view, sent = memoryview(data), 0
            drain = bytearray()
            sock.settimeout(0.0)
            while sent < len(data):
                size = rng.randint(1, 4096)
                try:
                    sent += sock.send(view[sent:sent + size])
                except BlockingIOError:
                    pass
                try:
                    drain += sock.recv(65536)  # read replies so the server never waits on us
                    del drain[:-64]
                except (BlockingIOError, InterruptedError):
                    pass
            time.sleep(0.3)   # the serial gap (0.1 s) ends a partial last frame
            sock.settimeout(5)
            try:
                while sock.recv(65536):
                    pass
            except TimeoutError:
                pass
            sock.sendall(GGP_66)
            ok = read_until(sock, REPLY_66)
        return {"frames fuzzed": n, "answers GGP 66 afterwards": ok, "server alive": proc.poll() is None}
    finally:
        proc.terminate()
        proc.communicate(timeout=30)


def kills(n: int) -> dict:
    from opentmcl import VirtualModule

    folder = Path(tempfile.mkdtemp(prefix="opentmcl-kills-"))
    ee = folder / "ee.json"
    loaded = 0
    for i in range(n):
        proc, port = serve("--eeprom", str(ee))
        with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
            for k in range(20 + i % 17):
                sock.sendall(frame(1, 9, 75, 0, k % 200))   # SGP 75: stored at once
            time.sleep(0.002 * (i % 5))
            proc.send_signal(signal.SIGKILL)
        proc.communicate(timeout=30)
        vm = VirtualModule("TMCM-6212", eeprom=ee)
        loaded += 0 <= vm.request(10, 75, 0).value < 200
    left_before = sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))
    proc, _ = serve("--eeprom", str(ee))
    proc.terminate()
    proc.communicate(timeout=30)
    left_after = [p.name for p in folder.iterdir() if p.name.endswith(".tmp")]
    for p in folder.iterdir():
        os.unlink(p)
    folder.rmdir()
    return {"kills": n, "EEPROM loaded after kill": loaded, "temp files left by the kills": len(left_before),
            "temp files after the next start": len(left_after)}


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=200_000)
    ap.add_argument("--kills", type=int, default=40)
    args = ap.parse_args(argv)
    out = {**fuzz_frames(args.frames), **kills(args.kills)}
    for k, v in out.items():
        print(f"{k:40} {v}")
    return out


if __name__ == "__main__":
    main()
