"""Motion of the TMC4210 model through its registers (datasheet 6.1, 9): the four modes, the
datasheet's rate formulas measured on the running chip, position wrap, start-stop speed."""
import math

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from opentmcl.chips.tmc4210 import TMC4210, units
from opentmcl.chips.tmc4210 import registers as R
from opentmcl.motion.pmulpdiv import calc_pmul_pdiv

from .helpers import run_until_reached, setup

F = 16_000_000


def test_step_rate_R_measured_in_velocity_mode():
    """6.1.12.1: R[Hz] = f_CLK * velocity / (2^PULSE_DIV * 2048 * 32)."""
    for f_clk, pd, v in ((16_000_000, 3, 1000), (32_000_000, 0, 2047), (10_000_000, 7, 333)):
        chip = setup(v_max=2047, a_max=2047, pulse_div=pd, ramp_div=pd, mode=2, f_clk=f_clk)
        chip.write("V_TARGET", v)
        chip.advance(0.05)
        assert chip.read("V_ACTUAL") == v
        x0 = chip.read("X_ACTUAL")
        chip.advance(1.0)
        steps = chip.read("X_ACTUAL") - x0
        assert abs(steps - units.step_rate(v, pd, f_clk)) <= 1


def test_rate_change_dR_and_steps_S_measured_during_acceleration():
    """6.1.12.1: dR = f_CLK^2 * A_MAX / 2^(PULSE_DIV+RAMP_DIV+29); 6.1.12.2: the steps during
    the linear acceleration S = 1/2 * v^2 / A_MAX * 2^RAMP_DIV / 2^PULSE_DIV / 2^3."""
    for v, a, pd, rd in ((1000, 100, 3, 5), (2000, 37, 2, 2), (500, 100, 6, 9)):
        chip = setup(v_max=2047, a_max=a, pulse_div=pd, ramp_div=rd, mode=2)
        chip.write("V_TARGET", v)
        t_acc = units.step_rate(v, pd) / units.rate_change(a, pd, rd)  # seconds to reach v
        chip.advance(t_acc * 0.999)
        assert chip.read("V_ACTUAL") < v
        chip.advance(t_acc * 0.002)
        assert chip.read("V_ACTUAL") == v
        s = units.steps_during_acceleration(v, a, pd, rd)
        assert chip.read("X_ACTUAL") == pytest.approx(s, rel=0.01, abs=3)


def test_ramp_mode_trapezoid_reaches_the_target_exactly():
    """6.1.1 / 6.1.9: ramp_mode drives X_ACTUAL to X_TARGET with a trapezoid limited by V_MAX and
    A_MAX, decelerating in time (no overshoot with p from 6.1.9.2.2), last steps at V_MIN;
    xEQt1 and int_pos_end report the arrival (5.2.2.2, 6.1.11)."""
    chip = setup(v_min=10, v_max=1000, a_max=100, pulse_div=5, ramp_div=8)
    chip.write("mask_pos_end", 1)
    chip.write("X_TARGET", 20_000)
    v_seen, x_seen = [], []
    for _ in range(600):
        chip.advance(0.01)
        v_seen.append(chip.read("V_ACTUAL"))
        x_seen.append(chip.read("X_ACTUAL"))
    assert max(v_seen) == 1000 and max(x_seen) == 20_000 and x_seen[-1] == 20_000
    assert v_seen[-1] == 0
    back = chip.spi(R.read_datagram(0x0B))
    assert back >> 24 & R.STATUS_XEQT1 and back >> 31 == 1
    assert back & 0xFF == R.INT_BIT["pos_end"]
    # 6.1.9.2 hints: "With a good parameter p the minimal velocity V_MIN is reached a couple of
    # steps before the target position" - the velocity follows V_TARGET down to V_MIN, no crawl
    moving = [(v, x) for v, x in zip(v_seen, x_seen, strict=True) if v]
    assert moving[-1][0] == 10 and moving[-2][0] > 10 and moving[-2][1] >= 20_000 - 3


