"""The PD28-1021 / TMCM-1021 profile (data/pd28_1021.toml).

Sources: PD28-1021 TMCL firmware manual V1.46 (partial copy: chapters 1-3.6 only), the parameter
numbers public clients use on this module (docs/sources.md "TMCM-1021 parameter numbers"), and
for their definitions the TMCM-1180 manual V4.45 (TMCM-6212 V1.05 where the 1180 lacks a number).
Choices: docs/assumptions.md.
"""
from __future__ import annotations

import tomllib
from importlib import resources

import pytest

from opentmcl.modules.profile import ModuleProfile, parse_profile


def _load(fname: str) -> ModuleProfile:
    text = resources.files("opentmcl.modules").joinpath("data", fname).read_text(encoding="utf-8")
    return parse_profile(tomllib.loads(text))


@pytest.fixture(scope="module")
def prof() -> ModuleProfile:
    return _load("pd28_1021.toml")


@pytest.fixture(scope="module")
def tmcm1180() -> ModuleProfile:
    return _load("pd86_1180.toml")


# docs/sources.md "TMCM-1021 parameter numbers": axis 0-13, 130, 140, 160-184, 193-197,
# 200, 204, 206-210, 212, 214, 215, 254; bank 0: 65, 66, 68, 69, 70, 71, 75, 76, 77, 79, 81, 82, 83, 84,
# 85, 87, 90, 128, 130, 132, 133, 255; bank 3: 0, 1, 2, 27, 28, 39, 40, 41, 42; I/O: OUT0-OUT1, IN0-IN3.
AXIS_NUMBERS = [*range(0, 14), 130, 140, *range(160, 185), *range(193, 198), 200, 204, *range(206, 211),
                212, 214, 215, 254]
BANK0_NUMBERS = [65, 66, 68, 69, 70, 71, 75, 76, 77, 79, 81, 82, 83, 84, 85, 87, 90, 128, 130, 132, 133, 255]
BANK3_NUMBERS = [0, 1, 2, 27, 28, 39, 40, 41, 42]
# Manual 3.5 Table 5 "Overview of all TMCL Commands" (its numbers), 3.7.51 UF0-UF7, 3.7.52 command 138,
# 3.7.53 TMCL control commands (128-137 as on the TMCM-1180), 3.4.1 command 139.
TABLE5 = {"ROR": 1, "ROL": 2, "MST": 3, "MVP": 4, "SAP": 5, "GAP": 6, "STAP": 7, "RSAP": 8, "SGP": 9,
          "GGP": 10, "STGP": 11, "RSGP": 12, "RFS": 13, "SIO": 14, "GIO": 15, "CALC": 19, "COMP": 20,
          "JC": 21, "JA": 22, "CSUB": 23, "RSUB": 24, "EI": 25, "DI": 26, "WAIT": 27, "STOP": 28,
          "SCO": 30, "GCO": 31, "CCO": 32, "CALCX": 33, "AAP": 34, "AGP": 35, "CLE": 36, "VECT": 37,
          "RETI": 38, "ACO": 39, "CALCVV": 40, "CALCVA": 41, "CALCAV": 42, "CALCVX": 43, "CALCXV": 44,
          "CALCV": 45, "MVPA": 46, "RST": 48, "DJNZ": 49, "ROLA": 50, "RORA": 51, "SIV": 55, "GIV": 56,
          "AIV": 57}


def test_module_identity(prof):
    """Cover page: "The PD28-1021 is a full mechatronic solution, made up of a TMCM-1021 stepper control
    module" ... "Single Axis Stepper motor control"; "Firmware Version V1.46"."""
    assert (prof.name, prof.aliases, prof.axes, prof.engine) == ("PD28-1021", ("TMCM-1021",), 1, "linear")
    assert prof.firmware_version == "1021V146"
    assert prof.firmware_binary == (1021 << 16) | (1 << 8) | 46


def test_opcodes_are_table_5_plus_control_commands(prof):
    """3.5 Table 5 lists the extended command set: "CALCVV 40 ... MVPA 46 ... RST 48 | DJNZ 49 |
    ROLA 50 | RORA 51 | SIV 55 | GIV 56 | AIV 57". 47, 52-54 are not in the table. Its contents list
    "3.7.44 CALL (Conditional Subroutine Call)", which the table lacks: number 80 (public TMCL headers)."""
    expected = set(TABLE5.values()) | set(range(64, 72)) | set(range(128, 140)) | {80}
    assert prof.opcodes == expected
    assert not prof.opcodes & {16, 17, 18, 29, 47, 52, 53, 54}


def test_ascii_interface(prof):
    """3.4.1: "The ASCII command line interface is entered by sending the binary command 139"; 3.4.4:
    "Global parameter 67 is used for this purpose"."""
    assert prof.ascii_mode is True and 139 in prof.opcodes
    p = prof.global_parameter(67)
    assert (p.name, p.default) == ("ascii_mode", 0)  # "else ... binary mode (default)"
    assert p.accepts(1) and p.accepts(0x10) and p.accepts(0x20)


def test_axis_numbers_are_the_public_set(prof):
    """docs/sources.md "TMCM-1021 parameter numbers": axis parameters public clients address on the
    TMCM-1021."""
    assert sorted(prof.axis_parameters) == AXIS_NUMBERS


def test_global_numbers_are_the_public_set_plus_ascii_mode(prof):
    """docs/sources.md "TMCM-1021 parameter numbers": bank 0 and bank 3 numbers, plus 67 which the
    manual's own 3.4.4 documents."""
    assert sorted(n for b, n in prof.global_parameters if b == 0) == sorted([*BANK0_NUMBERS, 67])
    assert sorted(n for b, n in prof.global_parameters if b == 3) == BANK3_NUMBERS


