"""ramp_mode follows the target velocity it computes on every ramp step (issue 10, item 1).

TMC4210 datasheet 6.1.9: the chip calculates "the velocity required for stopping in time to
exactly reach the target position without overshooting. This calculation is done for each ramp
step. The result of this calculation can be read in the register V_TARGET. Whenever V_TARGET
falls below the actual velocity, the TMC4210 decelerates." The consequences are checked on the
per-tick reference model (the oracle), over randomized moves; docs/assumptions.md gives the
integer rules chosen (remaining distance with the accumulator's fraction, stop at <= V_MIN on
arrival).
"""
from __future__ import annotations

from hypothesis import example, given, settings
from hypothesis import strategies as st

from opentmcl.motion.pmulpdiv import a_max_limits, registers_for
from opentmcl.motion.tmc429 import Tmc429Ramp

from ..chips.helpers import setup
from .tmc429_reference import ReferenceRamp


class Recorder(ReferenceRamp):
    """The oracle, recording for each step the position reached and |velocity| at that step."""

    def __init__(self) -> None:
        super().__init__(position_bits=32)
        self.trace: list[tuple[int, int]] = []
        self.last_step = 0

    def on_step(self, cycle: int, direction: int) -> None:
        x = (self.x_actual + (1 << 31)) % (1 << 32) - (1 << 31)
        self.trace.append((x, abs(self.v)))
        self.last_step = cycle