def test_v_target_in_ramp_mode_is_computed_by_the_chip():
    """6.1.5 / 6.1.9: in ramp_mode V_TARGET holds the target velocity the chip computes from
    p and the distance; the motor decelerates when it falls below V_ACTUAL."""
    chip = setup(v_min=5, v_max=2000, a_max=200, pulse_div=4, ramp_div=6)
    chip.write("X_TARGET", 100_000)
    chip.advance(0.05)
    assert chip.read("V_TARGET") == 2000
    chip.write("X_TARGET", chip.read("X_ACTUAL") + 10)
    assert 0 < chip.read("V_TARGET") < chip.read("V_ACTUAL")


def test_p_too_large_overshoots_and_oscillates_p_from_the_formula_does_not():
    """6.1.9.1 note: "Setting the factor p too large will cause overshooting and even oscillations
    around the target position"; 6.1.9.2.2's p with 1 % reduction reaches it directly."""
    good = setup(v_min=1, v_max=2047, a_max=500, pulse_div=2, ramp_div=4)
    bad = setup(v_min=1, v_max=2047, a_max=500, pulse_div=2, ramp_div=4, pmul=255, pdiv=0)
    for chip in (good, bad):
        chip.write("X_TARGET", 50_000)
    xs = {id(good): [], id(bad): []}
    for _ in range(300):
        for chip in (good, bad):
            chip.advance(0.005)
            xs[id(chip)].append(chip.read("X_ACTUAL"))
    assert max(xs[id(good)]) == 50_000
    assert max(xs[id(bad)]) > 50_000


def test_soft_mode_approaches_exponentially():
    """6.1.10.1: soft_mode approaches the target "with exponentially reduced velocity":
    V_TARGET = p * |dx| (clamped to V_MIN..V_MAX), so the remaining distance shrinks by a
    constant factor per unit time."""
    chip = setup(v_min=1, v_max=2047, a_max=2047, pulse_div=3, ramp_div=3, mode=1, pmul=128, pdiv=7)
    chip.write("X_TARGET", 60_000)  # p = 128 / 2^10 = 1/8
    chip.advance(1.0)
    dx = [60_000 - chip.read("X_ACTUAL")]
    for _ in range(4):
        chip.advance(0.1)
        dx.append(60_000 - chip.read("X_ACTUAL"))
    assert dx[0] < 2047 * 8  # below the V_MAX clamp: proportional region
    ratios = [b / a for a, b in zip(dx, dx[1:], strict=False)]
    k = F / (2 ** 3 * 2048 * 32) / 8  # dx' = -R(p * dx): rate constant in 1/s
    assert ratios == pytest.approx([math.exp(-k * 0.1)] * 4, abs=0.02)
    assert run_until_reached(chip, 10)
    assert chip.read("X_ACTUAL") == 60_000


def test_hold_mode_ignores_limits():
    """6.1.10.1 / 6.1.6: hold_mode: the microcontroller writes V_ACTUAL; V_MAX and A_MAX are ignored."""
    chip = setup(v_min=0, v_max=0, a_max=0, pulse_div=3, ramp_div=3, mode=3)
    chip.write("V_ACTUAL", -700)
    chip.advance(0.5)
    assert chip.read("V_ACTUAL") == -700
    assert abs(chip.read("X_ACTUAL") + units.step_rate(700, 3) * 0.5) <= 1


def test_overwriting_x_actual_in_ramp_mode_drives_to_x_target():
    """6.1.2: "If X_ACTUAL is overwritten in ramp_mode or soft_mode the motor directly drives to X_TARGET"."""
    chip = setup()
    chip.write("X_ACTUAL", 3000)
    assert chip.read("X_TARGET") == 0
    assert run_until_reached(chip, 20)
    assert chip.read("X_ACTUAL") == 0


