"""Plots of axis motion: record a trace (virtual run or any module), save it as CSV, render PNG/SVG.

    from opentmcl.plot import run_virtual, render, plan
    trace = run_virtual(assemble(src), module="TMCM-6212", axes=[0])   # until it stops or loops twice
    render(trace, "move.png", phases=True)
    plan(trace).panels[0].lines        # the data the picture is drawn from

See docs/plots.md.
"""
from ..trace import CHANNELS, Event, Mark, Trace, TraceError, derivative
from .figure import DEFAULT_CHANNELS, Figure, Panel, channel_names, plan
from .program import record_program
from .recording import Sampler, record
from .render import draw, render
from .virtual import run_virtual

__all__ = ["CHANNELS", "DEFAULT_CHANNELS", "Event", "Figure", "Mark", "Panel", "Sampler", "Trace", "TraceError",
           "channel_names", "derivative", "draw", "plan", "record", "record_program", "render", "run_virtual"]
