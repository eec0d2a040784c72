"""Record a trace from a virtual run: a TMCL program and/or a scenario on an in-process module.

The run uses virtual time (docs/architecture.md "Time"): the module advances only while the recorder
waits, so a ten-second program is recorded in a fraction of that and always gives the same
trace. The program is downloaded (132, instructions, 133) and started with 129 (TMCM-6212
manual 3.6.36), as `opentmcl run` does; plot/program.py records it.
"""
from __future__ import annotations

from ..trace import Trace
from .program import SETTLE_SAMPLES, idle, record_program

__all__ = ["SETTLE_SAMPLES", "run_virtual"]


def _stopped(module, loader, axes):
    """until(): the program no longer runs and every recorded axis has stood still for a while."""
    def done(trace: Trace) -> bool:
        if loader is not None and loader.status().mode == 1:
            return False
        return idle(trace)
    return done


def run_virtual(program=None, *, module: str = "TMCM-6212", axes=(0,), seconds: float | None = None,
                interval: float = 0.01, scenario=None, address: int = 1, vm=None,
                stop_when_idle: bool = True, loops: int | None = None) -> Trace:
    """Run `program` (a lang `Program`'s instructions, a list of 4-tuples, or None) on a new virtual
    `module` (or the given `vm`) with an optional loaded `scenario`, and return the trace of `axes`
    with the module's origin writes and hard stops (`Trace.events`) and the program's marks.

    The recording ends after `seconds`, or - with `stop_when_idle` - once the program has stopped
    and the recorded axes stand still, or after `loops` loop passes. `seconds=None`: as long as the
    program needs (until it stops or has looped twice, at most plot.program.AUTO_SECONDS).
    """
    from ..firmware.vm import VirtualModule
    from ..host import Client
    from ..host.transports.inprocess import InProcessTransport

    if vm is None:
        vm = VirtualModule(module, address=address, scenario=scenario)
    # A module in virtual time answers at once: a reply missing for `interval` is a module that is
    # off or hung (docs/faults.md), a gap of one sample in the trace, not seconds of it.
    client = Client(InProcessTransport(vm, clock="virtual"), address=vm.address, timeout=interval)
    try:
        m = client.module(vm.address, vm.profile)
        return record_program(m, program, axes, seconds, interval, stop_when_idle=stop_when_idle, loops=loops)
    finally:
        client.close()
