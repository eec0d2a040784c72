"""`opentmcl asm ... && opentmcl run ...`, `opentmcl load` (the issue's definition of done) and their
error handling."""
from __future__ import annotations

import shutil
from pathlib import Path

from opentmcl.cli import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
TIMER = "tmcm6212_3.5.6.4_timer_interrupt.tmc"


def test_asm_then_run_the_timer_example(tmp_path, capsys):
    """TMCM-6212 3.5.6.4 example: OUT3 toggles every 500 ms (main loop), OUT0 every 1000 ms (timer
    0 interrupt) - printed deterministically in virtual time."""
    src = tmp_path / TIMER
    shutil.copy(EXAMPLES / TIMER, src)
    assert main(["asm", str(src), "-m", "TMCM-6212"]) == 0
    capsys.readouterr()
    assert main(["run", str(src.with_suffix(".bin")), "-t", "2.2", "-w", "out0,out3"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["time", "[s]", "changes"]
    assert [ln.split() for ln in lines[1:-1]] == [
        ["0.000", "out0=0", "out3=0"], ["0.010", "out3=1"], ["0.510", "out3=0"],
        ["1.010", "out0=1", "out3=1"], ["1.510", "out3=0"], ["2.010", "out0=0", "out3=1"]]
    assert lines[-1].startswith("2.200 s elapsed, program still running")


def test_run_source_until_stop_with_default_watches(capsys):
    """7.6 example, Func2 (run command with address 1): ROL 0, 500 for 100 ticks, MST, STOP."""
    assert main(["run", str(EXAMPLES / "tmcm6212_7.6_host_routines.tmc"), "--from", "1", "--sample", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "state=run out0=0 out1=0 out2=0 out3=0 pos0=0" in out
    assert "state=stop" in out and "program stopped at address 11" in out


def test_run_on_the_pd86_1180(capsys):
    """PD86-1180 4.6.29 potentiometer example: target = 4 * analog input 0 (0 with nothing attached)."""
    assert main(["run", str(EXAMPLES / "pd86_1180_4.6.29_potentiometer.tmc"), "-m", "PD86-1180",
                 "-t", "0.02", "-w", "a,target0,state"]) == 0
    out = capsys.readouterr().out
    assert "a=0 target0=0 state=run" in out


def test_load_over_a_url(capsys):
    assert main(["load", str(EXAMPLES / "tmcm6212_7.2_main_loop.tmc"), "--to", "sim://TMCM-6212",
                 "--start", "5", "--run"]) == 0
    assert capsys.readouterr().out.splitlines() == ["loaded 8 instructions at 5..12, verified", "running from 5"]


def test_errors_are_one_line_messages(tmp_path, capsys):
    assert main(["load", str(EXAMPLES / TIMER)]) == 2
    assert "no module URL" in capsys.readouterr().err
    assert main(["run", str(tmp_path / "missing.tmc")]) == 2
    assert f"cannot read {tmp_path / 'missing.tmc'}: No such file" in capsys.readouterr().err
    assert main(["run", str(EXAMPLES / TIMER), "-w", "bogus"]) == 2
    assert "cannot watch 'bogus'" in capsys.readouterr().err
    bad = tmp_path / "bad.bin"
    bad.write_bytes(b"\x01\x02\x03")
    assert main(["run", str(bad)]) == 2
    assert "not a multiple of 8" in capsys.readouterr().err
    assert main(["run", str(EXAMPLES / TIMER), "--scenario", str(tmp_path / "none.toml")]) == 2
    assert "scenario" in capsys.readouterr().err
    assert main(["run", str(EXAMPLES / TIMER), "-m", "TMCM-9999"]) == 2
    capsys.readouterr()


def test_run_with_a_scenario_drives_the_potentiometer(tmp_path, capsys):
    """3.6.27 AAP example with a scenario: analog input 0 at 302, then 1000 from 0.5 s on; the target
    position follows as 4 x the input."""
    scenario = tmp_path / "pot.toml"
    scenario.write_text("[[input]]\nbank = 1\nport = 0\nsteps = [[0, 302], [0.5, 1000]]\n")
    assert main(["run", str(EXAMPLES / "tmcm6212_3.6.27_potentiometer.tmc"), "--scenario", str(scenario),
                 "-t", "1", "--sample", "0.25", "-w", "adc0,target0"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [ln.split() for ln in lines[1:5]] == [["0.000", "adc0=302", "target0=0"], ["0.250", "target0=1208"],
                                                 ["0.500", "adc0=1000"], ["0.750", "target0=4000"]]


def test_debug_bad_numbers_are_usage_errors_and_do_nothing(tmp_path, capsys):
    """Bad input to the debugger (preamble: "clear error, never a traceback or hang"): a step count
    that is not a positive number executes nothing (130 is not sent), `sleep inf` does not hang, a
    bad `set var` names the expected form; the session goes on."""
    cmds = tmp_path / "cmds.txt"
    cmds.write_text("step -3\nstep x\nsleep inf\nsleep abc\nset var 1 x\ninfo\nquit\n")
    assert main(["debug", str(EXAMPLES / TIMER), "-x", str(cmds)]) == 0
    out = capsys.readouterr().out
    assert out.count("usage: step [N]") == 2
    assert "seconds must be a finite number >= 0" in out and "usage: sleep SECONDS" in out
    assert "usage: set var N VALUE" in out
    assert "[reset]" in out and "PC=0 " in out and "[paused]" not in out
