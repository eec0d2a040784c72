"""What a plot shows, as plain data: the renderer (render.py) only draws a `Figure` made here.

    fig = plan(trace, ["position", "velocity"], phases=True)
    fig.panels[0].lines[0].y, fig.panels[0].ylim, fig.panels[1].spans, fig.marks

Units (TMCM-6212 manual 6.5 for pps and rpm, 4.1 for the parameters): position and target
position in µsteps (AP 1, AP 0), velocity in pps or rpm (AP 3), acceleration in pps² (derived),
the stallGuard2 load value 0...1023 (AP 206), the motor current in % of the module's maximum
current: AP 180 reads the coolStep scaling factor n = 0...31 ("1/32, 2/32, ... 32/32"), so the
current is (n + 1) / 32 of the maximum (AP 6: "255 which means 100% of the maximum current of the
module"); n itself is on the panel's right-hand axis. A trace of an in-process module
(`Trace.sample`) also has the encoder position (AP 209) and where the stage really is (µsteps,
docs/world.md): panels "encoder" and "stage". Breaks: plot/events.py.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from ..trace import CHANNELS, HARD_STOP, ORIGIN, SWITCHES, Event, Mark, Trace, TraceError
from .events import guess_origins

DEFAULT_CHANNELS = ("position", "velocity", "acceleration", "load", "current", "switches")
NAN = float("nan")
# Smallest y range of a panel, so that a change of a few counts does not fill it (docs/plots.md).
MIN_SPAN = {"position": 1000.0, "velocity": 100.0, "rpm": 1.0, "acceleration": 1000.0, "load": 100.0,
            "current": 25.0, "encoder": 1000.0, "stage": 1000.0}
LIMITS = {"load": (0.0, 1023.0), "current": (0.0, 100.0)}   # the range a reading can have
MARGIN = 0.05           # of the data range, above and below, when it is wider than MIN_SPAN
LEGEND_ANCHOR = (1.01, 1.0)   # legend's upper left corner in panel coordinates: right of the data
MAX_LABELLED = 40       # instruction marks with text; more are drawn as lines only
MAX_DRAWN = 400         # instruction marks drawn at all
LABEL_GAP = 0.015       # of the duration: closer marks do not all get their text
PHASES = ("accelerating", "constant", "decelerating")


@dataclass
class Line:
    """One curve: y may hold NaN (no value, or a break). `steps`: each value holds until the next."""

    label: str
    x: list[float]
    y: list[float]
    axis: int | None = None
    steps: bool = False
    dashed: bool = False


@dataclass
class Marker:
    """A vertical line at `time` with a short text: a break (ORIGIN, HARD_STOP)."""

    time: float
    kind: str
    text: str
    axis: int


@dataclass
class Span:
    """A ramp phase of `axis` from `start` to `end`, shaded in the band (low, high) of the panel height."""

    start: float
    end: float
    phase: str
    axis: int
    band: tuple[float, float] = (0.0, 1.0)


@dataclass
class Panel:
    channel: str
    ylabel: str
    lines: list[Line] = field(default_factory=list)
    ylim: tuple[float, float] | None = None
    markers: list[Marker] = field(default_factory=list)
    spans: list[Span] = field(default_factory=list)
    yticks: list[tuple[float, str]] | None = None
    raw: tuple[str, float, float] | None = None   # right-hand axis: label, raw = y * scale + offset
    legend: bool = False
    legend_anchor: tuple[float, float] = LEGEND_ANCHOR


@dataclass
class Figure:
    title: str
    panels: list[Panel]
    marks: list[Mark] = field(default_factory=list)   # instruction marks, on every panel
    labels: list[int] = field(default_factory=list)  # the marks (indices) drawn with their text
    xlim: tuple[float, float] = (0.0, 1.0)            # first and last sample time
    xlabel: str = "time [s]"


def channel_names() -> list[str]:
    return [c for c in CHANNELS if c not in SWITCHES and c != "target"] + ["switches"]


def current_percent(n: float) -> float:
    """AP 180 scaling factor n (0...31: 1/32 ... 32/32) as % of the module's maximum current."""
    return (n + 1) * 100.0 / 32


def plan(trace: Trace, channels: Iterable[str] = DEFAULT_CHANNELS, *, rpm: bool = False,
         phases: bool = False, marks: bool = True, target: bool = True, title: str | None = None) -> Figure:
    """The figure for `trace`: one panel per channel (less those no axis has), one line per axis."""
    if not len(trace):
        raise TraceError("the trace has no samples")
    breaks = {ax: _breaks(trace, ax) for ax in trace.axes}
    panels = []
    for ch in _panels(trace, list(channels)):
        if ch == "switches":
            panels.append(_switches(trace))
            continue
        panel = _panel(trace, ch, rpm, breaks, target)
        if ch == "velocity" and phases:
            panel.spans = [s for n, ax in enumerate(trace.axes)
                           for s in ramp_phases(trace, ax, breaks[ax], _band(n, len(trace.axes)))]
        panels.append(panel)
    which = f"axis {trace.axes[0]}" if len(trace.axes) == 1 else f"axes {', '.join(map(str, trace.axes))}"
    duration = trace.time[-1] - trace.time[0]
    shown = thin_marks(trace.marks, duration)[:MAX_DRAWN] if marks else []
    return Figure(title or f"{trace.module or 'module'}: {which}", panels, shown,
                  labels=mark_labels(shown, duration), xlim=(trace.time[0], trace.time[-1]))


