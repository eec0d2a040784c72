"""The PD86-1180 / TMCM-1180 profile (data/pd86_1180.toml) against the TMCM-1180 and PD86-1180 TMCL
firmware manual V4.45 (Rev. 1.10).

Manual rows quoted in docstrings as "Number | Name | Range | Access" (the PDF's table columns).
"""
from __future__ import annotations

import tomllib
from importlib import resources

import pytest

from opentmcl.modules.profile import ModuleProfile, Param, parse_profile


@pytest.fixture(scope="module")
def prof() -> ModuleProfile:
    text = resources.files("opentmcl.modules").joinpath("data", "pd86_1180.toml").read_text(encoding="utf-8")
    return parse_profile(tomllib.loads(text))


def _row(p: Param, *, name, lo, hi, access, unit=None, default=None, values=None) -> None:
    assert p.name == name
    assert (p.min, p.max) == (lo, hi)
    assert p.access == access
    if unit is not None:
        assert p.unit == unit
    if default is not None:
        assert p.default == default
    if values is not None:
        assert p.values == tuple(values)


# --- the manual's parameter numbers --------------------------------------------------------------

# Chapter 5 "Axis Parameters": every number of the table, plus 197 that the revision history (10.1,
# firmware 4.41) adds: "the last position before setting the counter to zero can be read out with
# axis parameter 197".
MANUAL_AXIS_NUMBERS = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 130, 135, 138, 140, 141, 149, 153, 154,
    160, 161, 162, 163, 164, 165, 166, 167, 168, 169, 170, 171, 172, 173, 174, 175, 176, 177, 178, 179,
    180, 181, 182, 183, 193, 194, 195, 196, 197, 200, 204, 206, 208, 209, 210, 212, 214, 215, 254,
]
# 6.1 "Bank 0" table, plus 84 (coordinate storage) that 4.6.24-4.6.27 (SCO/GCO/CCO/ACO) refer to.
MANUAL_BANK0_NUMBERS = [64, 65, 66, 67, 68, 69, 70, 71, 73, 75, 76, 77, 79, 80, 81, 82, 83, 84, 85, 87,
                        128, 129, 130, 132, 133]
# 6.4 "Interrupt parameters (bank 3)".
MANUAL_BANK3_NUMBERS = [0, 1, 2, 27, 28, 39, 40]
# 4.4.2.6.3 "Interrupt Vectors", plus 255 (EI 255 / DI 255, 4.4.2.6.5).
MANUAL_INTERRUPTS = {0: "Timer 0", 1: "Timer 1", 2: "Timer 2", 3: "(Target) position reached",
                     15: "Stall (stallGuard2)", 21: "Deviation", 27: "Stop left", 28: "Stop right",
                     39: "IN_0 change", 40: "IN_1 change"}


def test_module_identity(prof):
    """Manual 1 "Features": "Program memory (non volatile) for up to 2048 TMCL commands"; one motor;
    "based on the TMC428/429 stepper motor controller" (chapter 2)."""
    assert (prof.name, prof.aliases, prof.axes, prof.engine) == ("PD86-1180", ("TMCM-1180",), 1, "tmc429")
    assert prof.program_memory == 2048


def test_firmware_version_reply(prof):
    """4.6.39 command 136: type 0 "Version string (8 characters, e.g. 1180V1.30)"; type 1: value byte 1
    version low byte, 2 version high byte, 3/4 type number. Firmware V4.45."""
    assert prof.firmware_version == "1180V445"
    assert prof.firmware_binary.to_bytes(4, "big") == bytes([1180 >> 8, 1180 & 0xFF, 4, 45])


def test_axis_parameters_are_exactly_chapter_5(prof):
    """Chapter 5: "The following sections describe all axis parameters that can be used with the SAP,
    GAP, AAP, STAP and RSAP commands." The profile holds each number of the table (and 197 of the
    revision history) and no other."""
    assert len(MANUAL_AXIS_NUMBERS) == 61
    assert sorted(prof.axis_parameters) == MANUAL_AXIS_NUMBERS


def test_global_parameters_are_exactly_chapter_6(prof):
    """6.1 bank 0 and 6.4 bank 3 (bank 1 "is normally not available", bank 2 = user variables)."""
    bank0 = sorted(n for b, n in prof.global_parameters if b == 0)
    bank3 = sorted(n for b, n in prof.global_parameters if b == 3)
    assert bank0 == MANUAL_BANK0_NUMBERS
    assert bank3 == MANUAL_BANK3_NUMBERS
    assert {b for b, _ in prof.global_parameters} == {0, 3}


