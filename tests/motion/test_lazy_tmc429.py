"""Jumps inside cached phases of the TMC429 core and the PD86-1180 engine (docs/motion-tmc429.md
"Lazy reads").

The ramp is the TMC4210/TMC429 ramp generator, datasheet ch. 6.1 (6.1.9 ramp_mode target
velocity, 6.1.12 pulse generator; docs/motion-tmc429.md); PD86-1180 firmware manual ch. 5 maps
AP0/AP1/AP3/AP4/AP5/AP8 onto it. Inside the linear phase next_event() cached, `advance` jumps
from the phase's start without re-planning, however often it is called. The oracle is the per-tick model tests/motion/tmc429_reference.py: positions, velocities
(with the hidden fraction) and accumulators must be its values at every instant read, whether
the instant is inside a phase, at its event, or after a register write in the middle of one.
"""
from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from opentmcl.motion import CLOCK_HZ
from opentmcl.motion.tmc429 import RAMP_MODE, VELOCITY_MODE, Tmc429Ramp
from opentmcl.motion.tmc429_engine import Tmc429Engine

from .test_tmc429_agreement import RecordingReference, apply, registers, state, write
from .tmc429_reference import ReferenceRamp

# (write, then per sample: cycles to wait in units of 32, and whether to ask next_event first)
polled = st.lists(st.tuples(write, st.lists(st.tuples(st.integers(1, 400), st.booleans()),
                                            min_size=1, max_size=8)), min_size=1, max_size=5)


@settings(max_examples=80, deadline=None)
@given(registers, polled, st.sampled_from([24, 32]))
def test_core_polled_inside_phases_matches_per_tick_model(regs, actions, bits):
    """TMC4210 datasheet 6.1: the core polled like a host polls it -- next_event() (which caches
    the phase), then several advances inside that phase, writes in the middle of a phase -- has
    the per-tick model's state at every sampled cycle."""
    fast, ref = Tmc429Ramp(position_bits=bits), ReferenceRamp(position_bits=bits)
    apply((fast, ref), regs)
    for action, samples in actions:
        apply((fast, ref), action)
        for wait, ask in samples:
            if ask:
                event = fast.next_event()
                assert event is None or event > fast.now
            t = fast.now + 32 * wait
            fast.advance(t)
            ref.advance(t)
            assert state(fast) == state(ref)


@settings(max_examples=60, deadline=None)
@given(registers, st.integers(-3000, 3000), st.lists(st.integers(1, 300), min_size=1, max_size=6),
       st.integers(1, 3000))
def test_steps_listed_after_lazy_jumps_are_the_models(regs, target, waits, after):
    """6.1.12: after next_event() and jumps inside the cached phase, step_events lists exactly
    the model's steps from now on (none of those already made again)."""
    regs = {**regs, "mode": RAMP_MODE}
    fast, ref = Tmc429Ramp(), RecordingReference()
    apply((fast, ref), regs)
    apply((fast, ref), {"x_target": target})
    for w in waits:
        fast.next_event()
        fast.advance(fast.now + 32 * w)
    ref.advance(fast.now)
    made = len(ref.steps)
    t = fast.now + 32 * after
    listed = fast.step_events(t)
    ref.advance(t)
    assert listed == ref.steps[made:]
    assert state(fast) == state(ref)


# --- the PD86-1180 engine ---------------------------------------------------------------------
MIRRORED = ("x_target", "v_min", "v_max", "a_max", "pmul", "pdiv", "pulse_div", "ramp_div", "mode")

command = st.one_of(
    st.tuples(st.just("move_to"), st.integers(-40_000, 40_000)),
    st.tuples(st.just("rotate"), st.integers(-2047, 2047)),
    st.tuples(st.just("hard_stop")),
    st.tuples(st.just("configure"), st.sampled_from(["max_positioning_speed", "minimum_speed"]),
              st.integers(0, 2047)),
    st.tuples(st.just("configure"), st.just("max_acceleration"), st.integers(1, 2047)),
    st.tuples(st.just("configure"), st.sampled_from(["ramp_divisor", "pulse_divisor"]),
              st.integers(0, 4)),
)
# (cycles to wait in units of 32, ask next_event, read AP1/AP3/AP8)
poll = st.tuples(st.integers(1, 2000), st.booleans(), st.booleans())
session = st.lists(st.tuples(command, st.lists(poll, min_size=1, max_size=6)), min_size=1, max_size=5)