def thin_marks(marks: list[Mark], duration: float) -> list[Mark]:
    """The marks worth a line: a mark whose address already had a mark less than LABEL_GAP of the
    duration before is left out, so a loop the program spins in (polling) is marked once per
    address, not at every sample."""
    gap = duration * LABEL_GAP
    last: dict[int, float] = {}
    out = []
    for m in marks:
        seen = last.get(m.pc)
        last[m.pc] = m.time
        if seen is None or m.time - seen >= gap:
            out.append(m)
    return out


def mark_labels(marks: list[Mark], duration: float) -> list[int]:
    """The marks that get their text: each at least LABEL_GAP of the duration after the previous
    labelled one and before the next mark (of marks closer together the last, which held longest,
    is named); none when there are more than MAX_LABELLED."""
    gap = duration * LABEL_GAP
    out: list[int] = []
    for i, m in enumerate(marks):
        if i + 1 < len(marks) and marks[i + 1].time - m.time < gap:
            continue
        if out and m.time - marks[out[-1]].time < gap:
            continue
        out.append(i)
    return out if len(out) <= MAX_LABELLED else []


def _panels(trace: Trace, wanted: list[str]) -> list[str]:
    """The channels asked for, less those no axis of the trace has (e.g. no load value), unless
    that leaves none."""
    for ch in wanted:
        if ch not in channel_names():
            raise TraceError(f"unknown channel {ch!r}; channels: {', '.join(channel_names())}")
    return [ch for ch in wanted
            if ch == "switches" or any(trace.has(ax, ch) for ax in trace.axes)] or wanted


def _breaks(trace: Trace, ax: int) -> list[Event]:
    """The axis's events, or (a trace without events) the origin writes its samples imply."""
    if trace.events is not None:
        return sorted((e for e in trace.events if e.axis == ax), key=lambda e: e.time)
    return guess_origins(list(trace.time), trace.column(ax, "position"), trace.column(ax, "velocity"), ax)


def _scale(trace: Trace, ax: int, ch: str, rpm: bool) -> Callable[[float], float]:
    if ch == "velocity" and rpm:
        usteps, fullsteps = trace.microsteps.get(ax, (256, 200))
        return lambda v: v * 60.0 / (usteps * fullsteps)
    if ch == "current":
        return current_percent
    return float


def _panel(trace: Trace, ch: str, rpm: bool, breaks: dict[int, list[Event]], target: bool) -> Panel:
    kind = {"position": ORIGIN, "velocity": HARD_STOP}.get(ch)
    key = "rpm" if ch == "velocity" and rpm else ch
    panel = Panel(ch, _ylabel(ch, rpm))
    t = list(trace.time)
    for ax in trace.axes:
        f = _scale(trace, ax, ch, rpm)
        cuts = [e for e in breaks[ax] if e.kind == kind]
        ys = trace.column(ax, ch)
        if ch == "acceleration":
            ys = _drop_across(t, ys, [e for e in breaks[ax] if e.kind == HARD_STOP])
        x, y = broken(t, [None if v is None else f(v) for v in ys],
                      [(e.time, _opt(f, e.before), _opt(f, e.after)) for e in cuts])
        panel.lines.append(Line(f"axis {ax}", x, y, ax, steps=ch in ("load", "current")))
        panel.markers += [Marker(e.time, e.kind, _marker_text(e), ax) for e in cuts]
        if ch == "position" and target and trace.has(ax, "target"):   # an origin write may move it too
            tx, ty = broken(t, trace.column(ax, "target"), [(e.time, None, None) for e in cuts])
            panel.lines.append(Line(f"axis {ax} target (AP 0)", tx, ty, ax, steps=True, dashed=True))
    panel.ylim = span([v for line in panel.lines for v in line.y], MIN_SPAN[key], LIMITS.get(ch))
    if ch == "current":
        panel.raw = ("AP 180 n", 32 / 100.0, -1.0)
    panel.legend = len(panel.lines) > 1
    return panel


def _ylabel(ch: str, rpm: bool) -> str:
    if ch == "velocity":
        return "velocity [rpm]" if rpm else "velocity [pps]"
    return {"position": "position [µsteps]", "acceleration": "acceleration [pps²]",
            "load": "load value [0…1023]", "current": "current [% of module max.]",
            "encoder": "encoder position (AP 209)", "stage": "stage position [µsteps]"}[ch]


def _opt(f: Callable[[float], float], v: float | None) -> float | None:
    return None if v is None else f(v)