def test_interrupt_vectors(prof):
    """4.4.2.6.3: "The following table shows all interrupt vectors that can be used." The example in
    4.4.2.6.5 uses the Interrupts.inc names TI_TIMER0 and TI_GLOBAL."""
    assert {n: i.description for n, i in prof.interrupts.items() if n != 255} == MANUAL_INTERRUPTS
    assert prof.interrupts[0].name == "TI_TIMER0"
    assert prof.interrupts[255].name == "TI_GLOBAL"


def test_opcodes_are_the_command_overview(prof):
    """4.4.1 "TMCL Commands" (1-15, 19-28, 30-35, 37-39), CLE 36 (4.6.31), UF0-UF7 64-71 (4.6.36),
    138 (4.6.37), control commands 128-137 (4.6.39), 139 enter ASCII mode (4.4.2.7)."""
    expected = {*range(1, 16), *range(19, 29), *range(30, 40), *range(64, 72), *range(128, 140)}
    assert prof.opcodes == expected
    assert not prof.opcodes & set(range(40, 58))  # no extended (CALCVV ...) command set


def test_ascii_mode_and_memory_counts(prof):
    """4.4.2.7 "139 Enter ASCII mode"; 4.6.24 SCO "Up to 20 position values (coordinates) ... 0… 20";
    6.3 "the first 56 variables can be stored permanently ... Up to 256 user variables"."""
    assert prof.ascii_mode is True
    assert prof.coordinates == 20
    assert (prof.user_variables, prof.storable_user_variables) == (256, 56)


# --- spot checks of single rows --------------------------------------------------------------------

def test_ap0_target_position(prof):
    """5: "0 | Target (next) position | ± 2^31-1 [µsteps] | RW"."""
    _row(prof.axis_parameter(0), name="target_position", lo=-(2**31 - 1), hi=2**31 - 1, access="RW",
         unit="µsteps")


def test_ap2_target_speed_is_tmc429_internal(prof):
    """5: "2 | Target (next) speed | ±2047 [16MHz/65536 · 2^pulse_divisor µsteps/sec] | RW"."""
    _row(prof.axis_parameter(2), name="target_speed", lo=-2047, hi=2047, access="RW", unit="int_velocity")


def test_ap4_max_positioning_speed(prof):
    """5: "4 | Maximum positioning speed | 0… 2047 | RWE"."""
    _row(prof.axis_parameter(4), name="max_positioning_speed", lo=0, hi=2047, access="RWE",
         unit="int_velocity")


def test_ap5_max_acceleration(prof):
    """5: "5 | Maximum acceleration | 0… 2047* | RWE" (* unit of acceleration: 16MHz² /
    (536870912 · 2^(pulse_divisor+ramp_divisor)) microsteps/sec²)."""
    _row(prof.axis_parameter(5), name="max_acceleration", lo=0, hi=2047, access="RWE",
         unit="int_acceleration")


def test_ap6_max_current(prof):
    """5: "6 | Absolute max. current (CS / Current Scale) | 0… 255 | RWE"."""
    p = prof.axis_parameter(6)
    _row(p, name="max_current", lo=0, hi=255, access="RWE")
    assert p.storable and not p.auto_stored


def test_ap8_to_11_are_read_only_flags(prof):
    """5: "8 | Target pos. reached | 0/1 | R", "9 | Ref. switch status | 0/1 | R",
    "10 | Right limit switch status | 0/1 | R", "11 | Left limit switch status | 0/1 | R"."""
    for n in (8, 9, 10, 11):
        p = prof.axis_parameter(n)
        assert (p.min, p.max, p.access) == (0, 1, "R")
        assert not p.writable


def test_ap130_minimum_speed_default_1(prof):
    """5: "130 | Minimum speed | Should always be set 1 ... | 0… 2047 Default = 1 | RWE"."""
    _row(prof.axis_parameter(130), name="minimum_speed", lo=0, hi=2047, access="RWE", default=1)


def test_ap138_ramp_mode(prof):
    """5: "138 | Ramp mode | 0: position mode ... 2: velocity mode ... soft mode (value 1) | 0/1/2 | RWE"."""
    _row(prof.axis_parameter(138), name="ramp_mode", lo=0, hi=2, access="RWE", values=(0, 1, 2))


