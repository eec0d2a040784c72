"""Reference switches, stops, position latch, compare and the interrupts around them
(datasheet 6.1.10.2, 6.1.11, 6.1.13, 6.1.14, 6.2.1.1-2, 7)."""
from opentmcl.chips.tmc4210 import TMC4210
from opentmcl.chips.tmc4210 import registers as R

from .helpers import run_until_reached, setup

BIT = R.INT_BIT


def moving(chip, target, seconds=0.3):
    chip.write("X_TARGET", target)
    chip.advance(seconds)
    return chip.read("V_ACTUAL")


def test_left_switch_stops_only_motion_to_the_left():
    """6.1.10.2 disable_stop_l = 0: "The motor will be stopped when the velocity is negative and the
    left reference switch becomes active"; the stop "reacts only to the switch which corresponds to
    the actual motion direction"; soft_stop = 0: "Stopping takes place immediately"."""
    chip = setup()
    chip.write("mask_stop", 1)
    assert moving(chip, 50_000) > 0
    chip.set_inputs(ref_l=1)
    assert chip.read("V_ACTUAL") > 0 and chip.read("int_stop") == 0
    chip.set_inputs(ref_l=0)
    chip.write("X_TARGET", -50_000)
    chip.advance(2.0)
    assert chip.read("V_ACTUAL") < 0
    chip.set_inputs(ref_l=1)
    assert chip.read("V_ACTUAL") == 0
    assert chip.read("int_stop") == 1 and chip.spi(R.read_datagram(0)) >> 31 == 1
    x = chip.read("X_ACTUAL")
    chip.advance(1.0)
    assert chip.read("X_ACTUAL") == x


def test_a_new_target_into_an_active_stop_switch_does_not_move():
    """6.1.10.2: while the left switch is active the motor cannot move to the left; it may leave to the right."""
    chip = setup()
    chip.set_inputs(ref_l=1)
    chip.write("X_TARGET", -1000)
    chip.advance(1.0)
    assert chip.read("X_ACTUAL") == 0
    chip.write("X_TARGET", 1000)
    chip.advance(1.0)
    assert chip.read("X_ACTUAL") > 0


def test_disable_stop_l_lets_the_motor_pass():
    """6.1.10.2 disable_stop_l = 1: "Left reference switch is disabled as an automatic stop switch"."""
    chip = setup()
    chip.write("disable_stop_l", 1)
    moving(chip, -50_000, 2.0)
    chip.set_inputs(ref_l=1)
    assert chip.read("V_ACTUAL") < 0


def test_soft_stop_decelerates_with_a_max():
    """6.1.10.2 soft_stop = 1: "Stopping takes place in consideration of motion parameter limits;
    stops with linear ramp"."""
    chip = setup(a_max=50)
    chip.write("soft_stop", 1)
    chip.write("mot1r", 1)
    v0 = moving(chip, 50_000, 5.0)
    assert v0 == 1000
    chip.set_inputs(ref_r=1)
    x0 = chip.read("X_ACTUAL")
    chip.advance(0.5)
    v1 = chip.read("V_ACTUAL")
    assert 0 < v1 < v0
    chip.advance(5.0)
    assert chip.read("V_ACTUAL") == 0 and chip.read("X_ACTUAL") > x0 + 100


def test_right_switch_needs_mot1r():
    """7.1 / 1.5.4: "The right reference switch REF_R has to be initialized by writing 1 to mot1r";
    with mot1r = 0 only REF_L is a switch."""
    chip = setup()
    moving(chip, 50_000, 2.0)
    chip.set_inputs(ref_r=1)
    assert chip.read("V_ACTUAL") > 0
    chip.write("mot1r", 1)
    assert chip.read("V_ACTUAL") == 0


def test_disable_stop_r():
    """6.1.10.2 disable_stop_r = 1: the right switch does not stop positive motion."""
    chip = setup()
    chip.write("mot1r", 1)
    chip.write("disable_stop_r", 1)
    moving(chip, 50_000, 2.0)
    chip.set_inputs(ref_r=1)
    assert chip.read("V_ACTUAL") > 0


