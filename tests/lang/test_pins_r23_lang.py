"""Edges of the lang layer that the seeded lang mutation draw of round 23 found unpinned
(issue 12, docs/mutation.md): where size, include and expression errors point, the cycle a
self-referential constant names, bytes that are no UTF-8, the options assemble_file passes on,
the module checks of user variables, the PD86-1180 pull-up port and SCO/GCO motors, and the
include generator's name clashes and --check help."""
from __future__ import annotations

import dataclasses

import pytest

from opentmcl.lang import gen_includes
from opentmcl.lang.assembler import MAX_EXPR_TOKENS, MAX_INCLUDE_DEPTH, AsmError, assemble, assemble_file
from opentmcl.modules.profile import load_profile


def _error(src: str, **kw) -> AsmError:
    with pytest.raises(AsmError) as err:
        assemble(src, **kw)
    return err.value


def _warnings(src: str, module) -> list[str]:
    return [d.message for d in assemble(src, module=module).warnings]


# --- program memory and origin -----------------------------------------------------------------

def test_a_program_too_large_from_an_origin_is_reported_at_the_first_instruction_past_the_end():
    """TMCM-6212 manual 1 Features: "program memory (non volatile) for up to 6144 TMCL commands";
    docs/assumptions.md "Load address": with origin N "the size check counts from N". Loaded at
    6144 - 6, six instructions and the STOP fill the memory exactly; at 6144 - 4 the fifth
    instruction is the first one at address 6144, beyond the memory, and the error is on its line
    (docs/tmcl-assembler.md: "the column is that of the token at fault")."""
    size = load_profile("TMCM-6212").program_memory
    assert size == 6144
    src = "".join(f"MST {i}\n" for i in range(6))          # lines 1..6, then the appended STOP
    fits = assemble(src, module="TMCM-6212", origin=size - 7)
    assert len(fits.instructions) == 7 and fits.origin + len(fits.instructions) == size
    origin = size - 4                                    # addresses size-4 .. size+2
    e = _error(src, module="TMCM-6212", origin=origin)
    first_outside = size - origin + 1                    # line of the instruction at address `size`
    assert (e.line, e.column) == (first_outside, 1) == (5, 1)
    assert e.message == f"program has 7 instructions from address {origin}; TMCM-6212 program memory holds {size}"


# --- #include ----------------------------------------------------------------------------------

@pytest.mark.parametrize(("line", "close", "col"), [('#include "TMCLParam.tmc', '"', 1),
                                                    ("   #include <TMCLParam.tmc", ">", 4)])
def test_an_include_name_without_its_closing_quote_is_an_error_at_the_directive(line, close, col):
    """docs/assumptions.md (Assembler): "#include accepts `file`, `"file"` or `<file>`"; an opening
    quote or < without its partner is an AsmError at the '#' (file:line:column), with the closed
    form as the last valid spelling."""
    assert assemble(f'{line}{close}\nSAP APMaxPositioningSpeed, 0, 1').instructions[0] == (5, 4, 0, 1)
    e = _error(f"MST 0\n{line}\nMST 1")
    assert (e.file, e.line, e.column, e.message) == ("<source>", 2, col, f"missing closing {close} in #include")
    assert str(e) == f"<source>:2:{col}: missing closing {close} in #include"


def test_an_include_one_level_too_deep_is_an_error_at_its_directive(tmp_path):
    """docs/assumptions.md "#include": "32 include files nested inside each other are read, the
    33rd `#include` is refused" - on its own line, at the column of its '#'."""
    assert MAX_INCLUDE_DEPTH == 32

    def chain(depth: int):
        for i in range(1, depth + 1):
            body = f"   #include f{i + 1}.inc\n" if i < depth else "Deepest = 1\n"
            (tmp_path / f"f{i}.inc").write_text(f"// level {i}\n{body}")
        (tmp_path / "main.tmc").write_text("#include f1.inc\nMVP ABS, 0, Deepest\n")
        return tmp_path / "main.tmc"

    assert assemble_file(chain(32)).instructions[0] == (4, 0, 0, 1)
    with pytest.raises(AsmError) as info:
        assemble_file(chain(33))
    e = info.value
    assert e.file.endswith("f32.inc")
    assert (e.line, e.column, e.message) == (2, 4, "includes nested deeper than 32")
    assert str(e.errors[0]).endswith("f32.inc:2:4: includes nested deeper than 32")


# --- expressions and constants -----------------------------------------------------------------

def test_an_expression_one_token_too_long_is_an_error_at_the_limit_not_before():
    """docs/assumptions.md "Expression bounds": "1000 tokens per expression"; docs/tmcl-assembler.md:
    beyond that "the error names the line and column". '1+1+...': the 1000th token is the last
    one allowed; the error points at the place where the limit is reached (the 1000th or the
    1001st token), not at an earlier token and not without a column."""
    assert MAX_EXPR_TOKENS == 1000
    head = "MVP ABS, 0, "
    ok = "~" + "+".join(["1"] * 500)                     # 1000 tokens: ~1 + 499 ones
    assert assemble(head + ok).instructions[0].value == 497
    text = "+".join(["1"] * 501)                         # 1001 tokens, one character each
    col_of = {k: len(head) + k for k in (999, 1000, 1001)}   # 1-based column of the k-th token
    assert text[col_of[1001] - len(head) - 1] == "1" and len(text) == 1001
    e = _error(f"MST 0\n{head}{text}")
    assert e.message == "expression longer than 1000 numbers, names and operators"
    assert e.line == 2
    assert isinstance(e.column, int) and col_of[999] < e.column <= col_of[1001]


