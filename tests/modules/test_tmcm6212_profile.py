"""The TMCM-6212 profile (data/tmcm6212.toml) against the TMCM-6212 TMCL firmware manual V1.05.

Rows quoted in the docstrings are copied from the manual's tables (tab-separated columns shown as " | ").
"""
from __future__ import annotations

import tomllib
from importlib import resources

import pytest

from opentmcl.modules.profile import ModuleProfile, Param, parse_profile


@pytest.fixture(scope="module")
def prof() -> ModuleProfile:
    text = resources.files("opentmcl.modules").joinpath("data", "tmcm6212.toml").read_text(encoding="utf-8")
    return parse_profile(tomllib.loads(text))


def _check(p: Param, *, number, name, title, lo, hi, access, unit, default=None, values=None) -> None:
    assert (p.number, p.name, p.title) == (number, name, title)
    assert (p.min, p.max) == (lo, hi)
    assert p.access == access
    assert p.unit == unit
    if default is not None:
        assert p.default == default
    if values is not None:
        assert p.values == tuple(values)


# --- the manual's parameter numbers --------------------------------------------------------------

# 4.1, Table 14 "All TMCM-6212 Axis Parameters": every number in the Number column.
MANUAL_AXIS_NUMBERS = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26,
    27, 28, 29, 31, 32, 33, 127, 140, 162, 163, 164, 165, 166, 167, 168, 169, 170, 171, 172, 173, 174,
    180, 181, 182, 184, 185, 186, 187, 188, 193, 194, 195, 196, 197, 201, 202, 204, 206, 207, 208,
    209, 210, 212, 214, 255,
]
# 5.1, Table 16 "All Global Parameters of the TMCM-6212 Module in Bank 0".
MANUAL_BANK0_NUMBERS = [65, 66, 68, 69, 70, 71, 75, 76, 77, 81, 82, 83, 84, 85, 87, 128, 129, 130, 132, 133, 255]
# 5.4, Table 20 "Interrupt Parameters in Bank 3".
MANUAL_BANK3_NUMBERS = [0, 1, 2, *range(27, 43)]
# 3.5.6.1, Table 12 "Interrupt Vectors".
MANUAL_INTERRUPT_NUMBERS = [0, 1, 2, *range(3, 9), *range(15, 43), 255]


def test_axis_parameters_are_exactly_table_14(prof):
    """4.1: "This section contains a table which describes all axis parameters that can be used on
    the TMCM-6212 module." The profile holds each number of Table 14 and no other."""
    assert len(MANUAL_AXIS_NUMBERS) == 72
    assert sorted(prof.axis_parameters) == MANUAL_AXIS_NUMBERS


def test_bank0_parameters_are_exactly_table_16(prof):
    """5.1, Table 16: All Global Parameters of the TMCM-6212 Module in Bank 0."""
    bank0 = sorted(n for (b, n) in prof.global_parameters if b == 0)
    assert bank0 == MANUAL_BANK0_NUMBERS


def test_bank3_parameters_are_exactly_table_20(prof):
    """5.4, Table 20: Interrupt Parameters in Bank 3 (timers 0..2, trigger transitions 27..42)."""
    bank3 = sorted(n for (b, n) in prof.global_parameters if b == 3)
    assert bank3 == MANUAL_BANK3_NUMBERS


def test_only_banks_0_and_3_are_listed(prof):
    """5: "Bank 1: Not used. Bank 2: TMCL user variables." Bank 2 is described by the [module]
    user variable counts, not parameter by parameter."""
    assert {b for (b, _) in prof.global_parameters} == {0, 3}


def test_user_variables_bank_2(prof):
    """5.3, Table 18: "0...55 | user variables #0...#55 | ... | RWE"; "Up to 256 user variables are
    available" and "the first 56 variables can also be stored permanently in the EEPROM"."""
    assert prof.user_variables == 256
    assert prof.storable_user_variables == 56


# --- fixed names (shared with the firmware and the host library) ----------------------------------