def test_ap140_microstep_resolution(prof):
    """5: "140 | Microstep resolution | 0 full step ... 8 256 microsteps | 0… 8 | RWE"."""
    _row(prof.axis_parameter(140), name="microstep_resolution", lo=0, hi=8, access="RWE")


def test_ap153_154_divisors(prof):
    """5: "153 | Ramp divisor | 0… 13 | RWE", "154 | Pulse divisor | 0… 13 | RWE"."""
    _row(prof.axis_parameter(153), name="ramp_divisor", lo=0, hi=13, access="RWE")
    _row(prof.axis_parameter(154), name="pulse_divisor", lo=0, hi=13, access="RWE")


def test_ap167_chopper_off_time_skips_1(prof):
    """5: "167 | Chopper off time | ... | 0 / 2… 15 | RW"."""
    p = prof.axis_parameter(167)
    _row(p, name="chopper_off_time", lo=0, hi=15, access="RW")
    assert p.accepts(0) and p.accepts(2) and p.accepts(15)
    assert not p.accepts(1) and not p.accepts(16)


def test_ap174_stallguard2_threshold_is_signed(prof):
    """5: "174 | stallGuard2 threshold | ... | -64… 63 | RW"."""
    _row(prof.axis_parameter(174), name="stallguard2_threshold", lo=-64, hi=63, access="RW")


def test_ap193_reference_search_mode(prof):
    """5: "193 | Reference search mode | 1 ... 2 ... 3 ... Adding 128 to these values reverses the polarity
    of the home switch input. | 1… 3 | RWE"."""
    p = prof.axis_parameter(193)
    assert (p.name, p.access) == ("reference_search_mode", "RWE")
    assert p.values == (1, 2, 3, 129, 130, 131)
    assert not p.accepts(4) and not p.accepts(0)


def test_ap194_195_reference_speeds(prof):
    """5: "194 | Reference search speed | 0… 2047 | RWE", "195 | Reference switch speed | 0… 2047 | RWE";
    7.1: the calibrating speed "is a quarter of the maximum positioning speed by default"."""
    _row(prof.axis_parameter(194), name="reference_search_speed", lo=0, hi=2047, access="RWE")
    _row(prof.axis_parameter(195), name="reference_switch_speed", lo=0, hi=2047, access="RWE")
    assert prof.axis_parameter(195).default * 4 == prof.axis_parameter(4).default


def test_ap196_end_switch_distance(prof):
    """5: "196 | Reference switch distance | 0… 2.147.483.647 | R"."""
    _row(prof.axis_parameter(196), name="end_switch_distance", lo=0, hi=2147483647, access="R")


def test_ap204_freewheeling(prof):
    """5: "204 | Freewheeling | 0… 65535 0 = never [msec] | RWE"."""
    _row(prof.axis_parameter(204), name="freewheeling", lo=0, hi=65535, access="RWE", unit="ms")


def test_ap210_encoder_prescaler_default(prof):
    """7.2: "6400 | default 12.5 | SAP 210, 0, 6400 | 4 (16 microsteps)"; "The values 1, 2, 4, and 16
    must not be used for <p>"."""
    p = prof.axis_parameter(210)
    assert (p.name, p.access, p.default) == ("encoder_resolution", "RWE", 6400)
    assert prof.axis_parameter(140).default == 4


def test_ap214_power_down_delay(prof):
    """5: "214 | Power down delay | ... The standard value is 200 (value equates 2000msec). | 1… 65535
    [10msec] | RWE"."""
    _row(prof.axis_parameter(214), name="power_down_delay", lo=1, hi=65535, access="RWE", unit="10ms",
         default=200)


def test_ap254_step_dir_mode(prof):
    """5: "254 | Step/Dir mode | 1 ... 5 | 1… 5 | RWE"."""
    _row(prof.axis_parameter(254), name="step_dir_mode", lo=1, hi=5, access="RWE")


def test_gp64_eeprom_magic(prof):
    """6.1: "64 | EEPROM magic | Setting this parameter to a different value as $E4 will cause
    re-initialization ... | 0… 255 | RWE"."""
    _row(prof.global_parameter(64), name="eeprom_magic", lo=0, hi=255, access="RWE", default=0xE4)


