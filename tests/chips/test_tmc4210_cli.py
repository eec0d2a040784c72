"""`opentmcl tmc4210 ...`: the PMUL/PDIV calculator (datasheet 6.1.9.2.3), converters (6.1.12)
and the datagram trace."""
import subprocess
import sys
from pathlib import Path

import pytest

from opentmcl.cli import main

ROOT = Path(__file__).resolve().parents[2]


def run(capsys, *argv):
    rc = main(["tmc4210", *argv])
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_pmulpdiv_prints_the_example_programs_quantities(capsys):
    """6.1.9.2.3: the program prints a_max, ramp_div, pulse_div, p_reduction, p_mul, p_div, p_ideal,
    p_best, p_redu and the A_MAX limits; its usage example is "pmulpdiv -a 10 -r 3 -p 3 -pr 0.05".
    p = 10 / 128 = 0.078125, reduced by the C float 0.05 -> PMUL 151 with PDIV 8."""
    rc, out, _ = run(capsys, "pmulpdiv", "-a", "10", "-r", "3", "-p", "3", "-pr", "0.05")
    assert rc == 0
    assert out == ("\n\n  a_max=10\tramp_div=3\tpulse_div=3\tp_reduction=0.050000\n\n"
                   "    p_mul = 151\n    p_div =   8\n\n"
                   "    p_ideal = 0.078125\n    p_best = 0.073730\n    p_redu = 0.074219\n\n"
                   "\n  a_max_lower_limit = 0\n  a_max_upper_limit = 4095\n\n")


def test_pmulpdiv_warns_outside_the_a_max_limits(capsys):
    """6.1.7.1.1 and the program's warnings; no valid pair is reported as -1 / -1."""
    rc, out, _ = run(capsys, "pmulpdiv", "-a", "2047", "-r", "0", "-p", "5")
    assert rc == 0
    assert "p_mul =  -1" in out and "p_div =  -1" in out
    assert "a_max_upper_limit = 127    [WARNING: a_max > a_max_upper_limit]" in out
    rc, out, _ = run(capsys, "pmulpdiv", "-a", "3", "-r", "13", "-p", "0")
    assert "a_max_lower_limit = 4096    [WARNING: a_max < a_max_lower_limit]" in out


@pytest.mark.parametrize("argv", [
    ["pmulpdiv", "-a", "3000", "-r", "0", "-p", "0"], ["pmulpdiv", "-a", "1", "-r", "14", "-p", "0"],
    ["pmulpdiv", "-a", "1", "-r", "1", "-p", "1", "-pr", "1.5"],
    ["convert", "-v", "3000", "-p", "0"], ["convert", "-p", "0"], ["convert", "-a", "5", "-p", "0"],
    ["convert", "-v", "1", "-p", "0", "--f-clk", "40e6"], ["trace", "/nonexistent/script.txt"],
])
def test_bad_arguments_are_one_line_errors(capsys, argv):
    rc, _, err = run(capsys, *argv)
    assert rc == 2 and err.count("\n") == 1 and err.startswith("opentmcl tmc4210: error:")


def test_convert(capsys):
    """6.1.12.1: R = f_CLK * v / (2^PULSE_DIV * 2048 * 32), dR = f_CLK^2 * A_MAX / 2^(PD+RD+29)."""
    rc, out, _ = run(capsys, "convert", "-v", "1024", "-p", "0", "-a", "1", "-r", "0")
    assert rc == 0
    assert "velocity 1024 -> R = 250000 Hz" in out
    assert "A_MAX 1 -> dR = 476837 Hz/s" in out  # 16e6^2 / 2^29
    rc, out, _ = run(capsys, "convert", "--hz", "250000", "-p", "0", "--hz-per-s", "476837", "-r", "0")
    assert "-> velocity 1024" in out and "-> A_MAX 1 " in out


def test_trace_prints_each_datagram_decoded(tmp_path, capsys):
    """5.2.3's example datagrams as a script: write %001101 with $000123 and read it back."""
    script = tmp_path / "s.txt"
    script.write_text("# 5.2.3\nspi $1A000123\nspi %00011011000000000000000000000000\n"
                      "write V_MAX 1000\nadvance 10ms\ninputs ref_l=1\nread X_ACTUAL\n")
    rc, out, _ = run(capsys, "trace", str(script))
    assert rc == 0
    lines = out.splitlines()
    assert "> $1A000123  write DX_REF_TOLERANCE 291 ($000123)" in lines[0]
    assert "< $15000000  status=$15 [INT=0 R_R=0 GP_IN=0 R_L=0 xEQt1=1]" in lines[1]
    assert "< $15000123" in lines[3] and lines[3].endswith("291 ($000123)")
    assert "write V_MAX 1000" in lines[4]
    assert lines[6].strip().startswith("0.010000") and "R_L=1" in lines[7]