FIXED_AXIS_NAMES = {
    0: "target_position", 1: "actual_position", 2: "target_speed", 3: "actual_speed",
    4: "max_positioning_speed", 5: "max_acceleration", 6: "max_current", 7: "standby_current",
    8: "position_reached", 9: "home_switch", 10: "right_limit_switch", 11: "left_limit_switch",
    12: "right_limit_switch_disable", 13: "left_limit_switch_disable", 14: "swap_limit_switches",
    15: "acceleration_a1", 16: "velocity_v1", 17: "max_deceleration", 18: "deceleration_d1",
    19: "velocity_vstart", 20: "velocity_vstop", 21: "ramp_wait_time", 24: "right_limit_switch_polarity",
    25: "left_limit_switch_polarity", 26: "soft_stop_enable", 127: "relative_positioning_option",
    140: "microstep_resolution", 193: "reference_search_mode", 194: "reference_search_speed",
    195: "reference_switch_speed", 196: "end_switch_distance", 197: "last_reference_position",
    202: "motor_full_step_resolution", 204: "freewheeling", 206: "actual_load_value",
    207: "extended_error_flags", 208: "driver_error_flags", 209: "encoder_position",
    210: "encoder_resolution", 212: "max_encoder_deviation", 214: "power_down_delay", 255: "unit_mode",
}
FIXED_BANK0_NAMES = {
    65: "rs485_baud_rate", 66: "serial_address", 68: "serial_heartbeat", 69: "can_bit_rate",
    70: "can_reply_id", 71: "can_id", 75: "telegram_pause_time", 76: "serial_host_address",
    77: "auto_start_mode", 81: "tmcl_code_protection", 82: "can_heartbeat", 83: "can_secondary_address",
    84: "coordinate_storage", 85: "do_not_restore_user_variables", 87: "serial_secondary_address",
    128: "tmcl_application_status", 129: "download_mode", 130: "tmcl_program_counter", 132: "tick_timer",
    133: "random_number", 255: "suppress_reply",
}


def test_fixed_axis_parameter_names(prof):
    """4.1 Table 14 names in snake_case, as the firmware and the host library address them."""
    assert {n: prof.axis_parameters[n].name for n in FIXED_AXIS_NAMES} == FIXED_AXIS_NAMES


def test_fixed_global_parameter_names(prof):
    """5.1 Table 16 and 5.4 Table 20 names in snake_case."""
    assert {n: prof.global_parameters[(0, n)].name for n in FIXED_BANK0_NAMES} == FIXED_BANK0_NAMES
    assert prof.global_parameter("timer_0_period", 3).number == 0
    assert prof.global_parameters[(3, 27)].name == "stop_left_0_trigger_transition"
    assert prof.global_parameters[(3, 38)].name == "stop_right_5_trigger_transition"
    assert prof.global_parameters[(3, 42)].name == "input_3_trigger_transition"


def test_axis_parameter_names_are_unique(prof):
    """Each axis parameter is addressable by one name (ModuleProfile.axis_parameter)."""
    names = [p.name for p in prof.axis_parameters.values()]
    assert len(names) == len(set(names))
    for p in prof.axis_parameters.values():
        assert prof.axis_parameter(p.name) is p


def test_global_parameter_names_are_unique_across_banks(prof):
    """ModuleProfile.global_parameter(name) searches all banks, so names are unique across banks."""
    names = [p.name for p in prof.global_parameters.values()]
    assert len(names) == len(set(names))


def test_names_are_snake_case(prof):
    """Names are snake_case of the manual's parameter names."""
    for p in [*prof.axis_parameters.values(), *prof.global_parameters.values()]:
        assert p.name.isidentifier() and p.name == p.name.lower(), p.name


# --- consistency of every row -------------------------------------------------------------------------

def _all_params(prof):
    return [*prof.axis_parameters.values(), *prof.global_parameters.values()]


def test_defaults_are_within_ranges(prof):
    """Every factory default is a value the parameter accepts."""
    for p in _all_params(prof):
        assert p.min <= p.max, p.name
        assert p.accepts(p.default), (p.name, p.default)


def test_enumerated_values_lie_in_range(prof):
    """Discrete value lists stay inside [min, max] and include both ends."""
    for p in _all_params(prof):
        if p.values:
            assert list(p.values) == sorted(set(p.values)), p.name
            assert (p.values[0], p.values[-1]) == (p.min, p.max), p.name


