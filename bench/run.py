"""OpenTMCL benchmarks: one command, figures measured side by side in one run.

    python bench/run.py            # full run (about a minute)
    python bench/run.py --quick    # short run, as CI does it (tests/test_bench.py)

Prints, for the virtual module core:
- virtual seconds per wall second, TMCM-6212 with six axes doing back-and-forth MVP moves (target >= 3600);
- virtual seconds per wall second, PD86-1180 at pulse_div = ramp_div = 0 (target >= 100);
- speed-up of the event-driven TMC429 engine over the per-tick reference model (exact agreement checked);
- in-process round trips per second through VirtualModule.handle (target >= 50,000).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # for tests.motion (the per-tick oracle)

from opentmcl import VirtualModule  # noqa: E402
from opentmcl.protocol.frame import Request  # noqa: E402


def back_and_forth(vm: VirtualModule, virtual_seconds: float, distance: int, chunk: float = 0.05) -> float:
    """Run MVP moves between 0 and `distance` on every axis; return virtual s per wall s."""
    axes = range(vm.profile.axes)
    targets = {a: distance for a in axes}
    for a in axes:
        vm.request(4, 0, a, targets[a])
    start = time.perf_counter()
    steps = round(virtual_seconds / chunk)
    for _ in range(steps):
        vm.advance(chunk)
        for a in axes:
            if vm.request(6, 8, a).value:
                targets[a] = 0 if targets[a] else distance
                vm.request(4, 0, a, targets[a])
    wall = time.perf_counter() - start
    return virtual_seconds / wall


def bench_6212(seconds: float) -> float:
    vm = VirtualModule("TMCM-6212")
    for a in range(6):
        vm.request(5, 4, a, 100000 + 20000 * a)
        vm.request(5, 5, a, 200000)
    return back_and_forth(vm, seconds, 51200)


def bench_1180(seconds: float) -> float:
    vm = VirtualModule("PD86-1180")
    vm.request(5, 154, 0, 0)
    vm.request(5, 153, 0, 0)
    vm.request(5, 4, 0, 2047)
    vm.request(5, 5, 0, 1000)
    return back_and_forth(vm, seconds, 200000, chunk=0.01)


def bench_round_trips(n: int) -> float:
    vm = VirtualModule("TMCM-6212")
    frames = [Request(1, 6, 1, a % 6, 0).encode() for a in range(64)]
    start = time.perf_counter()
    for i in range(n):
        vm.handle(frames[i & 63])
    return n / (time.perf_counter() - start)


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="short run")
    args = ap.parse_args(argv)
    scale = 0.1 if args.quick else 1.0
    results: dict[str, float] = {}
    results["6212 six axes, virtual s per wall s"] = bench_6212(600 * scale)
    results["PD86-1180 pulse_div=ramp_div=0, virtual s per wall s"] = bench_1180(20 * scale)
    try:
        from bench_tmc429 import measure as tmc429_measure  # noqa: PLC0415
        for key, value in tmc429_measure(quick=args.quick).items():
            results[f"TMC429 {key}"] = value
    except ImportError:
        pass
    results["in-process round trips per s"] = bench_round_trips(int(200000 * scale))
    width = max(map(len, results))
    for key, value in results.items():
        print(f"{key:<{width}}  {value:>14,.1f}")
    return results


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    main()
