"""Traces: axis quantities sampled over time from any module, saved as CSV.

    trace = record(module, axes=[0], seconds=5, interval=0.01)
    trace.to_csv("run.csv"); Trace.from_csv("run.csv").column(0, "velocity")

Every sample reads, per axis, through the host library (so the same code works on a
real module): actual position (axis parameter 1, µsteps), target position (0), actual speed (3), position
reached (8), home / right / left switch (9, 10, 11), actual load value (206) and the
actual motor current (180, "smartEnergy actual current"); the names are those of the
TMCM-6212 manual 4.1 / PD86-1180 manual 5. Velocities are stored in pps: on TMC429
modules (PD86-1180) the internal velocity is converted with the pulse divisor
(axis parameter 154, PD86-1180 manual 5). Acceleration is derived from velocity.
Samples are kept in compact columns (opentmcl.columns): one hour at 10 ms of six axes takes
about 41 MB (`python bench/bench_trace.py`, "plot trace MB per hour").
"""
from __future__ import annotations

import csv
import io
import os
from array import array
from dataclasses import dataclass, field

from ..atomicfile import open_atomic
from ..columns import Column
from ..limits import CSV_MAX, LINE_MAX, open_regular, size_text
from ..trace import check_interval
from .events import Event, Mark, meta_lines, parse_event, parse_mark

# channel -> (axis parameter number, unit). position/velocity are always recorded.
CHANNELS: dict[str, tuple[int | None, str]] = {
    "position": (1, "µsteps"),
    "target": (0, "µsteps"),
    "velocity": (3, "pps"),
    "acceleration": (None, "pps²"),
    "target_reached": (8, ""),
    "home_switch": (9, ""),
    "right_switch": (10, ""),
    "left_switch": (11, ""),
    "load": (206, ""),
    "current": (180, ""),
}
MAX_SAMPLES = 400_000  # a longer recording or CSV trace is refused (memory): 4000 s at 10 ms
RECORDED = tuple(c for c, (num, _) in CHANNELS.items() if num is not None)
SWITCHES = ("target_reached", "home_switch", "right_switch", "left_switch")


class TraceError(ValueError):
    """A trace file that cannot be read, or a channel/axis that is not in the trace."""