def test_position_wraps_at_24_bits():
    """6.1.1: |X_TARGET - X_ACTUAL| < 2^23 for motion into the correct direction; positions are
    24-bit two's complement, so a move from 2^23-5 to -2^23+5 goes forward across the wrap."""
    chip = setup(capture=True)
    chip.write("RAMP_MODE", 3)
    chip.write("X_ACTUAL", (1 << 23) - 5)
    chip.write("X_TARGET", -(1 << 23) + 5)
    chip.write("RAMP_MODE", 0)
    assert run_until_reached(chip, 20)
    assert chip.read("X_ACTUAL") == -(1 << 23) + 5
    assert chip.spi(R.read_datagram(0x01)) & 0xFFFFFF == 0x800005
    assert [e for e in chip.drain_edges() if e.pin == "DIR"] == []  # never turned negative


def test_target_too_far_moves_the_wrong_way():
    """6.1.1: beyond |X_TARGET - X_ACTUAL| < 2^23 the direction is wrong (the shorter way on the 24-bit circle)."""
    chip = setup(v_max=2047, a_max=2047, pulse_div=0, ramp_div=0)
    chip.write("X_TARGET", (1 << 23) - 1 + 100)  # wraps to -2^23 + 99
    chip.advance(0.01)
    assert chip.read("V_ACTUAL") < 0


def test_start_stop_speed_procedure():
    """9.2: V_MIN := V_START_STOP, hold_mode, X_TARGET, V_ACTUAL := +V_MIN, ramp_mode: the motor
    starts at once with V_START_STOP and still ends exactly on target."""
    v_ss = 200
    chip = setup(v_min=v_ss, v_max=1500, a_max=20, pulse_div=4, ramp_div=9)
    chip.write("RAMP_MODE", 3)
    chip.write("X_TARGET", 5000)
    chip.write("V_ACTUAL", v_ss)
    chip.write("RAMP_MODE", 0)
    first_steps = 1.0 / units.step_rate(v_ss, 4)
    chip.advance(first_steps * 3.5)
    assert chip.read("X_ACTUAL") >= 3
    # without the procedure the ramp starts at 0 and is still far slower
    plain = setup(v_min=v_ss, v_max=1500, a_max=20, pulse_div=4, ramp_div=9)
    plain.write("X_TARGET", 5000)
    plain.advance(first_steps * 3.5)
    assert plain.read("X_ACTUAL") < 3
    assert run_until_reached(chip, 60)
    assert chip.read("X_ACTUAL") == 5000


def test_a_max_above_the_upper_limit_has_no_pmul_pdiv():
    """6.1.7.1.1: A_MAX <= 2^(RAMP_DIV-PULSE_DIV+12) - 1; above it p exceeds the largest PMUL/PDIV
    (255/8), so no valid pair exists and the deceleration cannot be made in time."""
    lower, upper = units.a_max_limits(ramp_div=0, pulse_div=3)
    assert upper == 511
    assert calc_pmul_pdiv(upper, 0, 3, 0.0).valid
    assert not calc_pmul_pdiv(upper + 2, 0, 3, 0.0).valid


def test_max_step_rate_is_f_clk_over_32():
    """1.4.1 / 8.1: the highest step rate is f_CLK / 32 (500 kHz at 16 MHz, 1 MHz at 32 MHz)."""
    for f_clk in (16_000_000, 32_000_000):
        chip = TMC4210(f_clk=f_clk, capture_edges=True)
        chip.write("STPDIV_4210", 0)
        chip.write("en_sd", 1)
        chip.write("RAMP_MODE", 3)
        chip.write("V_ACTUAL", 2047)
        chip.advance(0.001)
        rises = [e.cycle for e in chip.drain_edges() if e.pin == "STEP" and e.level == 1]
        assert min(b - a for a, b in zip(rises, rises[1:], strict=False)) >= 32
        assert len(rises) <= f_clk / 32 * 0.001
        assert len(rises) >= f_clk / 32 * 0.001 * 2047 / 2048 - 1
        assert chip.stepdir.lost_steps == 0


