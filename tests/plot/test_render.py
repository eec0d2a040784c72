"""PNG/SVG rendering and the `opentmcl plot` command."""
from __future__ import annotations

import importlib

import pytest

importlib.import_module("matplotlib")

from opentmcl.cli import main  # noqa: E402
from opentmcl.plot import Trace, TraceError, render  # noqa: E402

PROGRAM = """
    SAP 4, 0, 51200
    SAP 5, 0, 102400
    MVP ABS, 0, 25600
    WAIT POS, 0, 0
    STOP
"""


def _trace() -> Trace:
    tr = Trace([0], module="TMCM-6212", microsteps={0: (256, 200)})
    for i in range(10):
        v = 51200 if 2 <= i < 8 else 0
        tr.add(i * 0.1, {(0, "position"): i * 1000, (0, "velocity"): v, (0, "target_reached"): int(i == 9),
                         (0, "load"): 300, (0, "current"): 16, (0, "left_switch"): 0, (0, "right_switch"): 0,
                         (0, "home_switch"): 0})
    return tr


def test_svg_has_labelled_axes_with_units(tmp_path):
    """Manual 6.5: velocities in pps or rpm; positions in µsteps; time in s. Manual 4.1: the load
    value (AP 206) is 0...1023, the actual current (AP 180) a scaling factor 0...31: 1/32 ... 32/32,
    drawn as % of the module's maximum current (AP 6: "255 which means 100%") with n beside it."""
    out = tmp_path / "t.svg"
    assert render(_trace(), out) == "svg"
    text = out.read_text(encoding="utf-8")
    assert text.lstrip().startswith("<?xml") and "<svg" in text
    for label in ("position [µsteps]", "velocity [pps]", "acceleration [pps²]", "time [s]",
                  "load value [0…1023]", "current [% of module max.]", "AP 180 n"):
        assert label in text
    assert "(n+1)/32 CS" not in text


def test_rpm_label(tmp_path):
    out = tmp_path / "t.svg"
    render(_trace(), out, rpm=True, channels=["velocity"])
    assert "velocity [rpm]" in out.read_text(encoding="utf-8")


def test_png_signature(tmp_path):
    out = tmp_path / "t.png"
    assert render(_trace(), out) == "png"
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bad_output_name_and_channel(tmp_path):
    with pytest.raises(TraceError, match="png"):
        render(_trace(), tmp_path / "t.jpg")
    with pytest.raises(TraceError, match="channel"):
        render(_trace(), tmp_path / "t.png", channels=["torque"])
    with pytest.raises(TraceError, match="no samples"):
        render(Trace([0]), tmp_path / "t.png")