def test_switch_on_the_axis_stops_at_its_edge():
    """6.1.10.2: the motor stops when the switch becomes active - with a switch at positions
    <= -5000 a move to -20000 ends at -5000."""
    chip = setup()
    chip.attach_switch("ref_l", -(1 << 23), -5000)
    chip.write("X_TARGET", -20_000)
    chip.advance(20.0)
    assert chip.read("X_ACTUAL") == -5000 and chip.read("V_ACTUAL") == 0


def test_dx_ref_tolerance_excludes_the_origin_from_stopping():
    """6.1.13: "DX_REF_TOLERANCE disables automatic stopping by a switch around the origin";
    7.2 triple switch: a reference switch in series with the left stop switch, inside the
    tolerance range, does not stop the motor; the left stop switch still does."""
    for tol, stop_at in ((0, 40), (100, -9000)):
        chip = setup()
        chip.write("X_ACTUAL", 2000)
        chip.write("X_TARGET", 2000)
        chip.attach_switch("ref_l", -40, 40)          # reference switch at the origin
        chip.attach_switch("ref_l", -(1 << 23), -9000)  # left stop switch
        chip.write("DX_REF_TOLERANCE", tol)
        chip.write("X_TARGET", -20_000)
        chip.advance(30.0)
        assert chip.read("X_ACTUAL") == stop_at


def test_position_latch_on_the_reference_switch_edges():
    """6.1.14 / 7.3: a dummy write to X_LATCHED arms the latch (lp = 1); the next edge of the
    reference switch during motion stores X_ACTUAL and clears lp - entering the switch (x2) and,
    armed again, leaving it (x1); x_ref = (x1 + x2) / 2."""
    chip = setup()
    chip.write("X_ACTUAL", 3000)
    chip.write("X_TARGET", 3000)
    chip.attach_switch("ref_l", 300, 500)
    chip.write("DX_REF_TOLERANCE", 4095)  # the reference switch must not stop the motor
    chip.write("X_LATCHED", 0)
    assert chip.read("lp") == 1
    chip.write("X_TARGET", 400)
    chip.advance(20.0)
    assert chip.read("lp") == 0 and chip.read("X_LATCHED") == 500
    chip.write("X_LATCHED", 0)
    chip.write("X_TARGET", 0)
    chip.advance(20.0)
    assert chip.read("lp") == 0 and chip.read("X_LATCHED") == 299
    assert (chip.read("X_LATCHED") + 500) // 2 == 399


def test_ref_rnl_selects_the_right_switch_for_latching():
    """6.1.10.2 ref_RnL = 1: "The right (not left) reference switch controls reference switch functions"."""
    chip = setup()
    chip.write("mot1r", 1)
    chip.write("REF_CONF", 0b1010)  # ref_RnL, right switch not a stop switch
    chip.attach_switch("ref_r", 200, 300)
    chip.attach_switch("ref_l", 100, 150)
    chip.write("X_LATCHED", 0)
    chip.write("X_TARGET", 1000)
    chip.advance(20.0)
    assert chip.read("X_LATCHED") == 200


def test_switch_edge_interrupts_and_int_status():
    """6.1.11: int_stop_left_high / _low, int_stop_right_high / _low on the switch edges; the INT
    status bit (bit 31 of each answer) is set while a flag is set."""
    chip = TMC4210()
    chip.write("mot1r", 1)
    chip.write("INTERRUPT_MASK", 0xF0)
    assert chip.spi(R.read_datagram(0)) >> 31 == 0
    chip.set_inputs(ref_l=1)
    assert chip.read("INTERRUPT_FLAGS") == BIT["stop_left_high"]
    chip.set_inputs(ref_l=0, ref_r=1)
    chip.set_inputs(ref_r=0)
    assert chip.read("INTERRUPT_FLAGS") == 0xF0
    assert chip.spi(R.read_datagram(0)) >> 31 == 1 and chip.n_int == 0
    chip.write("INTERRUPT_FLAGS", 0xFF)
    assert chip.spi(R.read_datagram(0)) >> 31 == 0 and chip.n_int == 1


def test_inv_ref_inverts_the_switch_polarity():
    """6.2.1 inv_ref: "If this bit is set, a low level on the input signals an active reference switch"."""
    chip = setup()
    chip.write("inv_ref", 1)  # pins low: the left switch is now active
    chip.write("X_TARGET", -1000)
    chip.advance(1.0)
    assert chip.read("X_ACTUAL") == 0
    chip.set_inputs(ref_l=1)
    chip.advance(1.0)
    assert chip.read("X_ACTUAL") < 0


