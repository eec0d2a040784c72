"""Record a trace from a virtual run: a TMCL program and/or a scenario on an in-process module.

The run uses virtual time (docs/architecture.md "Time"): the module advances only while the recorder
waits, so a ten-second program is recorded in a fraction of that and always gives the same
trace. The program is downloaded (132, instructions, 133) and started with 129 (TMCM-6212
manual 3.6.36), as `opentmcl run` does.
"""
from __future__ import annotations

from .trace import Trace, record

SETTLE_SAMPLES = 5  # samples of standstill after the program stopped before the recording ends


def _stopped(module, loader, axes):
    """until(): the program no longer runs and every recorded axis has stood still for a while."""
    def done(trace: Trace) -> bool:
        if loader is not None and loader.status().mode == 1:
            return False
        if len(trace) < SETTLE_SAMPLES:
            return False
        for ax in axes:
            tail = trace.column(ax, "velocity")[-SETTLE_SAMPLES:]
            if any(v not in (0, None) for v in tail):
                return False
        return True
    return done


def run_virtual(program=None, *, module: str = "TMCM-6212", axes=(0,), seconds: float = 10.0,
                interval: float = 0.01, scenario=None, address: int = 1, vm=None,
                stop_when_idle: bool = True) -> Trace:
    """Run `program` (a lang `Program`, a list of 4-tuples, or None) on a new virtual `module`
    (or the given `vm`) with an optional loaded `scenario`, and return the trace of `axes`.

    The recording ends after `seconds`, or - with `stop_when_idle` - once the program has
    stopped and the recorded axes stand still.
    """
    from ..firmware.vm import VirtualModule
    from ..host import Client
    from ..host.loader import Loader
    from ..host.transports.inprocess import InProcessTransport

    if vm is None:
        vm = VirtualModule(module, address=address, scenario=scenario)
    client = Client(InProcessTransport(vm, clock="virtual"), address=vm.address)
    try:
        m = client.module(vm.address, vm.profile)
        loader = None
        if program is not None:
            loader = Loader(m)
            loader.download(program)
            loader.run(0)
        until = _stopped(m, loader, list(axes)) if stop_when_idle else None
        return record(m, axes, seconds, interval, until=until)
    finally:
        client.close()
