"""OpenTMCL benchmarks: one command, figures measured side by side in one run.

    python bench/run.py            # full run (about a minute)
    python bench/run.py --quick    # short run, as CI does it (tests/test_bench.py)

Prints, for the virtual module core:
- virtual seconds per wall second, TMCM-6212 with six axes doing back-and-forth MVP moves (target >= 3600);
- virtual seconds per wall second, PD86-1180 at pulse_div = ramp_div = 0 (target >= 100);
- speed-up of the event-driven TMC429 engine over the per-tick reference model (exact agreement checked);
- in-process round trips per second through VirtualModule.handle (target >= 50,000);
- the engines alone (bench_sixpoint.py, bench_tmc429.py);
- round trips through TCP and the pseudo-terminal next to a bare echo server on the same transport
  (target: ours >= 50 % of echo), and our client against PyTrinamic on the same module (target >= 1)
  (bench_endpoints.py);
- memory of the world and plot traces in MB per hour of recording at 10 ms, compact columns next to
  the old dict-per-row / list-per-channel layouts (target < 100 MB; bench_trace.py).
- the round-trip time `opentmcl proxy` adds on loopback, next to a direct connection to the same served
  module in the same run (target: < 1 ms added; bench_proxy.py).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # for tests.motion (the per-tick oracle)
sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_endpoints  # noqa: E402
import bench_proxy  # noqa: E402
import bench_sixpoint  # noqa: E402
import bench_tmc429  # noqa: E402
import bench_trace  # noqa: E402
from opentmcl import VirtualModule  # noqa: E402
from opentmcl.motion import CLOCK_HZ  # noqa: E402
from opentmcl.protocol.frame import Request  # noqa: E402


def back_and_forth(vm: VirtualModule, virtual_seconds: float, distance: int) -> float:
    """Every axis moves between 0 and `distance` (MVP ABS); the host hears of each arrival through
    command 138 and sends the next move at once. Returns virtual seconds per wall second."""
    axes = range(vm.profile.axes)
    targets = dict.fromkeys(axes, distance)
    vm.request(138, 1, 0, (1 << vm.profile.axes) - 1)
    for a in axes:
        vm.request(4, 0, a, distance)
    end = vm.now + round(virtual_seconds * CLOCK_HZ)
    start = time.perf_counter()
    while vm.now < end:
        step = vm.next_event_in()
        vm.advance_to(end if step is None else min(end, vm.now + max(1, round(step * CLOCK_HZ))))
        for raw in vm.drain_events():
            axis = raw[7].bit_length() - 1
            targets[axis] = 0 if targets[axis] else distance
            vm.request(4, 0, axis, targets[axis])
    return virtual_seconds / (time.perf_counter() - start)


def bench_6212(seconds: float) -> float:
    """Six axes at factory ramp settings (51200 pps, 51200 pps^2: one revolution per second at 256
    microsteps and 200 full steps), each moving back and forth over ten revolutions (512000 µsteps),
    axes 1-5 with slightly higher speeds so that their events do not coincide."""
    vm = VirtualModule("TMCM-6212")
    for a in range(1, 6):
        vm.request(5, 4, a, 51200 + 5000 * a)
    return back_and_forth(vm, seconds, 512000)


def bench_6212_short(seconds: float) -> float:
    """The same with short, fast moves (51200 µsteps at up to 200000 pps): the cost per move."""
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
    return back_and_forth(vm, seconds, 200000)


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
    results["6212 six axes, 10-revolution moves, virtual s per wall s (target >= 3600)"] = bench_6212(3600 * scale)
    results["6212 six axes, short fast moves, virtual s per wall s"] = bench_6212_short(300 * scale)
    results["PD86-1180 pulse_div=ramp_div=0, virtual s per wall s (target >= 100)"] = bench_1180(20 * scale)
    for label, measure in (("engine", bench_sixpoint.measure), ("TMC429", bench_tmc429.measure),
                           ("endpoints", bench_endpoints.measure), ("memory", bench_trace.measure),
                           ("proxy", bench_proxy.measure)):
        for key, value in measure(quick=args.quick).items():
            results[f"{label} {key}"] = value
    results["in-process round trips per s (target >= 50000)"] = bench_round_trips(int(200000 * scale))
    width = max(map(len, results))
    for key, value in results.items():
        print(f"{key:<{width}}  {value:>14,.2f}" if value < 100 else f"{key:<{width}}  {value:>14,.0f}")
    return results


if __name__ == "__main__":
    main()