def test_access_letters_are_the_manuals(prof):
    """Table 15: "R | GGP | Parameter readable", "W | SGP, AGP | Parameter writable",
    "E | STGP, RSGP | ...stored in the EEPROM", "A | SGP | Automatically stored in the EEPROM".
    Table 14 uses only "RW" and "R"."""
    for p in prof.axis_parameters.values():
        assert p.access in {"R", "RW"}, p.name
    for p in prof.global_parameters.values():
        assert p.access in {"R", "RW", "RWA"}, p.name
        assert p.bank in (0, 3)


def test_every_row_has_title_and_description(prof):
    """Each parameter carries the manual's name and a short description."""
    for p in _all_params(prof):
        assert p.title.strip() and p.description.strip(), p.name


def test_bank0_auto_stored_range(prof):
    """5.1: "The parameters with numbers between 64 and 128 are automatically stored in the EEPROM."
    Table 16 marks exactly those RWA."""
    for (bank, num), p in prof.global_parameters.items():
        if bank == 0:
            assert p.auto_stored == (64 <= num < 128), num


# --- spot checks: axis parameters (4.1, Table 14) ------------------------------------------------------

def test_ap0_target_position(prof):
    """Table 14: "0 | Target position | The desired target position in position mode |
    -2147483648 ... 2147483647 [μsteps] | RW"."""
    _check(prof.axis_parameters[0], number=0, name="target_position", title="Target position",
           lo=-2147483648, hi=2147483647, access="RW", unit="µsteps")


def test_ap2_target_speed_is_signed(prof):
    """Table 14: "2 | Target speed | The desired speed in velocity mode. Not valid in position mode. |
    -7999774 ... 7999774 [pps] | RW"."""
    _check(prof.axis_parameters[2], number=2, name="target_speed", title="Target speed",
           lo=-7999774, hi=7999774, access="RW", unit="pps")


def test_ap3_actual_speed_read_only(prof):
    """Table 14: "3 | Actual speed | The actual speed of the motor. | -7999774 ... 7999774 [pps] | R"."""
    p = prof.axis_parameters[3]
    _check(p, number=3, name="actual_speed", title="Actual speed", lo=-7999774, hi=7999774,
           access="R", unit="pps")
    assert p.readable and not p.writable


def test_ap5_max_acceleration(prof):
    """Table 14: "5 | Maximum acceleration | Maximum acceleration in positioning ramps. ... |
    0...7629278 [pps ²] | RW"."""
    _check(prof.axis_parameters[5], number=5, name="max_acceleration", title="Maximum acceleration",
           lo=0, hi=7629278, access="RW", unit="pps^2")


def test_ap6_max_current_accepts_every_value(prof):
    """Table 14: "6 | Maximum current | ... The maximum value is 255 ... The current can be adjusted
    in 32 steps | 0...255 | RW". The 32 steps are a property of the driver, not of the value range."""
    p = prof.axis_parameters[6]
    _check(p, number=6, name="max_current", title="Maximum current", lo=0, hi=255, access="RW", unit="")
    assert all(p.accepts(v) for v in range(256))
    assert not p.accepts(256) and not p.accepts(-1)
    assert "32 steps" in p.description


def test_ap16_velocity_v1(prof):
    """Table 14: "16 | Velocity V1 | ... Setting this value to 0 turns off the first acceleration /
    deceleration phase ... | 0 .. 1000000 [pps] | RW"."""
    _check(prof.axis_parameters[16], number=16, name="velocity_v1", title="Velocity V1",
           lo=0, hi=1000000, access="RW", unit="pps")


def test_ap19_20_vstart_vstop(prof):
    """Table 14: "19 | Velocity VSTART | Motor start velocity ... | 0 .. 249999 [pps] | RW" and
    "20 | Velocity VSTOP | Motor stop velocity ... | 0 .. 249999 [pps] | RW"."""
    _check(prof.axis_parameters[19], number=19, name="velocity_vstart", title="Velocity VSTART",
           lo=0, hi=249999, access="RW", unit="pps")
    _check(prof.axis_parameters[20], number=20, name="velocity_vstop", title="Velocity VSTOP",
           lo=0, hi=249999, access="RW", unit="pps")
    # "Do not set VSTART higher than VSTOP."
    assert prof.axis_parameters[19].default <= prof.axis_parameters[20].default


