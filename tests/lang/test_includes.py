"""Bundled include files (in the spirit of TMCLParam.tmc and Interrupts.inc, TMCM-6212 3.5.6.4, 7.3)."""
from __future__ import annotations

import pytest

from opentmcl.lang import gen_includes
from opentmcl.lang.assembler import INCLUDE_DIR, assemble, include_key
from opentmcl.modules.profile import load_profile, module_names


def test_include_files_are_up_to_date():
    """The files on disk are what the generator makes from the current profiles
    (run `python -m opentmcl.lang.gen_includes` after changing a profile)."""
    for name, text in gen_includes.generate().items():
        assert (INCLUDE_DIR / name).read_text(encoding="utf-8") == text, name


@pytest.mark.parametrize("module", module_names())
def test_every_parameter_and_interrupt_has_a_name(module):
    """Every axis parameter, global parameter and interrupt vector of the profile gets a constant
    with its number, and the module's include file assembles."""
    prof = load_profile(module)
    consts = assemble(f"#include {include_key(module)}.inc", module=module).constants
    for p in prof.axis_parameters.values():
        assert consts[f"AP{gen_includes.camel(p.name)}"] == p.number
    for p in prof.global_parameters.values():
        name = f"GP{gen_includes.camel(p.name)}"
        assert consts.get(name, consts.get(f"{name}_B{p.bank}")) == p.number
    for i in prof.interrupts.values():
        assert consts[i.name] == i.number
    assert consts["TI_GLOBAL"] == 255
    assert [consts[f"Motor{a}"] for a in range(prof.axes)] == list(range(prof.axes))


def test_manual_names():
    """Names the manuals' examples use: TI_TIMER0, TI_GLOBAL (3.5.6.4); APMaxPositioningSpeed,
    APMaxAcceleration, Motor0 (7.3)."""
    c = assemble("#include TMCLParam.tmc\n#include Interrupts.inc").constants
    assert (c["TI_TIMER0"], c["TI_GLOBAL"], c["APMaxPositioningSpeed"], c["APMaxAcceleration"], c["Motor0"]) == (
        0, 255, 4, 5, 0)


def test_module_selects_its_own_files():
    """`#include Interrupts.inc` resolves to the selected module's vectors: the TMCM-6212 has six
    axes' target-reached interrupts, the PD86-1180 one."""
    assert "TI_TARGET5" in assemble("#include Interrupts.inc", module="TMCM-6212").constants
    assert "TI_TARGET5" not in assemble("#include Interrupts.inc", module="PD86-1180").constants


def test_user_file_shadows_bundled(tmp_path):
    (tmp_path / "Interrupts.inc").write_text("TI_TIMER0 = 7\n")
    (tmp_path / "m.tmc").write_text("#include Interrupts.inc\nEI TI_TIMER0\n")
    from opentmcl.lang.assembler import assemble_file
    assert tuple(assemble_file(tmp_path / "m.tmc").instructions[0]) == (25, 7, 0, 0)


def test_camel():
    assert gen_includes.camel("max_positioning_speed") == "MaxPositioningSpeed"
    assert gen_includes.camel("timer_0_period") == "Timer0Period"


def test_check_mode(tmp_path, capsys):
    assert gen_includes.main(["--check", "--dir", str(tmp_path)]) == 1
    assert "stale:" in capsys.readouterr().out
    assert gen_includes.main(["--dir", str(tmp_path)]) == 0
    assert gen_includes.main(["--check", "--dir", str(tmp_path)]) == 0