def move(pd: int, rd: int, a_max: int, v_max: int, v_min: int, distance: int,
         pmul: int, pdiv: int, max_ticks: int = 3_000_000) -> Recorder:
    """One ramp_mode move from 0 to `distance` on the oracle, run until it rests."""
    r = Recorder()
    r.set(pulse_div=pd, ramp_div=rd, v_max=v_max, v_min=v_min, a_max=a_max, pmul=pmul, pdiv=pdiv)
    r.set(x_target=distance)
    chunk = 256 * (32 << max(pd, rd))
    for _ in range(max_ticks * (32 << min(pd, rd)) // chunk):
        r.advance(r.now + chunk)
        if r.v == 0:
            break
    return r


def v_min_zone(v_min: int, pmul: int, pdiv: int) -> int:
    """Steps before the target where the computed velocity sqrt(2048 p d) is below V_MIN: the
    hints' "approached with minimal velocity V_MIN, whenever the internally calculated target
    velocity becomes less than V_MIN"."""
    return -(-(v_min * v_min << (3 + pdiv)) // (2048 * pmul))


def tail_at_v_min(r: Recorder, distance: int) -> int:
    """Steps made at |v| <= V_MIN before the target, after the last faster step (0 for a move
    that never got faster than V_MIN: it has no deceleration to end)."""
    faster = [x for x, w in r.trace if w > r.v_min * 256]
    return distance - faster[-1] if faster else 0


chip_moves = st.tuples(st.integers(0, 3), st.integers(0, 3), st.integers(0, 2047), st.floats(0, 1),
                       st.integers(300, 2047), st.integers(1, 20), st.integers(1, 8_000))


def _params(pd, extra, a_pick, v_max, v_min, distance):
    rd = pd + extra
    lower, upper = a_max_limits(rd, pd, v_max)
    a_max = max(1, lower) + int(a_pick * (min(upper, 2047) - max(1, lower)))
    return rd, a_max


@example((0, 0, 0, 0.49, 2047, 1, 100_000))     # PD86-1180-like: crawled ~12 steps at V_MIN before
@settings(max_examples=8, deadline=None)
@given(chip_moves)
def test_datasheet_p_never_passes_the_target_and_reaches_v_min_near_it(m):
    """6.1.9: "target positions are quickly reached without overshooting"; 6.1.9.2 hints: "With a
    good parameter p the minimal velocity V_MIN is reached a couple of steps before the target
    position" (p from the datasheet's method, 1 % reduced, A_MAX within 6.1.7.1.1's limits).
    Then p without the reduction: 6.1.9.2 hints "With parameter p set a little bit too large and a
    small V_MIN overshooting of one step (respectively one microstep) may occur", 6.1.9.2.1 "q =
    1.0 ... overshooting could result because of finite numerical precision" - at most two steps
    past the target for A_MAX up to 1024 (two seen with q exactly 1.0 and RAMP_DIV - PULSE_DIV = 3;
    a p too large by a fraction e overshoots by about e times the braking distance), then back on it (6.1.3: V_MIN >= 1 "assures reaching each target
    position exactly"), still without a crawl."""
    pd, extra, _, a_pick, v_max, v_min, distance = m
    rd, a_max = _params(pd, extra, a_pick, v_max, v_min, distance)
    pmul, pdiv = registers_for(a_max, rd, pd)
    r = move(pd, rd, a_max, v_max, v_min, distance, pmul, pdiv)
    assert r.x_actual == distance and r.v == 0
    assert max(x for x, _ in r.trace) == distance                # never past the target
    assert tail_at_v_min(r, distance) <= v_min_zone(v_min, pmul, pdiv) + 3   # "a couple of steps"
    a_max = min(a_max, 1024)
    pmul, pdiv = registers_for(a_max, rd, pd, 0.0)
    r = move(pd, rd, a_max, v_max, 1, distance, pmul, pdiv)
    assert max(x for x, _ in r.trace) <= distance + 2
    assert r.x_actual == distance and r.v == 0
    assert tail_at_v_min(r, distance) <= v_min_zone(1, pmul, pdiv) + 3


def test_p_too_small_approaches_more_slowly_along_a_flatter_curve():
    """6.1.9.2 hints: "If the proportionality parameter p is too small, the target position will
    be reached slower, because the slow down ramp starts earlier." With q = 0.95 (TMC429 9.11's
    lower bound) instead of 0.99 the move takes longer and the deceleration starts further from
    the target, yet the motor does not crawl at V_MIN: the velocity follows the flatter curve."""
    runs = {}
    for reduction in (0.01, 0.05):
        pmul, pdiv = registers_for(100, 0, 0, reduction)
        r = move(0, 0, 100, 2047, 1, 100_000, pmul, pdiv)
        assert r.x_actual == 100_000 and r.v == 0
        top = max(w for _, w in r.trace)
        first_top = next(i for i, (_, w) in enumerate(r.trace) if w == top)
        slow_down = next(x for x, w in r.trace[first_top:] if w < top)   # the deceleration starts
        runs[reduction] = (r.last_step, slow_down, tail_at_v_min(r, 100_000))
    assert runs[0.05][0] > runs[0.01][0]          # reached slower
    assert runs[0.05][1] < runs[0.01][1]          # the slow-down starts earlier
    assert runs[0.05][2] <= 10                    # ~5 % of the 2600-step deceleration would be 130


def test_v_min_zero_may_stop_short():
    """6.1.3: "V_MIN should be set greater than zero ... the target position cannot be reached
    exactly, if the calculated velocity is less than one, before the target is reached." With
    V_MIN = 0 the computed velocity falls below one inside the last step and the motor stops one
    step short; V_MIN = 1 reaches the target."""
    pmul, pdiv = registers_for(4, 1, 1)
    short = move(1, 1, 4, 1884, 0, 175, pmul, pdiv)
    assert short.v == 0 and short.x_actual == 174
    exact = move(1, 1, 4, 1884, 1, 175, pmul, pdiv)
    assert exact.v == 0 and exact.x_actual == 175


def test_v_target_reads_what_the_ramp_follows_and_a_actual_is_signed():
    """6.1.5: in ramp_mode "The V_TARGET register holds the current target velocity calculated
    internally by the ramp generator"; 6.1.9: "Whenever V_TARGET falls below the actual velocity,
    the TMC4210 decelerates" - so while the chip decelerates towards the target V_TARGET is never
    above |V_ACTUAL|; 2.4: A_ACTUAL is a signed (two's complement) motion parameter, negative while
    the velocity falls. Read through the chip's registers at every ramp tick."""
    chip = setup(v_min=2, v_max=1500, a_max=100, pulse_div=3, ramp_div=4)
    chip.write("X_TARGET", 30_000)
    falling = rising = 0
    while chip.read("X_ACTUAL") != 30_000 or chip.read("V_ACTUAL"):
        chip.advance_cycles(32 << 4)
        v, vt, a = chip.read("V_ACTUAL"), chip.read("V_TARGET"), chip.read("A_ACTUAL")
        if a < 0:
            falling += 1
            assert 0 <= vt <= v
        elif a > 0:
            rising += 1
            assert a == 100
    assert falling > 100 and rising > 100


def test_fast_core_and_oracle_agree_on_a_follow_stretch_sampled_every_tick():
    """docs/architecture.md "Time": the fast core walks the square-root deceleration in runs; at every ramp
    tick of a move it holds the oracle's state (position, velocity with its fraction,
    accumulator), and V_MIN comes only at the end (6.1.9.2 hints: "reached a couple of steps
    before the target position"; the old latched ramp ran ~1 % of the deceleration at V_MIN)."""
    pmul, pdiv = registers_for(30, 2, 1)
    fast, ref = Tmc429Ramp(position_bits=32), ReferenceRamp(position_bits=32)
    for r in (fast, ref):
        r.set(pulse_div=1, ramp_div=2, v_min=3, v_max=900, a_max=30, pmul=pmul, pdiv=pdiv)
        r.set(x_target=12_345)
    peaked = False
    while not (ref.x_actual == 12_345 and ref.v == 0):
        t = fast.now + (32 << 2)
        fast.advance(t)
        ref.advance(t)
        assert (fast.x_actual, fast.v_internal, fast.pulse_accumulator[0]) == (ref.x_actual, ref.v, ref.acc)
        peaked |= ref.v > 3 * 256
        if peaked and ref.v <= 3 * 256:
            assert ref.x_actual >= 12_345 - 3
