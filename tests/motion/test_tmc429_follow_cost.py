"""The braking stretch of the fast TMC429 core: exact and O(velocity levels), for a small A_MAX.

TMC4210 datasheet 6.1.9: the chip calculates "the velocity required for stopping in time to
exactly reach the target position ... This calculation is done for each ramp step. ... Whenever
V_TARGET falls below the actual velocity, the TMC4210 decelerates." With a small A_MAX ("the
maximum acceleration A_MAX ... 0..2047", 6.1.7) that deceleration lasts |V| * 256 / A_MAX ramp
ticks; docs/architecture.md "Time" asks the event-driven core not to pay per tick. The cost is counted as
the number of target-velocity evaluations (integer square roots) the core does — the real
`isqrt` wrapped by a counter, no wall clock — and the result must still be the per-tick oracle's.
"""
from __future__ import annotations

import math
from contextlib import contextmanager

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from opentmcl.motion import tmc429, tmc429_arith, tmc429_follow
from opentmcl.motion.pmulpdiv import registers_for
from opentmcl.motion.tmc429 import HOLD_MODE, RAMP_MODE, Tmc429Ramp

from .test_tmc429_agreement import RecordingReference, apply, state


@contextmanager
def counted_isqrt():
    """Count the fast core's target-velocity evaluations (its calls of math.isqrt)."""
    calls = [0]

    def counting(x: int) -> int:
        calls[0] += 1
        return math.isqrt(x)

    modules = (tmc429_arith, tmc429_follow)       # the core's only square roots
    saved = [m.isqrt for m in modules]
    for m in modules:
        m.isqrt = counting
    try:
        yield calls
    finally:
        for m, f in zip(modules, saved, strict=True):
            m.isqrt = f


def level_budget(v: int) -> int:
    """Allowed evaluations for a stretch that starts at |V| = v: a few per velocity level
    (whatever A_MAX), plus the phase planning around it."""
    return 16 * (v + 1) + 400