def test_ap21_ramp_wait_time_unit(prof):
    """Table 14: "21 | Ramp wait time | ... Time range is 0 to 2 seconds. ... | 0 .. 65535 [0.000032s] | RW"."""
    _check(prof.axis_parameters[21], number=21, name="ramp_wait_time", title="Ramp wait time",
           lo=0, hi=65535, access="RW", unit="0.000032s")


def test_ap29_measured_speed(prof):
    """Table 14: "29 | Measured speed | Speed measured by the motor driver. | 0 .. 7999774 [pps] | R"."""
    _check(prof.axis_parameters[29], number=29, name="measured_speed", title="Measured speed",
           lo=0, hi=7999774, access="R", unit="pps")


def test_ap31_power_down_ramp_unit(prof):
    """Table 14: "31 | Power down ramp | ... 0=instant power down, 15=longest possible power down
    ramp. | 0...15 [0.16384s] | RW"."""
    _check(prof.axis_parameters[31], number=31, name="power_down_ramp", title="Power down ramp",
           lo=0, hi=15, access="RW", unit="0.16384s")


def test_ap127_relative_positioning_option(prof):
    """Table 14: "127 | Relative positioning option | Start position for MVP REL command: 0 last
    target position, 1 actual position, 2 encoder position | 0/1 | RW". The value table lists 2
    although the Range column says 0/1; the profile accepts all three listed values."""
    p = prof.axis_parameters[127]
    _check(p, number=127, name="relative_positioning_option", title="Relative positioning option",
           lo=0, hi=2, access="RW", unit="", default=0, values=[0, 1, 2])
    assert not p.accepts(3)


def test_ap140_microstep_resolution(prof):
    """Table 14: "140 | Microstep resolution | 0 fullstep ... 8 256 microsteps | 0..8 | RW";
    6.5: "microstep resolution setting of the module (axis parameter #140, default setting is 256
    microsteps per full step)"."""
    _check(prof.axis_parameters[140], number=140, name="microstep_resolution",
           title="Microstep resolution", lo=0, hi=8, access="RW", unit="", default=8, values=range(9))


def test_ap174_stallguard2_threshold_signed(prof):
    """Table 14: "174 | stallGuard2 threshold | This signed value controls stallGuard2 threshold
    level ... | -64...+63 | RW"."""
    p = prof.axis_parameters[174]
    _check(p, number=174, name="stallguard2_threshold", title="stallGuard2 threshold",
           lo=-64, hi=63, access="RW", unit="")
    assert p.accepts(-64) and p.accepts(63)
    assert not p.accepts(-65) and not p.accepts(64)


def test_ap180_smartenergy_actual_current(prof):
    """Table 14: "180 | smartEnergy actual current | ... 0...31: 1/32, 2/32, ... 32/32 | 0...31 | R"."""
    _check(prof.axis_parameters[180], number=180, name="smartenergy_actual_current",
           title="smartEnergy actual current", lo=0, hi=31, access="R", unit="")


def test_ap193_reference_search_mode(prof):
    """Table 14: "193 | Reference search mode | 1 ... 8 ... Add 128 to a mode value for inverting the
    home switch (can be used with mode 5...8). Add 64 to a mode for driving the right instead of the
    left reference switch (can be used with mode 1...4). | 1..8 | RW"; 6.1.5: "set axis parameter
    #193 to 129" (the manual's own example values 129..132 are accepted too)."""
    p = prof.axis_parameters[193]
    assert (p.name, p.title, p.access) == ("reference_search_mode", "Reference search mode", "RW")
    for mode in range(1, 9):
        assert p.accepts(mode)
    for mode in (65, 66, 67, 68, 133, 134, 135, 136, 129, 130, 131, 132):
        assert p.accepts(mode)
    for bad in (0, 9, 64, 69, 72, 128, 137, 255):
        assert not p.accepts(bad)


def test_ap196_end_switch_distance_read_only(prof):
    """Table 14: "196 | End switch distance | ... after executing the RFS command (with reference
    search mode 2 or 3). | -2147483648 ... 2147483647 [μsteps] | R"."""
    _check(prof.axis_parameters[196], number=196, name="end_switch_distance", title="End switch distance",
           lo=-2147483648, hi=2147483647, access="R", unit="µsteps")