def test_cli_plots_a_program_and_saves_the_trace(tmp_path, capsys):
    """TMCM-6212 manual 3.6.4: the program moves motor 0 to 25600; the CSV ends there."""
    src = tmp_path / "move.tmc"
    src.write_text(PROGRAM)
    png, csv = tmp_path / "move.png", tmp_path / "move.csv"
    assert main(["plot", str(src), "-o", str(png), "--csv", str(csv), "--seconds", "5"]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"
    trace = Trace.from_csv(csv)
    assert trace.column(0, "position")[-1] == 25600
    assert "wrote" in capsys.readouterr().out
    svg = tmp_path / "again.svg"
    assert main(["plot", str(csv), "-o", str(svg), "--channels", "position,velocity"]) == 0
    assert "<svg" in svg.read_text(encoding="utf-8")


def test_cli_errors_are_one_line(tmp_path, capsys):
    src = tmp_path / "bad.tmc"
    src.write_text("  FOO 1\n")
    assert main(["plot", str(src), "-o", str(tmp_path / "x.png")]) == 2
    assert main(["plot", str(src), "-o", str(tmp_path / "x.gif")]) == 2
    assert main(["plot", str(tmp_path / "none.csv"), "-o", str(tmp_path / "x.png")]) == 2
    assert main(["plot", str(src), "-o", str(tmp_path / "x.png"), "--axes", "a"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("error:") == 4


def test_cli_records_a_served_module_over_tcp(tmp_path):
    """A trace recorded against a module reached over TCP (manual 3.1 frames), as for a real
    module: `plot - --to URL` records what the module does (ROR 0, manual 3.6.1)."""
    from opentmcl import VirtualModule, connect
    from opentmcl.server import Server, TcpServer

    server = Server([VirtualModule("TMCM-6212", address=1)])
    endpoint = server.add(TcpServer(server.bus, "127.0.0.1", 0))
    server.start()
    try:
        with connect(endpoint.url) as m:
            m.axes[0].rotate(10000)
        csv = tmp_path / "live.csv"
        assert main(["plot", "-", "--to", endpoint.url, "--seconds", "0.3", "--interval", "0.05",
                     "-o", str(tmp_path / "live.png"), "--csv", str(csv)]) == 0
    finally:
        server.stop()
    trace = Trace.from_csv(csv)
    assert len(trace) == 7
    assert trace.column(0, "velocity")[-1] == 10000
    assert trace.column(0, "position")[-1] > trace.column(0, "position")[0]


def test_cli_record_only_needs_a_url(tmp_path, capsys):
    assert main(["plot", "-", "-o", str(tmp_path / "x.png")]) == 2
    assert "--to" in capsys.readouterr().err


def test_cli_refuses_recordings_it_cannot_hold_and_empty_channel_lists(tmp_path, capsys):
    """Bad numbers are one-line errors before anything runs: a nanosecond interval (10^9 samples
    a second) and an infinite duration never finish; `--channels ,` names no panel."""
    src = tmp_path / "move.tmc"
    src.write_text(PROGRAM)
    out = str(tmp_path / "x.png")
    assert main(["plot", str(src), "-o", out, "--seconds", "1", "--interval", "1e-9"]) == 2
    assert main(["plot", str(src), "-o", out, "--seconds", "inf"]) == 2
    assert main(["plot", str(src), "-o", out, "--channels", ","]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("error:") == 3
    assert "samples" in err and "--channels needs" in err
    assert not (tmp_path / "x.png").exists()


def test_cli_unwritable_output_and_binary_trace_are_one_line_errors(tmp_path, capsys):
    csv = tmp_path / "t.csv"
    _trace().to_csv(csv)
    assert main(["plot", str(csv), "-o", str(tmp_path / "no" / "x.png")]) == 2
    binary = tmp_path / "b.csv"
    binary.write_bytes(b"\xff\xfe\x00")
    assert main(["plot", str(binary), "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("opentmcl plot: error: cannot write") and "folder" in err and "does not exist" in err
    assert "cannot read" in err and "UTF-8" in err and "Traceback" not in err


def test_cli_axes_choose_from_a_csv_trace(tmp_path, capsys):
    """A two-axis trace: `--axes 0` draws axis 0 only (even though 0 is also the default for a
    recording); without --axes every axis of the trace is drawn; an axis the trace lacks is an error."""
    tr = Trace([0, 1], module="TMCM-6212")
    for i in range(5):
        tr.add(i * 0.1, {(0, "position"): i, (1, "position"): -i, (0, "velocity"): 0, (1, "velocity"): 0})
    csv = tmp_path / "two.csv"
    tr.to_csv(csv)
    png = str(tmp_path / "x.png")
    assert main(["plot", str(csv), "-o", png, "--axes", "0"]) == 0
    assert capsys.readouterr().out.rstrip().endswith("axes 0)")
    assert main(["plot", str(csv), "-o", png]) == 0
    assert capsys.readouterr().out.rstrip().endswith("axes 0, 1)")
    assert main(["plot", str(csv), "-o", png, "--axes", "2"]) == 2
    assert "not all in the trace" in capsys.readouterr().err
