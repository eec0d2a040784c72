"""The braking stretch of the TMC429 core at the PD86-1180's dividers: exact, and reported early enough.

TMC4210 datasheet 6.1.9: the target velocity is "calculated for each ramp step" and "Whenever
V_TARGET falls below the actual velocity, the TMC4210 decelerates"; 6.1.12: a ramp tick every
32 * 2^RAMP_DIV and a pulse tick every 32 * 2^PULSE_DIV clock cycles. The PD86-1180 runs
RAMP_DIV = 7 over PULSE_DIV = 3 by default (manual ch. 5, AP153/AP154), sixteen pulse ticks per
ramp tick, where the core walks the braking one velocity level per pass (docs/motion-tmc429.md
"Following the target"). Issue 33 wants the ramp exactly as before: every state here is the per-tick
oracle's (tests/motion/tmc429_reference.py). next_event() may report a long braking stretch by a
cycle proven to lie at or before its end (`tmc429_follow.end_bound`); the tests check that bound
against the oracle and that no arrival is ever skipped.
"""
from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from opentmcl.motion.pmulpdiv import registers_for
from opentmcl.motion.tmc429 import HOLD_MODE, RAMP_MODE, Tmc429Ramp
from opentmcl.motion.tmc429_follow import FollowRegisters, end_bound

from .test_tmc429_agreement import RecordingReference, apply, state
from .tmc429_reference import ReferenceRamp