def _marker_text(e: Event) -> str:
    if e.kind == ORIGIN:
        return "origin" if e.after is None else f"AP 1 := {e.after:g}"
    return "hard stop"


def broken(t: list[float], ys: list[float | None],
           cuts: list[tuple[float, float | None, float | None]]) -> tuple[list[float], list[float]]:
    """x and y of a curve with a gap at each cut (time, value before, value after): the curve runs
    to (time, before), stops, and goes on from (time, after); unknown values: the gap spans the
    sampling interval. Cuts outside (t[0], t[-1]] are ignored; None samples become NaN."""
    cuts = sorted(c for c in cuts if t and t[0] < c[0] <= t[-1])
    x: list[float] = []
    y: list[float] = []
    k = 0
    for i, ti in enumerate(t):
        while k < len(cuts) and i and cuts[k][0] <= ti:
            tc, before, after = cuts[k]
            pts = ([(tc, before)] if before is not None else []) + [(tc, NAN)]
            pts += [(tc, after)] if after is not None else []
            for px, py in pts:
                x.append(px)
                y.append(py)
            k += 1
        v = ys[i]
        x.append(ti)
        y.append(NAN if v is None else float(v))
    return x, y


def _drop_across(t: list[float], ys: list[float | None], stops: list[Event]) -> list[float | None]:
    """Acceleration samples whose interval holds a hard stop are no acceleration: None."""
    out = list(ys)
    for e in stops:
        for i in range(1, len(t)):
            if t[i - 1] < e.time <= t[i]:
                out[i] = None
    return out


def span(values: Iterable[float], minimum: float, limits: tuple[float, float] | None = None
         ) -> tuple[float, float] | None:
    """The y range of a panel: the data's range plus MARGIN on each side, widened about its middle
    to at least `minimum`, and moved (not shrunk) into `limits` (a reading's range, plus MARGIN of
    `minimum`). None without a finite value."""
    finite = [v for v in values if math.isfinite(v)]
    if not finite:
        return None
    lo, hi = min(finite), max(finite)
    pad = (hi - lo) * MARGIN
    lo, hi = lo - pad, hi + pad
    if hi - lo < minimum:
        mid = (lo + hi) / 2
        lo, hi = mid - minimum / 2, mid + minimum / 2
    if limits is not None:   # widened by MARGIN of `minimum`: a line on the bound stays visible
        bottom, top = limits[0] - minimum * MARGIN, limits[1] + minimum * MARGIN
        if lo < bottom:
            lo, hi = bottom, hi + (bottom - lo)
        if hi > top:
            lo, hi = max(bottom, lo - (hi - top)), top
    return lo, hi


def _band(n: int, count: int) -> tuple[float, float]:
    """Axis number n of `count` gets a horizontal band of the panel (the first at the top)."""
    return 1 - (n + 1) / count, 1 - n / count


def ramp_phases(trace: Trace, ax: int, breaks: Iterable[Event] = (),
                band: tuple[float, float] = (0.0, 1.0)) -> list[Span]:
    """Ramp phases of one axis from its actual speed: between two samples the motor accelerates
    when |v| grows, decelerates when it shrinks, runs at constant speed when it stays the same and
    is not 0. Intervals holding a hard stop, a standstill or a missing value have no phase;
    neighbouring intervals of one phase are one span."""
    t, v = list(trace.time), trace.column(ax, "velocity")
    stops = [e.time for e in breaks if e.kind == HARD_STOP]
    spans: list[Span] = []
    for i in range(1, len(t)):
        phase = _phase(v[i - 1], v[i])
        if phase is None or any(t[i - 1] < s <= t[i] for s in stops):
            continue
        if spans and spans[-1].phase == phase and spans[-1].end == t[i - 1]:
            spans[-1].end = t[i]
        else:
            spans.append(Span(t[i - 1], t[i], phase, ax, band))
    return spans


def _phase(a: float | None, b: float | None) -> str | None:
    if a is None or b is None:
        return None
    a, b = abs(a), abs(b)
    if b > a:
        return "accelerating"
    if b < a:
        return "decelerating"
    return "constant" if a else None


def _switches(trace: Trace) -> Panel:
    """Stacked 0/1 steps: one row per (axis, switch), named on the y axis."""
    ticks: list[tuple[float, str]] = []
    panel = Panel("switches", "switches", yticks=ticks)
    t, row = list(trace.time), 0
    for ax in trace.axes:
        for ch in SWITCHES:
            if not trace.has(ax, ch):
                continue
            ys = [None if v is None else row * 1.5 + (0.9 if v else 0.0) for v in trace.column(ax, ch)]
            x, y = broken(t, ys, [])
            name = f"{ch.replace('_', ' ')} {ax}"
            panel.lines.append(Line(name, x, y, ax, steps=True))
            ticks.append((row * 1.5 + 0.45, name))
            row += 1
    panel.ylim = (-0.3, max(row, 1) * 1.5 - 0.3)
    return panel
