"""The dashboard service on a virtual module in virtual time (no threads, no web server)."""
from __future__ import annotations

import pytest

import opentmcl
from opentmcl.web.service import Dashboard, DashboardError


@pytest.fixture
def dash():
    module = opentmcl.connect("sim://TMCM-6212")
    transport = module.client.transport
    yield Dashboard(module, vm=transport.module, vm_lock=transport.lock, url="sim://TMCM-6212")
    module.close()


def test_overview_names_module_version_and_address(dash):
    """TMCM-6212 manual 3.6.36 (command 136 type 0 "6212V105") and 5.1 (GP 66, default address 1)."""
    ov = dash.overview()
    assert (ov["module"], ov["version"], ov["address"], ov["axes"]) == ("TMCM-6212", "6212V105", 1, 6)
    assert ov["connected"] and ov["virtual"]
    assert {"OUT0", "IN3"} <= {p["name"] for p in ov["io"]}


def test_console_move_then_fast_sample_shows_the_target(dash):
    """Manual 3.6.4: "MVP ABS, 0, 51200" moves motor 0 to 51200; axis parameter 1 follows."""
    out = dash.console("MVP ABS, 0, 51200")
    assert out["ok"] and out["status"] == 100 and out["request"] == [4, 0, 0, 51200]
    assert "Successfully executed" in out["text"]
    dash.module.sleep(5.0)
    sample = dash.sample_fast()
    assert sample.position[0] == 51200 and sample.velocity[0] == 0
    assert sample.position[1] == 0


def test_console_reports_status_text_of_refused_command(dash):
    """Manual 3.2 status 4 "Invalid value": axis parameter 4 accepts 0..7999774 (manual 4.1)."""
    out = dash.console("SAP 4, 0, 8000000")
    assert not out["ok"] and out["status"] == 4 and "Invalid value" in out["text"]


def test_console_version_and_numeric_form(dash):
    """Manual 3.6.36: command 136 type 0 answers the version string."""
    out = dash.console("136, 0, 0, 0")
    assert out["value"] == "6212V105"


def test_console_rejects_unreadable_line(dash):
    with pytest.raises(DashboardError):
        dash.console("MVP SIDEWAYS, 0")
    with pytest.raises(DashboardError):
        dash.console("   ")


def test_parameter_tables_come_from_the_profile_with_values(dash):
    """Manual 4.1: axis parameter 4 "Maximum positioning speed" in pps, default 51200 here;
    5.1: global parameter 66 "Serial address" = 1."""
    rows = {r["number"]: r for r in dash.axis_parameters(0)}
    assert rows[4]["unit"] == "pps" and rows[4]["writable"] and rows[4]["max"] == 7999774
    assert rows[4]["value"] == dash.module.axes[0].get(4)
    assert rows[4]["description"]
    assert not rows[3]["writable"]  # actual speed is read-only on the TMCM-6212 (manual 4.1)
    glob = {(r["bank"], r["number"]): r for r in dash.global_parameters()}
    assert glob[(0, 66)]["value"] == 1


def test_set_axis_parameter_writes_and_reads_back(dash):
    """Manual 3.6.5 SAP / 3.6.6 GAP."""
    assert dash.set_axis_parameter(2, 4, 20000) == 20000
    assert dash.module.axes[2].get(4) == 20000
    with pytest.raises(DashboardError, match="Invalid value"):
        dash.set_axis_parameter(2, 4, 8000000)
    with pytest.raises(DashboardError, match="not writable"):
        dash.set_axis_parameter(2, 3, 5)
    with pytest.raises(DashboardError, match="axes 0..5"):
        dash.set_axis_parameter(6, 4, 1)


def test_store_needs_the_command_on_the_module(dash):
    """TMCM-6212 manual 3.4.1: the module has no STAP (7); its axis parameters are volatile."""
    with pytest.raises(DashboardError, match="no command 7"):
        dash.store("axis", 4, 0)


def test_store_and_restore_axis_parameter_on_pd86_1180():
    """PD86-1180 manual 4.6.7/4.6.8: STAP stores, RSAP restores the stored value."""
    module = opentmcl.connect("sim://PD86-1180")
    dash = Dashboard(module)
    dash.set_axis_parameter(0, 4, 1000)
    dash.store("axis", 4, 0)
    dash.set_axis_parameter(0, 4, 500)
    dash.store("axis", 4, 0, restore=True)
    assert module.axes[0].get(4) == 1000
    module.close()


def test_outputs_switch_and_inputs_can_be_forced_on_virtual_module(dash):
    """Manual 3.6.12 SIO / 3.6.13 GIO: bank 2 outputs, bank 0 digital inputs."""
    assert dash.set_output(2, 3, 1) == 1
    io = {(p["bank"], p["port"]): p for p in dash.read_io()}
    assert io[(2, 3)]["value"] == 1
    dash.force_input(0, 1, 1)
    assert dash.module.get_io(1, 0) == 1
    assert {(p["bank"], p["port"]): p for p in dash.read_io()}[(0, 1)]["forced"] == 1
    dash.force_input(0, 1, None)
    assert dash.module.get_io(1, 0) == 0
    with pytest.raises(DashboardError):
        dash.force_input(2, 0, 1)       # an output is not an input
    with pytest.raises(DashboardError):
        dash.force_input(1, 0, 70000)   # analog inputs are 0..65535 (manual 3.6.13)