@pytest.mark.parametrize(("src", "names"), [("X = Y + 1\nY = X - 1\nSAP 4, 0, X", {"X", "Y"}),
                                            ("Self = Self + 1\nSAP 4, 0, Self", {"Self"})])
def test_a_constant_defined_in_terms_of_itself_names_the_cycle(src, names):
    """TMCM-6212 manual 7.3 "Using Symbolic Constants"; docs/assumptions.md: constants "may refer
    to constants and labels defined later" - but not, through any chain, to themselves: the
    error names every constant of the cycle, joined by '->'."""
    e = _error(src)
    head, _, chain = e.message.partition(": ")
    assert head == "constant defined in terms of itself"
    parts = chain.split(" -> ")
    assert set(parts) == names and len(parts) == len(names) + 1 and parts[0] == parts[-1]


def test_source_bytes_that_are_no_utf8_are_read_like_a_file():
    """assemble() "takes the source text (str or bytes)" - bytes that are not UTF-8 (a Latin-1
    comment from an old TMCL-IDE file) assemble as assemble_file reads them: each bad byte
    becomes U+FFFD, the instructions are the same."""
    src = b"Start: ROL 0, 500 // Geschwindigkeit f\xfcr Motor 0\nJA Start\n"
    prog = assemble(src)
    assert prog.instructions == [(2, 0, 0, 500), (22, 0, 0, 0), (28, 0, 0, 0)]
    assert "\ufffd" in prog.source[0].text
    assert assemble(bytearray(src)).instructions == prog.instructions


def test_source_bytes_match_assemble_file(tmp_path):
    """The same bytes read from a file (assemble_file) and passed as bytes give the same image."""
    path = tmp_path / "latin1.tmc"
    path.write_bytes(b"// \xe9t\xe9\nMVP ABS, 0, 1000 // \xff\n")
    assert assemble(path.read_bytes()).image() == assemble_file(path).image()


# --- assemble_file passes every option on --------------------------------------------------------

def test_assemble_file_assembles_for_the_origin(tmp_path):
    """docs/assumptions.md "Load address": "`assemble(..., origin=N)` ... assembles for program
    memory address N: labels are absolute addresses"; assemble_file takes the same `origin`."""
    path = tmp_path / "loop.tmc"
    path.write_text("MST 0\nLoop: ROL 0, 500\nJA Loop\n")
    prog = assemble_file(path, origin=100)
    assert (prog.origin, prog.labels) == (100, {"Loop": 101})
    assert prog.instructions[2] == (22, 0, 0, 101)
    assert assemble_file(path).labels == {"Loop": 1}


def test_assemble_file_with_strict_refuses_what_the_module_cannot_execute(tmp_path):
    """docs/tmcl-assembler.md "Checking against a module": `--strict` makes the warnings errors
    (TMCM-6212 has motors 0..5: ROR 5 is the last valid motor, ROR 6 the first invalid one)."""
    path = tmp_path / "ror.tmc"
    path.write_text("ROR 5, 100\nROR 6, 100\n")
    assert [d.message for d in assemble_file(path, module="TMCM-6212").warnings] == [
        "ROR: motor 6 does not exist on TMCM-6212 (motors 0..5)"]
    with pytest.raises(AsmError) as info:
        assemble_file(path, module="TMCM-6212", strict=True)
    assert (info.value.line, info.value.message) == (2, "ROR: motor 6 does not exist on TMCM-6212 (motors 0..5)")
    path.write_text("ROR 5, 100\n")
    assert assemble_file(path, module="TMCM-6212", strict=True).warnings == []


# --- module checks -------------------------------------------------------------------------------

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


def test_pd86_1180_pullups_port_may_be_set():
    """PD86-1180 manual 4.6.14 SIO: "SIO is also used to switch the pull-up resistors for all
    digital inputs ON or OFF. Bank 0 is used for this purpose" (the profile's `pullups` port,
    bank 0 port 0, docs/assumptions.md "the `pullups` port of `[module]` allowed"); the next
    port of bank 0 is an input, which SIO cannot set."""
    prof = load_profile("PD86-1180")
    assert (prof.extra["pullups"]["bank"], prof.extra["pullups"]["port"]) == (0, 0)
    assert _warnings("SIO 0, 0, 7", "PD86-1180") == []
    assert _warnings("SIO 1, 0, 1", "PD86-1180") == ["SIO: port 1 in bank 0 (IN_1) of PD86-1180 is an input"]


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


# --- include generator -------------------------------------------------------------------------

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


def test_help_explains_the_check_option(capsys):
    """Module docstring: "``--check`` only compares" - `--help` lists `--check` with a description."""
    with pytest.raises(SystemExit) as ex:
        gen_includes.main(["--help"])
    assert ex.value.code == 0
    lines = capsys.readouterr().out.splitlines()
    at = next(i for i, line in enumerate(lines) if line.strip().startswith("--check"))
    described = lines[at].strip()[len("--check"):].strip() or lines[at + 1].strip()
    assert described and not described.startswith("-")
