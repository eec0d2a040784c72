"""The fast event-driven TMC429 core agrees exactly with the per-tick oracle.

docs/architecture.md "Time": where the chip is integer-exact (TMC429/TMC4210: velocity
accumulates A_MAX/256 per ramp-clock tick, a step fires when the pulse
accumulator overflows) the fast path must agree exactly with a slow per-tick
reference model. Every test here drives both with the same register writes and
compares position, velocity (with its hidden fraction), pulse accumulator and
X_TARGET at every sampled cycle.
"""
from __future__ import annotations

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from opentmcl.motion.pmulpdiv import registers_for
from opentmcl.motion.tmc429 import HOLD_MODE, RAMP_MODE, SOFT_MODE, VELOCITY_MODE, Tmc429Ramp

from .tmc429_reference import ReferenceRamp


def state(r) -> tuple:
    if isinstance(r, Tmc429Ramp):
        return (r.now, r.x_actual, r.x_target, r.v_internal, *r.pulse_accumulator, r.stopping,
                r.v_actual)
    return (r.now, r.x_actual, r.x_target, r.v, r.acc, r.acc_dir, r.stopping, r.v_actual)


class RecordingReference(ReferenceRamp):
    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self.steps: list[tuple[int, int]] = []

    def on_step(self, cycle: int, direction: int) -> None:
        self.steps.append((cycle, direction))


registers = st.fixed_dictionaries({
    "pulse_div": st.integers(0, 4),
    "ramp_div": st.integers(0, 4),
    "v_max": st.one_of(st.integers(1, 2047), st.integers(1, 60)),
    "v_min": st.integers(0, 6),
    "a_max": st.one_of(st.integers(1, 2047), st.integers(1, 40)),
    "pmul": st.integers(128, 255),
    "pdiv": st.integers(0, 13),
    "mode": st.sampled_from([RAMP_MODE, RAMP_MODE, SOFT_MODE, VELOCITY_MODE, HOLD_MODE]),
})

write = st.one_of(
    st.fixed_dictionaries({"x_target": st.integers(-4000, 4000)}),
    st.fixed_dictionaries({"x_target": st.integers(-(2**23), 2**24 - 1)}),
    st.fixed_dictionaries({"x_actual": st.integers(-4000, 4000)}),
    st.fixed_dictionaries({"v_target": st.integers(-2047, 2047)}),
    st.fixed_dictionaries({"v_actual": st.integers(-2047, 2047)}),
    st.fixed_dictionaries({"mode": st.integers(0, 3)}),
    st.fixed_dictionaries({"v_max": st.integers(0, 2047)}),
    st.fixed_dictionaries({"v_min": st.integers(0, 8)}),
    st.fixed_dictionaries({"a_max": st.integers(0, 2047)}),
    st.fixed_dictionaries({"pulse_div": st.integers(0, 4)}),
    st.fixed_dictionaries({"ramp_div": st.integers(0, 4)}),
    st.fixed_dictionaries({"pmul": st.integers(128, 255), "pdiv": st.integers(0, 13)}),
    st.sampled_from(["hard_stop", "soft_stop"]),
)

# (write, cycles to wait after it, in units of 32 clock cycles)
script = st.lists(st.tuples(write, st.lists(st.integers(1, 3000), min_size=1, max_size=4)),
                  min_size=1, max_size=6)


def apply(ramps, action) -> None:
    for r in ramps:
        if action == "hard_stop":
            r.stop(soft=False)
        elif action == "soft_stop":
            r.stop(soft=True)
        else:
            r.set(**action)


def run_script(regs, actions, position_bits=24) -> None:
    fast, ref = Tmc429Ramp(position_bits=position_bits), ReferenceRamp(position_bits=position_bits)
    apply((fast, ref), regs)
    for action, waits in actions:
        apply((fast, ref), action)
        for w in waits:
            t = fast.now + 32 * w
            fast.advance(t)
            ref.advance(t)
            assert state(fast) == state(ref)


