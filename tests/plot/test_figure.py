"""The data the renderer receives (plot/figure.py): series, labels, spans, breaks, phases, marks.

No image is looked at: `plan()` builds what `draw()` hands to matplotlib, and these tests read it.
"""
from __future__ import annotations

import math

import pytest

from opentmcl.plot import Event, Mark, Trace, plan
from opentmcl.plot.figure import LEGEND_ANCHOR, MARGIN, MIN_SPAN, broken, mark_labels, ramp_phases, span


def _trace(n=10, dt=0.1, **columns) -> Trace:
    """Axis 0 with the given per-sample lists (others 0)."""
    tr = Trace([0], module="TMCM-6212", microsteps={0: (256, 200)})
    for i in range(n):
        row = {(0, ch): 0 for ch in ("position", "velocity")}
        row.update({(0, ch): values[i] for ch, values in columns.items()})
        tr.add(i * dt, row)
    return tr


def _panel(fig, channel):
    return next(p for p in fig.panels if p.channel == channel)


def _gaps(line):
    return [i for i, v in enumerate(line.y) if math.isnan(v)]


# --- labels that match the numbers -------------------------------------------------------------

@pytest.mark.parametrize("n, percent", [(0, 3.125), (15, 50.0), (16, 53.125), (31, 100.0)])
def test_current_is_drawn_in_percent_of_the_module_maximum(n, percent):
    """TMCM-6212 manual 4.1, AP 180: "Actual motor current scaling factor: 0...31: 1/32, 2/32, ...
    32/32"; AP 6: "The maximum value is 255 which means 100% of the maximum current of the module".
    The plotted number is (n + 1) / 32 in %, the label says so, and the right-hand axis maps it
    back to n (first value 0, last valid value 31)."""
    fig = plan(_trace(current=[n] * 10), ["current"])
    panel = fig.panels[0]
    assert panel.ylabel == "current [% of module max.]"
    assert set(panel.lines[0].y) == {percent}
    label, scale, offset = panel.raw
    assert label == "AP 180 n" and percent * scale + offset == pytest.approx(n)


# --- minimum span ------------------------------------------------------------------------------

def test_a_two_count_change_of_the_load_value_does_not_fill_the_panel():
    """Manual 4.1, AP 206 "Actual load value" 0...1023: a change from 300 to 302 gets a panel of
    MIN_SPAN["load"] counts around it, not one from 300 to 302."""
    fig = plan(_trace(load=[300] * 5 + [302] * 5), ["load"])
    lo, hi = fig.panels[0].ylim
    assert hi - lo == pytest.approx(MIN_SPAN["load"])
    assert lo < 300 and hi > 302 and (lo + hi) / 2 == pytest.approx(301)


def test_the_span_keeps_inside_the_readable_range_and_widens_only_when_needed():
    """A load value at its top, 1023 (manual 4.1: 0...1023), is drawn with the panel moved down, not
    past 1023 by more than the margin; a range wider than the minimum is the data plus MARGIN."""
    top = span([1023.0, 1023.0], 100.0, (0.0, 1023.0))
    assert top == pytest.approx((1023 + 100 * MARGIN - 100, 1023 + 100 * MARGIN))
    assert span([0.0, 0.0], 100.0, (0.0, 1023.0))[0] == pytest.approx(-100 * MARGIN)
    assert span([0.0, 1000.0], 100.0) == pytest.approx((-50.0, 1050.0))
    # the last range that is widened and the first that is not: 100 / (1 + 2 * MARGIN)
    edge = 100.0 / (1 + 2 * MARGIN)
    assert span([0.0, edge], 100.0) == pytest.approx((edge / 2 - 50, edge / 2 + 50))
    wider = edge * 1.01
    assert span([0.0, wider], 100.0) == pytest.approx((-wider * MARGIN, wider * (1 + MARGIN)))
    assert span([math.nan], 100.0) is None


def test_every_channel_has_a_minimum_span():
    """docs/plots.md "What the panels show": minimum spans 1000 µsteps, 100 pps, 1000 pps², 100
    load counts, 25 % current (the documented numbers, not the code's table)."""
    documented = {"position": 1000, "velocity": 100, "acceleration": 1000, "load": 100, "current": 25}
    tr = _trace(position=[5, 6] * 5, velocity=[1, 2] * 5, load=[7] * 10, current=[3] * 10)
    for panel in plan(tr, ["position", "velocity", "acceleration", "load", "current"]).panels:
        lo, hi = panel.ylim
        assert hi - lo == pytest.approx(documented[panel.channel]), panel.channel