def test_no_steps_until_en_sd():
    """1.4 / 6.2.1: the Step/Dir interface has to be enabled with en_sd = 1; before that the outputs
    stay high and no step pulses are sent (the ramp generator itself runs)."""
    chip = setup(en_sd=0, capture=True)
    chip.drain_edges()
    chip.write("X_TARGET", 100)
    chip.advance(1.0)
    assert chip.read("X_ACTUAL") == 100
    assert chip.drain_edges() == [] and (chip.stepdir.step_level, chip.stepdir.dir_level) == (1, 1)
    chip.write("en_sd", 1)
    chip.write("X_TARGET", 0)
    chip.advance(1.0)
    edges = chip.drain_edges()
    assert sum(1 for e in edges if e.pin == "STEP" and e.level == 1) == 100


def test_step_pulse_length_and_direction_delay_on_the_chip():
    """8.1: t_STEP = 16 * (1 + STPDIV_4210) / f_CLK; the first step after a change of direction
    is delayed by t_DIR2STP = t_STEP."""
    chip = setup(capture=True)
    chip.write("STPDIV_4210", 4)
    chip.drain_edges()
    chip.write("X_TARGET", -3)
    chip.advance(2.0)
    e = chip.drain_edges()
    assert e[0].pin == "DIR" and e[0].level == 0
    assert e[1].pin == "STEP" and e[1].cycle - e[0].cycle == 80
    pulses = [(a, b) for a, b in zip(e, e[1:], strict=False) if a.pin == b.pin == "STEP" and a.level == 1]
    assert len(pulses) == 3 and all(b.cycle - a.cycle == 80 for a, b in pulses)
    assert pulses[0][1].time - pulses[0][0].time == pytest.approx(80 / F)


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 6), st.integers(0, 6), st.floats(0, 1), st.integers(10, 2047), st.integers(1, 10),
       st.integers(10, 200_000))
def test_within_the_a_max_limits_ramp_mode_never_overshoots(pd, extra, where, v_max, v_min, target):
    """6.1.7.1.1: with A_MAX_LOWER_LIMIT <= A_MAX <= A_MAX_UPPER_LIMIT and p from 6.1.9.2.2 (1 %
    reduction, the 6.1.9.2 hint against overshooting) every target is reached without oscillation.
    Moves shorter than the acceleration distance S to V_MAX (6.1.12.2) never reach the ramp the
    p calculation is made for: there one ramp tick's velocity step may carry the motor one step past
    the target before it returns (docs/assumptions.md, TMC4210), so the no-overshoot claim is checked
    for moves of at least 2 S; shorter ones come back and settle on their target as well."""
    rd = pd + extra
    lower, upper = units.a_max_limits(rd, pd)
    a_max = lower + int(where * (upper - lower))
    calc = calc_pmul_pdiv(a_max, rd, pd, 0.01)
    assert calc.valid
    chip = setup(v_min=v_min, v_max=v_max, a_max=a_max, pulse_div=pd, ramp_div=rd, pmul=calc.pmul,
                 pdiv=calc.pdiv)
    chip.write("X_TARGET", target)
    t_move = (2 * units.step_rate(v_max, pd) / units.rate_change(a_max, pd, rd)
              + target / units.step_rate(v_min, pd) + 1)
    peak = 0
    for _ in range(100):
        chip.advance(t_move / 50)
        peak = max(peak, chip.read("X_ACTUAL"))
    if target >= 2 * units.steps_during_acceleration(v_max, a_max, pd, rd):
        assert peak == target
        assert chip.read("X_ACTUAL") == target
    else:  # a short move may overshoot first; it settles (tests below)
        assert chip.read("X_ACTUAL") == target


def _short_move(pd, extra, where, v_max, v_min, target, a_max=None) -> TMC4210:
    rd = pd + extra
    lower, upper = units.a_max_limits(rd, pd)
    if a_max is None:
        a_max = lower + int(where * (upper - lower))
    assert lower <= a_max <= upper
    calc = calc_pmul_pdiv(a_max, rd, pd, 0.01)
    chip = setup(v_min=v_min, v_max=v_max, a_max=a_max, pulse_div=pd, ramp_div=rd, pmul=calc.pmul,
                 pdiv=calc.pdiv)
    chip.write("X_TARGET", target)
    return chip


