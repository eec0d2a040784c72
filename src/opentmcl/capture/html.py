"""The replay report as one self-contained HTML page (`replay --html DIR`, docs/capture.md "Reports").

Root causes come first, each with the divergences it explains folded beneath; then the agreement
score of every area, the move durations of the module against the twin's, and per axis a plot of
the module's against the twin's position and speed over time. The plots are inline SVG drawn here
(no plotting library, no script, nothing fetched): the page opens from disk in any browser.
"""
from __future__ import annotations

import html
import os
from pathlib import Path
from typing import TYPE_CHECKING

from ..atomicfile import write_atomic

if TYPE_CHECKING:
    from .outcome import ReplayReport

WIDTH, HEIGHT = 640, 220
MARGIN = (58, 14, 16, 30)   # left, right, top, bottom
MAX_POINTS = 1500
"""Most points drawn per series (evenly thinned beyond)."""
MODULE_COLOUR, TWIN_COLOUR = "#d62728", "#1f77b4"

_CSS = """
body{font-family:system-ui,sans-serif;margin:1.5em;max-width:1400px;color:#222}
h1{font-size:1.4em} h2{font-size:1.15em;margin-top:1.6em;border-bottom:1px solid #ccc}
.ok{color:#1a7f37} .bad{color:#b42318} table{border-collapse:collapse;margin:.5em 0}
td,th{border:1px solid #ccc;padding:.25em .6em;text-align:right} th{background:#f4f4f4}
td.l,th.l{text-align:left} .cause{margin:.6em 0} .root{font-family:monospace}
.knock{font-family:monospace;font-size:.9em;color:#555;margin-left:1.5em}
.note{color:#555} .bar{display:inline-block;height:.8em;background:#1a7f37;vertical-align:middle}
.barbg{display:inline-block;width:120px;height:.8em;background:#f3d1cf;vertical-align:middle}
figure{display:inline-block;margin:.4em 1em .4em 0} figcaption{font-size:.9em;color:#444}
svg text{font-size:11px;font-family:system-ui,sans-serif}
"""


def _e(x: object) -> str:
    return html.escape(str(x))


def _ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    if hi <= lo:
        return [lo]
    step = (hi - lo) / (n - 1)
    return [lo + i * step for i in range(n)]


def _thin(points: list, limit: int = MAX_POINTS) -> list:
    if len(points) <= limit:
        return points
    stride = len(points) / limit
    return [points[int(i * stride)] for i in range(limit)] + [points[-1]]


def svg_plot(series: list[tuple[str, list[tuple[float, float]], str, str]], title: str, unit: str) -> str:
    """An SVG chart: `series` of (label, [(t, y)], colour, "line"|"dots") against time in seconds."""
    pts = [p for _, points, _, _ in series for p in points]
    left, right, top, bottom = MARGIN
    w, h = WIDTH - left - right, HEIGHT - top - bottom
    if not pts:
        return (f'<svg class="plot" width="{WIDTH}" height="{HEIGHT}" role="img" aria-label="{_e(title)}">'
                f'<text x="{left}" y="{HEIGHT / 2}">no {_e(unit)} readings</text></svg>')
    t0, t1 = min(p[0] for p in pts), max(p[0] for p in pts)
    y0, y1 = min(p[1] for p in pts), max(p[1] for p in pts)
    if t1 == t0:
        t1 = t0 + 1
    if y1 == y0:
        y0, y1 = y0 - 1, y1 + 1
    pad = (y1 - y0) * 0.05
    y0, y1 = y0 - pad, y1 + pad

    def x_of(t: float) -> float:
        return left + (t - t0) / (t1 - t0) * w

    def y_of(y: float) -> float:
        return top + (1 - (y - y0) / (y1 - y0)) * h

    out = [f'<svg class="plot" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" '
           f'role="img" aria-label="{_e(title)}" xmlns="http://www.w3.org/2000/svg">',
           f'<rect x="{left}" y="{top}" width="{w}" height="{h}" fill="#fff" stroke="#999"/>']
    for t in _ticks(t0, t1):
        out.append(f'<line x1="{x_of(t):.1f}" y1="{top + h}" x2="{x_of(t):.1f}" y2="{top + h + 4}" stroke="#999"/>'
                   f'<text x="{x_of(t):.1f}" y="{top + h + 15}" text-anchor="middle">{t:.2f}</text>')
    for y in _ticks(y0, y1):
        out.append(f'<line x1="{left - 4}" y1="{y_of(y):.1f}" x2="{left + w}" y2="{y_of(y):.1f}" stroke="#eee"/>'
                   f'<text x="{left - 6}" y="{y_of(y) + 4:.1f}" text-anchor="end">{y:.0f}</text>')
    out.append(f'<text x="{left + w}" y="{HEIGHT - 2}" text-anchor="end">time s</text>')
    for i, (label, points, colour, style) in enumerate(series):
        points = _thin(sorted(points))
        if style == "line" and points:
            path = " ".join(f"{x_of(t):.1f},{y_of(y):.1f}" for t, y in points)
            out.append(f'<polyline class="series twin" fill="none" stroke="{colour}" stroke-width="1.5" '
                       f'points="{path}"/>')
        else:
            out += [f'<circle class="series module" cx="{x_of(t):.1f}" cy="{y_of(y):.1f}" r="2" fill="{colour}"/>'
                    for t, y in points]
        out.append(f'<text x="{left + 8}" y="{top + 14 + 14 * i}" fill="{colour}">{_e(label)}</text>')
    out.append("</svg>")
    return "".join(out)