def test_ap202_full_step_resolution_default(prof):
    """Table 14: "202 | Motor full step resolution | Full step resolution of the motor (Default: 200).
    | 0...65535 [fullsteps/round] | RW"."""
    _check(prof.axis_parameters[202], number=202, name="motor_full_step_resolution",
           title="Motor full step resolution", lo=0, hi=65535, access="RW", unit="fullsteps/round",
           default=200)


def test_ap204_freewheeling(prof):
    """Table 14: "204 | Freewheeling mode | 0 normal operation, 1 freewheeling, 2 coil shorted using
    low side drivers, 3 coil shorted using high side drivers | 0...3 | RW"."""
    _check(prof.axis_parameters[204], number=204, name="freewheeling", title="Freewheeling mode",
           lo=0, hi=3, access="RW", unit="", values=[0, 1, 2, 3])


def test_ap207_extended_error_flags(prof):
    """Table 14: "207 | Extended error flags | 1 stallGuard error, 2 deviation error | 0...3 | R"."""
    _check(prof.axis_parameters[207], number=207, name="extended_error_flags", title="Extended error flags",
           lo=0, hi=3, access="R", unit="")


def test_ap212_max_encoder_deviation_unit(prof):
    """Table 14: "212 | Maximum encoder deviation | ... switched off when the maximum deviation is set
    to zero. | 0...65535 [encoder steps] | RW"."""
    _check(prof.axis_parameters[212], number=212, name="max_encoder_deviation",
           title="Maximum encoder deviation", lo=0, hi=65535, access="RW", unit="encoder steps")


def test_ap214_power_down_delay(prof):
    """Table 14: "214 | Power down delay | ... The standard value is 200 (which means 2000ms). |
    0...417 [10ms] | RW"."""
    _check(prof.axis_parameters[214], number=214, name="power_down_delay", title="Power down delay",
           lo=0, hi=417, access="RW", unit="10ms", default=200)


def test_ap255_unit_mode_default(prof):
    """Table 14: "255 | Unit mode | ... 1 - the units are pps for velocity and pps ² for
    acceleration/deceleration Default value is 1 (pps units). | 0/1 | RW"."""
    _check(prof.axis_parameters[255], number=255, name="unit_mode", title="Unit mode",
           lo=0, hi=1, access="RW", unit="", default=1, values=[0, 1])


# --- spot checks: global parameters (5.1 Table 16, 5.4 Table 20) ---------------------------------------

def test_gp65_rs485_baud_rate(prof):
    """Table 16: "65 | RS485 baud rate | 0 9600 Default ... 7 115200 ... 11 1000000 Not supported by
    PCs | 0...7 | RWA"; values 8..11 are listed too, so they are accepted."""
    p = prof.global_parameters[(0, 65)]
    _check(p, number=65, name="rs485_baud_rate", title="RS485 baud rate", lo=0, hi=11, access="RWA",
           unit="", default=0, values=range(12))
    assert p.bank == 0 and p.auto_stored and p.storable


def test_gp66_serial_address(prof):
    """Table 16: "66 | Serial address | Module (target) address for RS485. | 1...255 | RWA";
    3.6.7 example "SGP 66, 0, 3" sets the serial address to 3."""
    p = prof.global_parameters[(0, 66)]
    _check(p, number=66, name="serial_address", title="Serial address", lo=1, hi=255, access="RWA",
           unit="", default=1)
    assert p.accepts(3) and not p.accepts(0)


def test_gp69_can_bit_rate(prof):
    """Table 16: "69 | CAN bit rate | 2 20kBit/s ... 8 1000kBit/s (Default) | 2...8 | RWA"."""
    _check(prof.global_parameters[(0, 69)], number=69, name="can_bit_rate", title="CAN bit rate",
           lo=2, hi=8, access="RWA", unit="", default=8, values=range(2, 9))


def test_gp70_71_can_ids(prof):
    """Table 16: "70 | CAN reply ID | The CAN ID for replies from the board (default: 2). | 0...2047 |
    RWA" and "71 | CAN ID | The module (target) address for CAN (default: 1). | 0...2047 | RWA"."""
    _check(prof.global_parameters[(0, 70)], number=70, name="can_reply_id", title="CAN reply ID",
           lo=0, hi=2047, access="RWA", unit="", default=2)
    _check(prof.global_parameters[(0, 71)], number=71, name="can_id", title="CAN ID",
           lo=0, hi=2047, access="RWA", unit="", default=1)