def _settle_bound(chip: TMC4210, target: int) -> float:
    """Seconds a move of |target| steps may take: twice (the time to ramp up to V_MAX and down
    again, 6.1.12.1 R and dR, plus the whole distance at V_MIN), and two ramp clock periods."""
    pd, rd = chip.read("PULSE_DIV"), chip.read("RAMP_DIV")
    v_max, v_min, a_max = chip.read("V_MAX"), chip.read("V_MIN"), chip.read("A_MAX")
    ramps = 2 * units.step_rate(v_max, pd) / units.rate_change(a_max, pd, rd)
    return 2 * (ramps + abs(target) / units.step_rate(v_min, pd)) + 2 * 32 * 2 ** rd / F


def _assert_settles(chip: TMC4210, target: int) -> None:
    chip.advance(_settle_bound(chip, target))
    for _ in range(5):
        assert (chip.read("X_ACTUAL"), chip.read("V_ACTUAL")) == (target, 0)
        assert chip.spi(R.read_datagram(0x05)) >> 24 & R.STATUS_XEQT1
        chip.advance(0.02)


@example(pd=0, extra=5, where=0.25, v_max=17, v_min=3, target=1)  # swung for ever before
@example(pd=3, extra=5, where=0.0, v_max=1514, v_min=3, target=-40)
@settings(deadline=None)
@given(st.integers(0, 6), st.integers(0, 6), st.floats(0, 1), st.integers(1, 2047), st.integers(1, 10),
       st.integers(-60, 60).filter(lambda t: t != 0))
def test_short_moves_settle_on_the_target_in_bounded_time(pd, extra, where, v_max, v_min, target):
    """6.1.7.1.1: with A_MAX_LOWER_LIMIT <= A_MAX <= A_MAX_UPPER_LIMIT "any target position" is
    reached "without oscillations"; 6.1.3: V_MIN >= 1 "assures reaching each target position
    exactly". Random short moves (too short for the ramp p is made for, 6.1.9.2) end on X_TARGET
    with V_ACTUAL = 0 and xEQt1 within twice the time of a full ramp plus the distance at V_MIN,
    and stay there (an overshoot of a step, 6.1.9.2 hints, comes back and settles)."""
    v_max = max(v_max, v_min)
    chip = _short_move(pd, extra, where, v_max, v_min, target)
    _assert_settles(chip, target)


def test_a_short_move_that_overshoots_by_one_step_settles():
    """6.1.9.2 hints: a one-step overshoot may occur; the motor comes back and stops on target
    (6.1.3: V_MIN >= 1 "assures reaching each target position exactly")."""
    chip = _short_move(pd=3, extra=6, where=0.5, v_max=42, v_min=2, target=13)
    peak = 0
    for _ in range(200):
        chip.advance(2 * 13 / units.step_rate(2, 3) / 200)
        peak = max(peak, chip.read("X_ACTUAL"))
    assert peak <= 14                                 # at most the one step the hints allow
    assert chip.read("X_ACTUAL") == 13 and chip.read("V_ACTUAL") == 0


@pytest.mark.parametrize("pd,extra,a_max,v_max,v_min,target", [
    (0, 5, 523, 17, 3, 1), (2, 6, 1024, 1842, 9, 14), (0, 5, 530, 491, 6, 6), (3, 5, 1345, 1514, 3, 40),
])
def test_short_moves_settle_on_the_target(pd, extra, a_max, v_max, v_min, target):
    """6.1.7.1.1: with A_MAX inside its limits "any target position" is reached "without
    oscillations"; 6.1.3: V_MIN >= 1 "assures reaching each target position exactly". These
    short moves (found by hypothesis) overshot under the latched-braking model and used to swing
    target-1 / target / target+1 for ever; with the ramp following V_TARGET each ramp step (6.1.9)
    they pass the target by at most one step (6.1.9.2 hints), the signed accumulator (6.1.12.1,
    range +-2047) walks such a step back, and the motor stops on the target."""
    chip = _short_move(pd, extra, None, v_max, v_min, target, a_max=a_max)
    peak, ramp_period = 0, 32 << (pd + extra)
    while chip.time < _settle_bound(chip, target):
        chip.advance_cycles(ramp_period)
        peak = max(peak, chip.read("X_ACTUAL"))
    assert peak <= target + 1  # at most one step past it (6.1.9.2 hints)
    seen = set()
    for _ in range(50):
        chip.advance(0.01)
        seen.add((chip.read("X_ACTUAL"), chip.read("V_ACTUAL")))
    assert seen == {(target, 0)}


