"""Every float option of the CLI refuses what makes no sense for it (house rules: bad input is one
line on stderr and exit status 2, docs/assumptions.md "Time options"): NaN and infinities always;
negative values for durations, intervals and timeouts; 0 where a step or wait of 0 would never end
or never wait. Each command is a real subprocess; each option also gets its last valid value."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

PROGRAM = "MVP ABS, 0, 100\nSTOP\n"
SIM = "sim://TMCM-6212"
NON_FINITE = ["nan", "inf", "-inf", "1e400"]     # 1e400 is inf once parsed


def cli(args: list[str], cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=60, stdin=subprocess.DEVNULL, env={**os.environ, "MPLBACKEND": "Agg"})


# command line (without the option), option, values refused besides NON_FINITE, a valid value
OPTIONS = [
    (["plot", "p.tmc", "-o", "x.svg"], "--seconds", ["-1", "-1e-9"], "0"),
    (["plot", "p.tmc", "-o", "x.svg"], "--interval", ["0", "-0.01"], "0.5"),
    (["demo"], "--duration", ["0", "-1"], "0.1"),
    (["demo"], "--interval", ["0", "-0.1"], "0.5"),
    (["run", "p.tmc"], "--seconds", ["-1"], "0"),
    (["run", "p.tmc"], "--sample", ["0", "-0.01"], "0.5"),
    (["send", "--to", SIM, "GAP 0, 0"], "--timeout", ["0", "-1"], "1e-3"),
    (["load", "p.tmc", "--to", SIM], "--timeout", ["0", "-1"], "1e-3"),
]


@pytest.fixture
def where(tmp_path):
    (tmp_path / "p.tmc").write_text(PROGRAM)
    return tmp_path


@pytest.mark.parametrize(("argv", "option", "bad", "good"), OPTIONS, ids=[f"{a[0]} {o}" for a, o, _, _ in OPTIONS])
def test_bad_values_are_one_line_errors_the_last_valid_one_runs(where, argv, option, bad, good):
    for value in NON_FINITE + bad:
        result = cli([*argv, option, value], where)
        lines = result.stderr.strip().splitlines()
        assert result.returncode == 2, (option, value, result.returncode, result.stderr[-300:])
        assert len(lines) == 1 and "Traceback" not in result.stderr, (option, value, result.stderr[-300:])
        assert not (where / "x.svg").exists()
    result = cli([*argv, option, good], where)
    assert result.returncode == 0, (option, good, result.stderr[-300:])


@pytest.mark.parametrize(("option", "bad", "good"), [("--gap", ["0", "-0.1"], "0.05"),
                                                     ("--idle-timeout", ["-1"], "0")])
def test_serve_time_options(where, option, bad, good):
    """`serve --gap` (silence that ends a partial frame) must be > 0; `--idle-timeout` 0 means
    "never" (docs/endpoints.md), below 0 and non-finite values are refused. The valid value is
    checked by the server starting (it prints its TCP URL), then it is stopped."""
    for value in NON_FINITE + bad:
        result = cli(["serve", "-m", "TMCM-6212", "--tcp", "127.0.0.1:0", option, value], where)
        assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1, (value, result.stderr)
    proc = subprocess.Popen([sys.executable, "-m", "opentmcl", "serve", "-m", "TMCM-6212", "--tcp", "127.0.0.1:0",
                             option, good], cwd=where, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        assert any("tcp://" in line for line, _ in zip(proc.stdout, range(10), strict=False))
    finally:
        proc.terminate()
        proc.communicate(timeout=30)