def braking_distance(v: int, pmul: int, pdiv: int) -> int:
    """Steps over which the computed target falls from v to 0: v^2 = 2048 p D (6.1.9)."""
    return max(1, (v * v << (3 + pdiv)) // (2048 * pmul))


braking = st.tuples(
    st.integers(0, 2), st.integers(0, 1), st.integers(1, 64), st.integers(16, 300),
    st.integers(1, 4), st.floats(0.3, 1.5), st.lists(st.floats(0.0, 1.0), min_size=1, max_size=4))


@settings(max_examples=20, deadline=None)
@given(braking)
def test_long_braking_at_small_a_max_is_exact_and_cheap(m):
    """TMC4210 6.1.9 ("This calculation is done for each ramp step"), 6.1.7 (A_MAX 1..64 here):
    a motor running at |V| (hold_mode, 6.1.10.1) switched to ramp_mode with its target within
    about its braking distance follows V_TARGET down for up to V*256/A_MAX ramp ticks. At random
    cycles inside that stretch (a `limit` cut) the state and every step (cycle, direction) are the
    oracle's, arrival and the V_MIN stop (6.1.3) happen on the oracle's cycle, and the whole
    stretch costs a bounded number of target evaluations per velocity level, not per tick."""
    pd, extra, a_max, v, v_min, f, cuts = m
    rd = pd + extra
    pmul, pdiv = registers_for(a_max, rd, pd)
    regs = {"pulse_div": pd, "ramp_div": rd, "v_max": v, "v_min": v_min, "a_max": a_max,
            "pmul": pmul, "pdiv": pdiv, "mode": HOLD_MODE}
    fast, ref = Tmc429Ramp(position_bits=32), RecordingReference(position_bits=32)
    apply((fast, ref), regs)
    apply((fast, ref), {"v_actual": v})
    apply((fast, ref), {"mode": RAMP_MODE,
                        "x_target": max(1, int(f * braking_distance(v, pmul, pdiv)))})
    span = v * 256 // a_max * (32 << rd)          # about the length of the braking
    tmc429.clear_memos()
    steps: list = []
    with counted_isqrt() as calls:
        for cut in sorted(cuts):
            t = max(fast.now, int(cut * span))
            steps += fast.step_events(t)
            ref.advance(t)
            assert state(fast) == state(ref)
        events = 0
        while (e := fast.next_event()) is not None and events < 200:
            steps += fast.step_events(e)
            ref.advance(e)
            assert state(fast) == state(ref)
            events += 1
    assert fast.position_reached
    assert steps == ref.steps
    assert calls[0] <= (len(cuts) + 2) * level_budget(v)


def test_first_braking_at_a_max_1_costs_levels_not_ticks():
    """TMC4210 6.1.9 / 6.1.7: a 3 000 000-step move at V_MAX = 2047, A_MAX = 1 (the smallest
    acceleration) brakes for 2047 * 256 = 524 032 ramp ticks; with a cold memo the fast core
    evaluates the target a few times per velocity level (at most 16 * 2048 + 400 times for the
    whole move) and lands where the per-tick oracle lands, on the same cycle."""
    pmul, pdiv = registers_for(1, 0, 0)
    regs = {"v_max": 2047, "v_min": 1, "a_max": 1, "pmul": pmul, "pdiv": pdiv}
    fast = Tmc429Ramp(position_bits=32)
    apply((fast,), regs)
    apply((fast,), {"x_target": 3_000_000})
    tmc429.clear_memos()
    with counted_isqrt() as calls:
        while (e := fast.next_event()) is not None:
            fast.advance(e)
    assert fast.position_reached and fast.x_actual == 3_000_000
    assert calls[0] <= level_budget(2047)
    # exactness on the same move, checked on the braking stretch only (the oracle is slow):
    # both models are put at the fast core's state when braking starts
    probe = Tmc429Ramp(position_bits=32)
    apply((probe,), regs)
    apply((probe,), {"x_target": 3_000_000})
    while probe.a_actual >= 0:
        probe.advance(probe.next_event())
    ref = RecordingReference(position_bits=32)
    apply((ref,), regs)
    ref.now, ref.x_actual, ref.x_target = probe.now, probe.x_actual, probe.x_target
    ref.v, (ref.acc, ref.acc_dir) = probe.v_internal, probe.pulse_accumulator
    ref.advance(fast.now)
    assert state(ref) == state(fast)


@pytest.mark.parametrize("a_max, v_max", [(32, 300), (100, 2047), (300, 2047), (1000, 300),
                                          (1000, 2047), (2047, 2047)])
@pytest.mark.parametrize("div", [0, 2])
def test_braking_at_equal_dividers_evaluates_the_target_on_few_ticks(a_max, v_max, div):
    """TMC4210 6.1.9: V_TARGET is "calculated for each ramp step"; while |V| falls by A_MAX above
    it ("Whenever V_TARGET falls below the actual velocity, the TMC4210 decelerates") the fast
    core at PULSE_DIV = RAMP_DIV (6.1.12) and A_MAX >= 32 decides each such tick with integer
    tests and evaluates the square root only on the other ticks: fewer than one braking tick in
    four (V_MAX * 256 / A_MAX ticks), plus the phase planning. The move arrives on the per-tick
    oracle's cycle. The move (10 * V_MAX steps) is long enough to reach V_MAX."""
    pmul, pdiv = registers_for(a_max, div, div)
    regs = {"pulse_div": div, "ramp_div": div, "v_max": v_max, "v_min": 1, "a_max": a_max,
            "pmul": pmul, "pdiv": pdiv}
    fast = Tmc429Ramp(position_bits=32)
    apply((fast,), regs)
    target = 10 * v_max
    apply((fast,), {"x_target": target})
    tmc429.clear_memos()
    with counted_isqrt() as calls:
        while (e := fast.next_event()) is not None:
            fast.advance(e)
    assert fast.position_reached and fast.x_actual == target
    assert calls[0] <= v_max * 256 // a_max // 4 + 50
    ref = RecordingReference(position_bits=32)
    apply((ref,), regs)
    apply((ref,), {"x_target": target})
    ref.advance(fast.now - 1)
    assert not (ref.x_actual == target and ref.v == 0)
    ref.advance(fast.now)
    assert state(ref) == state(fast)


@pytest.mark.parametrize("a_max", [1, 2, 4, 8, 16])
def test_first_braking_follows_the_levels_down_without_square_roots(a_max):
    """TMC4210 6.1.9: V_TARGET is calculated "for each ramp step" and "Whenever V_TARGET falls
    below the actual velocity, the TMC4210 decelerates"; with A_MAX (6.1.7) dividing 256 and p
    from 6.1.9.2 the velocity lands on each velocity level and stays there while the target
    does. The fast core walks those levels with the level starts ceil(n^2 * 2^(3+PDIV) / PMUL)
    (docs/motion-tmc429.md), so a cold 3 000 000-step move at V_MAX = 2047 evaluates the target
    at most 64 times in all (2047 levels; at least one evaluation per level before); the
    braking lands where the per-tick oracle lands, on the same cycle."""
    pmul, pdiv = registers_for(a_max, 0, 0)
    regs = {"v_max": 2047, "v_min": 1, "a_max": a_max, "pmul": pmul, "pdiv": pdiv}
    fast, probe = Tmc429Ramp(position_bits=32), Tmc429Ramp(position_bits=32)
    apply((fast, probe), regs)
    apply((fast, probe), {"x_target": 3_000_000})
    tmc429.clear_memos()
    with counted_isqrt() as calls:
        while (e := fast.next_event()) is not None:
            fast.advance(e)
    assert fast.position_reached and fast.x_actual == 3_000_000
    assert calls[0] <= 64
    if a_max != 4:          # the oracle is slow: one braking (131 008 ticks) checked
        return
    while probe.a_actual >= 0:
        probe.advance(probe.next_event())
    ref = RecordingReference(position_bits=32)
    apply((ref,), regs)
    ref.now, ref.x_actual, ref.x_target = probe.now, probe.x_actual, probe.x_target
    ref.v, (ref.acc, ref.acc_dir) = probe.v_internal, probe.pulse_accumulator
    ref.advance(fast.now - 1)
    assert not (ref.x_actual == 3_000_000 and ref.v == 0)
    ref.advance(fast.now)
    assert state(ref) == state(fast)


def test_a_repeated_move_is_planned_once():
    """TMC4210 6.1.9 / PD86-1180 MVP (4.6.4): back-and-forth moves of 20 000 steps at V_MAX =
    2047, A_MAX = 1000 repeat the same motion relative to their start once the pulse
    accumulator's fraction repeats. From the fourth move on the fast core takes every phase from
    its memo (docs/motion-tmc429.md): at most one target evaluation per event (the ramp tick
    it applies), where planning alone evaluates it several times. Every event, and cycles
    sampled inside the phases (a second core, planned from the same memo), match the per-tick
    oracle."""
    pmul, pdiv = registers_for(1000, 0, 0)
    regs = {"v_max": 2047, "v_min": 1, "a_max": 1000, "pmul": pmul, "pdiv": pdiv}
    fast, sampled = Tmc429Ramp(position_bits=32), Tmc429Ramp(position_bits=32)
    ref = RecordingReference(position_bits=32)
    apply((fast, sampled, ref), regs)
    tmc429.clear_memos()
    for move in range(8):
        target = 0 if move % 2 else 20_000
        apply((fast, sampled, ref), {"x_target": target})
        events = 0
        with counted_isqrt() as calls:
            while (e := fast.next_event()) is not None:
                fast.advance(e)
                events += 1
        assert fast.position_reached and fast.x_actual == target
        if move >= 3:
            assert calls[0] <= events
        while (e := sampled.next_event()) is not None:
            middle = (sampled.now + e) // 2
            for r in (sampled, ref):
                r.advance(middle)
            assert state(sampled) == state(ref)
            for r in (sampled, ref):
                r.advance(e)
            assert state(sampled) == state(ref)
        assert state(sampled)[1:] == state(fast)[1:]
