"""Plots of axis motion: record a trace (virtual run or any module), save it as CSV, render PNG/SVG.

    from opentmcl.plot import run_virtual, render
    trace = run_virtual(assemble(src), module="TMCM-6212", axes=[0], seconds=5)
    render(trace, "move.png")

See docs/plots.md.
"""
from .render import DEFAULT_CHANNELS, channel_names, render
from .trace import CHANNELS, Sampler, Trace, TraceError, derivative, record
from .virtual import run_virtual

__all__ = ["CHANNELS", "DEFAULT_CHANNELS", "Sampler", "Trace", "TraceError", "channel_names", "derivative",
           "record", "render", "run_virtual"]
