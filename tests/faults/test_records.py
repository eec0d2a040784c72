"""Faults that fired are recorded (issue 34, "faults that fired are recorded in traces and captures,
so a replay or a plot shows them"), and triggered by name from the dashboard (issue 34, "a control
that triggers a named fault while serving, from the CLI and from the dashboard"; docs/dashboard.md
"Threat model": every POST needs the X-OpenTMCL header and the page's own Origin)."""
from __future__ import annotations

import importlib
import io

import pytest

import opentmcl
import opentmcl.sim
from opentmcl import VirtualModule
from opentmcl.capture import read_capture, replay
from opentmcl.capture.proxy import Proxy, ProxySession
from opentmcl.host import TmclTimeout
from opentmcl.server import TcpServer
from opentmcl.trace import Trace

from ..capture.helpers import cli
from .helpers import GAP, plan_file


def test_a_trace_records_the_faults_and_its_file_keeps_them():
    """Trace.sample picks up what fired (module time); the trace file keeps it ('# fault=' lines);
    the plot draws it."""
    vm = VirtualModule("TMCM-6212", address=1)
    vm.faults.add({"kind": "step_loss", "at": 0.2, "duration": 0.2, "load": 3.0})
    vm.request(4, 0, 0, 50000)
    trace = Trace(axes=[0])
    trace.record(vm, 0.6, 0.05)
    assert [(f.time, f.kind) for f in trace.faults] == [(0.2, "step_loss"), (0.4, "step_loss")]
    stage = trace.column(0, "stage")
    assert stage[4] == stage[8] < trace.column(0, "position")[8]      # 0.2..0.4 s: the stage stood
    again = Trace.from_csv(io.StringIO(trace.to_csv()))
    assert again.faults == trace.faults
    from opentmcl.plot.figure import plan
    assert [f.time for f in plan(again, ["position"]).faults] == [0.2, 0.4]


def test_a_capture_records_the_faults_and_a_replay_names_them(tmp_path):
    """`opentmcl proxy --to sim://...?faults=FILE --log` writes a 'fault' record when one fires; the
    replay report lists it among its notes."""
    plan = plan_file(tmp_path, [{"name": "lost", "kind": "drop_reply"}])
    proxy = Proxy(f"sim://TMCM-6212?faults={plan}", log=str(tmp_path / "run.jsonl"))
    tcp = proxy.listen(TcpServer(proxy, "127.0.0.1", 0, session=ProxySession))
    proxy.start()
    try:
        m = opentmcl.connect(tcp.url, timeout=5.0, profile="TMCM-6212")
        assert m.request(GAP, 4, 0).status == 100
        proxy.upstream.faults.trigger("lost")
        with pytest.raises(TmclTimeout):
            m.request(GAP, 4, 0, timeout=0.3)
        assert m.request(GAP, 4, 0).status == 100
        m.close()
    finally:
        proxy.stop()
    cap = read_capture(tmp_path / "run.jsonl")
    assert [(f["kind"], f["name"], f["detail"]) for f in cap.faults] == [("drop_reply", "lost", "reply to GAP 4, 0 dropped")]
    report = replay(cap, "TMCM-6212")
    assert any(note.startswith("fault at ") and "lost (drop_reply): reply to GAP 4, 0 dropped" in note
               for note in report.notes)


@pytest.fixture
def web():
    importlib.import_module("starlette")
    from starlette.testclient import TestClient

    from opentmcl.web.app import create_app
    from opentmcl.web.service import Dashboard

    m = opentmcl.sim.connect("TMCM-6212", faults=[{"name": "cut", "kind": "power_loss", "duration": 0.1}],
                             timeout=0.3)
    dash = Dashboard(m)
    with TestClient(create_app(dash), base_url="http://127.0.0.1") as client:
        yield client, m
    dash.closed.set()
    m.close()


def test_the_dashboard_lists_and_triggers_named_faults(web):
    client, m = web
    assert client.get("/m/1/api/faults").json() == {"names": ["cut"], "seed": m.client.transport.faults.seed,
                                                     "fired": []}
    out = client.post("/m/1/api/faults/trigger", json={"name": "cut"}, headers={"X-OpenTMCL": "1"})
    assert out.status_code == 200 and "cut (power_loss): power lost for 0.1 s" in out.json()["fired"][0]
    with pytest.raises(TmclTimeout):
        m.request(GAP, 4, 0)
    bad = client.post("/m/1/api/faults/trigger", json={"name": "melt"}, headers={"X-OpenTMCL": "1"})
    assert bad.status_code == 400 and "no fault named 'melt'" in bad.json()["error"]


def test_the_dashboards_guard_keeps_other_sites_from_triggering(web):
    """No X-OpenTMCL header (a cross-site form) or another Origin: refused before the route runs."""
    client, m = web
    assert client.post("/m/1/api/faults/trigger", json={"name": "cut"}).status_code == 403
    foreign = client.post("/m/1/api/faults/trigger", json={"name": "cut"},
                          headers={"X-OpenTMCL": "1", "Origin": "http://evil.example"})
    assert foreign.status_code == 403
    assert m.client.transport.faults.log.count == 0