@dataclass
class Trace:
    """Samples over time: ``time`` (seconds) and, per (axis, channel), one value per sample.
    A channel the module does not have holds None."""

    axes: list[int]
    time: array = field(default_factory=lambda: array("d"))
    data: dict[tuple[int, str], Column] = field(default_factory=dict)
    module: str = ""
    microsteps: dict[int, tuple[int, int]] = field(default_factory=dict)  # axis -> (usteps/fullstep, fullsteps/rev)
    # Discontinuities seen by the module (origin writes, hard stops); None: not known, the renderer
    # guesses origin writes from the samples (plot/events.py).
    events: list[Event] | None = None
    marks: list[Mark] = field(default_factory=list)  # program counter changes of a program run

    def __len__(self) -> int:
        return len(self.time)

    def add(self, t: float, values: dict[tuple[int, str], float | None]) -> None:
        self.time.append(float(t))
        for ax in self.axes:
            for ch in RECORDED:
                self.data.setdefault((ax, ch), Column()).append(values.get((ax, ch)))

    def nbytes(self) -> int:
        """Bytes held by the samples (column arrays)."""
        return self.time.buffer_info()[1] * self.time.itemsize + sum(c.nbytes() for c in self.data.values())

    def column(self, axis: int, channel: str) -> list[float | None]:
        """The values of one channel; acceleration is the difference quotient of velocity."""
        if axis not in self.axes:
            raise TraceError(f"axis {axis} is not in this trace (axes {self.axes})")
        if channel == "acceleration":
            return derivative(list(self.time), self.column(axis, "velocity"))
        if channel not in CHANNELS:
            raise TraceError(f"unknown channel {channel!r}; channels: {', '.join(CHANNELS)}")
        col = self.data.get((axis, channel))
        return col.tolist() if col is not None else [None] * len(self.time)

    def has(self, axis: int, channel: str) -> bool:
        if channel == "acceleration":
            channel = "velocity"
        return any(v is not None for v in self.data.get((axis, channel), ()))

    def rpm(self, axis: int) -> list[float | None]:
        """Velocity in revolutions per minute: pps / (microsteps per full step * full steps per turn) * 60."""
        usteps, fullsteps = self.microsteps.get(axis, (256, 200))
        return [None if v is None else v * 60.0 / (usteps * fullsteps) for v in self.column(axis, "velocity")]

    # --- CSV -------------------------------------------------------------------------
    def to_csv(self, target: str | os.PathLike | io.TextIOBase) -> None:
        """Columns ``time_s`` then ``<channel>_<axis>`` for every recorded channel."""
        header = ["time_s"] + [f"{ch}_{ax}" for ax in self.axes for ch in RECORDED]
        cols = [self.data[(ax, ch)] for ax in self.axes for ch in RECORDED]
        rows = ([f"{t:.6f}"] + ["" if v is None else _fmt(v) for v in values]
                for t, *values in zip(self.time, *cols, strict=True))   # streamed, not a list
        meta = [f"# module={self.module}"] + [f"# microsteps_{ax}={u},{f}" for ax, (u, f) in self.microsteps.items()]
        meta += meta_lines(self)
        if isinstance(target, io.TextIOBase):
            _write(target, meta, header, rows)
            return
        with open_atomic(target, text=True) as fh:   # a failed or killed write keeps the old file
            _write(fh, meta, header, rows)

    @classmethod
    def from_csv(cls, source: str | os.PathLike | io.TextIOBase) -> Trace:
        """Read a trace written by `to_csv` (or any CSV with ``time_s`` and ``position_N`` columns).
        Read line by line: at most CSV_MAX bytes, LINE_MAX per line and MAX_SAMPLES rows."""
        if isinstance(source, io.TextIOBase):
            return _parse_csv(_lines(source, "the trace"))
        try:
            with io.TextIOWrapper(open_regular(source), encoding="utf-8", newline="") as fh:
                return _parse_csv(_lines(fh, str(source)))
        except OSError as exc:
            raise TraceError(f"cannot read {source}: {exc.strerror or exc}") from None
        except UnicodeDecodeError:
            raise TraceError(f"cannot read {source}: not a text (UTF-8) file") from None


def _lines(fh, name: str):
    """The lines of a text file, each at most LINE_MAX characters, CSV_MAX in all."""
    total = 0
    while line := fh.readline(LINE_MAX + 1):
        total += len(line)
        if len(line) > LINE_MAX:
            raise TraceError(f"cannot read {name}: a line longer than {size_text(LINE_MAX)}")
        if total > CSV_MAX:
            raise TraceError(f"cannot read {name}: larger than the {size_text(CSV_MAX)} limit")
        yield line.rstrip("\r\n")


def _fmt(v: float) -> str:
    return str(int(v)) if float(v).is_integer() else f"{v:.6g}"


def _write(fh, meta, header, rows) -> None:
    for line in meta:
        fh.write(line + "\n")
    w = csv.writer(fh, lineterminator="\n")
    w.writerow(header)
    w.writerows(rows)


