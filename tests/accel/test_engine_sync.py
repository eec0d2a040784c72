"""Round 24's compiled pieces against their pure-Python references (docs/performance.md "Round 24").

- `_accel.EngineSync`: the loop of `VirtualModule._sync_engines`, `for e in engines: if e.now <
  now: e.advance(now)`. Engines of exactly `SixPointRampEngine` whose first piece holds at `now`
  only get their clock set, as `SixPointRampEngine.advance` would do; every other engine (the
  linear engine of the PD28-1021, a subclass, the TMC429 engine of the PD86-1180, a class whose
  `advance` was patched, a tick that is no int) is called.
- The six-point reads (GAP 1 actual position, GAP 8 position reached, TMCM-6212 manual 3.6.6)
  keep the converted values of the last segment they read; a conversion that fails part-way
  (an operand beyond 128 bits) leaves that copy as it was. Operands at the 64- and 128-bit edges
  are converted without an intermediate int: the last value that fits and the first that does not.
"""
from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from opentmcl import accel
from opentmcl.motion.linear import LinearRampEngine
from opentmcl.motion.segments import PSCALE, Segment, SegmentQueue
from opentmcl.motion.sixpoint import SixPointRampEngine
from opentmcl.motion.tmc429_engine import Tmc429Engine

from .conftest import needs_compiled

pytestmark = needs_compiled

KINDS = [SixPointRampEngine, SixPointRampEngine, LinearRampEngine, Tmc429Engine]


def sync_python(engines, now):
    for engine in engines:
        if engine.now < now:
            engine.advance(now)


def sync_c(engines, now):
    accel.engine_sync(SixPointRampEngine)(engines, now)  # type: ignore[misc]


def engine_state(e):
    pieces = getattr(getattr(e, "_queue", None), "pieces", None)
    return (type(e), e.now, e.position, e.velocity, e.position_reached,
            None if pieces is None else tuple(tuple(p) for p in pieces))


commands = st.lists(st.tuples(st.integers(0, 3), st.sampled_from(["move", "rotate", "stop", "none"]),
                              st.integers(-2047, 2047)), max_size=4)  # the TMC429 range
plans = st.lists(st.tuples(commands, st.integers(0, 3_000_000)), min_size=1, max_size=25)


@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(plans)
def test_the_compiled_sync_equals_the_python_loop(plan):
    """Four engines of three kinds, commanded and synced at random ticks (some ending a ramp
    piece, some inside one, some not moving time at all): the same states after every sync."""
    sets = [[kind() for kind in KINDS] for _ in range(2)]
    now = 0
    for cmds, dt in plan:
        now += dt
        for engines, sync in zip(sets, (sync_python, sync_c), strict=True):
            for i, what, value in cmds:
                e = engines[i]
                if e.now < now - dt:
                    e.advance(now - dt)
                if what == "move":
                    e.move_to(value)
                elif what == "rotate":
                    e.rotate(value)
                elif what == "stop":
                    e.stop()
            sync(engines, now)
        assert [engine_state(e) for e in sets[0]] == [engine_state(e) for e in sets[1]]
        assert all(e.now == now for e in sets[1])


class Recording(SixPointRampEngine):
    def __init__(self):
        super().__init__()
        self.calls = []

    def advance(self, until):
        self.calls.append(until)
        super().advance(until)


def moving_engine():
    e = SixPointRampEngine()
    e.rotate(20_000)
    e.advance(16_000_000)  # at speed: one endless piece
    assert e._queue.pieces[0].k1 is None
    return e


def test_only_the_exact_class_is_synced_inline():
    """A subclass is called (its `advance` may do more); the exact class is not, and ends where
    its `advance` would have put it."""
    sub, plain, ref = Recording(), moving_engine(), moving_engine()
    sub.rotate(1000)
    sync_c([sub, plain], 16_000_000 * 2)
    ref.advance(16_000_000 * 2)
    assert sub.calls == [16_000_000 * 2]
    assert engine_state(plain) == engine_state(ref)


def test_a_patched_advance_is_called(monkeypatch):
    """`SixPointRampEngine.advance` patched onto the class after the sync was made: the sync calls
    the patch, as the Python loop does."""
    sync = accel.engine_sync(SixPointRampEngine)
    calls = []
    original = SixPointRampEngine.advance

    def patched(self, until):
        calls.append(until)
        original(self, until)
    e = moving_engine()
    monkeypatch.setattr(SixPointRampEngine, "advance", patched)
    sync([e], 16_000_000 * 3)  # type: ignore[misc]
    assert calls == [16_000_000 * 3] and e.now == 16_000_000 * 3


def test_an_engine_at_or_past_the_tick_is_left_alone():
    """`e.now < now` only: an engine at `now` or ahead of it is not touched (the Python loop's
    condition; `advance` would raise for a tick in the past)."""
    ahead, at = Recording(), Recording()
    ahead.advance(500)
    at.advance(300)
    ahead.calls.clear()
    at.calls.clear()
    sync_c([ahead, at], 300)
    assert ahead.calls == at.calls == [] and ahead.now == 500 and at.now == 300


