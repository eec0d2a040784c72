"""Render a trace with matplotlib (Agg backend, no display): one panel per channel, one line per axis.

Units on the axes: position in µsteps, velocity in pps (or rpm), acceleration in pps²,
time in s (TMCM-6212 manual 6.5 for pps and rpm); the stallGuard2 load value 0..1023 and the
current scaling factor n = 0..31, i.e. (n+1)/32 of the run current CS (manual 4.1, AP 206/180).
Switch states and the position reached flag share one panel, drawn as stacked 0/1 steps.
"""
from __future__ import annotations

import io
import os
from collections.abc import Iterable
from typing import TYPE_CHECKING

from ..atomicfile import write_atomic
from .trace import CHANNELS, SWITCHES, Trace, TraceError

if TYPE_CHECKING:
    from matplotlib.axes import Axes

DEFAULT_CHANNELS = ("position", "velocity", "acceleration", "load", "current", "switches")
FORMATS = {".png": "png", ".svg": "svg"}
LABELS = {
    "position": "position [µsteps]",
    "velocity": "velocity [pps]",
    "acceleration": "acceleration [pps²]",
    "load": "load [0…1023]",
    "current": "current [(n+1)/32 CS]",
}


def channel_names() -> list[str]:
    return [c for c in CHANNELS if c not in SWITCHES] + ["switches"]


def render(trace: Trace, path: str | os.PathLike, *, channels: Iterable[str] = DEFAULT_CHANNELS,
           rpm: bool = False, title: str | None = None, width: float = 9.0) -> str:
    """Write the plot to `path` (.png or .svg); return the format used."""
    fmt = FORMATS.get(os.path.splitext(str(path))[1].lower())
    if fmt is None:
        raise TraceError(f"cannot write {path}: use a .png or .svg file name")
    if not len(trace):
        raise TraceError("the trace has no samples")
    panels = _panels(trace, list(channels))

    import matplotlib

    matplotlib.use("Agg", force=True)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, 1.9 * len(panels) + 0.6), layout="constrained")
    axs = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    for panel, ch in zip(axs, panels, strict=True):
        if ch == "switches":
            _switches(panel, trace)
        else:
            _channel(panel, trace, ch, rpm)
    axs[-1].set_xlabel("time [s]")
    which = f"axis {trace.axes[0]}" if len(trace.axes) == 1 else f"axes {', '.join(map(str, trace.axes))}"
    fig.suptitle(title or f"{trace.module or 'module'}: {which}")
    image = io.BytesIO()
    fig.savefig(image, format=fmt, dpi=110)
    write_atomic(path, image.getvalue())   # a failed or killed render keeps the old image
    return fmt


def _panels(trace: Trace, wanted: list[str]) -> list[str]:
    """The panels to draw: the channels asked for, less those no axis of the trace has (e.g. no
    load value), unless that leaves none."""
    for ch in wanted:
        if ch not in channel_names():
            raise TraceError(f"unknown channel {ch!r}; channels: {', '.join(channel_names())}")
    return [ch for ch in wanted
            if ch == "switches" or any(trace.has(ax, ch) for ax in trace.axes)] or wanted


def _channel(panel: Axes, trace: Trace, ch: str, rpm: bool) -> None:
    """One line per axis of channel `ch` (velocity in rpm when `rpm`)."""
    for ax in trace.axes:
        ys = trace.rpm(ax) if ch == "velocity" and rpm else trace.column(ax, ch)
        panel.plot(trace.time, [float("nan") if y is None else y for y in ys], label=f"axis {ax}",
                   drawstyle="steps-post" if ch in ("load", "current") else "default", linewidth=1.2)
    panel.set_ylabel("velocity [rpm]" if ch == "velocity" and rpm else LABELS[ch])
    panel.grid(True, alpha=0.3)
    if len(trace.axes) > 1:
        panel.legend(loc="upper right", fontsize="small")


def _switches(panel: Axes, trace: Trace) -> None:
    """Stacked 0/1 traces: one row per (axis, switch), labelled on the y axis."""
    labels, row = [], 0
    for ax in trace.axes:
        for ch in SWITCHES:
            if not trace.has(ax, ch):
                continue
            ys = [float("nan") if v is None else row * 1.5 + (0.9 if v else 0.0) for v in trace.column(ax, ch)]
            panel.plot(trace.time, ys, drawstyle="steps-post", linewidth=1.2)
            labels.append((row * 1.5 + 0.45, f"{ch.replace('_', ' ')} {ax}"))
            row += 1
    panel.set_yticks([y for y, _ in labels], [name for _, name in labels], fontsize="small")
    panel.set_ylabel("switches")
    panel.grid(True, axis="x", alpha=0.3)
