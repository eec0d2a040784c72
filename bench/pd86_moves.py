"""Durations of a few PD86-1180 positioning moves with the module's default parameters.

    PYTHONPATH=src python bench/pd86_moves.py

Each row: a fresh VirtualModule("PD86-1180"), optional SAP, then MVP ABS from 0; the duration is the
virtual time until AP8 (position reached) reads 1. Only the public API is used (VirtualModule.request,
next_event_in, advance_to), so the table compares ramp models, not implementations.
"""
from __future__ import annotations

from opentmcl import VirtualModule
from opentmcl.motion import CLOCK_HZ

MOVES = [  # (label, [(axis parameter, value) set before the move], target)
    ("MVP ABS 1000", [], 1000),
    ("MVP ABS 10000", [], 10000),
    ("MVP ABS 100000", [], 100000),
    ("MVP ABS 1000000", [], 1000000),
    ("MVP ABS 100000, AP4=500", [(4, 500)], 100000),
    ("MVP ABS 100000, AP4=2047", [(4, 2047)], 100000),
]


def duration(sets: list[tuple[int, int]], target: int, limit_s: float = 3600.0) -> tuple[float, int]:
    """Virtual seconds from MVP ABS `target` until AP8 = 1, and the final position (AP1)."""
    vm = VirtualModule("PD86-1180")
    for number, value in sets:
        vm.request(5, number, 0, value)
    start = vm.now
    vm.request(4, 0, 0, target)
    end = start + round(limit_s * CLOCK_HZ)
    while vm.request(6, 8, 0).value != 1:
        if vm.now >= end:
            raise RuntimeError(f"MVP ABS {target} not reached within {limit_s} s")
        step = vm.next_event_in()
        vm.advance_to(end if step is None else min(end, vm.now + max(1, round(step * CLOCK_HZ))))
    return (vm.now - start) / CLOCK_HZ, vm.request(6, 1, 0).value


def main() -> None:
    print(f"{'move':<28} {'duration [s]':>13} {'AP1':>9}")
    for label, sets, target in MOVES:
        seconds, position = duration(sets, target)
        print(f"{label:<28} {seconds:>13.6f} {position:>9}")


if __name__ == "__main__":
    main()