# --- breaks ------------------------------------------------------------------------------------

def test_an_origin_write_is_a_break_with_the_values_either_side():
    """Manual 4.1 AP 1 "Actual position ... Should only be overwritten for reference point setting":
    the counter jumps from 10000 to 0 at the event's time; the curve ends at (t, 10000) and goes on
    from (t, 0), with a gap between, and a marker names the write."""
    tr = _trace(position=[0, 4000, 8000, 10000, 0, 0, 0, 0, 0, 0], velocity=[0] * 10)
    tr.events = [Event(0.35, 0, "origin", 10000, 0)]
    panel = _panel(plan(tr, ["position"]), "position")
    line = panel.lines[0]
    (gap,) = _gaps(line)
    assert (line.x[gap - 2], line.y[gap - 2]) == (pytest.approx(0.3), 10000)   # the last sample before
    assert line.x[gap - 1:gap + 2] == [0.35, 0.35, 0.35]
    assert line.y[gap - 1] == 10000 and line.y[gap + 1] == 0
    assert [(m.time, m.kind, m.text) for m in panel.markers] == [(0.35, "origin", "AP 1 := 0")]


def test_without_events_an_unexplained_jump_is_guessed_and_a_move_is_not():
    """A trace that does not know its events (a real module, an old CSV): a position change larger
    than 2 x speed x interval + 1 µstep is a break; the largest that speed explains is not. A trace
    with recorded events draws only those."""
    dt, v = 0.1, 1000
    limit = 2 * v * dt + 1   # 201 µsteps in one interval at 1000 pps
    moves = [0, 100, 200, 200 + limit, 200 + 2 * limit + 1, 2000, 2000, 2000]
    tr = _trace(n=8, dt=dt, position=moves, velocity=[v] * 5 + [0] * 3)
    assert tr.events is None
    line = _panel(plan(tr, ["position"]), "position").lines[0]
    gaps = _gaps(line)
    assert [line.x[i] for i in gaps] == [pytest.approx(0.4), pytest.approx(0.5)]
    tr.events = []   # known to be none (a virtual run): the module's word wins over the guess
    assert _gaps(_panel(plan(tr, ["position"]), "position").lines[0]) == []


def test_a_hard_stop_breaks_the_velocity_and_has_no_acceleration():
    """A hard stop sets the actual speed (AP 3) to 0 at once: the velocity curve stops at its speed
    and goes on from 0; the difference quotient across it (-20000 pps / 0.1 s) is no acceleration."""
    tr = _trace(velocity=[20000] * 5 + [0] * 5)
    tr.events = [Event(0.45, 0, "hard_stop", 20000.0, 0.0)]
    fig = plan(tr, ["velocity", "acceleration"])
    vel = _panel(fig, "velocity").lines[0]
    (gap,) = _gaps(vel)
    assert vel.x[gap - 1:gap + 2] == [0.45] * 3 and vel.y[gap - 1] == 20000 and vel.y[gap + 1] == 0
    acc = _panel(fig, "acceleration").lines[0]
    assert math.isnan(acc.y[5]) and acc.y[4] == 0 and acc.y[6] == 0
    assert _panel(fig, "velocity").markers[0].text == "hard stop"


def test_breaks_outside_the_samples_are_ignored_and_unknown_values_leave_a_gap():
    t = [0.0, 1.0, 2.0]
    assert broken(t, [1, 2, 3], [(0.0, 5, 6), (2.5, 5, 6)]) == (t, [1.0, 2.0, 3.0])
    x, y = broken(t, [1, None, 3], [(2.0, None, None)])
    assert x == [0.0, 1.0, 2.0, 2.0] and y[0] == 1 and math.isnan(y[1]) and math.isnan(y[2]) and y[3] == 3


# --- overlays, phases, marks, legend -------------------------------------------------------------

def test_target_position_is_overlaid_as_steps():
    """Manual 4.1 AP 0 "Target position": drawn dashed, as steps, with the position."""
    tr = _trace(position=[0, 100, 200] + [300] * 7, velocity=[1000] * 3 + [0] * 7, target=[300] * 10)
    panel = _panel(plan(tr, ["position"]), "position")
    target = panel.lines[1]
    assert target.label == "axis 0 target (AP 0)" and target.steps and target.dashed
    assert set(target.y) == {300}
    assert [line.label for line in _panel(plan(tr, ["position"], target=False), "position").lines] == ["axis 0"]


