"""Where the time of a polling host goes: the top functions (tottime) of the 6-axis 10 ms polling
scenario of bench_polling.py (`vm.advance(0.01)`, then GAP 8 + GAP 1 of each of six moving
TMCM-6212 axes through `vm.handle`; with `--host`, `Module.sleep(0.01)` and `Module.request` through
`connect("sim://TMCM-6212")`, the host library's request path).

    python bench/profile_polling.py [--polls N] [--top N] [--host]
"""
from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_polling import poll_requests, start_moves  # noqa: E402
from opentmcl import VirtualModule, connect  # noqa: E402
from opentmcl.host import Module  # noqa: E402
from opentmcl.protocol.frame import Request  # noqa: E402


def poll(vm: VirtualModule, frames: list[bytes], polls: int) -> None:
    for _ in range(polls):
        vm.advance(0.01)
        for f in frames:
            vm.handle(f)


def poll_host(module: Module, requests: list[tuple[int, int, int, int]], polls: int) -> None:
    sleep, request = module.sleep, module.request
    for _ in range(polls):
        sleep(0.01)
        for r in requests:
            request(*r)


def profile(polls: int, top: int, host: bool = False) -> str:
    """The polling loop only: the module is built and its moves started before profiling."""
    profiler = cProfile.Profile()
    if host:
        module = connect("sim://TMCM-6212")
        start_moves(module.request, 6)
        poll_host(module, poll_requests(6), 10)  # warm-up
        profiler.runcall(poll_host, module, poll_requests(6), polls)
        module.close()
    else:
        vm = VirtualModule("TMCM-6212")
        start_moves(vm.request, 6)
        frames = [Request(1, *r).encode() for r in poll_requests(6)]
        poll(vm, frames, 10)  # warm-up
        profiler.runcall(poll, vm, frames, polls)
    out = io.StringIO()
    stats = pstats.Stats(profiler, stream=out)
    stats.strip_dirs().sort_stats("tottime").print_stats(top)
    return out.getvalue()


def positive(text: str) -> int:
    value = int(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive whole number, got {text}")
    return value


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--polls", type=positive, default=5000, help="polls of 10 ms (default 5000: 50 virtual s)")
    ap.add_argument("--top", type=positive, default=10, help="functions listed (default 10)")
    ap.add_argument("--host", action="store_true",
                    help="poll through connect(\"sim://TMCM-6212\") and Module.request instead of vm.handle")
    args = ap.parse_args(argv)
    print(profile(args.polls, args.top, args.host))


if __name__ == "__main__":
    main()