def test_gp65_baud_rate(prof):
    """6.1: "65 | RS232/RS485 baud rate | 0 9600 baud Default ... 11 1000000 baud | 0… 11 | RWE"."""
    _row(prof.global_parameter(65), name="rs485_baud_rate", lo=0, hi=11, access="RWE", default=0)


def test_gp67_ascii_mode_bits(prof):
    """6.1: "67 | ASCII mode | Bit 0: 0 – start up in binary (normal) mode 1 – start up in ASCII mode;
    Bits 4 and 5: 00 – Echo back each character 01 – Echo back complete command 10 – Do not send echo"."""
    p = prof.global_parameter(67)
    assert (p.name, p.access, p.default) == ("ascii_mode", "RWE", 0)
    assert p.values == (0, 1, 16, 17, 32, 33)


def test_gp69_to_71_can(prof):
    """6.1: "69 | CAN bit rate | ... 8 1000kBit/s Default | 2… 8 | RWE",
    "70 | CAN reply ID | (default: 2) | 0… 7ff | RWE", "71 | CAN ID | (default: 1) | 0… 7ff | RWE"."""
    _row(prof.global_parameter(69), name="can_bit_rate", lo=2, hi=8, access="RWE", default=8)
    _row(prof.global_parameter(70), name="can_reply_id", lo=0, hi=0x7FF, access="RWE", default=2)
    _row(prof.global_parameter(71), name="can_id", lo=0, hi=0x7FF, access="RWE", default=1)


def test_gp73_eeprom_lock(prof):
    """6.1: "73 | Configuration EEPROM lock flag | Write: 1234 to lock the EEPROM, 4321 to unlock it.
    Read: 1=EEPROM locked, 0=EEPROM unlocked. | 0/1 | RWE"."""
    p = prof.global_parameter(73)
    assert p.name == "eeprom_lock"
    assert p.accepts(1234) and p.accepts(4321) and not p.accepts(1000)


def test_gp81_code_protection(prof):
    """6.1: "81 | TMCL code protection | 0 – no protection ... 3 | 0,1,2,3 | RWE"."""
    _row(prof.global_parameter(81), name="tmcl_code_protection", lo=0, hi=3, access="RWE")


def test_gp128_to_130_are_read_only(prof):
    """6.1: "128 | TMCL application status | 0… 3 | R", "129 | Download mode | 0/1 | R",
    "130 | TMCL program counter | R"."""
    for n in (128, 129, 130):
        assert prof.global_parameter(n).access == "R"
    assert prof.global_parameter(130).max == prof.program_memory - 1


def test_gp133_random_number(prof):
    """6.1: "133 | Random number | Choose a random number. | 0… 2147483647 | RW"."""
    _row(prof.global_parameter(133), name="random_number", lo=0, hi=2147483647, access="RW")


def test_bank3_rows(prof):
    """6.4: "0 | Timer 0 period (ms) | 0… 4.294.967.295 [ms] | RW",
    "27 | Stop left 0 trigger transition | 0=off, 1=low-high, 2=high-low, 3=both | 0… 3 | RW"."""
    _row(prof.global_parameter(0, bank=3), name="timer_0_period", lo=0, hi=4294967295, access="RW", unit="ms")
    _row(prof.global_parameter(27, bank=3), name="stop_left_0_trigger_transition", lo=0, hi=3, access="RW")
    _row(prof.global_parameter(40, bank=3), name="input_1_trigger_transition", lo=0, hi=3, access="RW")


def test_io_banks(prof):
    """4.6.15: bank 0 digital inputs (and "GIO 12, 0" reads OC_EN), bank 1 "IN_0 GIO 0, 1 0… 1023",
    bank 2 "OUT_0 GIO 0, 2, <n> 1/0"; 4.6.14: "SIO 0, 0,<bitmask> 0… 7" switches the pull-ups."""
    io = prof.io
    assert sorted(k for k, p in io.items() if not p.measures) == [(0, 0), (0, 1), (0, 12), (1, 0), (1, 1),
                                                                  (2, 0), (2, 1)]
    assert [(k, p.measures) for k, p in io.items() if p.measures] == [((1, 8), "supply_voltage")]  # extension
    assert (io[(1, 0)].kind, io[(1, 0)].max) == ("analog", 1023)
    assert (io[(2, 1)].name, io[(2, 1)].kind, io[(2, 1)].access) == ("OUT_1", "output", "RW")
    assert io[(0, 12)].name == "OC_EN"
    assert prof.extra["pullups"] == {"bank": 0, "port": 0, "max": 7}
