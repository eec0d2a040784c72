"""One way to describe faults (issue 34, docs/faults.md "Describing faults"): the tables of a fault
file, a scenario file, the pytest marker and the Python API are read by one parser; a bad one is a
FaultError naming the key."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.faults import KINDS, LINK_KINDS, MODULE_KINDS, FaultError, load_plan, parse_fault
from opentmcl.motion.scenario import ScenarioError, load_scenario

MINIMAL = {"delay": {"delay": 0.1}, "link_down": {"duration": 1.0}, "hang": {"duration": 1.0},
           "stuck_switch": {"switch": "left"}, "bouncing_switch": {"switch": "home"}}


@pytest.mark.parametrize("kind", KINDS)
def test_every_kind_is_described_by_a_table(kind):
    f = parse_fault({"kind": kind, "probability": 0.5, **MINIMAL.get(kind, {})})
    assert f.kind == kind and f.link == (kind in LINK_KINDS) and f.probability == 0.5
    assert set(LINK_KINDS) | set(MODULE_KINDS) == set(KINDS)


@pytest.mark.parametrize(("table", "message"), [
    ({"kind": "melt", "at": 1}, "unknown fault kind 'melt'"),
    ({"at": 1}, "'kind' is required"),
    ({"kind": "drop_reply", "probability": -0.01}, "must be 0..1"),
    ({"kind": "drop_reply", "probability": 1.01}, "must be 0..1"),
    ({"kind": "drop_reply", "probability": True}, "expected a number"),
    ({"kind": "drop_reply", "at": -1}, "must be >= 0"),
    ({"kind": "drop_reply", "at": float("nan")}, "expected a number"),
    ({"kind": "link_down", "at": 1, "duration": 0}, "must be > 0"),
    ({"kind": "link_down", "at": 1, "duration": -2}, "must be >= 0"),
    ({"kind": "delay", "at": 1, "delay": -0.1}, "must be >= 0"),
    ({"kind": "drop_reply", "command": "FOO", "count": 1}, "unknown TMCL mnemonic 'FOO'"),
    ({"kind": "drop_reply", "command": 99, "count": 1}, "unknown TMCL command number 99"),
    ({"kind": "drop_reply", "count": 3}, "give the command too"),
    ({"kind": "drop_reply", "command": "MVP", "count": 3, "probability": 0.1}, "not both"),
    ({"kind": "drop_reply", "command": "MVP", "count": 0}, "must be 1.."),
    ({"kind": "drop_reply"}, "it would never fire"),
    ({"kind": "drop_reply", "at": 1, "colour": "red"}, "unknown key(s) colour"),
    ({"kind": "power_loss", "at": 1, "delay": 1}, "unknown key(s) delay for a power_loss fault"),
    ({"kind": "delay", "at": 1}, "needs 'delay'"),
    ({"kind": "split_request", "at": 1, "pieces": 1}, "must be 2..9"),
    ({"kind": "split_request", "at": 1, "pieces": 10}, "must be 2..9"),
    ({"kind": "corrupt_reply", "at": 1, "byte": 9}, "must be 0..8"),
    ({"kind": "overtemperature", "at": 1, "level": "boiling"}, "one of prewarning, shutdown"),
    ({"kind": "stuck_switch", "at": 1, "switch": "middle"}, "one of left, right, home"),
    ({"kind": "power_loss", "at": 1, "store": "half"}, "one of complete, absent, either"),
    ({"kind": "hang", "name": "a b", "duration": 1}, "letters, digits"),
    ({"kind": "delay", "at": 1, "delay": 1e308}, "must be at most 1e+06 s"),
    ({"kind": "hang", "duration": 1e6 + 1, "at": 1}, "must be at most 1e+06 s"),
    ({"kind": "drop_reply", "at": 2e6}, "must be at most 1e+06 s"),
    ({"kind": "drop_reply", True: "MVP", "count": 3}, "YAML reads a key 'on' as true"),
])
def test_a_bad_fault_names_its_key(table, message):
    with pytest.raises(FaultError) as info:
        parse_fault(table, "fault[0]")
    assert message in str(info.value) and "\n" not in str(info.value)


def test_the_edges_that_are_allowed():
    """Probability 0 and 1, time 0 and 1e6 s (the longest), a split into 2 and 9 pieces, bytes 0 and 8,
    a command by number."""
    for table in ({"kind": "drop_reply", "probability": 0}, {"kind": "drop_reply", "probability": 1},
                  {"kind": "drop_reply", "at": 0}, {"kind": "split_reply", "at": 0, "pieces": 2},
                  {"kind": "split_reply", "at": 0, "pieces": 9}, {"kind": "corrupt_reply", "at": 0, "byte": 0},
                  {"kind": "corrupt_reply", "at": 0, "byte": 8}, {"kind": "drop_reply", "command": 4, "count": 1},
                  {"kind": "drop_reply", "command": "mvp", "count": 1}, {"kind": "drop_reply", "at": 1e6},
                  {"kind": "delay", "at": 0, "delay": 1e6, "jitter": 1e6}, {"kind": "hang", "at": 0, "duration": 1e6}):
        parse_fault(table)
    assert parse_fault({"kind": "drop_reply", "command": "mvp", "count": 1}).command == 4


def test_names_are_distinct_and_the_file_forms_agree(tmp_path):
    with pytest.raises(FaultError, match="fault\\[1\\].name: 'x' is given twice"):
        load_plan({"fault": [{"kind": "drop_reply", "name": "x"}, {"kind": "hang", "name": "x", "duration": 1}]})
    toml = tmp_path / "f.toml"
    toml.write_text('seed = 9\n[[fault]]\nkind = "drop_reply"\ncommand = "GAP"\ncount = 2\n', encoding="utf-8")
    yaml = tmp_path / "f.yml"
    yaml.write_text("seed: 9\nfault:\n  - kind: drop_reply\n    command: GAP\n    count: 2\n", encoding="utf-8")
    assert load_plan(toml) == load_plan(yaml) and load_plan(toml).seed == 9
    bad = tmp_path / "bad.toml"
    bad.write_text('[[fault]]\nkind = "drop_reply"\nprobability = 2\n', encoding="utf-8")
    with pytest.raises(FaultError, match=r"bad.toml: fault\[0\].probability: must be 0..1"):
        load_plan(bad)


def test_a_scenario_file_holds_faults_too(tmp_path):
    """[[fault]] tables and a seed in a scenario (docs/scenarios.md): the module faults act on the
    module built with it; a bad table is a ScenarioError naming the key."""
    path = tmp_path / "s.toml"
    path.write_text('seed = 4\n[[fault]]\nname = "cut"\nkind = "power_loss"\n[axis.0]\nstart = 0\n', encoding="utf-8")
    scenario = load_scenario(path)
    assert scenario.faults.seed == 4 and scenario.faults.names() == ["cut"]
    vm = VirtualModule("TMCM-6212", address=1, scenario=path)
    vm.request(5, 4, 0, 1234)
    assert vm.faults.trigger("cut") and vm.request(6, 4, 0) is None
    with pytest.raises(ScenarioError, match=r"fault\[0\].kind: unknown fault kind"):
        load_scenario({"fault": [{"kind": "melt"}]})


def test_a_module_fault_for_an_axis_the_module_lacks():
    with pytest.raises(FaultError, match="has no axis 1"):
        VirtualModule("PD86-1180", faults=[{"kind": "step_loss", "axis": 1, "at": 1}])
    with pytest.raises(FaultError, match="is a link fault"):
        VirtualModule("PD86-1180").faults.add({"kind": "drop_reply", "at": 1})