def test_ramp_phases_from_the_actual_speed():
    """|v| growing: accelerating; equal and not 0: constant; shrinking: decelerating; 0: none."""
    v = [0, 10, 20, 20, 20, 10, 0, 0, -10, -10]
    tr = _trace(velocity=v)
    phases = [(s.start, s.end, s.phase) for s in ramp_phases(tr, 0)]
    assert phases == [(0.0, pytest.approx(0.2), "accelerating"), (pytest.approx(0.2), pytest.approx(0.4), "constant"),
                      (pytest.approx(0.4), pytest.approx(0.6), "decelerating"),
                      (pytest.approx(0.7), pytest.approx(0.8), "accelerating"),
                      (pytest.approx(0.8), pytest.approx(0.9), "constant")]
    fig = plan(tr, ["velocity"], phases=True)
    assert len(fig.panels[0].spans) == 5 and fig.panels[0].spans[0].band == (0.0, 1.0)
    assert plan(tr, ["velocity"]).panels[0].spans == []


def test_two_axes_shade_their_phases_in_their_own_bands():
    tr = Trace([0, 1])
    for i in range(4):
        tr.add(i * 0.1, {(0, "velocity"): i * 10, (1, "velocity"): 30 - i * 10, (0, "position"): 0, (1, "position"): 0})
    spans = plan(tr, ["velocity"], phases=True).panels[0].spans
    assert {(s.axis, s.phase, s.band) for s in spans} == {(0, "accelerating", (0.5, 1.0)),
                                                          (1, "decelerating", (0.0, 0.5))}


def test_a_hard_stop_is_no_deceleration_phase():
    tr = _trace(velocity=[20000] * 5 + [0] * 5)
    tr.events = [Event(0.45, 0, "hard_stop", 20000.0, 0.0)]
    assert {s.phase for s in plan(tr, ["velocity"], phases=True).panels[0].spans} == {"constant"}


def test_legends_are_right_of_the_data():
    """A legend inside the axes covers curves: its anchor is past the right edge (x > 1)."""
    tr = Trace([0, 1])
    for i in range(3):
        tr.add(i * 0.1, {(0, "position"): i, (1, "position"): -i, (0, "velocity"): 0, (1, "velocity"): 0})
    fig = plan(tr, ["position", "velocity"])
    assert all(p.legend and p.legend_anchor == LEGEND_ANCHOR for p in fig.panels)
    assert LEGEND_ANCHOR[0] > 1


def test_marks_go_to_every_panel_and_close_ones_share_a_label():
    """Of marks closer than LABEL_GAP of the duration, the last (the one that held) is named."""
    marks = [Mark(0.0, 0, "SAP 4, 0, 51200"), Mark(0.01, 3, "WAIT POS, 0, 0"), Mark(5.0, 4, "STOP")]
    assert mark_labels(marks, 10.0) == [1, 2]
    assert mark_labels(marks[:1], 10.0) == [0]
    tr = _trace(n=3, dt=5.0)
    tr.marks = marks
    fig = plan(tr, ["position", "velocity"])
    assert fig.marks == marks and fig.labels == [1, 2]
    assert plan(tr, ["position"], marks=False).marks == []


def test_a_polling_loop_is_marked_once_per_address():
    """A loop the program spins in (GAP / COMP / JC, manual 3.6.15) changes the program counter at
    almost every sample: each address gets one mark, not one per sample; an address seen again
    after LABEL_GAP of the duration is marked again."""
    from opentmcl.plot.figure import LABEL_GAP, thin_marks

    spin = [Mark(0.01 * i, 5 + i % 3, "") for i in range(100)]           # 5, 6, 7, 5, 6, 7 ... for 1 s
    later = Mark(1.0 + LABEL_GAP * 10.0, 5, "GAP 1, 0")
    assert [m.pc for m in thin_marks(spin + [later], 10.0)] == [5, 6, 7, 5]
    tr = _trace(n=3, dt=5.0)
    tr.marks = spin
    assert len(plan(tr, ["position"]).marks) == 3


def test_an_origin_write_breaks_the_target_overlay_too():
    """The target follows the new origin (it is not a new move command): no vertical step there."""
    tr = _trace(position=[0, 500, 1000, 1000, 0, 0, 0, 0, 0, 0], target=[1000] * 4 + [0] * 6)
    tr.events = [Event(0.35, 0, "origin", 1000, 0)]
    target = _panel(plan(tr, ["position"]), "position").lines[1]
    (gap,) = _gaps(target)
    assert target.x[gap] == 0.35 and target.y[gap - 1] == 1000 and target.y[gap + 1] == 0