@given(registers, script)
def test_fast_core_matches_per_tick_model(regs, actions):
    """TMC4210 datasheet 6.1 (ramp generator): randomized registers, moves, target
    changes during motion, mode switches, X_ACTUAL overwrites and switch stops give
    the identical state at every sampled cycle."""
    run_script(regs, actions)


@given(registers, script)
def test_fast_core_matches_with_32_bit_positions(regs, actions):
    """PD86-1180 manual ch. 5 AP0/AP1: the module's 32-bit position counter behaves
    like the chip's 24-bit one, only wider."""
    run_script(regs, actions, position_bits=32)


@pytest.mark.slow
@pytest.mark.timeout(1800)
@settings(max_examples=2000, deadline=None)
@given(registers, script)
def test_fast_core_matches_per_tick_model_long(regs, actions):
    """TMC4210 datasheet 6.1: the randomized agreement check with many more examples."""
    run_script(regs, actions)


@given(registers, st.integers(-3000, 3000), st.integers(1, 2000), st.integers(-3000, 3000),
       st.integers(1, 6000))
def test_target_change_during_motion(regs, first, when, second, after):
    """TMC4210 datasheet 6.1.1: "Target position X_TARGET and current position
    X_ACTUAL may be altered on the fly" — a new target mid-move, both models agree
    on every step (cycle and direction)."""
    regs = {**regs, "mode": RAMP_MODE}
    fast, ref = Tmc429Ramp(), RecordingReference()
    apply((fast, ref), regs)
    apply((fast, ref), {"x_target": first})
    t = 32 * when
    fast_steps = fast.step_events(t)
    ref.advance(t)
    apply((fast, ref), {"x_target": second})
    t += 32 * after
    fast_steps += fast.step_events(t)
    ref.advance(t)
    assert fast_steps == ref.steps
    assert state(fast) == state(ref)


@given(registers, st.integers(-3000, 3000), st.integers(-3000, 3000))
def test_arrival_cycle_and_next_event(regs, target, probe):
    """TMC4210 datasheet 6.1.11 int_pos_end / PD86-1180 AP8: walking from event to
    event reaches the target at the same cycle as the per-tick model, next_event
    never lies in the past, and time_at_position names the first cycle the oracle
    passes a position."""
    regs = {**regs, "mode": RAMP_MODE, "v_min": max(1, regs["v_min"])}
    fast, ref = Tmc429Ramp(), RecordingReference()
    apply((fast, ref), regs)
    apply((fast, ref), {"x_target": target})
    horizon = 32 * 25_000
    predicted = fast.time_at_position(probe)
    events = 0
    while fast.now < horizon and not fast.position_reached:
        e = fast.next_event()
        if e is None:
            break
        assert e > fast.now
        fast.advance(min(e, horizon))
        events += 1
        assert events < 10_000
    ref.advance(fast.now)
    assert state(fast) == state(ref)
    if fast.position_reached and fast.now > 0:
        # the oracle had not arrived one cycle earlier
        early = ReferenceRamp()
        apply((early,), regs)
        apply((early,), {"x_target": target})
        early.advance(fast.now - 1)
        assert not (early.x_actual == early.x_target and early.v == 0)
    first_pass = None
    position = 0
    for cycle, direction in ref.steps:
        position = (position + direction) % 2**24
        if position == probe % 2**24:
            first_pass = cycle
            break
    if probe % 2**24 == 0:
        assert predicted == 0
    elif first_pass is not None:
        assert predicted == first_pass
    elif fast.position_reached:
        assert predicted is None


def test_long_move_is_cheap_and_exact():
    """docs/architecture.md "Time": a long move costs a handful of phase computations — 200 000
    steps at V_MAX = 2047 in ramp_mode take a few events, and land where the
    per-tick model lands at the same cycle."""
    regs = {"v_max": 2047, "v_min": 1, "a_max": 100, "pmul": 198, "pdiv": 5}
    fast, ref = Tmc429Ramp(position_bits=32), ReferenceRamp(position_bits=32)
    apply((fast, ref), regs)
    apply((fast, ref), {"x_target": 200_000})
    events = 0
    while (e := fast.next_event()) is not None:
        fast.advance(e)
        events += 1
    assert fast.position_reached and fast.x_actual == 200_000
    assert events <= 8
    ref.advance(fast.now)
    assert state(fast) == state(ref)


