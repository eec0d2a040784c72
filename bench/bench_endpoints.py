"""Endpoint benchmark: round trips per second through TCP and through a pseudo-terminal.

    python bench/bench_endpoints.py [--quick]

Each figure stands next to its yardstick, measured in the same run over the same transport:

- our server (`opentmcl serve --module TMCM-6212 --tcp` / `--pty`, a TMCM-6212 answering GAP 1 =
  actual position, TMCM-6212 manual 3.6.6) against a bare echo server that sends every received
  byte straight back (target: ours >= 50 % of the echo rate). Every server runs in a process of
  its own, started by this benchmark (the echo servers: this file with `--echo tcp|pty`); the
  client is the same plain socket / pyserial loop for both (send nine bytes, read nine bytes), in
  this process, which does nothing else meanwhile. Each pair is measured in interleaved rounds and
  the best round of each is kept (the least disturbed one on a busy machine);
- our client (`opentmcl.connect("tcp://...")`, `Module.request`) against PyTrinamic's
  (`socket_serial_tmcl` interface, `get_axis_parameter`) on the same served virtual module, in
  this process (target: ours at least as fast). Skipped when PyTrinamic is not installed.
"""
from __future__ import annotations

import argparse
import os
import select
import socket
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from opentmcl.protocol.frame import Request
from procs import endpoint, start, start_tool, stop

GAP_1 = Request(1, 6, 1, 0, 0).encode()  # GAP 1, 0: actual position (manual 3.6.6)
FRAME = len(GAP_1)
READY_LINE = "Press Ctrl-C to stop."


def rate(round_trip: Callable[[], None], seconds: float, warmup: int = 20) -> float:
    """Round trips per second of `round_trip()` repeated for about `seconds`."""
    for _ in range(warmup):
        round_trip()
    n = 0
    start_t = time.perf_counter()
    end = start_t + seconds
    while True:
        for _ in range(50):
            round_trip()
        n += 50
        now = time.perf_counter()
        if now >= end:
            return n / (now - start_t)


# --- bare echo servers: the yardsticks, each run as `bench_endpoints.py --echo KIND` ---------

def serve_tcp_echo() -> None:
    """A TCP server on loopback that writes back what it reads, one connection at a time."""
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    host, port = listener.getsockname()
    print(f"tcp tcp://{host}:{port}\n{READY_LINE}", flush=True)
    while True:
        conn, _ = listener.accept()
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        with conn:
            while True:
                try:
                    data = conn.recv(4096)
                except OSError:
                    break
                if not data:
                    break
                conn.sendall(data)


def serve_pty_echo() -> None:
    """A pseudo-terminal whose master writes back what it reads."""
    import tty

    master, slave = os.openpty()
    tty.setraw(slave)
    print(f"pty {os.ttyname(slave)}\n{READY_LINE}", flush=True)
    while True:
        select.select([master], [], [])
        try:
            data = os.read(master, 4096)
        except OSError:  # no client has the slave open at the moment
            time.sleep(0.01)
            continue
        os.write(master, data)


@contextmanager
def echo_server(kind: str) -> Iterator[str]:
    """An echo server in its own process; yields its address (tcp://HOST:PORT or the pty path)."""
    proc, lines = start([sys.executable, os.path.abspath(__file__), "--echo", kind])
    try:
        yield endpoint(lines, kind)
    finally:
        stop(proc)


@contextmanager
def our_server(kind: str) -> Iterator[str]:
    """`opentmcl serve` of one TMCM-6212 in its own process; yields the tcp:// URL or pty path."""
    option = ["--tcp", "127.0.0.1:0"] if kind == "tcp" else ["--pty"]
    proc, lines = start_tool("serve", "--module", "TMCM-6212", *option)
    try:
        yield endpoint(lines, kind)
    finally:
        stop(proc)


# --- the same plain clients for both -----------------------------------------------------

