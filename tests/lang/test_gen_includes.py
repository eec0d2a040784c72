"""The include generator (lang/gen_includes.py) beyond the bundled profiles: what it does for a
profile without vector 255, names that are no identifiers, and its command line - in-process, so
the mutation run reaches it (docs/mutation.md)."""
from __future__ import annotations

import dataclasses

import pytest

from opentmcl.lang import gen_includes
from opentmcl.lang.assembler import INCLUDE_DIR, assemble
from opentmcl.modules.profile import load_profile


def test_ti_global_is_added_when_the_profile_has_no_vector_255(tmp_path):
    """TMCM-6212 manual 3.5.6.4: "Globally enable interrupts using an EI 255 command" - the
    Interrupts.inc of a profile that does not list vector 255 still names it TI_GLOBAL."""
    prof = load_profile("PD86-1180")
    without = dataclasses.replace(prof, interrupts={n: i for n, i in prof.interrupts.items() if n != 255})
    assert 255 not in without.interrupts
    (tmp_path / "Interrupts.inc").write_text(gen_includes.interrupt_file(without))
    consts = assemble("#include Interrupts.inc", filename=str(tmp_path / "m.tmc")).constants
    assert consts["TI_GLOBAL"] == 255
    assert consts["TI_TIMER0"] == 0
    assert "Global interrupts (EI/DI 255)" in gen_includes.interrupt_file(without)


def test_unique_keeps_the_first_of_each_name_and_makes_identifiers():
    """A name repeated with the same value is kept once, with another value dropped (the first
    wins); a name that starts with a digit gets a leading ``_`` (TMCL identifiers start with a
    letter or ``_``, docs/tmcl-assembler.md "Source format")."""
    rows = [("9Pin", 1, "a"), ("Speed", 4, "b"), ("Speed", 4, "c"), ("Speed", 5, "d"), ("_x", 2, "")]
    assert gen_includes._unique(rows) == [("_9Pin", 1, "a"), ("Speed", 4, "b"), ("_x", 2, "")]
    assert assemble("_9Pin = 1\nSAP 4, 0, _9Pin").instructions[0].value == 1


def test_camel_splits_on_every_character_that_is_no_letter_or_digit():
    """Upper-case letters are kept (the port names IN0, OUT_1 of the profiles)."""
    assert gen_includes.camel("IN_0") == "IN0"
    assert gen_includes.camel("OUT0") == "OUT0"
    assert gen_includes.camel("stallGuard2 threshold") == "StallGuard2Threshold"


def test_check_without_dir_compares_the_bundled_files(capsys):
    """`--check` without `--dir` compares the bundled include files: up to date, exit 0, silent."""
    assert gen_includes.main(["--check"]) == 0
    assert capsys.readouterr().out == ""
    assert {p.name for p in INCLUDE_DIR.iterdir()} >= set(gen_includes.generate())


def test_write_mode_names_each_file_it_wrote(tmp_path, capsys):
    """Without `--check` every file that differs is written and named "wrote: <file>"; a second
    run writes nothing; `--check` then names nothing and exits 0, after a change it names the file
    "stale: <file>" and exits 1."""
    out_dir = tmp_path / "new" / "include"  # created, with its parents
    assert gen_includes.main(["--dir", str(out_dir)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert sorted(lines) == sorted(f"wrote: {name}" for name in gen_includes.generate())
    assert gen_includes.main(["--dir", str(out_dir)]) == 0
    assert capsys.readouterr().out == ""
    (out_dir / "tmcm6212.inc").write_text("// changed\n")
    assert gen_includes.main(["--check", "--dir", str(out_dir)]) == 1
    assert capsys.readouterr().out == "stale: tmcm6212.inc\n"
    assert (out_dir / "tmcm6212.inc").read_text() == "// changed\n"  # --check writes nothing


def test_help_describes_the_generator(capsys):
    """`--help` gives the first line of the module's docstring as the description."""
    with pytest.raises(SystemExit) as ex:
        gen_includes.main(["--help"])
    assert ex.value.code == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "Write the bundled include files from the module profiles (modules/data/*.toml)." in out
    assert out.startswith("usage: python -m opentmcl.lang.gen_includes")


def test_help_explains_the_check_option(capsys):
    """Module docstring: "``--check`` only compares" - `--help` lists `--check` with a description."""
    with pytest.raises(SystemExit) as ex:
        gen_includes.main(["--help"])
    assert ex.value.code == 0
    lines = capsys.readouterr().out.splitlines()
    at = next(i for i, line in enumerate(lines) if line.strip().startswith("--check"))
    described = lines[at].strip()[len("--check"):].strip() or lines[at + 1].strip()
    assert described and not described.startswith("-")


def test_an_interrupt_name_without_ti_prefix_gets_one():
    """The TI_ names of TMCM-6212 3.5.6.4 (TI_TIMER0): a profile name without the prefix is
    written as TI_ + its CamelCase in upper case."""
    prof = load_profile("TMCM-6212")
    timer = dataclasses.replace(prof.interrupts[0], name="timer_0")
    text = gen_includes.interrupt_file(dataclasses.replace(prof, interrupts={**prof.interrupts, 0: timer}))
    assert "\nTI_TIMER0 " in text


def test_global_parameters_are_listed_by_bank_then_number():
    """"the bank is given in each comment": bank 0 first, then the others in order, each by number
    (a bank 1, as a profile file of one's own may have, lies between 0 and 3)."""
    prof = load_profile("TMCM-6212")
    extra = dataclasses.replace(prof.global_parameters[(0, 255)], bank=1, number=0, name="bank_one_zero")
    mine = dataclasses.replace(prof, global_parameters={**prof.global_parameters, (1, 0): extra})
    text = gen_includes.param_file(mine)
    rows = text.split("// Global parameters", 1)[1].split("\n\n", 1)[0].splitlines()[1:]
    keys = [(int(r.split("// bank ")[1].split(":")[0]), int(r.split("=")[1].split("//")[0])) for r in rows]
    assert keys == sorted(keys)
    assert (1, 0) in keys and keys[0][0] == 0


def test_a_global_parameter_name_in_two_banks_gets_the_bank_suffix_on_both():
    """docs/assumptions.md "Bundled names": "`GP<CamelCaseName>` per global parameter (suffix
    `_B<bank>` only on a clash)": a name two banks share is written with the bank on both, so each
    parameter keeps its own name; a name used once keeps none."""
    prof = load_profile("TMCM-6212")
    b0 = next(g for (b, _), g in sorted(prof.global_parameters.items()) if b == 0)
    b3 = next(g for (b, _), g in sorted(prof.global_parameters.items()) if b == 3)
    other = next(g for (b, _), g in sorted(prof.global_parameters.items()) if b == 0 and g is not b0)
    shared = {(0, b0.number): dataclasses.replace(b0, name="shared_name"),
              (3, b3.number): dataclasses.replace(b3, name="shared_name")}
    text = gen_includes.param_file(dataclasses.replace(prof, global_parameters={**prof.global_parameters, **shared}))
    consts = assemble(text).constants
    assert consts["GPSharedName_B0"] == b0.number and consts["GPSharedName_B3"] == b3.number
    assert "GPSharedName" not in consts
    assert consts[f"GP{gen_includes.camel(other.name)}"] == other.number