def test_most_important_axis_parameters_table_1(prof):
    """2.3 Table 1: "4 | Maximum positioning speed | 1... 2147483647 [pps] | RW",
    "5 | Maximum acceleration | 1... 2147483647 [pps2] | RW", "6 | Maximum current | 0... 255 | RW",
    "7 | Standby current | 0... 255 | RW"."""
    p4, p5, p6, p7 = (prof.axis_parameter(n) for n in (4, 5, 6, 7))
    assert (p4.name, p4.min, p4.max, p4.unit) == ("max_positioning_speed", 1, 2147483647, "pps")
    assert (p5.name, p5.min, p5.max, p5.unit) == ("max_acceleration", 1, 2147483647, "pps^2")
    assert (p6.name, p6.min, p6.max) == ("max_current", 0, 255)
    assert (p7.name, p7.min, p7.max) == ("standby_current", 0, 255)
    for p in (p4, p5, p6, p7):
        assert p.readable and p.writable
    assert not p4.accepts(0)


def test_first_steps_examples_are_accepted_speeds(prof):
    """2.2: "Try entering 51200 (pps) as the value" (ROL); 3.4.2: "AROL 2, 500"."""
    p4 = prof.axis_parameter(4)
    assert p4.accepts(51200) and p4.accepts(500)
    assert prof.axis_parameter(2).accepts(51200) and prof.axis_parameter(2).accepts(-51200)


def test_speeds_are_pps_not_tmc429_units(prof):
    """docs/architecture.md "Capabilities": the PD28-1021 has a linear ramp in pps; no TMC429 divisors or internal units."""
    units = {p.unit for p in prof.axis_parameters.values()}
    assert "int_velocity" not in units and "int_acceleration" not in units
    for n in (2, 3, 130, 181, 182, 194, 195):
        assert prof.axis_parameter(n).unit == "pps", n
    assert not {135, 138, 153, 154} & set(prof.axis_parameters)


def test_definitions_follow_the_tmcm1180(prof, tmcm1180):
    """Numbers both modules have carry the TMCM-1180 manual's name, and, except the pps speeds, its
    range and access letters (chapter 5 / 6.1 of the 1180 manual)."""
    pps = {2, 3, 4, 5, 130, 181, 182, 194, 195}
    changed = {193, 215}  # 8 reference search modes (1021 manual 7.1.1-7.1.8); 1024-count encoder
    for n, p in prof.axis_parameters.items():
        q = tmcm1180.axis_parameters.get(n)
        if q is None:
            continue
        assert p.name == q.name, n
        if n not in pps | changed:
            assert (p.min, p.max, p.access, p.values) == (q.min, q.max, q.access, q.values), n
    for key, p in prof.global_parameters.items():
        q = tmcm1180.global_parameters.get(key)
        if q is not None:
            assert (p.name, p.min, p.max, p.access) == (q.name, q.min, q.max, q.access), key


def test_numbers_the_tmcm1180_lacks(prof):
    """TMCM-6212 manual 4.1: "184 | Random TOff mode | 0/1 | RW", "197 | Last reference position |
    -2147483648 ... 2147483647 [μsteps] | R", "207 | Extended error flags | 0...3 | R"; 5.1:
    "255 | Suppress reply | 0/1 | RW"."""
    assert (prof.axis_parameter(184).name, prof.axis_parameter(184).max) == ("random_toff_mode", 1)
    p197 = prof.axis_parameter(197)
    assert (p197.name, p197.min, p197.max, p197.access) == ("last_reference_position", -2**31, 2**31 - 1, "R")
    p207 = prof.axis_parameter(207)
    assert (p207.name, p207.max, p207.access) == ("extended_error_flags", 3, "R")
    p255 = prof.global_parameter(255)
    assert (p255.name, p255.access, p255.storable) == ("suppress_reply", "RW", False)


def test_reference_search_has_eight_modes(prof):
    """Contents 7.1.1 "Mode 1" ... 7.1.8 "Mode 8"; adding 128 reverses the home switch polarity
    (TMCM-1180 manual 5, row 193)."""
    p = prof.axis_parameter(193)
    assert all(p.accepts(m) and p.accepts(m + 128) for m in range(1, 9))
    assert not p.accepts(0) and not p.accepts(9)


def test_io_ports(prof):
    """Chapter 1: "Up to four general-purpose digital inputs ... Two general purpose outputs"; besides
    them the supply voltage (bank 1 port 8, OpenTMCL extension) and the temperature the TMCM-1021
    manual V1.42 lists ("Temperature GIO 9, 1 [°C]"; docs/assumptions.md)."""
    manual = sorted(k for k, p in prof.io.items() if not p.measures)
    assert manual == [(0, 0), (0, 1), (0, 2), (0, 3), (2, 0), (2, 1)]
    assert {k: (p.measures, p.per_unit) for k, p in prof.io.items() if p.measures} == {
        (1, 8): ("supply_voltage", 10), (1, 9): ("temperature", 1)}
    assert [prof.io[(0, i)].name for i in range(4)] == ["IN0", "IN1", "IN2", "IN3"]
    assert [prof.io[(2, i)].kind for i in range(2)] == ["output", "output"]


def test_interrupts_cover_bank_3(prof):
    """Bank 3 configures the interrupts of the same number: inputs IN0-IN3 are vectors 39-42
    (numbering as the TMCM-6212 manual Table 12 "Input change 0..3")."""
    assert sorted(prof.interrupts) == [0, 1, 2, 3, 15, 21, 27, 28, 39, 40, 41, 42, 255]
    assert [prof.interrupts[n].name for n in (39, 42)] == ["TI_INPUTCHANGE0", "TI_INPUTCHANGE3"]
