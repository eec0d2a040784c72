"""`opentmcl asm ... && opentmcl run ...`, `opentmcl load` (the issue's definition of done) and their
error handling."""
from __future__ import annotations

import re
import shutil
import socket
import time
from pathlib import Path

from opentmcl.cli import main
from opentmcl.protocol.frame import Reply, Request

from ..capture.helpers import Tool, cli

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
TIMER = "tmcm6212_3.5.6.4_timer_interrupt.tmc"
WAIT = 30.0  # seconds a condition may take on a loaded machine; nothing here is timed
GGP, STATUS = 10, 135


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


def test_load_run_starts_a_fresh_program_at_its_first_instruction(tmp_path):
    """Issue 29 item 10. TMCM-6212 manual 3.6.36: 129 "0 – from current address, 1 – from specific
    address"; 132/133 say nothing of the program counter, so after a download it stays where the
    last program stopped (docs/assumptions.md). `opentmcl load --run` starts at the program's first
    instruction (129 type 1, the load address): the second program's first SGP runs. The module is
    an `opentmcl serve` process; every `load` is a process of its own."""
    first = tmp_path / "first.tmc"
    first.write_text("    SGP 8, 2, 1\n    SGP 8, 2, 2\n    SGP 8, 2, 3\n    SGP 8, 2, 4\n")
    second = tmp_path / "second.tmc"
    second.write_text("    SGP 9, 2, 42\n    SGP 8, 2, 5\n    SGP 8, 2, 6\n    SGP 8, 2, 7\n    SGP 8, 2, 8\n")
    with Tool("serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0") as p:
        url = p.endpoint("tcp")
        r = cli("load", str(first), "--to", url, "--run")
        assert r.returncode == 0, r.stderr
        _wait_user_variable(url, 8, 4)
        assert _status(url) & 0xFFFF == 4                   # stopped on the appended STOP
        r = cli("load", str(second), "--to", url)            # no --run: the counter stays
        assert r.returncode == 0, r.stderr
        assert _status(url) & 0xFFFF == 4
        r = cli("load", str(second), "--to", url, "--run")
        assert r.returncode == 0 and "running from 0" in r.stdout, r.stderr
        _wait_user_variable(url, 8, 8)
        assert _user_variable(url, 9) == 42                 # its first instruction ran


def _frames(url: str, *requests: tuple[int, int, int, int]) -> list[Reply]:
    host, port = re.match(r"tcp://([\d.]+):(\d+)", url).groups()
    with socket.create_connection((host, int(port)), timeout=WAIT) as s:
        out = []
        for req in requests:
            s.sendall(Request(1, *req).encode())
            buf = b""
            while len(buf) < 9:
                buf += s.recv(9 - len(buf))
            out.append(Reply.decode(buf))
        return out


def _user_variable(url: str, n: int) -> int:
    return _frames(url, (GGP, n, 2, 0))[0].value


def _status(url: str) -> int:
    """135 type 1: mode, wait flag and program counter (TMCM-6212 3.6.36)."""
    return _frames(url, (STATUS, 1, 0, 0))[0].value


def _wait_user_variable(url: str, n: int, want: int) -> None:
    deadline = time.monotonic() + WAIT
    while _user_variable(url, n) != want:
        assert time.monotonic() < deadline, f"user variable {n} never became {want}"
        time.sleep(0.02)


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