def braking_distance(v: int, pmul: int, pdiv: int) -> int:
    """Steps over which the computed target falls from v to 0: v^2 = 2048 p D (6.1.9)."""
    return max(1, (v * v << (3 + pdiv)) // (2048 * pmul))


# (PULSE_DIV, RAMP_DIV - PULSE_DIV, A_MAX, V_MAX, V_MIN, distance as a fraction of the braking
# distance, sample points as fractions of the braking time)
dividers = st.tuples(st.integers(0, 4), st.integers(0, 6))
braking = st.tuples(dividers, st.one_of(st.integers(1, 255), st.integers(256, 2047)),
                    st.integers(40, 2047), st.integers(0, 6), st.floats(0.2, 1.3),
                    st.lists(st.floats(0.0, 1.0), min_size=1, max_size=5))


def _registers(pd: int, extra: int, a_max: int, v: int, v_min: int) -> dict | None:
    rd = pd + extra
    pmul, pdiv = registers_for(a_max, rd, pd)
    if pmul is None:
        return None
    return {"pulse_div": pd, "ramp_div": rd, "v_max": v, "v_min": v_min, "a_max": a_max,
            "pmul": pmul, "pdiv": pdiv}


@settings(max_examples=40, deadline=None)
@given(braking)
def test_braking_from_speed_matches_the_oracle(m):
    """6.1.9, 6.1.10.1 (hold_mode keeps V_ACTUAL), 6.1.12: a motor at |V| = V_MAX switched to
    ramp_mode with its target within about its braking distance follows V_TARGET down with up to
    64 pulse ticks per ramp tick and any A_MAX (below 256: a velocity level per pass, else a
    tick per pass); at random cycles and at every next_event() it is the oracle, advanced there
    or listing its steps on the way (step_events, 6.1.12 Step/Dir)."""
    (pd, extra), a_max, v, v_min, f, cuts = m
    regs = _registers(pd, extra, a_max, v, v_min)
    if regs is None:
        return
    fast, lister = Tmc429Ramp(position_bits=32), Tmc429Ramp(position_bits=32)
    ref = RecordingReference(position_bits=32)
    cores = (fast, lister, ref)
    apply(cores, {**regs, "mode": HOLD_MODE})
    apply(cores, {"v_actual": v})
    distance = max(1, int(f * braking_distance(v, regs["pmul"], regs["pdiv"])))
    apply(cores, {"mode": RAMP_MODE, "x_target": distance})
    span = v * 256 // a_max * (32 << regs["ramp_div"])
    steps: list = []
    for cut in sorted(cuts):
        t = max(fast.now, int(cut * span))
        fast.advance(t)                      # the walk without a step list
        steps += lister.step_events(t)       # the walk listing the steps
        ref.advance(t)
        assert state(fast) == state(ref) == state(lister)
    for _ in range(12):
        e = fast.next_event()
        if e is None:
            break
        fast.advance(e)
        steps += lister.step_events(e)
        ref.advance(e)
        assert state(fast) == state(ref) == state(lister)
    assert steps == ref.steps


moves = st.tuples(dividers, st.one_of(st.integers(1, 255), st.integers(256, 2047)),
                  st.integers(1, 2047), st.integers(1, 6), st.integers(1, 20_000),
                  st.lists(st.integers(1, 1 << 22), min_size=1, max_size=6))


@settings(max_examples=30, deadline=None)
@given(moves)
def test_polled_move_matches_the_oracle_and_reports_its_arrival(m):
    """PD86-1180 MVP (4.6.4) as the VM drives it: next_event() then advance to it or to the next
    poll, whichever comes first. Every state read is the oracle's, and the cycle at which the
    oracle first has X_ACTUAL = X_TARGET at rest (AP8, 6.1.11 pos_end) is one of the cycles the
    core reported, not skipped over."""
    (pd, extra), a_max, v_max, v_min, distance, polls = m
    regs = _registers(pd, extra, a_max, v_max, v_min)
    if regs is None:
        return
    fast, ref = Tmc429Ramp(position_bits=32), ReferenceRamp(position_bits=32)
    apply((fast, ref), regs)
    apply((fast, ref), {"x_target": distance})
    reported = set()
    poll = iter(polls * 40)
    while not fast.position_reached:
        e = fast.next_event()
        assert e is not None and e > fast.now
        reported.add(e)
        t = min(e, fast.now + next(poll, 1 << 22))
        fast.advance(t)
        ref.advance(t)
        assert state(fast) == state(ref)
    arrival = fast.now
    assert arrival in reported
    early = ReferenceRamp(position_bits=32)
    apply((early,), regs)
    apply((early,), {"x_target": distance})
    early.advance(arrival - 1)
    assert not (early.x_actual == early.x_target and early.v == 0)


class StretchEnd(ReferenceRamp):
    """The oracle noting where a stretch towards X_TARGET ends: the cycle of the arrival step, or
    the cycle after the ramp tick that leaves |v| at V_MIN * 256 (or 0)."""

    end: int | None = None

    def ramp_tick(self) -> None:
        super().ramp_tick()
        if self.end is None and abs(self.v) in (min(self.v_min, self.v_max) * 256, 0):
            self.end = self.now + 1        # `now` is still the cycle before this tick here

    def on_step(self, cycle: int, direction: int) -> None:
        if self.end is None and self.x_actual == self.x_target:
            self.end = cycle

    def advance(self, until: int) -> None:
        ramp_period, pulse_period = 32 << self.ramp_div, 32 << self.pulse_div
        base = min(ramp_period, pulse_period)
        c = (self.now // base + 1) * base
        while c <= until and self.end is None:
            self.now = c - 1
            if c % ramp_period == 0:
                self.ramp_tick()
            if c % pulse_period == 0:
                self.pulse_tick(c)
            c += base
        self.now = until if self.end is None else c - base


def _check_bound(regs: dict, t0: int, x: int, xt: int, v: int, acc: int, acc_dir: int) -> int:
    """end_bound for a ramp_mode state moving towards its target, checked on the oracle."""
    follow = FollowRegisters(32 << regs["ramp_div"], 32 << regs["pulse_div"], regs["a_max"],
                             regs["pmul"] | 0x80, regs["pdiv"], regs["v_min"], regs["v_max"])
    made = acc if acc_dir in (0, 1) else 2047 - acc
    units = (xt - x) * 2048 - made
    bound = end_bound(follow, t0, abs(v), units)
    assert bound > t0
    ref = StretchEnd(position_bits=32)
    ref.set(**regs)
    ref.now, ref.x_actual, ref.x_target, ref.v, ref.acc, ref.acc_dir = t0, x, xt, v, acc, acc_dir
    ref.advance(bound - 1)
    assert ref.end is None, f"the stretch ended at {ref.end}, before the bound {bound}"
    return bound


@settings(max_examples=50, deadline=None)
@given(braking, st.sampled_from([1, 1, 2, 4, 16]))
def test_end_bound_holds_inside_real_brakings(m, too_large):
    """6.1.9: inside a braking that follows V_TARGET down (the setting of
    test_braking_from_speed_matches_the_oracle), `end_bound` read at random cycles is after now
    and at or before the first cycle the oracle ends the stretch on: the arrival step, or the
    ramp tick after which |v| is V_MIN * 256 (or 0). Also with p up to 16 times too large
    (6.1.9.1: the motor overshoots), where only the weaker bounds apply."""
    (pd, extra), a_max, v, v_min, f, cuts = m
    regs = _registers(pd, extra, min(2047, a_max * too_large), v, v_min)
    if regs is None:
        return
    regs["a_max"] = a_max                    # PMUL/PDIV stay those of the larger A_MAX
    fast = Tmc429Ramp(position_bits=32)
    apply((fast,), {**regs, "mode": HOLD_MODE})
    apply((fast,), {"v_actual": v})
    distance = max(1, int(f * braking_distance(v, regs["pmul"], regs["pdiv"])))
    apply((fast,), {"mode": RAMP_MODE, "x_target": distance})
    span = v * 256 // a_max * (32 << regs["ramp_div"])
    for cut in sorted(cuts):
        fast.advance(max(fast.now, int(cut * span)))
        if fast.v_internal <= min(v_min, v) * 256 or fast.x_actual >= distance:
            break                            # the stretch has ended
        _check_bound({**regs, "mode": RAMP_MODE}, fast.now, fast.x_actual, distance,
                     fast.v_internal, *fast.pulse_accumulator)


stretches = st.tuples(dividers, st.integers(1, 2047), st.integers(1, 2047), st.integers(0, 6),
                      st.integers(1, 2047 * 256), st.integers(1, 1 << 20), st.integers(0, 1 << 12),
                      st.integers(0, 2047), st.integers(-1, 1), st.booleans())


@settings(max_examples=150, deadline=None)
@given(stretches)
def test_end_bound_holds_from_any_state(m):
    """6.1.9: from any ramp_mode state moving towards its target (|v| above, on or below its
    target, PMUL/PDIV from 6.1.9.2 or drawn at random, the accumulator counting either way),
    `end_bound` is after now and at or before the oracle's end of the stretch."""
    (pd, extra), a_max, v_max, v_min, w, d, t0, acc, acc_dir, ideal = m
    pmul, pdiv = registers_for(a_max, pd + extra, pd) if ideal else (None, None)
    if pmul is None:
        pmul, pdiv = 128 + d % 128, d % 14
    regs = {"pulse_div": pd, "ramp_div": pd + extra, "v_max": v_max, "v_min": v_min,
            "a_max": a_max, "pmul": pmul, "pdiv": pdiv, "mode": RAMP_MODE}
    w = min(w, v_max * 256 + 255)
    if w <= min(v_min, v_max) * 256:
        return                               # at V_MIN: a linear phase, no stretch
    _check_bound(regs, t0, 0, d, w, acc, acc_dir)


def test_pd86_default_braking_is_reported_in_few_events():
    """PD86-1180 defaults (manual ch. 5: AP4 1000, AP5 100, AP130 1, AP153 7, AP154 3) and MVP
    200 000: the deceleration lasts about 2 600 ramp ticks over 1 000 velocity levels; the core
    reports the whole move in five events (end of the acceleration, start of the braking, a
    cycle shortly before its end, the last steps at V_MIN, arrival) and lands on the oracle's
    cycle and position."""
    pmul, pdiv = registers_for(100, 7, 3)
    regs = {"pulse_div": 3, "ramp_div": 7, "v_max": 1000, "v_min": 1, "a_max": 100, "pmul": pmul,
            "pdiv": pdiv}
    fast, ref = Tmc429Ramp(position_bits=32), ReferenceRamp(position_bits=32)
    apply((fast, ref), regs)
    apply((fast, ref), {"x_target": 200_000})
    events = []
    while (e := fast.next_event()) is not None:
        fast.advance(e)
        events.append(e)
    assert fast.position_reached and fast.x_actual == 200_000
    assert len(events) <= 5
    ref.advance(fast.now)
    assert state(ref) == state(fast)