@pytest.mark.parametrize("pulse_div,ramp_div", [(0, 0), (3, 1), (1, 4)])
def test_oracle_itself_follows_the_datasheet_formulas(pulse_div, ramp_div):
    """TMC4210 datasheet 6.1.12.1: the oracle's step rate is f_CLK * v / (2^PULSE_DIV *
    2048 * 32) and its velocity grows by A_MAX/256 per ramp-clock tick of
    32 * 2^RAMP_DIV cycles (so that agreement with it means agreement with the datasheet)."""
    r = ReferenceRamp()
    r.set(mode=HOLD_MODE, pulse_div=pulse_div, ramp_div=ramp_div)
    r.set(v_actual=700)
    pulse_ticks = 3000
    r.advance(pulse_ticks * 32 * 2**pulse_div)
    assert r.x_actual == pulse_ticks * 700 // 2048
    r = ReferenceRamp()
    r.set(mode=VELOCITY_MODE, pulse_div=pulse_div, ramp_div=ramp_div, v_max=2047, a_max=77, v_target=-2047)
    r.advance(50 * 32 * 2**ramp_div)
    assert r.v == -50 * 77


follow_moves = st.tuples(
    st.integers(0, 3), st.integers(-1, 3), st.integers(1, 2047), st.integers(100, 2047),
    st.integers(0, 6), st.integers(1, 6000), st.floats(0.3, 1.0),
    st.one_of(st.fixed_dictionaries({"x_target": st.integers(-6000, 6000)}),
              st.fixed_dictionaries({"v_max": st.integers(0, 400)}),
              st.sampled_from(["hard_stop", "soft_stop"])),
    st.lists(st.integers(1, 900), min_size=1, max_size=5))


@settings(deadline=None)
@given(follow_moves)
def test_agreement_while_following_the_computed_target(m):
    """TMC4210 datasheet 6.1.9: "This calculation is done for each ramp step" - in the stretch
    where the velocity follows V_TARGET down, a target change on the fly (6.1.1), a V_MAX below the
    present velocity (6.1.4 "except if the limit V_MAX is changed during motion to a value below
    the current velocity") or a switch stop (6.1.10.2) gives the oracle's state at every sampled
    cycle and its steps, event by event."""
    pd, extra, a_max, v_max, v_min, distance, when, action, waits = m
    rd = max(0, pd + extra)
    pmul, pdiv = registers_for(a_max, rd, pd)
    regs = {"pulse_div": pd, "ramp_div": rd, "v_max": v_max, "v_min": v_min, "a_max": a_max,
            "pmul": pmul, "pdiv": pdiv}
    fast, ref = Tmc429Ramp(), RecordingReference()
    apply((fast, ref), regs)
    apply((fast, ref), {"x_target": distance})
    steps = []
    while fast.a_actual >= 0 and not fast.position_reached:   # up to the deceleration
        e = fast.next_event()
        if e is None:
            break
        steps += fast.step_events(e)
    assume(fast.a_actual < 0)        # in the stretch that follows V_TARGET down (signed, 2.4)
    ref.advance(fast.now)
    assert state(fast) == state(ref)
    lead = fast.time_at_position(distance)
    t = fast.now + int(when * ((lead or fast.now) - fast.now)) + 1
    steps += fast.step_events(t)
    ref.advance(t)
    assert state(fast) == state(ref)
    apply((fast, ref), action)
    for w in waits:
        t = fast.now + 32 * w
        steps += fast.step_events(t)
        ref.advance(t)
        assert state(fast) == state(ref)
    for _ in range(6):                                           # and on, event by event
        e = fast.next_event()
        if e is None:
            break
        steps += fast.step_events(e)
        ref.advance(e)
        assert state(fast) == state(ref)
    assert steps == ref.steps