def test_ref_wrong_and_ref_miss():
    """6.1.11: int_ref_wrong - the reference switch active outside the DX_REF_TOLERANCE range;
    int_ref_miss - the reference switch inactive at the 0 position."""
    chip = setup()
    chip.write("INTERRUPT_MASK", BIT["ref_wrong"] | BIT["ref_miss"])
    chip.write("DX_REF_TOLERANCE", 50)
    chip.write("disable_stop_l", 1)
    chip.attach_switch("ref_l", 1000, 1100)
    chip.write("X_TARGET", 2000)
    chip.advance(10.0)
    assert chip.read("INTERRUPT_FLAGS") == BIT["ref_wrong"]
    chip.write("INTERRUPT_FLAGS", 0xFF)
    chip.write("X_TARGET", -100)
    chip.advance(30.0)
    assert chip.read("INTERRUPT_FLAGS") & BIT["ref_miss"]
    chip.write("INTERRUPT_FLAGS", 0xFF)
    chip.detach_switches()
    chip.attach_switch("ref_l", -20, 20)  # now the switch is at the origin: neither flag
    chip.write("X_TARGET", 100)
    chip.advance(10.0)
    assert chip.read("INTERRUPT_FLAGS") == 0


def test_position_compare_interrupt():
    """6.2.1.1-2: POS_COMP_4210 is compared to the motor position; POS_COMP_INT_4210 holds the
    mask M (bit 8) and the flag I (bit 0), which drives INT."""
    chip = setup()
    chip.write("POS_COMP_4210", 777)
    chip.write("POS_COMP_INT_M", 1)
    chip.write("X_TARGET", 700)
    assert run_until_reached(chip, 20)
    assert chip.read("POS_COMP_INT_I") == 0
    chip.write("X_TARGET", 800)
    assert run_until_reached(chip, 20)
    assert chip.read("POS_COMP_INT_I") == 1
    assert chip.spi(R.read_datagram(0)) >> 31 == 1
    chip.write("POS_COMP_INT_I", 1)
    assert chip.read("POS_COMP_INT_I") == 0 and chip.spi(R.read_datagram(0)) >> 31 == 0


def test_ustep_count_follows_the_steps():
    """5.3: USTEP_COUNT_4210 holds the actual microstep pointer (8 bit): it follows each step and
    is writable."""
    chip = setup()
    chip.write("USTEP_COUNT_4210", 250)
    chip.write("X_TARGET", 10)
    assert run_until_reached(chip, 20)
    assert chip.read("USTEP_COUNT_4210") == 4
    chip.write("X_ACTUAL", 500)  # the sequencer does not jump with the position counter
    chip.write("X_TARGET", 500)
    assert chip.read("USTEP_COUNT_4210") == 4


def test_a_switch_on_the_axis_stays_put_when_x_actual_is_overwritten():
    """6.1.2: X_ACTUAL can be overwritten "for the reference switch position calibration"; the
    switch is part of the mechanics and keeps its place on the axis."""
    chip = setup()
    chip.attach_switch("ref_l", -(1 << 23), -100)
    chip.write("RAMP_MODE", 3)
    chip.write("X_ACTUAL", 1000)
    chip.write("X_TARGET", 1000)
    chip.write("RAMP_MODE", 0)
    chip.write("X_TARGET", -5000)
    chip.advance(20.0)
    assert chip.read("X_ACTUAL") == 900


def test_register_writes_are_no_arrivals():
    """6.1.11 int_pos_end "If a target position is reached", int_ref_miss at the 0 position and the
    position compare are raised by motion; overwriting X_TARGET / X_ACTUAL / POS_COMP_4210 so that
    they match (homing, 7.3) raises none of them."""
    chip = setup()
    chip.write("INTERRUPT_MASK", 0xFF)
    chip.write("POS_COMP_INT_M", 1)
    chip.write("RAMP_MODE", 3)
    chip.write("X_ACTUAL", 40)
    chip.write("X_TARGET", 40)
    chip.write("POS_COMP_4210", 40)
    chip.write("X_ACTUAL", 0)
    chip.write("X_TARGET", 0)
    assert chip.read("INTERRUPT_FLAGS") == 0 and chip.read("POS_COMP_INT_I") == 0
