"""Recording a trace of any module through the host library (so the same code works on a real
module, a served one and sim://).

    trace = record(module, axes=[0], seconds=5, interval=0.01)
    trace.to_csv("run.csv"); Trace.from_csv("run.csv").column(0, "velocity")

Every sample reads, per axis, the channels of HOST_CHANNELS the module has (opentmcl/trace.py):
actual position (axis parameter 1, µsteps), target position (0), actual speed (3), position
reached (8), home / right / left switch (9, 10, 11), actual load value (206) and the actual motor
current (180, "smartEnergy actual current"); the names are those of the TMCM-6212 manual 4.1 /
PD86-1180 manual 5. On TMC429 modules (PD86-1180) the trace keeps the internal velocity with the
pulse divisor (axis parameter 154, PD86-1180 manual 5) and gives it in pps. The samples go into
the one `Trace` (opentmcl.trace): one hour at 10 ms of six axes takes well under 100 MB
(`python bench/bench_trace.py`, "plot trace MB per hour").
"""
from __future__ import annotations

from ..trace import CHANNELS, HOST_CHANNELS, MAX_SAMPLES, Trace, check_interval

__all__ = ["MAX_SAMPLES", "SILENCE", "Sampler", "check_duration", "record"]

SILENCE = 10.0
"""Seconds (the module's clock) a recording goes on while the module answers nothing."""


class Sampler:
    """Reads one sample of the chosen axes of a host `Module`; channels the profile lacks give None."""

    def __init__(self, module, axes: list[int]):
        self.module = module
        self.axes = list(axes)
        prof = module.profile
        for ax in self.axes:
            module.axis(ax)  # UnknownParameterError for an axis the module does not have
        self.params = {ch: num for ch in HOST_CHANNELS
                       if (num := CHANNELS[ch][0]) is not None and num in prof.axis_parameters}
        self.tmc429 = prof.capabilities.velocity_unit == "tmc429"
        self.pulse_div: dict[int, int] = {}
        self.microsteps: dict[int, tuple[int, int]] = {}
        for ax in self.axes:
            axis = module.axis(ax)
            if self.tmc429 and 154 in prof.axis_parameters:
                self.pulse_div[ax] = axis.get(154)
            usteps = 1 << axis.microstep_resolution() if 140 in prof.axis_parameters else 256
            self.microsteps[ax] = (usteps, axis.fullstep_resolution())

    def to_pps(self, axis: int, velocity: float) -> float:
        """A velocity in the units of actual speed (AP 3) in pps (TMC429 modules: pulse divisor)."""
        from ..host.units import tmc429_velocity_to_pps

        if axis in self.pulse_div:
            return tmc429_velocity_to_pps(velocity, self.pulse_div[axis])
        return float(velocity)

    def trace(self) -> Trace:
        """An empty trace of this sampler's axes, with the module's name and units."""
        return Trace(self.axes, module=self.module.profile.name, microsteps=self.microsteps,
                     channels=HOST_CHANNELS, pulse_div=self.pulse_div)

    def sample(self) -> dict[tuple[int, str], float | None]:
        """(axis, channel) -> the value GAP answers (velocity in the module's unit); None for a
        value refused or garbled. TmclTimeout when the module does not answer (`record`: a gap)."""
        from ..host import TmclChecksumError, TmclStatusError

        out: dict[tuple[int, str], float | None] = {}
        for ax in self.axes:
            axis = self.module.axis(ax)
            for ch, num in self.params.items():
                try:
                    value: float | None = axis.get(num)
                except (TmclStatusError, TmclChecksumError):
                    value = None
                out[(ax, ch)] = value
        return out


def check_duration(seconds: float, interval: float) -> None:
    """ValueError unless `interval` is finite > 0, `seconds` finite >= 0 and at most MAX_SAMPLES samples."""
    check_interval(seconds, interval)
    if seconds / interval > MAX_SAMPLES:
        raise ValueError(f"{seconds:g} s every {interval:g} s is more than {MAX_SAMPLES} samples; "
                         "record less or sample less often")


def record(module, axes=(0,), seconds: float = 10.0, interval: float = 0.01, *, until=None,
           sampler: Sampler | None = None) -> Trace:
    """Sample `axes` of a host `Module` every `interval` seconds for `seconds` (module time: virtual
    for sim:// modules, the wall clock for real ones). `until(trace) -> bool` may end it early.
    `sampler`: a `Sampler` of `module` made before (it reads the microstep settings when made).

    A sample the module does not answer (a power loss, a hung firmware, a lost reply: docs/faults.md)
    is a gap, its values None; after `SILENCE` seconds without an answer the time-out ends the
    recording."""
    from ..host import TmclTimeout

    check_duration(seconds, interval)
    sampler = sampler or Sampler(module, list(axes))
    trace = sampler.trace()
    clock = module.client.transport.monotonic
    start = answered = clock()
    steps = round(seconds / interval)
    for i in range(steps + 1):
        t = clock() - start
        done = False
        try:
            values = sampler.sample()
        except TmclTimeout:
            if clock() - answered > SILENCE:
                raise
            trace.add(t, {})
        else:
            trace.add(t, values)
            answered = clock()
            try:
                done = until is not None and until(trace)
            except TmclTimeout:   # the module went silent just now: the next sample tells
                pass
        if done:
            break
        if i < steps:
            module.sleep(interval)
    return trace
