"""`opentmcl asm`, `run` and `load` report every error and the target's capability warnings
(docs/tmcl-assembler.md "Errors and warnings", "Checking against a module"; issue 15 item 6).
Each case is a real `opentmcl` subprocess."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "lang" / "examples"


def cli(*args, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "opentmcl", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=120, stdin=subprocess.DEVNULL)


def test_three_errors_in_one_run_in_source_order(tmp_path):
    """Every error, one line each `file:line:column: message`, in the file's order, then the
    count; exit status 2 and no output file."""
    (tmp_path / "bad.tmc").write_text("SAP 4, 0, Speed\nFOO 1\nROL 0, 1\nJA Nowhere\n")
    r = cli("asm", "bad.tmc", cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.splitlines() == ["bad.tmc:1:11: undefined symbol 'Speed'",
                                     "bad.tmc:2:1: unknown mnemonic 'FOO'",
                                     "bad.tmc:4:4: undefined symbol 'Nowhere'",
                                     "opentmcl asm: error: 3 errors"]
    assert not (tmp_path / "bad.bin").exists()


def test_many_errors_are_cut_at_fifty(tmp_path):
    (tmp_path / "many.tmc").write_text("".join(f"BAD{i}\n" for i in range(57)))
    r = cli("asm", "many.tmc", cwd=tmp_path)
    lines = r.stderr.splitlines()
    assert r.returncode == 2 and len(lines) == 52
    assert lines[49] == "many.tmc:50:1: unknown mnemonic 'BAD49'"
    assert lines[50].startswith("... and 7 more errors")
    assert lines[51] == "opentmcl asm: error: 57 errors"


def test_module_warns_and_strict_refuses(tmp_path):
    """--module TMCM-6212: `ROR 7, 1000` (six motors, 0..5) and `SAP 250, 0, 1` (no such axis
    parameter in Table 14) are warnings and the binary is written; --strict refuses both."""
    (tmp_path / "cap.tmc").write_text("ROR 7, 1000\nSAP 250, 0, 1\n")
    r = cli("asm", "cap.tmc", "--module", "TMCM-6212", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stderr.splitlines() == ["cap.tmc:1:5: warning: ROR: motor 7 does not exist on TMCM-6212 (motors 0..5)",
                                     "cap.tmc:2:5: warning: SAP: TMCM-6212 has no axis parameter 250"]
    assert (tmp_path / "cap.bin").read_bytes()[:7] == bytes([1, 0, 7, 0, 0, 0x03, 0xE8])  # ROR 7, 1000
    (tmp_path / "cap.bin").unlink()
    r = cli("asm", "cap.tmc", "--module", "TMCM-6212", "--strict", cwd=tmp_path)
    assert r.returncode == 2
    assert r.stderr.splitlines() == ["cap.tmc:1:5: ROR: motor 7 does not exist on TMCM-6212 (motors 0..5)",
                                     "cap.tmc:2:5: SAP: TMCM-6212 has no axis parameter 250",
                                     "opentmcl asm: error: 2 errors"]
    assert not (tmp_path / "cap.bin").exists()


def test_manual_example_has_no_warning(tmp_path):
    """The TMCM-6212 manual's 2.4 example program runs on the TMCM-6212 as it is."""
    r = cli("asm", EXAMPLES / "tmcm6212_2_4_simple.tmc", "-o", tmp_path / "s.bin", "-m", "TMCM-6212",
            "--strict", cwd=tmp_path)
    assert r.returncode == 0 and r.stderr == ""


def test_the_same_program_warns_for_a_one_axis_module(tmp_path):
    """The 2.4 example moves motor 0 only, so it fits the one-motor PD86-1180 too; a second axis
    does not."""
    (tmp_path / "two.tmc").write_text("ROL 0, 51200\nROL 1, 51200\n")
    r = cli("asm", "two.tmc", "-m", "PD86-1180", cwd=tmp_path)
    assert r.returncode == 0
    assert r.stderr == "two.tmc:2:5: warning: ROL: motor 1 does not exist on PD86-1180 (motor 0 only)\n"


def test_the_assembler_says_138_is_direct_mode_only(tmp_path):
    """Issue 29 item 4. TMCM-6212 manual 3.6.35 "This instruction can only be used in direct mode":
    `asm --module` warns, as it warns of what the module would refuse (docs/tmcl-assembler.md
    "Checking against a module"); --strict refuses (exit 2, nothing written). `asm` without
    --module warns too: no module runs it."""
    src = tmp_path / "p.tmc"
    src.write_text("    MVP ABS, 0, 500\n    RAW 138, 1, 0, 1\n")
    out = tmp_path / "p.bin"
    r = cli("asm", src, "-o", out, "--module", "TMCM-6212", cwd=tmp_path)
    warning = f"{src}:2:9: warning: command 138 can only be used in direct mode: in a program the module skips it (status 6)"
    assert (r.returncode, r.stderr.strip()) == (0, warning)
    out.unlink()
    r = cli("asm", src, "-o", out, "--module", "TMCM-6212", "--strict", cwd=tmp_path)
    assert r.returncode == 2 and not out.exists()
    r = cli("asm", src, "-o", out, cwd=tmp_path)    # no module: 138 is direct mode only on every one
    assert (r.returncode, r.stderr.strip()) == (0, warning)


