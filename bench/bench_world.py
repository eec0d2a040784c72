"""Virtual seconds per wall second in a physical world (docs/world.md): the next-event scan of
the axis world (`EventLookup.scan`, firmware/world_events.py) is on this path at every event.
Run: python bench/bench_world.py [--quick] (process time, so other load on the machine matters less)

- TMCM-6212, examples/scenarios/tmcm6212_stage.toml: axes 0 and 1 (stage with switches, loads,
  hard stops, encoder; rotary table) move back and forth between switches, with stop-on-stall
  (AP181) and the deviation limit (AP212) armed on axis 0;
- PD86-1180, examples/scenarios/pd86_1180_three_switch.toml: the axis moves back and forth through
  the home switch with the encoder null channel clear (AP210 + 4) armed.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from opentmcl import VirtualModule
from opentmcl.motion import CLOCK_HZ

SCENARIOS = Path(__file__).resolve().parent.parent / "examples" / "scenarios"


def _shuttle(vm: VirtualModule, targets: dict[int, tuple[int, int]], virtual_seconds: float) -> float:
    """Each axis moves between its two targets; the next move starts as soon as one arrives."""
    at = {a: 0 for a in targets}
    for a, (lo, _) in targets.items():
        vm.request(4, 0, a, lo)
    end = vm.now + round(virtual_seconds * CLOCK_HZ)
    start = time.process_time()
    while vm.now < end:
        vm.advance_to(min(end, vm.now + CLOCK_HZ // 100))
        for a, pair in targets.items():
            if vm.request(6, 8, a).value:          # AP8: position reached
                at[a] ^= 1
                vm.request(4, 0, a, pair[at[a]])
    return virtual_seconds / (time.process_time() - start)


def bench_6212_world(seconds: float) -> float:
    vm = VirtualModule("TMCM-6212", scenario=SCENARIOS / "tmcm6212_stage.toml")
    for a in (0, 1):
        vm.request(5, 4, a, 40000)
        vm.request(5, 12, a, 1)       # right limit switch disabled: the shuttle crosses it
        vm.request(5, 13, a, 1)
    vm.request(5, 181, 0, 1000)       # stop-on-stall armed (never reached at this load)
    vm.request(5, 212, 0, 100000)     # deviation limit armed
    return _shuttle(vm, {0: (-45000, 45000), 1: (-30000, 30000)}, seconds)


def bench_1180_world(seconds: float) -> float:
    vm = VirtualModule("TMCM-1180", scenario=SCENARIOS / "pd86_1180_three_switch.toml")
    vm.request(5, 4, 0, 1000)
    vm.request(5, 210, 0, 512 + 4)   # prescaler 1 and clear at the next null channel
    return _shuttle(vm, {0: (-20000, 20000)}, seconds)


def bench_next_event_scan(calls: int) -> float:
    """Microseconds (process time) per next-event scan of axis 0 of the TMCM-6212 stage scenario,
    mid-move with every event source armed (switch edges, load steps, ends, stall, deviation)."""
    vm = VirtualModule("TMCM-6212", scenario=SCENARIOS / "tmcm6212_stage.toml")
    vm.request(5, 181, 0, 1000)
    vm.request(5, 212, 0, 100000)
    vm.request(4, 0, 0, 45000)
    vm.advance(0.3)
    aw = vm.world.axis(0)
    now = vm.now
    start = time.process_time()
    for _ in range(calls):
        aw.events.scan(now)
    return (time.process_time() - start) / calls * 1e6


def main() -> dict[str, float]:
    seconds = 2.0 if "--quick" in sys.argv else 20.0
    # the TMC429 engine's position search dominates the PD86-1180 run: a shorter one
    out = {"TMCM-6212 world (stage scenario) virtual s per wall s": bench_6212_world(seconds),
           "PD86-1180 world (three-switch scenario) virtual s per wall s": bench_1180_world(seconds / 20),
           "AxisWorld next-event scan, TMCM-6212 stage axis 0, microseconds per call":
               bench_next_event_scan(2_000 if seconds < 20 else 20_000)}
    for k, v in out.items():
        print(f"{k}: {v:,.3g}")
    return out


if __name__ == "__main__":
    main()