def test_trace_reports_the_bad_line(tmp_path, capsys):
    script = tmp_path / "bad.txt"
    script.write_text("write V_MAX 1000\nwrite V_MAX lots\n")
    rc, _, err = run(capsys, "trace", str(script))
    assert rc == 2 and "bad.txt:2" in err


def test_trace_runs_the_getting_started_example():
    """9.1: the example driver positions the motor; the trace shows its datagrams."""
    proc = subprocess.run([sys.executable, "-m", "opentmcl", "tmc4210", "trace",
                           str(ROOT / "examples" / "tmc4210_getting_started.py")],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    assert "write IF_CONFIGURATION_4210 [en_sd] ($000020)" in proc.stdout
    assert "write X_TARGET 20000" in proc.stdout
    assert proc.stdout.rstrip().endswith("X_ACTUAL = 0, V_ACTUAL = 0, INT = 0")


def test_homing_example_finds_the_switch_centre(capsys):
    """7.3: latch x2 on the way in, x1 on the way out (DX_REF_TOLERANCE lets the motor drive
    inside the switch), x_ref = (x1 + x2) / 2 becomes the origin."""
    import importlib.util

    from opentmcl.chips.tmc4210 import TMC4210

    spec = importlib.util.spec_from_file_location("homing", ROOT / "examples" / "tmc4210_homing.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    chip = TMC4210()
    module.main(chip)
    out = capsys.readouterr().out
    assert "switch width 801 steps" in out  # the switch covers 801 positions
    assert chip.read("X_ACTUAL") == 0
    assert "X_ACTUAL  -401: REF_L inactive" in out and "X_ACTUAL  -400: REF_L active" in out
    assert "X_ACTUAL     0: REF_L active" in out
    assert "X_ACTUAL   400: REF_L active" in out and "X_ACTUAL   401: REF_L inactive" in out


def test_trace_until(tmp_path, capsys):
    """Script `until`: advance until a register condition holds, an error when it never does."""
    script = tmp_path / "u.txt"
    script.write_text("write RAMP_MODE 3\nwrite V_ACTUAL 2047\nuntil X_ACTUAL >= 5000 1\n")
    rc, out, _ = run(capsys, "trace", str(script))
    assert rc == 0 and "# end at t = 0.011000 s" in out  # 499.75 steps per ms (6.1.12.1)
    script.write_text("until X_ACTUAL == 5 0.5\n")
    rc, _, err = run(capsys, "trace", str(script))
    assert rc == 2 and "u.txt:1" in err and "not reached within 0.5 s" in err


@pytest.mark.parametrize("name,text,expect", [
    ("timeout.py", "def main(chip):\n    raise TimeoutError('target 5 not reached')\n",
     "timeout.py: the script stopped with TimeoutError: target 5 not reached"),
    ("crash.py", "def main(chip):\n    raise RuntimeError('boom')\n",
     "crash.py: the script stopped with RuntimeError: boom"),
    ("syntax.py", "def main(chip)\n    pass\n", "syntax.py:1:"),
    ("binary.txt", b"\xff\xfe\x00", "binary.txt: not a UTF-8 text file"),
])
def test_trace_reports_a_failing_script_in_one_line(tmp_path, capsys, name, text, expect):
    """Bad input (audit brief): a script that fails is reported as one line naming the script and
    the failure - not as an internal error or a traceback, and a TimeoutError raised by the
    script's own polling loop is not mistaken for a file that cannot be read."""
    script = tmp_path / name
    if isinstance(text, bytes):
        script.write_bytes(text)
    else:
        script.write_text(text)
    rc, _, err = run(capsys, "trace", str(script))
    assert rc == 2
    assert expect in err and "cannot read" not in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_trace_reads_and_writes_registers_holding_several_fields(tmp_path, capsys):
    """5.3 / 6.1.9: PMUL_PDIV by its register name - the 24 data bits as they are, PMUL's MSB
    fixed to 1 (6.1.9.1)."""
    script = tmp_path / "p.txt"
    script.write_text("write PMUL_PDIV $004608\nread PMUL_PDIV\n")
    rc, out, _ = run(capsys, "trace", str(script))
    assert rc == 0
    lines = out.splitlines()
    assert "> $12004608  write PMUL_PDIV" in lines[0]
    assert "< $1500C608" in lines[3] and "PMUL=198 PDIV=8" in lines[3]