def test_module_profile_file(tmp_path):
    """--module FILE takes a profile file (docs/profiles.md)."""
    (tmp_path / "two.toml").write_text('extends = "TMCM-6212"\n[module]\nname = "TMCM-2212"\naxes = 2\n')
    (tmp_path / "p.tmc").write_text("ROR 2, 10\n")
    r = cli("asm", "p.tmc", "--module", "two.toml", cwd=tmp_path)
    assert r.returncode == 0
    assert r.stderr == "p.tmc:1:5: warning: ROR: motor 2 does not exist on TMCM-2212 (motors 0..1)\n"


def test_strict_needs_a_module(tmp_path):
    (tmp_path / "p.tmc").write_text("STOP\n")
    r = cli("asm", "p.tmc", "--strict", cwd=tmp_path)
    assert r.returncode == 2 and "--strict needs --module" in r.stderr
    assert not (tmp_path / "p.bin").exists()


def test_missing_source_has_no_fake_position(tmp_path):
    r = cli("asm", "none.tmc", cwd=tmp_path)
    assert r.returncode == 2
    assert r.stderr == "opentmcl asm: error: none.tmc: cannot read file: No such file or directory\n"


def test_run_prints_the_warnings_of_its_target(tmp_path):
    """`run` knows its target (here the in-process TMCM-6212): the warnings come before the run."""
    (tmp_path / "r.tmc").write_text("ROR 7, 1000\nSTOP\n")
    r = cli("run", "r.tmc", "-t", "0.1", cwd=tmp_path)
    assert r.returncode == 0
    assert r.stderr == "r.tmc:1:5: warning: ROR: motor 7 does not exist on TMCM-6212 (motors 0..5)\n"
    assert "program stopped" in r.stdout


def test_run_strict_refuses_before_anything_runs(tmp_path):
    (tmp_path / "r.tmc").write_text("ROR 7, 1000\nSTOP\n")
    r = cli("run", "r.tmc", "-t", "0.1", "--strict", "--module", "PD86-1180", cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr == "opentmcl run: error: r.tmc:1:5: ROR: motor 7 does not exist on PD86-1180 (motor 0 only)\n"


def test_run_checks_a_binary_program_too(tmp_path):
    """A .bin has no source lines: the record number names the instruction."""
    (tmp_path / "r.tmc").write_text("ROL 0, 1\nSAP 250, 0, 1\n")
    assert cli("asm", "r.tmc", cwd=tmp_path).returncode == 0
    r = cli("run", "r.bin", "-t", "0.1", cwd=tmp_path)
    assert r.returncode == 0
    assert r.stderr == "r.bin: warning: record 1: SAP: TMCM-6212 has no axis parameter 250\n"
    r = cli("run", "r.bin", "-t", "0.1", "--strict", cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.splitlines() == ["r.bin: record 1: SAP: TMCM-6212 has no axis parameter 250",
                                     "opentmcl run: error: 1 error"]


def test_load_warns_and_strict_refuses_the_download(tmp_path):
    """`load` asks the module its type (command 136) and checks the program for it."""
    (tmp_path / "l.tmc").write_text("ROR 7, 1000\nSTOP\n")
    r = cli("load", "l.tmc", "--to", "sim://TMCM-6212", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stderr == "l.tmc:1:5: warning: ROR: motor 7 does not exist on TMCM-6212 (motors 0..5)\n"
    assert r.stdout.startswith("loaded 3 instructions")  # and the appended STOP
    r = cli("load", "l.tmc", "--to", "sim://TMCM-6212", "--strict", cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr == "opentmcl load: error: l.tmc:1:5: ROR: motor 7 does not exist on TMCM-6212 (motors 0..5)\n"


def test_load_checks_a_binary_against_the_module_it_reaches(tmp_path):
    """docs/tmcl-assembler.md: `load` knows its target (it asks command 136), so a .bin program is
    checked too - motor 7 on the six-axis TMCM-6212 (manual 1 "Features": motors 0..5) warns, and
    --strict refuses the download (it used to load unchecked)."""
    (tmp_path / "b.tmc").write_text("ROR 7, 1000\nSTOP\n")
    assert cli("asm", "b.tmc", cwd=tmp_path).returncode == 0
    r = cli("load", "b.bin", "--to", "sim://TMCM-6212", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stderr == "b.bin: warning: record 0: ROR: motor 7 does not exist on TMCM-6212 (motors 0..5)\n"
    r = cli("load", "b.bin", "--to", "sim://TMCM-6212", "--strict", cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert "record 0: ROR: motor 7 does not exist on TMCM-6212" in r.stderr


def test_debug_strict_refuses_too(tmp_path):
    """`debug` shares the connection options of `run` and `load`: --strict refuses the program."""
    (tmp_path / "d.tmc").write_text("ROR 7, 1000\nSTOP\n")
    r = cli("debug", "d.tmc", "--strict", cwd=tmp_path)
    assert r.returncode == 2
    assert r.stderr == "opentmcl debug: error: d.tmc:1:5: ROR: motor 7 does not exist on TMCM-6212 (motors 0..5)\n"
