"""The world on the command line and the Trace recorder (item 6); the example scenarios."""
import csv
from pathlib import Path

import pytest

from opentmcl import VirtualModule
from opentmcl.cli import main
from opentmcl.motion.scenario import load_scenario
from opentmcl.trace import Trace

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


@pytest.mark.parametrize("name", sorted(p.name for p in EXAMPLES.glob("*.toml")))
def test_example_scenarios_load_and_run(name):
    """Issue 5: "the example scenarios in examples/ run" - each names its module and runs the demo."""
    sc = load_scenario(EXAMPLES / name)
    vm = VirtualModule(sc.module, scenario=EXAMPLES / name)
    trace = Trace()
    trace.record(vm, 1.0, 0.25)
    assert len(trace.rows) == 5


def test_trace_rows_and_csv(tmp_path):
    """A Trace row holds time and per axis position, velocity, switches, load value, current."""
    vm = VirtualModule("TMCM-1180", scenario={"axis": {"0": {"right": {"position": 1000}}}})
    vm.request(1, 0, 0, 300)
    trace = Trace()
    trace.record(vm, 2.0, 0.5)
    last = trace.rows[-1]
    assert last["pos0"] == 1000 and last["right0"] == 1 and last["vel0"] == 0
    assert set(last) == {"time", "pos0", "vel0", "left0", "right0", "home0", "load0", "current0",
                         "encoder0", "stage0"}
    out = tmp_path / "t.csv"
    trace.to_csv(out, layout="table")     # the table of `run --csv` (the default: the trace file)
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 5 and rows[-1]["right0"] == "1"
    with pytest.raises(ValueError):
        Trace(axes=[3]).sample(vm)


def test_demo_with_a_scenario_prints_the_trace(capsys, tmp_path):
    """`opentmcl demo --scenario FILE` prints the trace; --csv saves it."""
    sc = EXAMPLES / "pd28_1021_home.toml"
    assert main(["demo", "--scenario", str(sc), "--duration", "0.5", "--interval", "0.25"]) == 0
    out = capsys.readouterr().out
    assert "PD28-1021" in out and "load0" in out and "current0" in out
    target = tmp_path / "demo.csv"
    assert main(["demo", "--scenario", str(sc), "--duration", "0.5", "--csv", str(target)]) == 0
    assert target.read_text().startswith("time,pos0,vel0,left0,right0,home0,load0,current0")


def test_demo_scenario_errors_are_one_line(capsys, tmp_path):
    """House rules: bad input is a clear error (exit status 2), no traceback."""
    assert main(["demo", "--scenario", str(tmp_path / "none.toml")]) == 2
    assert "cannot read scenario" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text("[axis.0]\ntype = 'helix'\n")
    assert main(["demo", "--scenario", str(bad)]) == 2
    assert "helix" in capsys.readouterr().err
    assert main(["demo", "--scenario", str(EXAMPLES / "pd28_1021_home.toml"), "--module", "TMCM-6212"]) == 2
    assert "not TMCM-6212" in capsys.readouterr().err


def test_run_homing_program_with_csv(capsys, tmp_path):
    """`opentmcl run PROGRAM --scenario FILE --csv OUT`: the stallGuard homing example stops at the
    hard stop of the example stage and zeroes there; the CSV holds the world trace."""
    target = tmp_path / "run.csv"
    assert main(["run", str(EXAMPLES / "stallguard_homing.tmc"), "--scenario", str(EXAMPLES / "tmcm6212_stage.toml"),
                 "-t", "6", "--sample", "0.5", "-w", "pos0", "--csv", str(target)]) == 0
    out = capsys.readouterr().out
    assert "program stopped" in out
    rows = list(csv.DictReader(target.open()))
    assert rows[-1]["pos0"] == "0" and rows[-1]["stage0"] == "-60000"


def test_run_takes_the_module_from_the_scenario(capsys, tmp_path):
    """docs/scenarios.md: a scenario names its module, so `opentmcl run` needs no --module. PD86-1180
    manual 7.1 three-switch mode (AP193 = 3) on the example stage wired that way: the search ends
    (WAIT RFS) with the position counter zeroed."""
    program = tmp_path / "rfs.tmc"
    program.write_text("    SAP 193, 0, 3\n    RFS START, 0\n    WAIT RFS, 0, 0\n    STOP\n")
    scenario = str(EXAMPLES / "pd86_1180_three_switch.toml")
    assert main(["run", str(program), "--scenario", scenario, "-t", "60", "-w", "state,pos0"]) == 0
    out = capsys.readouterr().out
    assert "program stopped at address 3" in out and out.splitlines()[-2].endswith("pos0=0")
    assert main(["run", str(program), "--scenario", scenario, "--module", "TMCM-6212"]) == 2
    assert "not TMCM-6212" in capsys.readouterr().err


def test_documented_examples_are_valid_scenarios():
    """docs/scenarios.md: every TOML example in the schema document loads and runs on its module."""
    import re
    import tomllib
    doc = (EXAMPLES.parents[1] / "docs" / "scenarios.md").read_text()
    blocks = re.findall(r"```toml\n(.*?)```", doc, re.S)
    assert len(blocks) == 3
    for text in blocks:
        data = tomllib.loads(text)
        vm = VirtualModule(data["module"], scenario=data)
        vm.advance(0.5)


def test_csv_to_stdout(capsys):
    """`--csv -` prints the CSV trace instead of writing a file."""
    sc = EXAMPLES / "pd28_1021_home.toml"
    assert main(["demo", "--scenario", str(sc), "--duration", "0.2", "--interval", "0.1", "--csv", "-"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("time,pos0") and len(lines) == 4
    assert lines[2].split(",")[1] == "200"       # 0.1 s into the demo move (AP5 = 40000 pps^2)
