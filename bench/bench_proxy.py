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
import socket
import statistics
import tempfile
import time

from opentmcl.protocol.frame import Request
from procs import endpoint, start_tool, stop

GAP_1 = Request(1, 6, 1, 0, 0).encode()


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
    server, lines = start_tool("serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0")
    direct_url = endpoint(lines, "tcp")
    with tempfile.TemporaryDirectory() as tmp:
        try:
            proxy, lines = start_tool("proxy", "--to", direct_url, "--tcp", "127.0.0.1:0", "--log",
                                      os.path.join(tmp, "bench.jsonl"))
            proxy_url = endpoint(lines, "tcp")
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