def test_a_piece_that_ended_is_dropped_by_advance():
    """MVP: the acceleration piece ends at k1; a sync to k1 or later goes through `advance`,
    which drops it (SegmentQueue.drop_before), exactly as the Python loop."""
    e, ref = SixPointRampEngine(), SixPointRampEngine()
    for x in (e, ref):
        x.move_to(100_000)
    k1 = e._queue.pieces[0].k1
    assert k1 is not None
    for t in (k1 - 1, k1, k1 + 5):
        sync_c([e], t)
        sync_python([ref], t)
        assert engine_state(e) == engine_state(ref)


@pytest.mark.parametrize("now", [Fraction(16_000_000), True, 2.0e7])
def test_a_tick_that_is_no_int_is_handed_to_advance(now):
    """`advance` checks the tick (an Integral; a Fraction or a float raises TypeError, a bool is
    an int): the sync hands it over instead of setting the clock to it."""
    results = []
    for sync in (sync_python, sync_c):
        e = moving_engine() if now is not True else SixPointRampEngine()
        try:
            sync([e], now)
            results.append(("ok", e.now, type(e.now)))
        except Exception as exc:  # noqa: BLE001 - compared between the two loops
            results.append((type(exc), str(exc)))
    assert results[0] == results[1]


def test_errors_propagate_as_in_the_python_loop():
    """An engine without a clock raises AttributeError in both loops; a list is required."""
    class NoClock:
        pass
    for sync in (sync_python, sync_c):
        with pytest.raises(AttributeError):
            sync([NoClock()], 5)
    with pytest.raises(TypeError):
        accel.engine_sync(SixPointRampEngine)((SixPointRampEngine(),), 5)  # type: ignore[misc]
    with pytest.raises(TypeError):
        accel.engine_sync(SixPointRampEngine)([])  # type: ignore[misc]


def test_the_module_syncs_through_the_compiled_loop():
    """A module on the compiled path uses it; one built inside `accel.pure()` the Python loop."""
    from opentmcl import VirtualModule
    with accel.pure():
        ref = VirtualModule("TMCM-6212")
    fast = VirtualModule("TMCM-6212")
    for vm in (ref, fast):
        vm.request(1, 0, 0, 5000)  # ROR 0
        vm.advance(1.234)
    assert [engine_state(ax.engine) for ax in ref.axes] == [engine_state(ax.engine) for ax in fast.axes]


# --- the six-point read's copy of its segment -----------------------------------------------------
def c_read(engine, attribute):
    calls = []

    def fallback():
        calls.append(1)
        return getattr(engine, attribute)
    return accel.sixpoint_read(engine, attribute, fallback), calls


def test_a_failed_conversion_leaves_the_copy_of_the_segment_intact():
    """Segment A (moving) is read and kept; segment B, whose k1 and k0 fit but whose p0 does not
    (beyond 128 bits), is answered by the property; A again (the same object) must be read with
    A's values, not with B's half-converted ones."""
    e = SixPointRampEngine()
    read, calls = c_read(e, "position")
    seg_a = Segment(0, None, 123 * PSCALE, 7 * PSCALE // 16_000, 0, None)
    seg_b = Segment(5_000, 10**9, 2**140, 1, 0, None)
    e.now = 4_000_000
    e._queue = SegmentQueue([seg_a])
    assert read() == e.position and calls == []
    e._queue = SegmentQueue([seg_b, Segment(10**9, None, 0, 0, 0, None)])
    assert read() == e.position and calls == [1]
    e._queue = SegmentQueue([seg_a])
    e.now = 8_000_000
    assert read() == e.position and calls == [1]


@pytest.mark.parametrize("p0, in_c", [
    (2**63 - 1, True), (2**63, True), (-2**63, True), (-2**63 - 1, True), (2**64, True),
    (2**127 - 1, True), (-2**127, True), (2**127, False), (-2**127 - 1, False)])
def test_operands_at_the_64_and_128_bit_edges(p0, in_c):
    """A standing piece at p0 (position floor(p0 / PSCALE), wrapped to 32 bits): the C read
    converts every value that fits in 128 bits, the last one included, and hands the first one
    beyond to the property; the answers are the property's. (AP8 also multiplies the target by
    PSCALE, which leaves 128 bits sooner: there the property may answer before the edge.)"""
    e = SixPointRampEngine()
    e._queue = SegmentQueue([Segment(0, None, p0, 0, 0, None)])
    e._target_abs = p0 // PSCALE
    e._target = ((e._target_abs + 2**31) % 2**32) - 2**31
    read, calls = c_read(e, "position")
    assert read() == e.position
    assert (calls == []) is in_c
    read, calls = c_read(e, "position_reached")
    assert read() == e.position_reached is True
    if not in_c:
        assert calls == [1]