def _parse_csv(lines) -> Trace:
    meta: dict[str, str] = {}
    repeated: list[tuple[str, str]] = []   # event / mark lines, in order

    def data_lines():
        for line in lines:
            if line.startswith("#"):
                key, _, value = line[1:].strip().partition("=")
                meta[key] = value
                repeated.append((key, value))
            elif line.strip():
                yield line

    rows = csv.reader(data_lines())
    header = next(rows, None)
    if not header or header[0] != "time_s":
        raise TraceError("not a trace: the first column must be time_s")
    columns: dict[tuple[int, str], int] = {}
    for i, name in enumerate(header[1:], start=1):
        ch, _, ax = name.rpartition("_")
        if ch not in RECORDED or not ax.isdigit():
            raise TraceError(f"unknown trace column {name!r}")
        columns[(int(ax), ch)] = i
    axes = sorted({ax for ax, _ in columns})
    if not axes:
        raise TraceError("the trace has no axis columns")
    trace = Trace(axes)
    for n, row in enumerate(rows, start=2):
        if len(row) != len(header):
            raise TraceError(f"trace row {n} has {len(row)} fields, expected {len(header)}")
        if len(trace) >= MAX_SAMPLES:
            raise TraceError(f"the trace has more than {MAX_SAMPLES} samples (the limit)")
        try:
            t = float(row[0])
            values = {key: (float(row[i]) if row[i] != "" else None) for key, i in columns.items()}
        except ValueError:
            raise TraceError(f"trace row {n}: not a number") from None
        trace.add(t, values)
    trace.module = meta.get("module", "")
    _read_events(trace, repeated)
    for key, value in meta.items():
        if key.startswith("microsteps_"):
            try:
                u, f = (int(x) for x in value.split(","))
                trace.microsteps[int(key.split("_")[1])] = (u, f)
            except ValueError:
                raise TraceError(f"bad trace metadata line {'# ' + key + '=' + value!r}") from None
    return trace


def _read_events(trace: Trace, lines: list[tuple[str, str]]) -> None:
    """The ``# events=``, ``# event=`` and ``# mark=`` lines (plot/events.py) into `trace`."""
    for key, value in lines:
        try:
            if key == "events" and trace.events is None:
                trace.events = []
            elif key == "mark":
                trace.marks.append(parse_mark(value))
            elif key == "event":
                if trace.events is None:
                    raise TraceError("a trace's '# event=' lines need '# events=recorded' before them")
                trace.events.append(parse_event(value))
        except TraceError:
            raise
        except ValueError:
            raise TraceError(f"bad trace metadata line {'# ' + key + '=' + value!r}") from None


def derivative(t: list[float], v: list[float | None]) -> list[float | None]:
    """Backward difference quotient; None at the first sample and across gaps."""
    out: list[float | None] = [None] * len(v)
    for i in range(1, len(v)):
        a, b, dt = v[i - 1], v[i], t[i] - t[i - 1]
        if a is not None and b is not None and dt > 0:
            out[i] = (b - a) / dt
    return out


# --- recording through the host library -------------------------------------------------

class Sampler:
    """Reads one sample of the chosen axes of a host `Module`; channels the profile lacks give None."""

    def __init__(self, module, axes: list[int]):
        self.module = module
        self.axes = list(axes)
        prof = module.profile
        for ax in self.axes:
            module.axis(ax)  # UnknownParameterError for an axis the module does not have
        self.params = {ch: num for ch, (num, _) in CHANNELS.items()
                       if num is not None and num in prof.axis_parameters}
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

    def sample(self) -> dict[tuple[int, str], float | None]:
        from ..host import TmclStatusError
        from ..host.units import tmc429_velocity_to_pps

        out: dict[tuple[int, str], float | None] = {}
        for ax in self.axes:
            axis = self.module.axis(ax)
            for ch, num in self.params.items():
                try:
                    value: float | None = axis.get(num)
                except TmclStatusError:
                    value = None
                if ch == "velocity" and value is not None and ax in self.pulse_div:
                    value = tmc429_velocity_to_pps(value, self.pulse_div[ax])
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
    `sampler`: a `Sampler` of `module` made before (it reads the microstep settings when made)."""
    check_duration(seconds, interval)
    sampler = sampler or Sampler(module, list(axes))
    trace = Trace(sampler.axes, module=module.profile.name, microsteps=dict(sampler.microsteps))
    clock = module.client.transport.monotonic
    start = clock()
    steps = round(seconds / interval)
    for i in range(steps + 1):
        trace.add(clock() - start, sampler.sample())
        if until is not None and until(trace):
            break
        if i < steps:
            module.sleep(interval)
    return trace
