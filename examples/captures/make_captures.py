"""Regenerate the example captures by running the tools, as a user would (docs/capture.md).

    python examples/captures/make_captures.py [OUTDIR]      # default: this directory

Each capture is written by `opentmcl proxy --log` between a host (plain sockets and pyserial,
sending the manuals' commands) and `opentmcl serve`, both real processes:

- tmcm6212_program_reference_events.jsonl: TMCM-6212 with the stage scenario, over TCP: identity,
  command 138 events, a TMCL program downloaded (132/133), run (129) and read back (134), a
  reference search (RFS START, RFS STATUS polled) and a stray byte (garbage);
- bus_ascii_two_modules.jsonl: a PD86-1180 (address 1) and a PD28-1021 (address 2) on one pty:
  both addressed, then the PD86-1180 in ASCII mode (command 139, text lines, BIN) and back.
"""
from __future__ import annotations

import os
import select
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import serial

from opentmcl.protocol.frame import Request

HERE = Path(__file__).resolve().parent
SCENARIO = HERE.parent / "scenarios" / "tmcm6212_stage.toml"


class Tool:
    """`python -m opentmcl ARGS` that prints its endpoints and then "Press Ctrl-C"."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "opentmcl", *args], stdout=subprocess.PIPE)
        self.lines: list[str] = []
        deadline = time.monotonic() + 30
        buf = b""
        while not any(line.startswith("Press Ctrl-C") for line in self.lines):
            ready, _, _ = select.select([self.proc.stdout], [], [], max(0.0, deadline - time.monotonic()))
            ch = os.read(self.proc.stdout.fileno(), 1) if ready else b""
            if not ch:
                self.proc.kill()
                raise SystemExit(f"{args[0]} did not start: {self.lines}")
            buf += ch
            if ch == b"\n":
                self.lines.append(buf.decode().strip())
                buf = b""

    def endpoint(self, kind: str) -> str:
        return next(line.split()[1] for line in self.lines if line.startswith(kind + " "))

    def stop(self) -> None:
        self.proc.send_signal(signal.SIGTERM)
        self.proc.wait(timeout=20)


def frame(command: int, type_: int = 0, motor: int = 0, value: int = 0, address: int = 1) -> bytes:
    return Request(address, command, type_, motor, value).encode()


class Host:
    """Send a frame, read n bytes: the simplest host program, over a socket or a serial port."""

    def __init__(self, read, write) -> None:
        self.read, self.write = read, write

    def ask(self, data: bytes, n: int = 9) -> bytes:
        self.write(data)
        return self.read(n)


def socket_host(url: str) -> Host:
    host, port = url.removeprefix("tcp://").rsplit(":", 1)
    sock = socket.create_connection((host, int(port)), timeout=10)

    def read(n: int) -> bytes:
        buf = b""
        while len(buf) < n:
            chunk = sock.recv(n - len(buf))
            if not chunk:
                break
            buf += chunk
        return buf

    return Host(read, sock.sendall)


def program_reference_events(out: Path) -> None:
    served = Tool("serve", "--module", "TMCM-6212", "--scenario", str(SCENARIO), "--tcp", "127.0.0.1:0")
    proxy = Tool("proxy", "--to", served.endpoint("tcp"), "--tcp", "127.0.0.1:0", "--log",
                 str(out / "tmcm6212_program_reference_events.jsonl"))
    try:
        h = socket_host(proxy.endpoint("tcp"))
        h.ask(frame(136, 0))                       # identity (3.6.36)
        h.ask(frame(138, 1, 0, 1))                 # an event after every MVP of motor 0 (3.6.35)
        h.ask(frame(4, 0, 0, 20000))               # MVP ABS 0, 20000
        h.read(9)                                  # ... the event (status 128)
        h.ask(frame(6, 1, 0))                      # GAP 1: actual position
        h.ask(frame(132))                          # enter download mode
        for instruction in (frame(4, 0, 0, 5000), frame(27, 1, 0, 0), frame(28)):  # MVP, WAIT POS, STOP
            h.ask(instruction)
        h.ask(frame(133))                          # exit download mode
        h.ask(frame(134, 0, 0, 1))                 # read back instruction 1
        h.ask(frame(129, 1, 0, 0))                 # run from address 0
        h.read(9)                                  # the program's MVP is an MVP too: event
        time.sleep(0.2)
        h.ask(frame(135))                          # application status
        h.ask(frame(13, 0, 0))                     # RFS START
        for _ in range(200):
            reply = h.ask(frame(13, 2, 0))         # RFS STATUS, 0 when done
            if reply[4:8] == b"\0\0\0\0":
                break
            time.sleep(0.05)
        h.ask(frame(6, 1, 0))                      # position after the search
        h.write(b"\x01\x06")                       # a stray partial frame
        time.sleep(0.3)                            # longer than the gap: dropped
        h.ask(frame(6, 8, 0))                      # GAP 8: position reached
        h.ask(frame(10, 66, 0))                    # GGP 66
    finally:
        proxy.stop()
        served.stop()


def bus_ascii_two_modules(out: Path) -> None:
    served = Tool("serve", "--module", "PD86-1180", "--module", "PD28-1021", "--pty")
    proxy = Tool("proxy", "--to", f"serial://{served.endpoint('pty')}", "--pty", "--log",
                 str(out / "bus_ascii_two_modules.jsonl"))
    try:
        port = serial.Serial(proxy.endpoint("pty"), 9600, timeout=5)
        h = Host(port.read, port.write)
        for address in (1, 2):
            h.ask(frame(136, 0, address=address))
            h.ask(frame(6, 4, 0, address=address))
            h.ask(frame(5, 4, 0, 300, address=address))
            h.ask(frame(10, 66, 0, address=address))
        h.ask(frame(139, address=1))               # PD86-1180 4.5: into ASCII mode
        port.write(b"AGAP 4, 0\r")
        time.sleep(0.3)
        port.read(port.in_waiting)
        port.write(b"ABIN\r")                      # back to binary
        time.sleep(0.3)
        port.read(port.in_waiting)
        h.ask(frame(6, 4, 0, address=1))
        h.ask(frame(6, 4, 0, address=2))
        port.close()
    finally:
        proxy.stop()
        served.stop()


def main(argv: list[str]) -> int:
    out = Path(argv[0]) if argv else HERE
    out.mkdir(parents=True, exist_ok=True)
    program_reference_events(out)
    bus_ascii_two_modules(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