def _areas(report: ReplayReport) -> str:
    rows = []
    for area, (ok, total) in report.areas.items():
        if not total:
            rows.append(f'<tr><td class="l">{_e(area)}</td><td colspan="3" class="l note">not checked</td></tr>')
            continue
        score = ok / total
        cls = "ok" if ok == total else "bad"
        rows.append(f'<tr><td class="l">{_e(area)}</td><td class="{cls}">{score * 100:.1f} %</td>'
                    f'<td>{ok} / {total}</td><td><span class="barbg"><span class="bar" '
                    f'style="width:{score * 120:.0f}px"></span></span></td></tr>')
    return ('<table id="areas"><tr><th class="l">area</th><th>agreement</th><th>checks</th><th></th></tr>'
            + "".join(rows) + "</table>")


def _causes(report: ReplayReport) -> str:
    if not report.causes:
        return '<p id="causes" class="ok">No divergence: every reply of the module lies where the twin puts it.</p>'
    items = []
    for cause in report.causes:
        more = cause.repeats + cause.knock_on
        folded = ""
        if more:
            lines = "".join(f'<div class="knock">{_e(d)}{" (again)" if d in cause.repeats else ""}</div>'
                            for d in sorted(more, key=lambda d: d.t))
            parts = ([f"{len(cause.repeats)} more like it"] if cause.repeats else []) + \
                ([f"{len(cause.knock_on)} knock-on divergences"] if cause.knock_on else [])
            folded = f"<details><summary>{', '.join(parts)}</summary>{lines}</details>"
        note = f'<div class="note">{_e(cause.note)}</div>' if cause.note else ""
        items.append(f'<li class="cause"><b>{_e(cause.title())}</b><div class="root">{_e(cause.root)}</div>'
                     f"{note}{folded}</li>")
    return f'<ol id="causes">{"".join(items)}</ol>'