def test_gp81_code_protection(prof):
    """Table 16: "81 | TMCL code protection | 0 - no protection ... 3 - protection against
    disassembling and overwriting ... | 0/1/2/3 | RWA"."""
    _check(prof.global_parameters[(0, 81)], number=81, name="tmcl_code_protection",
           title="TMCL code protection", lo=0, hi=3, access="RWA", unit="", values=[0, 1, 2, 3])


def test_gp128_application_status_read_only(prof):
    """Table 16: "128 | TMCL application status | 0 - stop 1 - run 2 - step 3 - reset | 0...3 | R"."""
    p = prof.global_parameters[(0, 128)]
    _check(p, number=128, name="tmcl_application_status", title="TMCL application status",
           lo=0, hi=3, access="R", unit="")
    assert not p.writable and not p.storable


def test_gp132_tick_timer(prof):
    """Table 16: "132 | TMCL tick timer | A 32 bit counter that gets incremented by one every
    millisecond. It can also be reset to any start value. | 0...2147483647 | RW"."""
    _check(prof.global_parameters[(0, 132)], number=132, name="tick_timer", title="TMCL tick timer",
           lo=0, hi=2147483647, access="RW", unit="ms")


def test_gp255_suppress_reply_not_storable(prof):
    """Table 16: "255 | Suppress reply | ... This parameter cannot be stored to EEPROM and will be
    reset to 0 on startup. ... | 0/1 | RW"."""
    p = prof.global_parameters[(0, 255)]
    _check(p, number=255, name="suppress_reply", title="Suppress reply", lo=0, hi=1, access="RW",
           unit="", default=0, values=[0, 1])
    assert not p.storable


def test_bank3_timer_period_unsigned_32_bit(prof):
    """Table 20: "0 | Timer 0 period | Time between two interrupts | 0 .. 4294967295 [ms] | RW" and
    "1 | Timer 1 period (ms) | Time between two interrupts | 0 .. 4294967295 [ms] | RW"."""
    _check(prof.global_parameters[(3, 0)], number=0, name="timer_0_period", title="Timer 0 period",
           lo=0, hi=4294967295, access="RW", unit="ms")
    _check(prof.global_parameters[(3, 1)], number=1, name="timer_1_period", title="Timer 1 period (ms)",
           lo=0, hi=4294967295, access="RW", unit="ms")


def test_bank3_trigger_transitions(prof):
    """Table 20: "27 | Stop left 0 trigger transition | 0=off, 1=low-high, 2=high-low, 3=both |
    0 .. 3 | RW" ... "42 | Input 3 trigger transition | ... | 0 .. 3 | RW"."""
    _check(prof.global_parameters[(3, 27)], number=27, name="stop_left_0_trigger_transition",
           title="Stop left 0 trigger transition", lo=0, hi=3, access="RW", unit="")
    for num in range(27, 43):
        p = prof.global_parameters[(3, num)]
        assert (p.min, p.max, p.access, p.bank) == (0, 3, "RW", 3)
    # Stop switch pairs alternate left/right per axis 0..5, then inputs 0..3.
    for axis in range(6):
        assert prof.global_parameters[(3, 27 + 2 * axis)].name == f"stop_left_{axis}_trigger_transition"
        assert prof.global_parameters[(3, 28 + 2 * axis)].name == f"stop_right_{axis}_trigger_transition"
    for inp in range(4):
        assert prof.global_parameters[(3, 39 + inp)].name == f"input_{inp}_trigger_transition"


# --- [module] table ------------------------------------------------------------------------------------

def test_module_identity(prof):
    """Title page: "Firmware Version V1.05"; 1 Features: "six axis controller/driver module"."""
    assert prof.name == "TMCM-6212"
    assert prof.axes == 6
    assert prof.engine == "sixpoint"
    assert prof.firmware_version == "6212V105"
    assert len(prof.firmware_version) == 8 and prof.firmware_version.isascii()


