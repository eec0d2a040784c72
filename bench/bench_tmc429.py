"""Benchmark of the event-driven TMC429 core against its per-tick oracle.

    python bench/bench_tmc429.py [--quick]

`measure()` runs a PD86-1180 back-and-forth scenario (MVP between 0 and a
distance, next move as soon as the previous one has arrived) at
pulse_div = ramp_div = 0, V_MAX = 2047, A_MAX = 1000 and returns:

- the speed-up of the fast core over the per-tick reference model
  (tests/motion/tmc429_reference.py) on the same moves, after checking that
  both arrive at exactly the same cycles and positions;
- virtual seconds per wall second of the fast engine (Tmc429Engine) on a long
  run of that scenario, and the same with the plan memo emptied before every
  event (the cost of planning each phase);
- wall milliseconds of one long ramp_mode move at a small A_MAX (first braking,
  memos cleared), where the braking stretch lasts V_MAX * 256 / A_MAX ramp
  ticks (lower is better).
"""
from __future__ import annotations

import argparse
import importlib.util
import time
from pathlib import Path

from opentmcl.motion import CLOCK_HZ, tmc429
from opentmcl.motion.pmulpdiv import registers_for
from opentmcl.motion.tmc429 import Tmc429Ramp
from opentmcl.motion.tmc429_engine import Tmc429Engine

V_MAX, A_MAX = 2047, 1000


def _reference_class():
    path = Path(__file__).resolve().parent.parent / "tests" / "motion" / "tmc429_reference.py"
    spec = importlib.util.spec_from_file_location("tmc429_reference", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.ReferenceRamp


def _configure(r) -> None:
    pmul, pdiv = registers_for(A_MAX, 0, 0)
    r.set(pulse_div=0, ramp_div=0, v_max=V_MAX, v_min=1, a_max=A_MAX, pmul=pmul, pdiv=pdiv)


def _fast_arrivals(moves: int, distance: int) -> tuple[list[tuple[int, int]], float]:
    r = Tmc429Ramp(position_bits=32)
    _configure(r)
    arrivals = []
    start = time.perf_counter()
    target = distance
    for _ in range(moves):
        r.set(x_target=target)
        while (e := r.next_event()) is not None:
            r.advance(e)
        arrivals.append((r.now, r.x_actual))
        target = distance - target
    return arrivals, time.perf_counter() - start


def _reference_arrivals(moves: int, distance: int, chunk: int) -> tuple[list[tuple[int, int]], float]:
    """The oracle has no next_event: step it in chunks of `chunk` cycles and find the
    arrival cycle inside the chunk by replaying from a copy."""
    import copy

    ref_cls = _reference_class()
    r = ref_cls(position_bits=32)
    _configure(r)
    arrivals = []
    start = time.perf_counter()
    target = distance
    for _ in range(moves):
        r.set(x_target=target)
        while True:
            before = copy.copy(r)
            r.advance(r.now + chunk)
            if r.x_actual == r.x_target and r.v == 0:
                break
        lo, hi = before.now + 1, r.now        # arrival cycle: first with x == target, v == 0
        while lo < hi:
            mid = (lo + hi) // 2
            probe = copy.copy(before)
            probe.advance(mid)
            if probe.x_actual == probe.x_target and probe.v == 0:
                hi = mid
            else:
                lo = mid + 1
        r = copy.copy(before)
        r.advance(lo)
        arrivals.append((r.now, r.x_actual))
        target = distance - target
    return arrivals, time.perf_counter() - start


def _engine_run(virtual_seconds: float, distance: int, cold: bool = False) -> float:
    """Virtual s per wall s; `cold` empties the plan and follow memo before every event."""
    e = Tmc429Engine()
    e.configure(pulse_divisor=0, ramp_divisor=0, max_positioning_speed=V_MAX, max_acceleration=A_MAX,
                minimum_speed=1)
    horizon = int(virtual_seconds * CLOCK_HZ)
    target = distance
    e.move_to(target)
    start = time.perf_counter()
    while e.now < horizon:
        if cold:
            tmc429.clear_memos()
        t = e.next_event()
        if t is None:
            target = distance - target
            e.move_to(target)
            continue
        e.advance(min(t, horizon))
    wall = time.perf_counter() - start
    return virtual_seconds / wall


def _small_a_max_move_ms(a_max: int, distance: int) -> float:
    """Wall ms of one ramp_mode move from 0 at V_MAX = 2047 and `a_max`, memo cold."""
    pmul, pdiv = registers_for(a_max, 0, 0)
    r = Tmc429Ramp(position_bits=32)
    r.set(pulse_div=0, ramp_div=0, v_max=V_MAX, v_min=1, a_max=a_max, pmul=pmul, pdiv=pdiv)
    r.set(x_target=distance)
    tmc429.clear_memos()
    start = time.perf_counter()
    while (e := r.next_event()) is not None:
        r.advance(e)
    wall = time.perf_counter() - start
    if r.x_actual != distance or not r.position_reached:
        raise AssertionError(f"small A_MAX move ended at {r.x_actual}, not {distance}")
    return wall * 1000


def measure(quick: bool = False) -> dict:
    """Speed-up over the per-tick model and virtual s per wall s (higher is better)."""
    moves, distance = (2, 20_000) if quick else (6, 50_000)
    fast, fast_wall = _fast_arrivals(moves, distance)
    ref, ref_wall = _reference_arrivals(moves, distance, chunk=32 * 4096)
    if fast != ref:
        raise AssertionError(f"fast core and per-tick model disagree: {fast} != {ref}")
    # time the oracle without the arrival search, on the same virtual span
    ref_cls = _reference_class()
    r = ref_cls(position_bits=32)
    _configure(r)
    start = time.perf_counter()
    target, prev = distance, 0
    for t_arrive, _x in fast:
        r.set(x_target=target)
        r.advance(t_arrive)
        prev = t_arrive
        target = distance - target
    ref_wall = min(ref_wall, time.perf_counter() - start)
    span_s = prev / CLOCK_HZ
    return {
        "fast vs per-tick speed-up (exact agreement checked)": ref_wall / max(fast_wall, 1e-9),
        "per-tick model virtual s per wall s": span_s / ref_wall,
        "PD86-1180 engine back-and-forth, pulse_div=ramp_div=0, virtual s per wall s":
            _engine_run(20.0 if quick else 600.0, 200_000),
        "the same, memo emptied before every event (each phase planned), virtual s per wall s":
            _engine_run(20.0 if quick else 600.0, 200_000, cold=True),
        "one move at A_MAX=4, V_MAX=2047, 3e6 steps, first braking (memo cold), wall ms":
            _small_a_max_move_ms(4, 3_000_000),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    for k, v in measure(ap.parse_args().quick).items():
        print(f"{k:80s} {v:14,.1f}")


if __name__ == "__main__":
    main()