def socket_rate(address, seconds: float) -> float:
    with socket.create_connection(address, timeout=5) as s:
        s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

        def round_trip():
            s.sendall(GAP_1)
            got = 0
            while got < FRAME:
                chunk = s.recv(FRAME - got)
                if not chunk:
                    raise ConnectionError("server closed the connection")
                got += len(chunk)

        return rate(round_trip, seconds)


def serial_rate(path: str, seconds: float) -> float:
    import serial

    with serial.Serial(path, 115200, timeout=5) as port:

        def round_trip():
            port.write(GAP_1)
            if len(port.read(FRAME)) != FRAME:
                raise TimeoutError("no reply")

        return rate(round_trip, seconds)


def client_rates(seconds: float) -> dict:
    """Our client and PyTrinamic's, one after the other, against one served TMCM-6212."""
    from opentmcl.host import connect

    out = {}
    with our_server("tcp") as url:
        host, port = url.removeprefix("tcp://").rsplit(":", 1)
        module = connect(url)
        try:
            out["ours"] = rate(lambda: module.request(6, 1, 0), seconds)
        finally:
            module.client.close()
        try:
            from pytrinamic.connections import ConnectionManager
        except ImportError:
            return out
        interface = ConnectionManager(f"--interface socket_serial_tmcl --port {host}:{port}").connect()
        try:
            out["pytrinamic"] = rate(lambda: interface.get_axis_parameter(1, 0), seconds)
        finally:
            interface.close()
    return out


def client_rate(kind: str, target: str, seconds: float) -> float:
    if kind == "tcp":
        host, port = target.removeprefix("tcp://").rsplit(":", 1)
        return socket_rate((host, int(port)), seconds)
    return serial_rate(target, seconds)


def best_pair(kind: str, rounds: int, seconds: float) -> tuple[float, float]:
    """Best rate of our server and of the echo server over `rounds` interleaved rounds: on a
    busy machine the best round is the least disturbed one, and interleaving puts both servers
    under the same load. Both server processes run for the whole measurement."""
    ours = echo = 0.0
    with our_server(kind) as ours_at, echo_server(kind) as echo_at:
        for _ in range(rounds):
            ours = max(ours, client_rate(kind, ours_at, seconds))
            echo = max(echo, client_rate(kind, echo_at, seconds))
    return ours, echo


def measure(quick: bool = False) -> dict:
    """Round trips per second and the ratios against their yardsticks (higher is better)."""
    rounds, seconds = (1, 0.15) if quick else (5, 0.5)
    results: dict[str, float] = {}
    ours, echo = best_pair("tcp", rounds, seconds)
    results["TCP round trips/s: ours"] = ours
    results["TCP bare echo round trips/s"] = echo
    results["TCP ours/echo ratio (target >= 0.5)"] = ours / echo
    if sys.platform != "win32":
        ours, echo = best_pair("pty", rounds, seconds)
        results["pty round trips/s: ours"] = ours
        results["pty bare echo round trips/s"] = echo
        results["pty ours/echo ratio (target >= 0.5)"] = ours / echo
    clients = client_rates(seconds * rounds / 2)
    results["TCP round trips/s: our client (opentmcl.connect)"] = clients["ours"]
    if "pytrinamic" in clients:
        results["TCP round trips/s: PyTrinamic client"] = clients["pytrinamic"]
        results["client vs PyTrinamic ratio (target >= 1)"] = clients["ours"] / clients["pytrinamic"]
    return results


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--echo", choices=("tcp", "pty"), help="internal: run a bare echo server (until SIGTERM)")
    args = ap.parse_args()
    if args.echo:
        serve_tcp_echo() if args.echo == "tcp" else serve_pty_echo()
        return
    results = measure(args.quick)
    width = max(map(len, results))
    for key, value in results.items():
        print(f"{key:<{width}}  {value:>12,.2f}")


if __name__ == "__main__":
    main()