def test_firmware_binary_layout(prof):
    """3.6.36 Table 13: "136 - get firmware version | Return firmware version in string format
    (special reply) or binary format)". Binary: type number in the upper, version 1.05 in the
    lower 16 bits."""
    assert prof.firmware_binary >> 16 == 6212
    assert (prof.firmware_binary >> 8) & 0xFF == 1
    assert prof.firmware_binary & 0xFF == 5


def test_program_memory(prof):
    """1 Features: "program memory (non volatile) for up to 6144 TMCL commands"."""
    assert prof.program_memory == 6144


def test_coordinates(prof):
    """3.6.22 SCO: "Up to 20 position values (coordinates) can be stored for every axis";
    "<coordinate number> 0...20"."""
    assert prof.coordinates == 20


def test_opcodes(prof):
    """3.4.1 Table 5 (ROR 1 ... ACO 39), 3.6.34 "64...71" (UF0..UF7), 3.6.36 Table 13 (128..137),
    3.6.35 (138). Table 5 lists no STAP/RSAP (7/8) and no ASCII command 139."""
    table5 = {1, 2, 3, 4, 5, 6, 9, 10, 11, 12, 13, 14, 15, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28,
              30, 31, 32, 33, 34, 35, 36, 37, 38, 39}
    expected = table5 | set(range(64, 72)) | set(range(128, 139))
    assert prof.opcodes == expected
    assert not prof.ascii_mode
    assert {7, 8, 139}.isdisjoint(prof.opcodes)


# --- I/O (3.6.12 SIO, 3.6.13 GIO) ----------------------------------------------------------------------

def test_io_banks(prof):
    """3.6.13: "IN0 | GIO 0, 0 | 0/1" ... "IN3 | GIO 3, 1 | 0...65535"; 3.6.12: "OUT3 | SIO 3, 2,
    <value> | 0/1"."""
    assert sorted(k for k, p in prof.io.items() if not p.measures) == [(b, p) for b in (0, 1, 2) for p in range(4)]
    assert [(k, p.measures) for k, p in prof.io.items() if p.measures] == [((1, 8), "supply_voltage")]  # extension
    for port in range(4):
        d, a, o = prof.io[(0, port)], prof.io[(1, port)], prof.io[(2, port)]
        assert (d.name, d.kind, d.access, d.min, d.max) == (f"IN{port}", "digital", "R", 0, 1)
        assert (a.name, a.kind, a.access, a.min, a.max) == (f"IN{port}", "analog", "R", 0, 65535)
        assert (o.name, o.kind, o.access, o.min, o.max) == (f"OUT{port}", "output", "RW", 0, 1)


# --- interrupts (3.5.6.1, Table 12) --------------------------------------------------------------------

def test_interrupt_vector_numbers(prof):
    """3.5.6.1 Table 12: "0 | Timer 0" ... "42 | Input change 3", "255 | Global interrupts"."""
    assert sorted(prof.interrupts) == MANUAL_INTERRUPT_NUMBERS


def test_interrupt_names(prof):
    """3.5.6.4: "VECT TI_TIMER0, Timer0Irq" ... "EI TI_GLOBAL"; Table 12 "3 | Target position
    reached 0", "15 | stallGuard axis 0", "21 | Deviation axis 0", "27 | Left stop switch 0",
    "28 | Right stop switch 0", "39 | Input change 0"."""
    iv = prof.interrupts
    assert (iv[0].name, iv[255].name) == ("TI_TIMER0", "TI_GLOBAL")
    assert iv[0].description == "Timer 0"
    assert iv[3].description == "Target position reached 0"
    assert iv[15].description == "stallGuard axis 0"
    assert iv[21].description == "Deviation axis 0"
    assert iv[28].description == "Right stop switch 0"
    assert iv[39].description == "Input change 0"
    names = [i.name for i in iv.values()]
    assert len(names) == len(set(names))
    assert all(n.startswith("TI_") for n in names)


def test_stop_switch_interrupts_match_bank3_numbers(prof):
    """5.4: bank 3 configures interrupts by the same number ("SGP <type>, 3, <value>"): each trigger
    transition parameter 27..42 has an interrupt vector of that number."""
    for num in range(27, 43):
        assert num in prof.interrupts
        title = prof.global_parameters[(3, num)].title.lower()
        desc = prof.interrupts[num].description.lower()
        side = "left" if "left" in title else "right" if "right" in title else "input"
        assert side in desc
