"""Engine-level benchmark of the motion engines (no firmware in the loop).

    python bench/bench_sixpoint.py [--quick]

`measure()` returns virtual seconds per wall second for six six-point
engines (a TMCM-6212) and for one linear engine doing back-and-forth MVP
moves, driven purely by next_event() (docs/architecture.md "Time"), and the wall cost
of one move_to() in microseconds: for a distance moved before (the planner's
per-distance cache, the back-and-forth case) and for a new distance each time.
"""
from __future__ import annotations

import argparse
import time

from opentmcl.motion import CLOCK_HZ
from opentmcl.motion.linear import LinearRampEngine
from opentmcl.motion.sixpoint import SixPointRampEngine


def _back_and_forth(engines, moves: int, distance: int) -> float:
    """Every engine moves 0 -> distance -> 0 ... `moves` times, each as soon as it
    arrives; all engines share one clock. Returns virtual s per wall s."""
    targets = [distance] * len(engines)
    done = [0] * len(engines)
    for e, t in zip(engines, targets, strict=True):
        e.move_to(t)
    now = 0
    start = time.perf_counter()
    while min(done) < moves:
        nxt = min(n for e in engines if (n := e.next_event()) is not None)
        now = nxt
        for i, e in enumerate(engines):
            e.advance(now)
            if e.position_reached and done[i] < moves:
                done[i] += 1
                targets[i] = 0 if targets[i] else distance
                e.move_to(targets[i])
    wall = time.perf_counter() - start
    return (now / CLOCK_HZ) / wall


def _us_per_move(moves: int, repeated: bool) -> float:
    """Microseconds per MVP from a standstill (the move is planned, then run to
    its end through next_event()/advance()/position_reached, as a VM does)."""
    e = SixPointRampEngine(max_positioning_speed=200000, max_acceleration=200000)
    start = time.perf_counter()
    target = 0
    for i in range(moves):
        if repeated:
            target = 0 if target else 51200
        else:
            target = 0 if target else 1000 + (i * 7919) % 200000
        e.move_to(target)
        while (n := e.next_event()) is not None:
            e.advance(n)
            e.position_reached  # noqa: B018 -- polled after every event, as the VM does
    return (time.perf_counter() - start) / moves * 1e6


def measure(quick: bool = False) -> dict:
    """Virtual seconds per wall second (higher is better)."""
    moves = 20 if quick else 200
    six = [SixPointRampEngine(velocity_v1=20000, acceleration_a1=100000, deceleration_d1=100000,
                              velocity_vstart=100, velocity_vstop=200, ramp_wait_time=100)
           for _ in range(6)]
    for i, e in enumerate(six):          # slightly different ramps so events do not coincide
        e.configure(max_positioning_speed=51200 + 1000 * i)
    lin = [LinearRampEngine()]
    return {
        "sixpoint_6axes_virtual_s_per_wall_s": _back_and_forth(six, moves, 51200 * 4),
        "linear_1axis_virtual_s_per_wall_s": _back_and_forth(lin, moves, 51200 * 4),
        "sixpoint_us_per_move_same_distance": _us_per_move(moves * 10, repeated=True),
        "sixpoint_us_per_move_new_distance": _us_per_move(moves * 10, repeated=False),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    for k, v in measure(ap.parse_args().quick).items():
        print(f"{k:40s} {v:12.1f}")


if __name__ == "__main__":
    main()
