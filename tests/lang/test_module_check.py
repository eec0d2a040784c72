"""Instructions the target module cannot execute are warnings (errors with strict), read from
the module's profile (docs/tmcl-assembler.md "Checking against a module"; issue 15 item 6).

The firmware answers such instructions with status 2 "Invalid command", 3 "Wrong type" or
4 "Invalid value" (TMCM-6212 manual 3.2); the assembler says so before the program runs.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from opentmcl.lang import AsmError, assemble, assemble_file
from opentmcl.modules.profile import load_profile


def warned(source: str, module: str = "TMCM-6212") -> list[tuple[int, int, str]]:
    prog = assemble(source, filename="m.tmc", module=module)
    return [(d.line, d.column, d.message) for d in prog.warnings]


def _error(src: str, **kw) -> AsmError:
    with pytest.raises(AsmError) as err:
        assemble(src, **kw)
    return err.value


def _warnings(src: str, module) -> list[str]:
    return [d.message for d in assemble(src, module=module).warnings]


def test_motor_beyond_the_axes():
    """TMCM-6212 manual 3.6.22 SCO: "<motor number> 0...5" - six axes; ROR 5 is the last motor,
    ROR 6 the first that does not exist, ROR 7 the issue's example. The PD86-1180 has one
    motor (manual 4.6.4: "only one motor is involved")."""
    assert warned("ROR 5, 1000") == []
    assert warned("ROR 6, 1000\nROR 7, 1000") == [
        (1, 5, "ROR: motor 6 does not exist on TMCM-6212 (motors 0..5)"),
        (2, 5, "ROR: motor 7 does not exist on TMCM-6212 (motors 0..5)")]
    assert warned("ROL 0, 10", "PD86-1180") == []
    assert warned("MVP ABS, 1, 10", "PD86-1180") == [
        (1, 10, "MVP: motor 1 does not exist on PD86-1180 (motor 0 only)")]


def test_wait_checks_the_motor_only_where_it_is_one():
    """TMCM-6212 3.6.20 WAIT: TICKS ignores the motor field, POS waits for a motor."""
    assert warned("WAIT TICKS, 9, 10") == []
    assert warned("WAIT POS, 9, 0") == [(1, 11, "WAIT: motor 9 does not exist on TMCM-6212 (motors 0..5)")]


def test_axis_parameter_numbers_come_from_the_profile():
    """TMCM-6212 Table 14 lists the axis parameters; 250 is not one of them (the issue's
    `SAP 250, 0, 1`), 255 is. Actual speed (3) is read-only ("R")."""
    assert warned("SAP 255, 0, 1") == []
    assert warned("SAP 250, 0, 1") == [(1, 5, "SAP: TMCM-6212 has no axis parameter 250")]
    assert warned("GAP 3, 0") == []
    assert warned("SAP 3, 0, 100") == [(1, 5, "SAP: axis parameter 3 (actual_speed) of TMCM-6212 "
                                              "cannot be written")]


def test_global_parameter_banks_and_user_variables():
    """TMCM-6212 3.6.7: "bank 0 is used for global parameters, and bank 2 is used for user
    variables. Bank 3 is used for interrupt configuration." 256 user variables (0..255); STGP
    stores the first 56 (0..55)."""
    assert warned("SGP 255, 2, 1\nSTGP 55, 2") == []
    assert warned("STGP 56, 2") == [(1, 6, "STGP: TMCM-6212 has 56 storable user variables (0..55), not 56")]
    assert warned("SGP 0, 1, 1") == [(1, 8, "SGP: TMCM-6212 has no global parameter bank 1 (banks 0, 2, 3)")]
    assert warned("GGP 1, 0") == [(1, 5, "GGP: TMCM-6212 has no global parameter 1 in bank 0")]


def test_user_variables_of_a_profile_with_fewer_than_256():
    """docs/profiles.md: `user_variables` is the size of bank 2 (TMCM-6212 manual 5.3: "Up to 256
    user variables are available"); a profile of one's own may have fewer. With 100, GGP/SGP 99
    is the last variable, 100 the first that does not exist (worded as the storable ones are,
    docs/tmcl-assembler.md: "STGP: TMCM-6212 has 56 storable user variables (0..55), not 56")."""
    mine = dataclasses.replace(load_profile("TMCM-6212"), user_variables=100)
    assert _warnings("GGP 99, 2\nSGP 99, 2, 1", mine) == []
    assert _warnings("GGP 100, 2\nSGP 100, 2, 1", mine) == [
        "GGP: TMCM-6212 has 100 user variables (0..99), not 100",
        "SGP: TMCM-6212 has 100 user variables (0..99), not 100"]


def test_global_parameter_access_in_the_warning():
    """TMCM-6212 5.1 (Bank 0): GP128 "TMCL application status ... R" cannot be written (SGP), GP132 "TMCL
    tick timer ... RW" can, but has no E, so STGP cannot store it (Table 15, the access letters)."""
    warnings = assemble("SGP 128, 0, 1\nSGP 132, 0, 1\nSTGP 132, 0", module="TMCM-6212").warnings
    assert [(w.line, w.message) for w in warnings] == [
        (1, "SGP: global parameter 128 (tmcl_application_status) of TMCM-6212 cannot be written"),
        (3, "STGP: global parameter 132 (tick_timer) of TMCM-6212 cannot be stored to or restored from EEPROM"),
    ]


def test_ports_and_outputs():
    """TMCM-6212 3.6.12 SIO: outputs are in bank 2; bank 0 holds the inputs."""
    assert warned("SIO 3, 2, 1\nSIO 255, 2, 15\nGIO 0, 0") == []
    assert warned("SIO 0, 0, 1") == [(1, 5, "SIO: port 0 in bank 0 (IN0) of TMCM-6212 is an input")]
    assert warned("GIO 4, 2") == [(1, 5, "GIO: TMCM-6212 has no port 4 in I/O bank 2")]
    assert warned("GIO 0, 5") == [(1, 8, "GIO: TMCM-6212 has no I/O bank 5")]


def test_pd86_1180_pullups_port_may_be_set():
    """PD86-1180 manual 4.6.14 SIO: "SIO is also used to switch the pull-up resistors for all
    digital inputs ON or OFF. Bank 0 is used for this purpose" (the profile's `pullups` port,
    bank 0 port 0, docs/assumptions.md "the `pullups` port of `[module]` allowed"); the next
    port of bank 0 is an input, which SIO cannot set."""
    prof = load_profile("PD86-1180")
    assert (prof.extra["pullups"]["bank"], prof.extra["pullups"]["port"]) == (0, 0)
    assert _warnings("SIO 0, 0, 7", "PD86-1180") == []
    assert _warnings("SIO 1, 0, 1", "PD86-1180") == ["SIO: port 1 in bank 0 (IN_1) of PD86-1180 is an input"]


def test_coordinates_and_interrupts():
    """TMCM-6212 3.6.4 MVP COORD: "<coordinate number (0..20)>"; 3.6.30 EI: "Interrupt number 255
    globally enables interrupt processing"."""
    assert warned("MVP COORD, 0, 20\nSCO 20, 0, 5\nEI 255\nEI 0") == []
    assert warned("MVP COORD, 0, 21") == [(1, 15, "MVP: TMCM-6212 has coordinates 0..20, not 21")]
    assert warned("GCO 21, 0") == [(1, 5, "GCO: TMCM-6212 has coordinates 0..20, not 21")]
    assert warned("EI 99") == [(1, 4, "EI: TMCM-6212 has no interrupt 99")]
    assert warned("L: VECT 255, L") == [(1, 9, "VECT: 255 is not an interrupt vector (it switches all interrupts)")]


def test_opcodes_the_module_lacks():
    """The PD28-1021 extended command set (manual 3.5) is not in the TMCM-6212's (3.4.1)."""
    assert warned("CALCVV ADD, 1, 2", "PD28-1021") == []
    assert warned("  CALCVV ADD, 1, 2") == [(1, 3, "CALCVV (command 40) is not available on TMCM-6212")]
    assert warned("RAW 40, 0, 1, 2") == [(1, 5, "CALCVV (command 40) is not available on TMCM-6212")]


def test_strict_turns_every_warning_into_an_error():
    with pytest.raises(AsmError) as info:
        assemble("ROR 7, 1000\nSAP 250, 0, 1\nROL 0, 1\n", filename="s.tmc", module="TMCM-6212", strict=True)
    assert [(d.line, d.severity) for d in info.value.errors] == [(1, "error"), (2, "error")]
    assert info.value.warnings == []


def test_a_profile_file_is_the_target(tmp_path):
    """--module FILE: the checks read the profile, so a two-axis variant of the TMCM-6212 makes
    motor 2 the first missing one - no table in the assembler knows it (docs/profiles.md)."""
    path = tmp_path / "two.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "TMCM-2212"\naxes = 2\n')
    assert warned("ROR 1, 10", str(path)) == []
    assert warned("ROR 2, 10", str(path)) == [(1, 5, "ROR: motor 2 does not exist on TMCM-2212 (motors 0..1)")]


def test_a_bad_profile_file_is_one_error(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[module\n")
    with pytest.raises(AsmError) as info:
        assemble("STOP", module=str(path))
    assert str(info.value).startswith(f"{path}: cannot use the module profile") and "\n" not in str(info.value)


def test_a_profile_file_that_cannot_be_used_has_no_position(tmp_path):
    """docs/assumptions.md (Assembler, Diagnostics): "A diagnostic without a position (unreadable
    file, bad `--module`) prints `file: message`" - line and column 0."""
    bad = tmp_path / "bad.toml"
    bad.write_text("not toml [[[\n")
    e = _error("MST 0", module=str(bad))
    assert (e.file, e.line, e.column) == (str(bad), 0, 0)
    assert e.message.startswith(f"cannot use the module profile: {bad}: not TOML")
    assert str(e).startswith(f"{bad}: cannot use the module profile")


def test_the_manuals_own_slips_are_found():
    """TMCM-6212 manual 7.4 prints "AAP MyVariable, 2 //Store contents of accumulator register to
    variable" with MyVariable = 42: a user variable is stored with AGP (3.6.28), and axis
    parameter 42 does not exist (Table 14), so the example as printed gets a warning. The
    PD86-1180's 4.4.2.6.5 example switches OUT3 ("SIO 3, 2, 1"), a port only the TMCM-6212 has
    (PD86-1180 4.6.14: OUT_0 and OUT_1)."""
    examples = Path(__file__).parent / "examples"
    prog = assemble_file(examples / "tmcm6212_7_4_variables.tmc", module="TMCM-6212")
    assert [(d.line, d.column, d.message) for d in prog.warnings] == [
        (9, 5, "AAP: TMCM-6212 has no axis parameter 42")]
    timer = Path(__file__).parents[2] / "examples" / "pd86_1180_4.4.2.6.5_timer_interrupt.tmc"
    prog = assemble_file(timer, module="PD86-1180")
    assert [(d.line, d.message) for d in prog.warnings] == [
        (11, "SIO: PD86-1180 has no port 3 in I/O bank 2"), (13, "SIO: PD86-1180 has no port 3 in I/O bank 2")]


def test_a_loaded_profile_is_the_target(tmp_path):
    """assemble(module=PROFILE): a profile already loaded (e.g. the module a client talks to) is
    checked as it is, even when its name is no built-in module's (docs/profiles.md)."""
    from opentmcl.modules import load_profile

    path = tmp_path / "two.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "TMCM-2212"\naxes = 2\n')
    profile = load_profile(str(path))
    prog = assemble("ROR 1, 10\nROR 2, 10\n", filename="m.tmc", module=profile)
    assert prog.module == "TMCM-2212"
    assert [(d.line, d.column, d.message) for d in prog.warnings] == [
        (2, 5, "ROR: motor 2 does not exist on TMCM-2212 (motors 0..1)")]


def test_motor_255_copies_coordinates_only_for_sco_and_gco():
    """TMCM-6212 3.6.22-3.6.23: "SCO 0, 255, 0 copies all coordinates ... from RAM to the EEPROM",
    GCO 0, 255 back; CCO (3.6.24) and ACO (3.6.25) have no such form: their motor 255 is no motor."""
    assert warned("SCO 0, 255, 0\nGCO 5, 255") == []
    assert warned("CCO 0, 255\nACO 1, 255") == [
        (1, 8, "CCO: motor 255 does not exist on TMCM-6212 (motors 0..5)"),
        (2, 8, "ACO: motor 255 does not exist on TMCM-6212 (motors 0..5)")]


@pytest.mark.parametrize("mnemonic", ["SCO", "GCO"])
def test_sco_gco_check_their_motor_except_the_eeprom_copy_255(mnemonic):
    """TMCM-6212 manual 3.6.22 SCO: "<motor number> 0...5"; "SCO <coordinate number>, 255, 0
    copies the coordinate ... to the EEPROM" (GCO 3.6.23 likewise from the EEPROM). Motor 5 is
    the last axis, 6 the first that does not exist, 255 the copy."""
    args = ", 0" if mnemonic == "SCO" else ""
    assert _warnings(f"{mnemonic} 1, 5{args}\n{mnemonic} 1, 255{args}", "TMCM-6212") == []
    assert _warnings(f"{mnemonic} 1, 6{args}", "TMCM-6212") == [
        f"{mnemonic}: motor 6 does not exist on TMCM-6212 (motors 0..5)"]
    assert _warnings(f"{mnemonic} 1, 254{args}", "TMCM-6212") == [
        f"{mnemonic}: motor 254 does not exist on TMCM-6212 (motors 0..5)"]


@pytest.mark.parametrize("src", ["ROR 255, 100", "MST 255", "SAP 4, 255, 1"])
def test_motor_255_of_other_axis_commands_does_not_exist(src):
    """docs/assumptions.md "Module checks": "SCO/GCO motor 255 (copy to/from EEPROM) is allowed" -
    only there: ROR/MST/SAP take "<motor number> 0...5" (TMCM-6212 3.6.2, 3.6.4, 3.6.6)."""
    mnemonic = src.split()[0]
    assert _warnings(src, "TMCM-6212") == [f"{mnemonic}: motor 255 does not exist on TMCM-6212 (motors 0..5)"]


def test_the_pd28_and_pd86_commands_on_a_motor():
    """PD28-1021 3.5 Table 5: MVPA, ROLA and RORA take a <motor number>; PD86-1180 4.4.1: STAP and
    RSAP take <parameter>, <motor number>. The PD28-1021 and PD86-1180 have one motor (0)."""
    assert warned("MVPA ABS, 0\nROLA 0\nRORA 0", "PD28-1021") == []
    assert [m for _, _, m in warned("MVPA ABS, 1\nROLA 1\nRORA 1", "PD28-1021")] == [
        f"{name}: motor 1 does not exist on PD28-1021 (motor 0 only)" for name in ("MVPA", "ROLA", "RORA")]
    assert [m for _, _, m in warned("STAP 4, 1\nRSAP 4, 1", "PD86-1180")] == [
        f"{name}: motor 1 does not exist on PD86-1180 (motor 0 only)" for name in ("STAP", "RSAP")]


def test_the_check_reads_what_fields_name_from_the_command_set():
    """Issue 33: "No bare opcode sets remain outside [the command table]". The check compares no
    command number with a literal: what each field names is `Command.meanings` (protocol/opcodes.py)."""
    import ast

    from opentmcl.lang import capabilities_check

    tree = ast.parse(Path(capabilities_check.__file__).read_text(encoding="utf-8"))
    numbers = [node.lineno for node in ast.walk(tree)
               if isinstance(node, ast.Compare)
               and any(isinstance(n, ast.Attribute) and n.attr == "command" for n in (node.left, *node.comparators))
               and any(isinstance(c, ast.Constant) and isinstance(c.value, int)
                       or isinstance(c, (ast.Set, ast.Tuple, ast.List)) for c in node.comparators)]
    sets = [node.lineno for node in ast.walk(tree)
            if isinstance(node, (ast.Set, ast.Tuple)) and len(node.elts) > 1
            and all(isinstance(e, ast.Constant) and isinstance(e.value, int) for e in node.elts)]
    assert numbers == [] and sets == []
