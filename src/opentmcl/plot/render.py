"""Draw a `Figure` (plot/figure.py) with matplotlib (Agg backend, no display): one panel per
channel, one line per axis; breaks and instruction marks as vertical lines, ramp phases as shaded
bands, the legend right of the data. Everything drawn comes from the figure's data.
"""
from __future__ import annotations

import io
import os
from collections.abc import Iterable
from typing import TYPE_CHECKING

from ..atomicfile import write_atomic
from ..trace import Trace, TraceError
from .figure import DEFAULT_CHANNELS, PHASES, Figure, Panel, channel_names, plan

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["DEFAULT_CHANNELS", "FORMATS", "channel_names", "draw", "render"]

FORMATS = {".png": "png", ".svg": "svg"}
PHASE_COLOURS = dict(zip(PHASES, ("tab:green", "tab:gray", "tab:red"), strict=True))
BREAK_STYLE = {"origin": ("tab:purple", ":"), "hard_stop": ("black", "--")}


def render(trace: Trace, path: str | os.PathLike, *, channels: Iterable[str] = DEFAULT_CHANNELS,
           rpm: bool = False, title: str | None = None, width: float = 9.0, phases: bool = False,
           marks: bool = True, target: bool = True) -> str:
    """Write the plot of `trace` to `path` (.png or .svg); return the format used. `phases`: shade
    the ramp phases in the velocity panel; `marks`: the instruction marks of a program run;
    `target`: the target position (AP 0) over the position."""
    fmt = FORMATS.get(os.path.splitext(str(path))[1].lower())
    if fmt is None:
        raise TraceError(f"cannot write {path}: use a .png or .svg file name")
    figure = plan(trace, channels, rpm=rpm, phases=phases, marks=marks, target=target, title=title)
    write_atomic(path, draw(figure, fmt, width=width))   # a failed or killed render keeps the old image
    return fmt


def draw(figure: Figure, fmt: str = "png", *, width: float = 9.0) -> bytes:
    """The image bytes of `figure` in `fmt` ("png" or "svg")."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    from matplotlib.figure import Figure as MplFigure

    panels = figure.panels
    fig = MplFigure(figsize=(width, 1.9 * len(panels) + 0.6), layout="constrained")
    axs = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    for n, (ax, panel) in enumerate(zip(axs, panels, strict=True)):
        _panel(ax, panel, figure)
        _marks(ax, figure, label=n == 0)
    axs[-1].set_xlabel(figure.xlabel)
    fig.suptitle(figure.title)
    image = io.BytesIO()
    fig.savefig(image, format=fmt, dpi=110)
    return image.getvalue()


def _panel(ax: Axes, panel: Panel, figure: Figure) -> None:
    for s in panel.spans:
        ax.axvspan(s.start, s.end, ymin=s.band[0], ymax=s.band[1], color=PHASE_COLOURS[s.phase],
                   alpha=0.15, linewidth=0)
    for line in panel.lines:
        ax.plot(line.x, line.y, label=line.label, drawstyle="steps-post" if line.steps else "default",
                linestyle="--" if line.dashed else "-", linewidth=0.9 if line.dashed else 1.2)
    t0, t1 = figure.xlim
    for m in panel.markers:
        colour, style = BREAK_STYLE.get(m.kind, ("black", ":"))
        ax.axvline(m.time, color=colour, linestyle=style, linewidth=0.9)
        right = m.time > (t0 + t1) / 2   # text on the side with room, inside the panel
        ax.annotate(m.text, (m.time, 1.0), xycoords=("data", "axes fraction"), xytext=(-2 if right else 2, -2),
                    textcoords="offset points", va="top", ha="right" if right else "left",
                    fontsize="x-small", color=colour)
    if panel.ylim is not None:
        ax.set_ylim(*panel.ylim)
    if panel.yticks is not None:
        ax.set_yticks([y for y, _ in panel.yticks], [name for _, name in panel.yticks], fontsize="small")
        ax.grid(True, axis="x", alpha=0.3)
    else:
        ax.grid(True, alpha=0.3)
    ax.set_ylabel(panel.ylabel)
    if panel.raw is not None:
        label, scale, offset = panel.raw

        def to_raw(y):
            return y * scale + offset

        def from_raw(r):
            return (r - offset) / scale

        from matplotlib.ticker import MaxNLocator

        raw = ax.secondary_yaxis("right", functions=(to_raw, from_raw))
        raw.set_ylabel(label)
        raw.yaxis.set_major_locator(MaxNLocator(integer=True))   # the raw reading is a whole number
    _legend(ax, panel)


def _legend(ax: Axes, panel: Panel) -> None:
    from matplotlib.patches import Patch

    handles, labels = ax.get_legend_handles_labels()
    for phase in PHASES:
        if any(s.phase == phase for s in panel.spans):
            handles.append(Patch(color=PHASE_COLOURS[phase], alpha=0.3))
            labels.append(phase)
    if panel.legend or panel.spans:
        ax.legend(handles, labels, loc="upper left", bbox_to_anchor=panel.legend_anchor,
                  borderaxespad=0.0, fontsize="small")


def _marks(ax: Axes, figure: Figure, *, label: bool) -> None:
    named = set(figure.labels) if label else set()
    for i, m in enumerate(figure.marks):
        ax.axvline(m.time, color="tab:olive", linestyle=":", linewidth=0.6, alpha=0.8)
        if i in named:
            ax.annotate(f"{m.pc}: {m.text}".rstrip(": "), (m.time, 1.0), xycoords=("data", "axes fraction"),
                        xytext=(1, 3), textcoords="offset points", rotation=90, va="bottom",
                        fontsize="xx-small", color="tab:olive")