def test_forcing_inputs_needs_a_virtual_module():
    module = opentmcl.connect("sim://TMCM-6212")
    dash = Dashboard(module)  # no vm: as for a real module
    with pytest.raises(DashboardError, match="virtual"):
        dash.force_input(0, 0, 1)
    module.close()


def test_assemble_reports_line_and_column(dash):
    out = dash.assemble("    MVP ABS, 0, 1\n  FOO 1\n")
    assert not out["ok"]
    assert out["errors"][0]["line"] == 2 and out["errors"][0]["column"] == 3


def test_download_step_and_program_state(dash):
    """Manual 3.6.36: 130 executes one instruction; 135 reports PC, A and X.
    Manual 3.6.26 CALC LOAD / ADD work on the accumulator; AGP 42, 2 stores it in user variable 42."""
    src = "// demo\n    CALC LOAD, 5\n    CALC ADD, 2\n    AGP 42, 2\n    STOP\n"
    out = dash.download(src)
    assert out["ok"] and out["count"] == 5  # four instructions and the appended STOP
    st = dash.step()
    assert (st["pc"], st["line"], st["a"]) == (1, 3, 5)
    dash.step()
    st = dash.step()
    assert st["pc"] == 3 and st["line"] == 5
    assert st["variables"][42] == 7  # shown because the program uses it
    assert 0 in st["variables"]


def test_run_to_breakpoint_stops_before_the_line(dash):
    """Host-side breakpoints as in `opentmcl debug`: single-step (130) until the PC is at the line."""
    src = "    CALC LOAD, 1\nLoop:\n    CALC ADD, 1\n    JA Loop\n"
    dash.download(src)
    assert dash.set_breakpoints([3]) == [1]
    dash.run()
    dash.runner.join(timeout=30)
    st = dash.program_state()
    assert st["pc"] == 1 and st["line"] == 3 and st["a"] == 1
    dash.run()
    dash.runner.join(timeout=30)
    st = dash.program_state()
    assert st["pc"] == 1 and st["a"] == 2
    dash.stop()


def test_breakpoints_need_a_program(dash):
    with pytest.raises(DashboardError):
        dash.set_breakpoints([1])


def test_slow_sample_has_axis_cards(dash):
    """Manual 4.1: axis parameters 8 (position reached), 9-11 (switches), 206 (load value)."""
    state = dash.sample_slow()
    card = state["axes"][0]
    assert set(card) >= {"position", "velocity", "target_reached", "home", "left", "right", "load", "current"}
    assert card["target_reached"] == 1
    assert state["program"]["mode"] is not None


def test_dashboard_drives_a_module_over_tcp_like_a_real_one():
    """`opentmcl dashboard --to tcp://...`: everything goes over the wire (manual 3.1 frames);
    the console moves the motor (3.6.4) and forcing inputs is refused without in-process access."""
    from opentmcl import VirtualModule
    from opentmcl.server import Server, TcpServer

    server = Server([VirtualModule("TMCM-6212", address=1)])
    endpoint = server.add(TcpServer(server.bus, "127.0.0.1", 0))
    server.start()
    try:
        module = opentmcl.connect(endpoint.url)
        dash = Dashboard(module, url=endpoint.url)
        assert dash.overview()["version"] == "6212V105" and not dash.overview()["virtual"]
        assert dash.console("SAP 4, 0, 2000")["ok"]
        assert dash.axis_parameters(0)[4]["value"] == 2000
        with pytest.raises(DashboardError, match="virtual"):
            dash.force_input(0, 0, 1)
        module.close()
    finally:
        server.stop()


def test_live_charts_keep_sixty_seconds_at_twenty_samples_a_second_or_more():
    """Issue 7: live charts of position and velocity, at least 20 updates per second, the last 60 s
    kept. The poller's period and the sample history are checked on a clock the test advances."""
    from opentmcl.web.service import Poller

    module = opentmcl.connect("sim://PD86-1180")
    now = [0.0]
    dash = Dashboard(module, clock=lambda: now[0])
    poller = Poller(dash)
    try:
        assert poller.period <= 1 / 20
        for _ in range(int(70 / poller.period)):  # 70 s of samples
            dash.sample_fast()
            now[0] += poller.period
        kept = list(dash.samples)
        assert kept[-1].t - kept[0].t >= 60.0 - poller.period
        assert kept[0].t > 0  # the oldest ones are dropped
    finally:
        module.close()


def test_program_states_are_numbered_in_the_order_they_are_read(dash):
    """A Step's answer and a live update can cross on their way to the page: each program state
    (command 135, manual 3.6.35) carries the number of its reading, later readings larger, so the
    editor drops one older than what it shows (docs/dashboard-program.md)."""
    first, second = dash.program_state(), dash.program_state()
    assert isinstance(first["seq"], int) and second["seq"] > first["seq"]