def test_a_served_bus_gives_its_dashboards_the_plan():
    importlib.import_module("starlette")
    from opentmcl.server import Server
    from opentmcl.web.server import bus_dashboards

    server = Server([VirtualModule("TMCM-6212", address=1)], faults=[{"name": "hot", "kind": "overtemperature"}])
    dashboards, close = bus_dashboards(server.bus)
    try:
        assert dashboards[0].faults is server.faults and server.faults.names() == ["hot"]
    finally:
        close()


PROGRAM = "  SAP 212, 0, 0\n  MVP ABS, 0, 200000\nloop: WAIT TICKS, 0, 10\n  JA loop\n"
SCENARIO = """module = "TMCM-6212"
seed = 4
[[fault]]
name = "heavy"
kind = "step_loss"
at = 0.3
duration = 0.3
load = 3.0
"""
POWER_LOSS = """[[fault]]
kind = "power_loss"
at = 0.8
duration = 0.1
"""


def test_a_plot_of_a_scenario_shows_its_faults(tmp_path):
    """`opentmcl plot PROGRAM --scenario FILE` whose [[fault]] tables fire a step loss and a power
    loss: the trace it saves has a '# fault=' line for each (at trace time), the samples while the
    power is off are gaps (the module answers nothing), and after the power-up the position counter
    reads 0 (docs/faults.md "power_loss"); the plot draws the faults (red dashed lines)."""
    program, scenario = tmp_path / "move.tmc", tmp_path / "s.toml"
    program.write_text(PROGRAM, encoding="utf-8")
    scenario.write_text(SCENARIO + POWER_LOSS, encoding="utf-8")
    out = cli("plot", str(program), "--scenario", str(scenario), "-t", "1.2", "-o", str(tmp_path / "p.svg"),
              "--csv", str(tmp_path / "p.csv"))
    assert out.returncode == 0, out.stderr
    trace = Trace.from_csv(tmp_path / "p.csv")
    assert [(f.time, f.kind, f.name) for f in trace.faults] == [
        (0.3, "step_loss", "heavy"), (0.6, "step_loss", "heavy"), (0.8, "power_loss", ""), (0.9, "power_loss", "")]
    position = trace.column(0, "position")
    off = [p for t, p in zip(trace.time, position, strict=True) if 0.8 <= t < 0.9]
    assert off and all(p is None for p in off)
    before = [p for t, p in zip(trace.time, position, strict=True) if t < 0.8]
    after = [p for t, p in zip(trace.time, position, strict=True) if t >= 0.9]
    assert before[-1] > 10000 and after[0] == 0
    assert (tmp_path / "p.svg").read_text(encoding="utf-8").count("stroke-dasharray") >= 4


def test_the_table_of_run_keeps_the_faults(tmp_path):
    """`opentmcl run PROGRAM --scenario FILE --csv OUT`: the row table starts with the '# fault='
    lines, and `opentmcl plot OUT` reads them back."""
    program, scenario = tmp_path / "move.tmc", tmp_path / "s.toml"
    program.write_text(PROGRAM, encoding="utf-8")
    scenario.write_text(SCENARIO, encoding="utf-8")
    out = cli("run", str(program), "--scenario", str(scenario), "-t", "1", "--csv", str(tmp_path / "run.csv"))
    assert out.returncode == 0, out.stderr
    assert [(f.time, f.kind) for f in Trace.from_csv(tmp_path / "run.csv").faults] == [
        (0.3, "step_loss"), (0.6, "step_loss")]


def test_a_recording_bridges_a_silent_module_and_gives_up_after_a_while():
    """`opentmcl.plot.record` over a link to a module that hangs (docs/faults.md "hang"): 3 s of
    silence are a gap in the trace and the recording goes on; a module silent for longer than
    `SILENCE` (10 s) ends it with the time-out."""
    from opentmcl.plot import record
    from opentmcl.plot.recording import SILENCE

    m = opentmcl.sim.connect("TMCM-6212", faults=[{"kind": "hang", "at": 0.5, "duration": 3.0}], timeout=0.2)
    trace = record(m, [0], seconds=5.0, interval=0.1)
    silent = [t for t, p in zip(trace.time, trace.column(0, "position"), strict=True) if p is None]
    assert silent and 0.5 <= silent[0] and silent[-1] < 3.5 and trace.time[-1] >= 5.0
    m = opentmcl.sim.connect("TMCM-6212", faults=[{"kind": "hang", "at": 0.5, "duration": 3 * SILENCE}],
                             timeout=0.2)
    with pytest.raises(TmclTimeout):
        record(m, [0], seconds=4 * SILENCE, interval=0.1)
    assert SILENCE < m.client.transport.monotonic() < 3 * SILENCE