def _moves(report: ReplayReport) -> str:
    if not report.moves:
        return '<p id="moves" class="note">No move was seen to end in the capture.</p>'
    rows = []
    for m in report.moves:
        twin_mid = m.twin_mid
        twin = "no end" if twin_mid is None else f"{twin_mid:.3f}"
        pct = "" if m.percent is None else f"{m.percent:+.1f} %"
        cls = "ok" if m.ok else "bad"
        rows.append(f'<tr class="{cls}"><td>{m.t:.3f}</td><td>{m.axis}</td><td class="l">{_e(m.request)}</td>'
                    f'<td class="l">{_e(m.kind)}</td><td>{m.real_mid:.3f} ({m.real[0]:.3f}..{m.real[1]:.3f})</td>'
                    f'<td>{twin}</td><td>{pct}</td><td class="l">{"agrees" if m.ok else "differs"}</td></tr>')
    acc = []
    for axis, kinds in sorted(report.accelerations.items()):
        for kind, (real, twin_acc) in sorted(kinds.items()):
            acc.append(f"<li>axis {axis} {kind}: module about {real:.0f} pps², twin {twin_acc:.0f} pps²</li>")
    extra = f"<ul>{''.join(acc)}</ul>" if acc else ""
    return ('<table id="moves"><tr><th>t s</th><th>axis</th><th class="l">request</th><th class="l">until</th>'
            '<th>module s</th><th>twin s</th><th>module vs twin</th><th class="l"></th></tr>'
            + "".join(rows) + "</table>" + extra)


def _moving_span(trace: dict) -> tuple[float, float] | None:
    """From a little before the axis first moves to a little after it last stops (either side)."""
    times = [t for t, _, v in trace["twin"] if v] + [t for t, v in trace["module"]["speed"] if v]
    if not times:
        return None
    lo, hi = min(times), max(times)
    margin = max(0.2, (hi - lo) * 0.05)
    return lo - margin, hi + margin


def _clip(points: list, span: tuple[float, float] | None) -> list:
    return points if span is None else [p for p in points if span[0] <= p[0] <= span[1]]


def _plots(report: ReplayReport) -> str:
    out = []
    for axis, trace in sorted(report.traces.items()):
        span = _moving_span(trace)
        module = {k: _clip(v, span) for k, v in trace["module"].items()}
        twin = _clip(trace["twin"], span)
        for key, index, unit in (("position", 1, "µsteps"), ("speed", 2, "pps")):
            series = [("twin", [(q[0], q[index]) for q in twin], TWIN_COLOUR, "line"),
                      ("module (read by the host)", module[key], MODULE_COLOUR, "dots")]
            title = f"axis {axis} {key}"
            out.append(f'<figure class="plot-{key}" data-axis="{axis}">{svg_plot(series, title, unit)}'
                       f"<figcaption>{_e(title)} ({unit}) against time</figcaption></figure>")
    return "".join(out) or '<p class="note">No axis moved in the capture.</p>'


def page(report: ReplayReport) -> str:
    verdict = ('<p id="verdict" class="ok">All replies agree.</p>' if report.ok else
               f'<p id="verdict" class="bad">{len(report.divergences)} divergences from {len(report.causes)} '
               "root causes.</p>")
    link = report.link or {}
    tol = report.tolerance
    notes = "".join(f"<li>{_e(n)}</li>" for n in report.notes)
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>Replay of {_e(os.path.basename(report.capture))}</title><style>{_CSS}</style></head><body>"
            f"<h1>Replay of {_e(report.capture)} against {_e(report.module)} at address {report.address}</h1>"
            f"{verdict}<p class=\"note\">{_e(report.summary())}<br>link: {_e(link.get('interface'))}, "
            f"{_e(link.get('baud') or 'speed unknown')} baud, {float(link.get('frame_time') or 0) * 1000:.2f} ms "
            f"per frame; tolerances: time {tol.time:g} s, position {tol.position:g}, velocity {tol.velocity:g}, "
            f"load {tol.load:g}, timer {'not compared' if tol.timer is None else f'{tol.timer:g}'}, "
            f"event latency {tol.latency:g} s</p>"
            f"<h2>Root causes</h2>{_causes(report)}"
            f"<h2>Agreement by area</h2>{_areas(report)}"
            f"<h2>Move durations</h2>{_moves(report)}"
            f"<h2>Position and speed, module against twin</h2><div id=\"plots\">{_plots(report)}</div>"
            f"<h2>Notes</h2><ul id=\"notes\">{notes}</ul></body></html>\n")


def write_html(report: ReplayReport, directory: str | os.PathLike[str]) -> Path:
    """Write DIR/index.html (the directory is made if needed); returns its path."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "index.html"
    write_atomic(path, page(report).encode("utf-8"))
    return path
