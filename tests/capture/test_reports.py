"""Issue 30 item 5: root causes first with their knock-on divergences grouped beneath, move
durations of the module against the twin's per move and in %, and the reports for CI (JSON, JUnit
XML) and people (HTML; its look is checked in test_report_browser.py). The capture comes from a
module with planted differences (tests/capture/recorder.py PLANTED)."""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import pytest

from opentmcl.capture import replay

from .helpers import cli
from .recorder import planted_session, record, reply_of


@pytest.fixture(scope="module")
def planted(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("planted")
    return planted_session(tmp), tmp


def test_root_causes_come_first_and_knock_ons_are_grouped_beneath(planted):
    """The four planted differences are the four causes, in capture order; every speed and
    position reading that differs because the ramp is slower is a knock-on of the motion cause,
    none a root of its own; the motion cause names the accelerations measured on both sides."""
    path, _ = planted
    report = replay(path, "TMCM-6212")
    titles = [c.title() for c in report.causes]
    assert titles[0] == "identity: 136 0 (firmware string): firmware string"
    assert titles[1] == "parameters: axis 0: GAP 194, 0 [reference_search_speed]: value"
    assert titles[2] == "status codes: axis 0: SAP 4, 0, 7999774 [max_positioning_speed]: status"
    assert titles[3].startswith("move durations: axis 0: ROR 0, 10000: duration") and len(titles) == 4
    motion = report.causes[3]
    assert motion.knock_on and {d.area for d in motion.knock_on} <= {"ramp shape", "move durations"}
    assert "acceleration about 5" in motion.note and "204800 on the twin" in motion.note
    assert sum(c.count() for c in report.causes) == len(report.divergences)
    lines = report.text().splitlines()
    roots = [i for i, line in enumerate(lines) if line.startswith("t=")]
    assert len(roots) == 4 and all(lines[i + 1].startswith("    t=") for i in roots[3:])


def test_move_durations_module_against_twin_per_move_and_in_percent(planted):
    """A ramp at 51200 pps^2 where the twin ramps at 204800 (AP5): speeding up to 10000 pps takes
    about 0.195 s on the module and 0.049 s on the twin (+300 %); the move back to 0 takes longer
    too, and so does MST, which brakes at the same rate. Durations are intervals bounded by the
    polls; the twin's lies outside the module's."""
    path, _ = planted
    report = replay(path, "TMCM-6212")
    by_request = {m.request: m for m in report.moves}
    ramp = by_request["ROR 0, 10000"]
    assert ramp.real[0] <= 10000 / 51200 <= ramp.real[1] + 0.001 and ramp.twin == (10000 / 204800, 10000 / 204800)
    assert 250 < ramp.percent < 350 and not ramp.ok
    assert not by_request["MST 0"].ok   # MST brakes at the ramp's acceleration too (the twin's AP5)
    assert not by_request["MVP ABS, 0, 0"].ok and by_request["MVP ABS, 0, 0"].percent > 10
    for kind in ("acceleration", "deceleration"):
        module, twin = report.accelerations[0][kind]
        assert 45000 < module < 56000 and twin == pytest.approx(204800, rel=0.01)


def test_json_and_junit_reports_for_ci(planted):
    """`replay --report FILE.json --junit FILE.xml --html DIR`: exit 1 (divergences), the JSON holds
    the causes with their knock-ons, the area scores and the moves; JUnit has one test case per
    checked area, failed where something diverged."""
    path, tmp = planted
    done = cli("replay", str(path), "-m", "TMCM-6212", "--report", str(tmp / "r.json"), "--junit",
               str(tmp / "r.xml"), "--html", str(tmp / "html"))
    assert done.returncode == 1, done.stderr
    data = json.loads((tmp / "r.json").read_text())
    assert data["format"] == "opentmcl-replay-report" and data["ok"] is False
    assert [c["area"] for c in data["causes"]] == ["identity", "parameters", "status codes", "move durations"]
    assert data["causes"][3]["knock_on"] and all(not d["root"] for d in data["causes"][3]["knock_on"])
    assert data["areas"]["identity"] == {"agree": 0, "checks": 1, "score": 0.0}
    assert data["areas"]["parameters"]["checks"] == 1 and data["areas"]["programs"]["checks"] == 0
    assert 0 < data["areas"]["ramp shape"]["score"] < 1
    assert data["moves"][0]["request"] == "ROR 0, 10000" and data["moves"][0]["percent"] > 250
    suite = ET.parse(tmp / "r.xml").getroot()
    cases = {c.get("name"): c for c in suite.iter("testcase")}
    assert set(cases) == {"identity", "parameters", "status codes", "move durations", "ramp shape"}
    failed = {name for name, case in cases.items() if case.find("failure") is not None}
    assert failed == {"identity", "parameters", "status codes", "move durations", "ramp shape"}
    assert suite.get("failures") == "5" and "6212V200" in cases["identity"].find("failure").text
    assert (tmp / "html" / "index.html").read_text().startswith("<!DOCTYPE html>")


def test_the_same_session_on_the_twin_itself_agrees_everywhere(tmp_path):
    """The same host session recorded from an unchanged TMCM-6212: no cause, every area 100 %."""
    report = replay(planted_session(tmp_path, "TMCM-6212"), "TMCM-6212")
    assert report.ok and not report.causes
    assert all(ok == total for ok, total in report.areas.values()) and report.areas["move durations"][1] >= 4


def test_a_move_to_a_stored_coordinate_is_measured_like_any_position_move(tmp_path):
    """TMCM-6212 3.6.4 MVP COORD "moves the motor to a previously stored coordinate" (SCO, 3.6.22),
    and AP8 reports it reached (4.1) as for MVP ABS: the report measures its duration, module
    against twin, as it does for MVP ABS (capture/moves.py; before, only ABS and REL counted)."""
    steps = [(0.0, (30, 1, 0, 20_000)), (0.01, (4, 2, 0, 1))]   # SCO 1, 0, 20000; MVP COORD, 0, 1
    steps += [(0.02 + 0.05 * k, (6, 8, 0, 0)) for k in range(60)]  # GAP 8, 0 until it is reached
    path = record(tmp_path / "coord.jsonl", steps)
    assert reply_of(path, lambda r: r.get("command") == 6 and r.get("kind") == "reply" and r["value"] == 1)
    report = replay(path, "TMCM-6212")
    moves = [m for m in report.moves if m.request.startswith("MVP COORD")]
    assert len(moves) == 1 and moves[0].kind == "position" and moves[0].ok and moves[0].twin is not None
    assert moves[0].real[0] <= moves[0].twin_mid <= moves[0].real[1] + 0.05