def test_a_max_far_below_the_lower_limit_oscillates_around_the_target():
    """6.1.7.1.1: below A_MAX_LOWER_LIMIT = 2^(RAMP_DIV-PULSE_DIV-1) "oscillations around a target
    position may occur": there A_MAX = 4 (limit 32) needs p = 4 / (128 * 2^6) below the smallest
    PMUL/PDIV (128 / 2^16, 6.1.9.1), so no pair exists (6.1.9.2.2), the nearest one's p is too
    large (6.1.9.1 note) and the motor swings across the target several times before it settles."""
    lower, _ = units.a_max_limits(ramp_div=6, pulse_div=0)
    assert lower == 32
    assert not calc_pmul_pdiv(4, 6, 0, 0.01).valid
    chip = setup(v_min=1, v_max=1000, a_max=4, pulse_div=0, ramp_div=6, pmul=128, pdiv=13)
    chip.write("X_TARGET", 3_000_000)
    xs = []
    for _ in range(1200):
        chip.advance(0.1)
        xs.append(chip.read("X_ACTUAL") - 3_000_000)
    crossings = sum(1 for a, b in zip(xs, xs[1:], strict=False) if a * b < 0)
    assert max(xs) > 0 and crossings >= 4
    good = setup(v_min=1, v_max=1000, a_max=lower, pulse_div=0, ramp_div=6)
    good.write("X_TARGET", 3_000_000)
    peak = 0
    for _ in range(600):
        good.advance(0.1)
        peak = max(peak, good.read("X_ACTUAL"))
    assert peak == 3_000_000 == good.read("X_ACTUAL")


def test_reset_restores_the_power_on_registers():
    """5 / 11: power-on reset - all registers 0 except STPDIV_4210 = 15; virtual time goes on."""
    chip = setup()
    chip.write("X_TARGET", 500)
    chip.advance(1.0)
    t = chip.time
    chip.reset()
    assert chip.time == t
    assert chip.read("X_ACTUAL") == 0 and chip.read("V_MAX") == 0 and chip.read("STPDIV_4210") == 15
    assert chip.read("IF_CONFIGURATION_4210") == 0


def test_the_pd86_1180_engine_and_the_chip_share_one_ramp_core():
    """Issue 6 / docs/architecture.md "Layers": the TMC4210 model and the PD86-1180 firmware engine run the same
    TMC429 ramp core, so the same registers give the same motion, cycle for cycle."""
    from opentmcl.motion.tmc429 import Tmc429Ramp
    from opentmcl.motion.tmc429_engine import Tmc429Engine

    engine = Tmc429Engine()
    engine.configure(max_positioning_speed=1000, max_acceleration=100, minimum_speed=10,
                     ramp_divisor=8, pulse_divisor=5)
    chip = setup(v_min=10, v_max=1000, a_max=100, pulse_div=5, ramp_div=8)
    assert type(chip.ramp) is type(engine.ramp) is Tmc429Ramp
    assert (chip.read("PMUL"), chip.read("PDIV")) == (engine.pmul, engine.pdiv)
    engine.move_to(20_000)
    chip.write("X_TARGET", 20_000)
    for _ in range(70):  # 70 * 1234567 cycles = 5.4 s at 16 MHz
        chip.advance_cycles(1_234_567)
        engine.advance(chip.cycle)
        assert chip.read("X_ACTUAL") == engine.position
        assert chip.read("V_ACTUAL") == engine.velocity
    assert chip.read("X_ACTUAL") == 20_000