def engine() -> Tmc429Engine:
    e = Tmc429Engine()
    e.configure(max_positioning_speed=1000, max_acceleration=200, minimum_speed=1)
    return e


def do(e: Tmc429Engine, cmd: tuple) -> None:
    name, *args = cmd
    if name == "configure":
        e.configure(**{args[0]: args[1]})
    else:
        getattr(e, name)(*args)


def mirror(e: Tmc429Engine, ref: ReferenceRamp, cmd: tuple) -> None:
    """The register writes the engine made, applied to the per-tick model."""
    if cmd[0] == "hard_stop":
        ref.stop(soft=False)
        return
    r = e.ramp
    regs = {name: getattr(r, name) for name in MIRRORED if getattr(r, name) != getattr(ref, name)}
    if r.mode == VELOCITY_MODE and r.v_target != ref.v_target:
        regs["v_target"] = r.v_target
    ref.set(**regs)


def s32(x: int) -> int:
    return (x + 2**31) % 2**32 - 2**31


@settings(max_examples=60, deadline=None)
@given(session)
def test_engine_polled_lazily_matches_per_tick_model(steps):
    """PD86-1180 manual ch. 5: AP1 (actual position), AP3 (actual speed) and AP8 (position
    reached) read while polling -- many advances inside one cached phase, next_event() asked or
    not, reads at arbitrary cycles and right after MVP/ROR/SAP in the middle of a phase -- are the per-tick
    model's X_ACTUAL, V_ACTUAL and position reached at that cycle."""
    e, ref = engine(), ReferenceRamp(position_bits=32)
    mirror(e, ref, ("configure",))
    for cmd, polls in steps:
        do(e, cmd)
        mirror(e, ref, cmd)
        assert e.position == s32(ref.x_actual)
        for wait, ask, read in polls:
            if ask:
                event = e.next_event()
                assert event is None or event > e.now
            t = e.now + 32 * wait
            e.advance(t)
            assert e.now == t
            if read:
                ref.advance(t)
                assert (e.position, e.velocity, e.position_reached) == (
                    s32(ref.x_actual), ref.v_actual,
                    ref.x_actual == ref.x_target and ref.v == 0 and ref.mode != VELOCITY_MODE)
        ref.advance(e.now)
        assert state(e.ramp) == state(ref)


def event_run(e: Tmc429Engine, limit: int = 400) -> list[tuple[int, int, int, bool]]:
    out = []
    horizon = e.now + CLOCK_HZ
    while len(out) < limit and (t := e.next_event()) is not None and t <= horizon:
        e.advance(t)
        out.append((t, e.position, e.velocity, e.position_reached))
    return out


@settings(max_examples=60, deadline=None)
@given(session)
def test_engine_reading_does_not_change_later_behaviour(steps):
    """An engine read and asked for its next event at every poll and one only advanced (same
    commands at the same cycles) then report the same event sequence and state."""
    busy, quiet = engine(), engine()
    for cmd, polls in steps:
        do(busy, cmd)
        do(quiet, cmd)
        for wait, _ask, _read in polls:
            busy.next_event()
            _ = (busy.position, busy.velocity, busy.position_reached, busy.target_velocity)
            t = busy.now + 32 * wait
            busy.advance(t)
            quiet.advance(t)
            _ = busy.moving
    assert event_run(busy) == event_run(quiet)
    assert state(busy.ramp) == state(quiet.ramp)


def test_engine_advance_rejects_the_past():
    """Bad input gets a clear error: a cycle before the present one, also right after a jump
    inside the cached phase."""
    e = engine()
    e.move_to(10_000)
    e.next_event()
    e.advance(1000)
    e.advance(1000)                       # the same cycle again is fine
    with pytest.raises(ValueError, match="cannot go back in time"):
        e.advance(999)
    assert e.now == 1000
