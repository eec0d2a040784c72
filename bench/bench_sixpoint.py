"""Engine-level benchmark of the motion engines (no firmware in the loop).

    python bench/bench_sixpoint.py [--quick]

`measure()` returns virtual seconds per wall second for six six-point
engines (a TMCM-6212) and for one linear engine doing back-and-forth MVP
moves, driven purely by next_event() (DESIGN.md "Time").
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
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    for k, v in measure(ap.parse_args().quick).items():
        print(f"{k:40s} {v:12.0f}")


if __name__ == "__main__":
    main()
