"""One Trace for the world and the plot (issue 33, "Names that say what they are: one `Trace`"): a
trace sampled from an in-process module in its world is plotted, written as a trace file and read
back; the row table `opentmcl run --csv` / `demo --csv` write (``time,pos0,vel0,...``) reads as a
trace too, so `opentmcl plot` draws it."""
from __future__ import annotations

import io
from pathlib import Path

import pytest

from opentmcl import VirtualModule
from opentmcl.cli import main
from opentmcl.host.units import tmc429_velocity_to_pps
from opentmcl.plot import plan
from opentmcl.trace import WORLD_CHANNELS, Trace, TraceError

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


@pytest.fixture(scope="module")
def stage_trace() -> Trace:
    """TMCM-6212 on the example stage: axis 0 through the home switch into the right limit switch."""
    vm = VirtualModule("TMCM-6212", scenario=SCENARIOS / "tmcm6212_stage.toml")
    vm.request(5, 4, 0, 40000)
    vm.request(4, 0, 0, 70000)            # MVP ABS (TMCM-6212 manual 3.6.4)
    trace = Trace(axes=[0, 1])
    trace.record(vm, 3.0, 0.01)
    return trace


def test_a_world_trace_round_trips_as_a_trace_file(stage_trace):
    """The trace file keeps every channel the world trace holds (encoder AP209 and stage too), the
    module and its microstep settings (AP140 = 8: 256, 200 full steps)."""
    buf = io.StringIO()
    stage_trace.to_csv(buf)
    text = buf.getvalue()
    assert text.splitlines()[:2] == ["# module=TMCM-6212", "# microsteps_0=256,200"]
    assert "encoder_0" in text and "stage_1" in text
    back = Trace.from_csv(io.StringIO(text))
    assert back.axes == [0, 1] and back.module == "TMCM-6212" and back.microsteps == stage_trace.microsteps
    assert back.time == pytest.approx(stage_trace.time, abs=1e-6)
    for ax in (0, 1):
        for ch in WORLD_CHANNELS:
            assert back.column(ax, ch) == stage_trace.column(ax, ch), (ax, ch)
    assert back.rows[-1] == stage_trace.rows[-1]


def test_a_world_trace_is_plotted_with_its_stage_and_encoder(stage_trace):
    """The right switch (50000) stopped the motor (TMCM-6212 manual 4.1 AP12 = 0: stop enabled)."""
    fig = plan(stage_trace, ["position", "stage", "encoder", "switches"])
    assert [p.channel for p in fig.panels] == ["position", "stage", "encoder", "switches"]
    stage = fig.panels[1].lines[0]
    assert stage.y[-1] == stage_trace.column(0, "stage")[-1] == stage_trace.rows[-1]["pos0"]
    assert 50000 <= stage.y[-1] < 55000
    names = [line.label for line in fig.panels[3].lines]
    assert names == ["home switch 0", "right switch 0", "left switch 0",
                     "home switch 1", "right switch 1", "left switch 1"]


def test_the_row_table_reads_as_a_trace(stage_trace, tmp_path):
    """`run --csv` writes the row table: `from_csv` reads it (as the module answered: no units to
    convert, no events known), and `opentmcl plot` draws it."""
    table = tmp_path / "run.csv"
    stage_trace.to_csv(table, layout="table")
    assert table.read_text().startswith("time,pos0,vel0,left0,right0,home0,load0,current0,encoder0,stage0,pos1")
    back = Trace.from_csv(table)
    assert back.axes == [0, 1] and back.events is None and back.module == ""
    assert [dict(r) for r in back.rows] == [dict(r) for r in stage_trace.rows]
    out = tmp_path / "run.svg"
    assert main(["plot", str(table), "-o", str(out), "--channels", "position,stage,switches"]) == 0
    assert "<svg" in out.read_text(encoding="utf-8")


def test_tmc429_velocity_rows_as_read_columns_in_pps(tmp_path):
    """PD86-1180 manual 5: actual speed (AP3) is in the TMC429's internal unit; pps = f_CLK * v /
    (2^pulse_div * 2048 * 32) with the pulse divisor AP154 (TMC4210 datasheet 6.1.12.1). Rows and
    the row table keep what GAP answers; `column`, plots and the trace file give pps."""
    vm = VirtualModule("PD86-1180")
    vm.request(1, 0, 0, 1000)             # ROR 1000
    trace = Trace()
    trace.record(vm, 2.0, 0.5)
    pulse_div = vm.request(6, 154, 0).value
    assert trace.rows[-1]["vel0"] == vm.request(6, 3, 0).value == 1000
    assert trace.column(0, "velocity")[-1] == pytest.approx(tmc429_velocity_to_pps(1000, pulse_div))
    back = Trace.from_csv(io.StringIO(trace.to_csv()))
    assert back.column(0, "velocity")[-1] == pytest.approx(tmc429_velocity_to_pps(1000, pulse_div), rel=1e-5)
    assert trace.to_csv(layout="table").splitlines()[-1].split(",")[2] == "1000"


def test_channels_and_layouts_are_checked():
    vm = VirtualModule("TMCM-6212")
    host = Trace([0])
    host.add(0.0, {(0, "position"): 1})   # the channels of a host recording
    with pytest.raises(ValueError, match="channels"):
        host.sample(vm)
    with pytest.raises(ValueError, match="layout"):
        host.to_csv(layout="json")
    with pytest.raises(ValueError, match="channel"):
        Trace([0], channels=["torque"])
    with pytest.raises(TraceError, match="unknown trace column"):
        Trace.from_csv(io.StringIO("time,pos0,speed0\n0,1,2\n"))
    with pytest.raises(TraceError, match="time_s"):
        Trace.from_csv(io.StringIO("t,pos0\n0,1\n"))
