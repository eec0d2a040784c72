"""Real-time benchmark: request latency of a served module that runs a costly TMCL program.

    python bench/bench_realtime.py [--seconds 5] [--modules 1,8] [--burners 0,2] [--module TMCM-6212]

Issue 28's program runs on every module of the bus (download, then 129):

    L: MVP ABS, 0, 100000
       MVP ABS, 0, -100000
       JA L

It re-plans the ramp every 100 µs of module time, so simulating it costs a large share of a CPU.
For each combination of bus size (1 and 8 modules, `opentmcl serve` in its own process) and load
(idle, and two CPU-burner processes alongside), one client sends GAP 1 (actual position, manual
3.6.6) to module 1 over TCP, one request at a time, and records each round trip; twice a second
it also reads GGP 132 (the tick timer, 1 ms per tick) to find the **module clock lag**: wall time
since the program started minus the module time that passed. At the end it sends 128 ("stop
application", manual 3.6.36) and 135 and reports how long the stop took to be answered.

The reference is a bare TCP echo server (bench_endpoints.py `--echo tcp`) in its own process,
measured in the same run with the same client loop and the same burners: its latency is what the
machine and the socket cost anyway. Figures: p50, p99 and max latency in ms, the lag at the end
and at worst (s), and the 128 round trip (ms).
"""
from __future__ import annotations

import argparse
import socket
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager

from bench_endpoints import echo_server
from opentmcl.protocol.frame import Reply, Request
from procs import endpoint, start_tool, stop

PROGRAM = "L: MVP ABS, 0, 100000\n   MVP ABS, 0, -100000\n   JA L\n"


@contextmanager
def burners(count: int) -> Iterator[None]:
    procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]
    try:
        yield
    finally:
        for p in procs:
            p.kill()
            p.wait()


class Link:
    """One TCP connection, one request at a time."""

    def __init__(self, url: str) -> None:
        host, port = url.removeprefix("tcp://").rsplit(":", 1)
        self.sock = socket.create_connection((host, int(port)), timeout=30)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def exchange(self, frame: bytes) -> bytes:
        self.sock.sendall(frame)
        got = b""
        while len(got) < 9:
            chunk = self.sock.recv(9 - len(got))
            if not chunk:
                raise ConnectionError("server closed the connection")
            got += chunk
        return got

    def request(self, address: int, command: int, type_: int = 0, motor: int = 0, value: int = 0) -> Reply:
        return Reply.decode(self.exchange(Request(address, command, type_, motor, value).encode()))

    def close(self) -> None:
        self.sock.close()


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def load_program(url: str, module: str, addresses: list[int]) -> None:
    import opentmcl
    from opentmcl.host.loader import download
    from opentmcl.lang.assembler import assemble

    program = assemble(PROGRAM, module=module)
    for address in addresses:
        target = opentmcl.connect(url, address=address, timeout=30)
        try:
            download(target, program)
        finally:
            target.close()


def measure(url: str, seconds: float, modules: int | None) -> dict[str, float]:
    """Latency of GAP 1 round trips for `seconds`; with `modules`, the program runs on them and
    the lag and the 128 round trip are measured too."""
    link = Link(url)
    lat: list[float] = []
    lags: list[float] = []
    frame = Request(1, 6, 1, 0, 0).encode()
    if modules:
        for address in range(1, modules + 1):
            link.request(address, 129)  # run from the current address (0 after the download)
        t0 = time.monotonic()
        tick0 = link.request(1, 10, 132).value
    end = time.monotonic() + seconds
    next_lag = time.monotonic() + 0.5
    while True:
        now = time.perf_counter()
        link.exchange(frame)
        lat.append(time.perf_counter() - now)
        if modules and time.monotonic() >= next_lag:
            ticks = link.request(1, 10, 132).value - tick0
            lags.append((time.monotonic() - t0) - ticks / 1000.0)
            next_lag += 0.5
        if time.monotonic() >= end:
            break
    out = {"n": len(lat), "p50": percentile(lat, 0.5) * 1e3, "p99": percentile(lat, 0.99) * 1e3,
           "max": max(lat) * 1e3, "mean": statistics.fmean(lat) * 1e3}
    if modules:
        out["lag_end"] = lags[-1] if lags else 0.0
        out["lag_worst"] = max(lags, default=0.0)
        stops = []
        for address in range(1, modules + 1):
            t = time.perf_counter()
            link.request(address, 128)
            stops.append(time.perf_counter() - t)
        out["stop_ms"] = max(stops) * 1e3
        out["stopped"] = float(all(link.request(a, 135).value >> 24 == 0 for a in range(1, modules + 1)))  # bits 24-31: mode
    link.close()
    return out


def run_served(module: str, count: int, seconds: float) -> dict[str, float]:
    argv = ["serve", "--tcp", "127.0.0.1:0", "-q"]
    for _ in range(count):
        argv += ["--module", module]
    proc, lines = start_tool(*argv)
    try:
        url = endpoint(lines, "tcp")
        load_program(url, module, list(range(1, count + 1)))
        return measure(url, seconds, count)
    finally:
        stop(proc)


def run_echo(seconds: float) -> dict[str, float]:
    with echo_server("tcp") as url:
        return measure(url, seconds, None)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--modules", default="1,8")
    parser.add_argument("--burners", default="0,2")
    parser.add_argument("--module", default="TMCM-6212")
    args = parser.parse_args(argv)
    sizes = [int(n) for n in args.modules.split(",")]
    loads = [int(n) for n in args.burners.split(",")]
    print(f"{'server':<22}{'burners':>8}{'n':>8}{'p50 ms':>9}{'p99 ms':>9}{'max ms':>9}"
          f"{'lag end s':>11}{'lag max s':>11}{'128 ms':>9}")
    for load in loads:
        with burners(load):
            rows = [("echo (reference)", run_echo(args.seconds))]
            rows += [(f"{args.module} x{n}", run_served(args.module, n, args.seconds)) for n in sizes]
        for name, r in rows:
            extra = (f"{r['lag_end']:>11.3f}{r['lag_worst']:>11.3f}{r['stop_ms']:>9.1f}"
                     + ("" if r["stopped"] else "  NOT STOPPED")) if "lag_end" in r else ""
            print(f"{name:<22}{load:>8}{r['n']:>8.0f}{r['p50']:>9.2f}{r['p99']:>9.2f}{r['max']:>9.2f}{extra}",
                  flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
