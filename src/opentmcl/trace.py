"""Traces: axis quantities sampled over time, kept as compact columns, written and read as CSV.

    trace = Trace()                     # all axes of the module
    trace.sample(vm)                    # one sample of a VirtualModule and its world, at vm.time
    trace.record(vm, 2.0, 0.01)         # now and every 10 ms for 2 virtual seconds
    trace.column(0, "velocity"); trace.rows[-1]["pos0"]; print(trace.table())
    trace.to_csv("run.csv")             # the trace file: Trace.from_csv reads it back, `plot` draws it
    trace.to_csv("run.csv", layout="table")   # the row table `opentmcl run --csv` writes

A trace holds ``time`` (seconds) and, per (axis, channel), one value per sample; None where the
module has no such value. Channels (CHANNELS) are axis parameters as GAP reads them (TMCM-6212
manual 4.1, PD86-1180 manual 5) and the world's stage: position (AP1), target (AP0), velocity
(AP3), target_reached (AP8), home/right/left switch (AP9/AP10/AP11), load (AP206), current (AP180,
0..31), encoder (AP209), stage (where the slider really is, µsteps; docs/world.md) and the derived
acceleration. `sample(vm)` reads WORLD_CHANNELS from an in-process module; opentmcl.plot records
HOST_CHANNELS of any module through the host library (`add`). Velocity is kept as read; on TMC429
modules (PD86-1180) `column` converts it to pps with the pulse divisor (AP154).

Samples are kept in compact columns (opentmcl.columns): one hour at 10 ms of six axes takes well
under 100 MB (`python bench/bench_trace.py`); at most `max_rows` samples (TraceFull beyond). Rows
(`rows`, `table`, the table CSV) are dicts built only when read, named ``pos<n>``, ``vel<n>``, ...
(SHORT). Origin writes, hard stops (`events`) and program marks (`marks`) go with the trace file.
"""
from __future__ import annotations

import csv
import io
import math
import os
from array import array
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, overload

from .atomicfile import open_atomic
from .columns import Column
from .firmware.effects import WRITE
from .limits import CSV_MAX, LINE_MAX, open_regular, size_text
from .motion import CLOCK_HZ

if TYPE_CHECKING:
    from .firmware.vm import VirtualModule

Row = dict[str, float | int | None]
"""One sample as a dict: ``time`` and ``<short name><axis>`` -> value (None: the module has none)."""
Key = tuple[int, str]
"""(axis, channel)."""

# channel -> (axis parameter GAP reads it from, or None: derived or the world's; unit)
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
    "encoder": (209, ""),
    "stage": (None, "µsteps"),
}
STORED = tuple(c for c in CHANNELS if c != "acceleration")
"""The channels a trace can hold (acceleration is derived from velocity)."""
HOST_CHANNELS = ("position", "target", "velocity", "target_reached", "home_switch", "right_switch",
                 "left_switch", "load", "current")
"""What a recording through the host library reads (opentmcl.plot.Sampler) and `add` keeps by default."""
WORLD_CHANNELS = ("position", "velocity", "left_switch", "right_switch", "home_switch", "load", "current",
                  "encoder", "stage")
"""What `sample(vm)` reads from an in-process module and its world, in this order."""
SWITCHES = ("target_reached", "home_switch", "right_switch", "left_switch")
SHORT = {"position": "pos", "target": "target", "velocity": "vel", "target_reached": "reached",
         "left_switch": "left", "right_switch": "right", "home_switch": "home", "load": "load",
         "current": "current", "encoder": "encoder", "stage": "stage"}
"""Row and table column names (``pos0``, ``vel0``, ...), in the order of a row."""
LONG = {short: name for name, short in SHORT.items()}
MAX_ROWS = 1_000_000     # a trace's samples: about 2.8 hours at 10 ms; `run` takes at most this many looks
MAX_SAMPLES = 400_000    # a longer recording or CSV trace is refused (memory): 4000 s at 10 ms
FLUSH_ROWS = 128         # samples kept as a list before they go into the columns together
ORIGIN, HARD_STOP = "origin", "hard_stop"
KINDS = (ORIGIN, HARD_STOP)
LAYOUTS = ("trace", "table")


class TraceError(ValueError):
    """A trace file that cannot be read, or a channel/axis that is not in the trace."""


class TraceFull(ValueError):
    """A trace that already holds max_rows samples."""


def check_interval(seconds: float, interval: float) -> None:
    """ValueError unless `interval` is a finite number > 0 and `seconds` one >= 0 (NaN too)."""
    if not 0 < interval < math.inf or not 0 <= seconds < math.inf:
        raise ValueError("interval must be a finite number > 0 and seconds a finite number >= 0")


def derivative(t: Sequence[float], v: Sequence[float | None]) -> list[float | None]:
    """Backward difference quotient; None at the first sample and across gaps."""
    out: list[float | None] = [None] * len(v)
    for i in range(1, len(v)):
        a, b, dt = v[i - 1], v[i], t[i] - t[i - 1]
        if a is not None and b is not None and dt > 0:
            out[i] = (b - a) / dt
    return out


# --- events and marks (drawn by opentmcl.plot; plot/events.py) ------------------------------------

@dataclass(frozen=True)
class Event:
    """A discontinuity at `time` (trace seconds) on `axis`: ORIGIN (`before`/`after`: actual
    position in µsteps) or HARD_STOP (`before`: actual speed in pps just before, `after`: 0).
    None where the value is not known (a guessed event)."""

    time: float
    axis: int
    kind: str
    before: float | None = None
    after: float | None = None


@dataclass(frozen=True)
class Mark:
    """The program counter `pc` seen first at `time`, with the instruction's text."""

    time: float
    pc: int
    text: str = ""


@dataclass(frozen=True)
class FaultMark:
    """A fault that fired at `time` (trace seconds): its kind, its name ("" if it has none) and
    what it did (docs/faults.md "Seeing what fired")."""

    time: float
    kind: str
    name: str = ""
    detail: str = ""

    @property
    def label(self) -> str:
        return self.name or self.kind


def _num(v: float | None) -> str:
    if v is None:
        return ""
    return str(int(v)) if float(v).is_integer() else f"{v:.9g}"


def meta_lines(trace: Trace) -> list[str]:
    """``# events=recorded`` (the module reported its events, even none), one ``# event=`` line per
    event and one ``# mark=`` line per program mark."""
    lines = []
    if trace.events is not None:
        lines.append("# events=recorded")
        lines += [f"# event={e.time:.6f},{e.axis},{e.kind},{_num(e.before)},{_num(e.after)}"
                  for e in trace.events]
    lines += [f"# mark={m.time:.6f},{m.pc},{m.text}" for m in trace.marks]
    return lines + fault_lines(trace)


def fault_lines(trace: Trace) -> list[str]:
    """One ``# fault=`` line per fault that fired (docs/faults.md "Seeing what fired")."""
    return [f"# fault={f.time:.6f},{f.kind},{f.name},{' '.join(f.detail.split())}" for f in trace.faults]


def _opt(text: str) -> float | None:
    return float(text) if text else None


def parse_event(value: str) -> Event:
    """ValueError unless `value` is ``time,axis,kind,before,after``."""
    t, axis, kind, before, after = value.split(",")
    if kind not in KINDS:
        raise ValueError(kind)
    return Event(float(t), int(axis), kind, _opt(before), _opt(after))


def parse_fault(value: str) -> FaultMark:
    """ValueError unless `value` is ``time,kind,name,detail`` (the detail may hold commas)."""
    t, kind, name, detail = value.split(",", 3)
    if not kind:
        raise ValueError(value)
    return FaultMark(float(t), kind, name, detail)


def parse_mark(value: str) -> Mark:
    """ValueError unless `value` is ``time,pc,text`` (the text may hold commas)."""
    t, pc, text = value.split(",", 2)
    return Mark(float(t), int(pc), text)


# --- reading an in-process module ---------------------------------------------------------------

WORLD_NUMBERS = (11, 10, 9, 206, 180, 209)
"""The world's readings of a sample, in the order of WORLD_CHANNELS (left, right, home switch, load
value, current, encoder); a parameter the module lacks reads as 0 (`readings` answers None)."""


class WorldReads:
    """One sample of WORLD_CHANNELS from an in-process VirtualModule: per axis what GAP answers at
    this instant (the same readers and the same parts of the axis's world that GAP reads through,
    firmware/world.py `read_axis`) and the stage. The engines are brought to now once for the whole
    sample and the stage follows the counter once per axis; nothing is invalidated, so the next
    `advance` goes on as without the sample. A read that ends a step loss (the rotor follows the
    counter again) changes the world as a GAP would, and tells the scheduler so (a GAP's effect)."""

    def __init__(self, vm: VirtualModule, axes: list[int]) -> None:
        self.vm = vm
        self.module_axes = vm.axes          # a power-up makes new axes (and readers)
        self.scheduler = vm.scheduler
        self.faults = vm.faults             # its `log`: what fired
        world = vm.world
        self.parts = [self._parts(vm, world.axis(a), a) for a in axes]

    @staticmethod
    def _parts(vm: VirtualModule, aw: Any, a: int) -> tuple[Any, ...]:
        axis = vm.axes[a]
        readable = axis.readable
        missing = tuple(i for i, ch in enumerate(WORLD_CHANNELS)
                        if CHANNELS[ch][0] is not None and CHANNELS[ch][0] not in readable)
        position = axis.reader(1) if 1 in readable else _none
        velocity = axis.reader(3) if 3 in readable else _none
        numbers = tuple(n if n in readable else 0 for n in WORLD_NUMBERS)
        return position, velocity, axis, aw.rotor, numbers, missing

    def bound_to(self, vm: VirtualModule) -> bool:
        """Made for this module, since its last power-up."""
        return vm is self.vm and vm.axes is self.module_axes

    def read(self, out: list[Any] | None = None) -> list[int | None]:
        """The values of one sample, appended to `out` (a new list by default): per axis in the
        order of WORLD_CHANNELS."""
        self.scheduler.sync_for_read()
        readings = self.vm.world.readings
        if out is None:
            out = []
        append = out.append
        ended = False
        for position, velocity, axis, rotor, numbers, missing in self.parts:
            slipping = rotor.slipping
            start = len(out)
            counter = position()               # WORLD_CHANNELS: position (AP1, the engine's
            append(counter)                    # position: the counter the stage follows),
            append(velocity())                 # velocity, the world's readings, the stage
            readings(axis, numbers, out, counter)
            append(rotor.phys)
            if slipping and not rotor.slipping:
                ended = True
            for i in missing:
                out[start + i] = None
        if ended:
            self.scheduler.invalidate(WRITE)
        return out


def _none() -> None:
    return None


# --- the trace -----------------------------------------------------------------------------------

class _Rows(Sequence[Row]):
    """The samples of a Trace as dicts, made on demand from its columns."""

    def __init__(self, trace: Trace) -> None:
        self.trace = trace
        self.names = ["time"] + [name for name, _ in trace.row_keys()]
        self.columns: list[Any] = [trace.time] + [trace.data[key] for _, key in trace.row_keys()]

    def __len__(self) -> int:
        return len(self.trace)

    @overload
    def __getitem__(self, i: int) -> Row: ...

    @overload
    def __getitem__(self, i: slice) -> list[Row]: ...

    def __getitem__(self, i: int | slice) -> Row | list[Row]:
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        if not -len(self) <= i < len(self):
            raise IndexError("trace row index out of range")
        return {n: c[i] for n, c in zip(self.names, self.columns, strict=True)}


class Trace:
    """Samples over time: ``time`` (seconds) and, per (axis, channel), one value per sample.

    `axes`: the axes to sample (None: every axis of the module at the first `sample`). `channels`:
    the channels kept (None: WORLD_CHANNELS for `sample`, HOST_CHANNELS for `add`). `module`,
    `microsteps` (axis -> (µsteps per full step, full steps per turn)), `pulse_div` (axis -> AP154
    of a TMC429 module, whose velocity is kept in its internal unit) describe the module."""

    def __init__(self, axes: Iterable[int] | None = None, *, module: str = "",
                 microsteps: dict[int, tuple[int, int]] | None = None, events: list[Event] | None = None,
                 marks: list[Mark] | None = None, channels: Iterable[str] | None = None,
                 pulse_div: dict[int, int] | None = None, max_rows: int = MAX_ROWS) -> None:
        self.all_axes = axes is None
        self.axes: list[int] = [] if axes is None else list(axes)
        self.module = module
        self.microsteps = dict(microsteps or {})
        self.pulse_div = dict(pulse_div or {})
        # Discontinuities seen by the module (origin writes, hard stops); None: not known, the
        # renderer guesses origin writes from the samples (plot/events.py).
        self.events = events
        self.marks = list(marks or [])      # program counter changes of a program run
        self.faults: list[FaultMark] = []   # faults that fired (docs/faults.md), read by `sample`
        self._faults_seen = 0
        self.channels: tuple[str, ...] | None = None if channels is None else _known(channels)
        self.max_rows = max_rows
        self.time: array[float] = array("d")
        self._data: dict[Key, Column] = {}
        self._columns: list[Column] = []         # the columns in the order of a sample's values
        self._pending: list[float | int | None] = []   # the values of the samples not yet in the columns
        self._reads: WorldReads | None = None

    def __len__(self) -> int:
        return len(self.time)

    # --- filling ----------------------------------------------------------------------------------
    def _open(self, channels: tuple[str, ...]) -> None:
        """The columns, at the first sample: every (axis, channel), axis by axis."""
        if self.channels is not None and self.channels != channels:
            raise ValueError(f"this trace keeps the channels {', '.join(self.channels)}; a sample of "
                             f"{', '.join(channels)} does not fit")
        if not self._data:
            self.channels = channels
            self._data = {(ax, ch): Column() for ax in self.axes for ch in channels}
            self._columns = list(self._data.values())

    def _room(self) -> None:
        if len(self.time) >= self.max_rows:
            raise TraceFull(f"the trace holds {self.max_rows} rows already (the limit)")

    @property
    def data(self) -> dict[Key, Column]:
        """(axis, channel) -> its column of values."""
        if self._pending:
            self._flush()
        return self._data

    def _flush(self) -> None:
        """The pending samples into the columns, a column at a time (Column.extend)."""
        pending, width = self._pending, len(self._columns)
        for i, col in enumerate(self._columns):
            col.extend(pending[i::width])
        pending.clear()

    def _keep(self, values: Iterable[float | int | None]) -> None:
        self._pending += values
        self._flush_when_full()

    def _flush_when_full(self) -> None:
        if len(self._pending) >= len(self._columns) * FLUSH_ROWS:
            self._flush()

    def add(self, t: float, values: Mapping[Key, float | int | None]) -> None:
        """One sample at time `t`: (axis, channel) -> value; what `values` lacks is None."""
        if not self._data:
            self._open(self.channels or HOST_CHANNELS)
        self.add_row(t, [values.get(key) for key in self._data])

    def add_row(self, t: float, values: Sequence[float | int | None]) -> None:
        """One sample at time `t`: the values of `data`'s keys, in their order."""
        if len(values) != len(self._columns):
            raise ValueError(f"a sample of this trace has {len(self._columns)} values, not {len(values)}")
        self._room()
        self.time.append(float(t))
        self._keep(values)

    def sample(self, vm: VirtualModule) -> None:
        """Read one sample of WORLD_CHANNELS from the virtual module at its present time (no time
        passes; the values are those GAP answers now). `rows[-1]` is it as a dict."""
        reads = self._reads
        if reads is None or not reads.bound_to(vm):
            reads = self._reads = self._bind(vm)
        self._room()
        pending = self._pending
        start = len(pending)
        try:
            reads.read(pending)  # the values, kept straight away
        except BaseException:
            del pending[start:]
            raise
        self.time.append(round(reads.scheduler.now / CLOCK_HZ, 9))   # vm.now
        self._flush_when_full()
        log = reads.faults.log
        if log.count != self._faults_seen:
            self.faults += [FaultMark(f.t, f.kind, f.name or "", f.detail) for f in log.since(self._faults_seen)]
            self._faults_seen = log.count

    def _bind(self, vm: VirtualModule) -> WorldReads:
        """The reads of `vm`; at the first sample the axes, channels and units of the module."""
        n, first = len(vm.axes), not self._data
        if self.all_axes and first:
            self.axes = list(range(n))
        bad = [a for a in self.axes if not 0 <= a < n]
        if bad:
            raise ValueError(f"{vm.profile.name} has no axis {bad[0]}")
        self._open(WORLD_CHANNELS)
        if first:
            self._describe(vm)
        return WorldReads(vm, self.axes)

    def _describe(self, vm: VirtualModule) -> None:
        """Module name, microstep settings (AP140, AP202) and TMC429 pulse divisors (AP154), unless
        given when the trace was made."""
        self.module = self.module or vm.profile.name
        for a in self.axes:
            axis = vm.axes[a]
            readable = axis.readable
            usteps = 1 << axis.get(140) if 140 in readable else 256
            self.microsteps.setdefault(a, (usteps, axis.get(202) if 202 in readable else 200))
            if vm.profile.capabilities.velocity_unit == "tmc429" and 154 in readable:
                self.pulse_div.setdefault(a, axis.get(154))

    def record(self, vm: VirtualModule, seconds: float, interval: float) -> _Rows:
        """Sample now and every `interval` virtual seconds for `seconds` (advances the module)."""
        check_interval(seconds, interval)
        steps = round(seconds / interval)
        if len(self) + steps + 1 > self.max_rows:
            raise TraceFull(f"{steps + 1} more rows would pass the limit of {self.max_rows} rows")
        self.sample(vm)
        for _ in range(steps):
            vm.advance(interval)
            self.sample(vm)
        return self.rows

    # --- reading ----------------------------------------------------------------------------------
    def nbytes(self) -> int:
        """Bytes held by the samples (column arrays)."""
        return self.time.buffer_info()[1] * self.time.itemsize + sum(c.nbytes() for c in self.data.values())

    def column(self, axis: int, channel: str) -> list[float | int | None]:
        """The values of one channel; velocity in pps, acceleration its difference quotient."""
        if axis not in self.axes:
            raise TraceError(f"axis {axis} is not in this trace (axes {self.axes})")
        if channel == "acceleration":
            return derivative(self.time, self.column(axis, "velocity"))
        if channel not in CHANNELS:
            raise TraceError(f"unknown channel {channel!r}; channels: {', '.join(CHANNELS)}")
        col = self.data.get((axis, channel))
        if col is None:
            return [None] * len(self.time)
        if channel == "velocity" and axis in self.pulse_div:
            return _pps(col, self.pulse_div[axis])
        return col.tolist()

    def has(self, axis: int, channel: str) -> bool:
        if channel == "acceleration":
            channel = "velocity"
        return any(v is not None for v in self.data.get((axis, channel), ()))

    def rpm(self, axis: int) -> list[float | None]:
        """Velocity in revolutions per minute: pps / (microsteps per full step * full steps per turn) * 60."""
        usteps, fullsteps = self.microsteps.get(axis, (256, 200))
        return [None if v is None else v * 60.0 / (usteps * fullsteps) for v in self.column(axis, "velocity")]

    def row_keys(self) -> list[tuple[str, Key]]:
        """(row name, (axis, channel)) of the kept channels, axis by axis in the order of SHORT."""
        kept = self.channels or ()
        return [(f"{SHORT[ch]}{ax}", (ax, ch)) for ax in self.axes for ch in SHORT if ch in kept]

    @property
    def rows(self) -> _Rows:
        """The samples as dicts (a read-only sequence): values as the module answered them."""
        return _Rows(self)

    def cells(self) -> tuple[list[str], list[list[str]]]:
        """The row names and the rows as text (time to the millisecond, "" for None)."""
        rows = self.rows
        return rows.names, [["" if v is None else f"{v:.3f}" if n == "time" else str(v) for n, v in r.items()]
                            for r in rows]

    def table(self) -> str:
        """The rows as an aligned text table."""
        names, cells = self.cells()
        if not cells:
            return ""
        widths = [max(len(c), *(len(row[i]) for row in cells)) for i, c in enumerate(names)]
        return "\n".join(" ".join(v.rjust(w) for v, w in zip(row, widths, strict=True)) for row in [names, *cells])

    # --- CSV --------------------------------------------------------------------------------------
    @overload
    def to_csv(self, target: None = None, *, layout: str = "trace") -> str: ...

    @overload
    def to_csv(self, target: str | os.PathLike[str] | io.TextIOBase, *, layout: str = "trace") -> None: ...

    def to_csv(self, target: str | os.PathLike[str] | io.TextIOBase | None = None, *,
               layout: str = "trace") -> str | None:
        """Write the samples as CSV to `target` (a path, replaced only once the whole file is
        written, or an open text file); without one return the text.

        layout "trace": ``# module=``, ``# microsteps_<axis>=`` and event/mark lines, then ``time_s``
        and ``<channel>_<axis>`` with velocity in pps (`from_csv` and `opentmcl plot` read it).
        layout "table": ``time`` and ``pos<axis>``, ``vel<axis>``, ... as the module answered
        (`opentmcl run --csv`, `demo --csv`), after the ``# fault=`` lines of faults that fired."""
        write = {"trace": self._write_file, "table": self._write_table}.get(layout)
        if write is None:
            raise ValueError(f"a CSV layout is one of {', '.join(LAYOUTS)}, not {layout!r}")
        if target is None:
            buf = io.StringIO()
            write(buf)
            return buf.getvalue()
        if isinstance(target, io.TextIOBase):
            write(target)
            return None
        with open_atomic(target, text=True) as fh:   # a failed or killed write keeps the old file
            write(fh)
        return None

    def _write_table(self, fh: Any) -> None:
        fh.writelines(line + "\n" for line in fault_lines(self))   # none without faults
        names = self.row_keys()
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["time"] + [name for name, _ in names])
        w.writerows([t, *("" if v is None else v for v in values)]   # streamed, not a list
                    for t, *values in zip(self.time, *(self.data[key] for _, key in names), strict=True))

    def _write_file(self, fh: Any) -> None:
        meta = [f"# module={self.module}"] + [f"# microsteps_{ax}={u},{f}" for ax, (u, f) in self.microsteps.items()]
        fh.writelines(line + "\n" for line in meta + meta_lines(self))
        keys = [(ax, ch) for ax in self.axes for ch in STORED if (ax, ch) in self.data]
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["time_s"] + [f"{ch}_{ax}" for ax, ch in keys])
        w.writerows([f"{t:.6f}", *("" if v is None else _fmt(v) for v in values)]
                    for t, *values in zip(self.time, *map(self._written, keys), strict=True))

    def _written(self, key: Key) -> Iterable[float | int | None]:
        """A column as the trace file has it: velocity in pps."""
        ax, ch = key
        if ch == "velocity" and ax in self.pulse_div:
            return _pps(self.data[key], self.pulse_div[ax])
        return self.data[key]

    @classmethod
    def from_csv(cls, source: str | os.PathLike[str] | io.TextIOBase) -> Trace:
        """Read a trace file (`to_csv`: ``time_s``, ``<channel>_<axis>``) or a row table (``time``,
        ``pos<axis>``, ...: `opentmcl run --csv`; its velocity as the module answered). Read line by
        line: at most CSV_MAX bytes, LINE_MAX per line and MAX_SAMPLES rows."""
        if isinstance(source, io.TextIOBase):
            return _parse_csv(_lines(source, "the trace"))
        try:
            with io.TextIOWrapper(open_regular(source), encoding="utf-8", newline="") as fh:
                return _parse_csv(_lines(fh, str(source)))
        except OSError as exc:
            raise TraceError(f"cannot read {source}: {exc.strerror or exc}") from None
        except UnicodeDecodeError:
            raise TraceError(f"cannot read {source}: not a text (UTF-8) file") from None


def _known(channels: Iterable[str]) -> tuple[str, ...]:
    out = tuple(channels)
    bad = [c for c in out if c not in STORED]
    if bad:
        raise ValueError(f"unknown channel {bad[0]!r}; channels: {', '.join(STORED)}")
    return out


def _pps(values: Iterable[float | int | None], pulse_div: int) -> list[float | int | None]:
    """TMC429 internal velocities in pps (PD86-1180 manual 5, TMC4210 datasheet 6.1.12.1)."""
    from .host.units import tmc429_velocity_to_pps

    return [None if v is None else tmc429_velocity_to_pps(v, pulse_div) for v in values]


def _fmt(v: float) -> str:
    return str(int(v)) if float(v).is_integer() else f"{v:.6g}"


# --- reading CSV -----------------------------------------------------------------------------------

def _lines(fh: Any, name: str) -> Iterator[str]:
    """The lines of a text file, each at most LINE_MAX characters, CSV_MAX in all."""
    total = 0
    while line := fh.readline(LINE_MAX + 1):
        total += len(line)
        if len(line) > LINE_MAX:
            raise TraceError(f"cannot read {name}: a line longer than {size_text(LINE_MAX)}")
        if total > CSV_MAX:
            raise TraceError(f"cannot read {name}: larger than the {size_text(CSV_MAX)} limit")
        yield line.rstrip("\r\n")


def _column_key(name: str, table: bool) -> Key:
    """(axis, channel) of a column name: ``position_0`` in a trace file, ``pos0`` in a row table."""
    if table:
        stem = name.rstrip("0123456789")
        ch, ax = LONG.get(stem, ""), name[len(stem):]
    else:
        ch, _, ax = name.rpartition("_")
    if ch not in STORED or not ax.isdigit():
        raise TraceError(f"unknown trace column {name!r}")
    return int(ax), ch


def _parse_csv(lines: Iterator[str]) -> Trace:
    meta: dict[str, str] = {}
    repeated: list[tuple[str, str]] = []   # event / mark lines, in order

    def data_lines() -> Iterator[str]:
        for line in lines:
            if line.startswith("#"):
                key, _, value = line[1:].strip().partition("=")
                meta[key] = value
                repeated.append((key, value))
            elif line.strip():
                yield line

    rows = csv.reader(data_lines())
    header = next(rows, None)
    if not header or header[0] not in ("time_s", "time"):
        raise TraceError("not a trace: the first column must be time_s (or time: a row table of `opentmcl run`)")
    keys = [_column_key(name, header[0] == "time") for name in header[1:]]
    axes = sorted({ax for ax, _ in keys})
    if not axes:
        raise TraceError("the trace has no axis columns")
    kept = {ch for _, ch in keys}
    channels = tuple(ch for ch in STORED if ch in kept)
    trace = Trace(axes, channels=channels, max_rows=MAX_SAMPLES)
    trace._open(channels)
    where = {key: i for i, key in enumerate(trace.data)}
    order = [where[key] for key in keys]
    width = len(trace.data)
    for n, row in enumerate(rows, start=2):
        _read_row(trace, row, n, len(header), order, width)
    trace.module = meta.get("module", "")
    _read_events(trace, repeated)
    _read_microsteps(trace, meta)
    return trace


def _read_row(trace: Trace, row: list[str], n: int, fields: int, order: list[int], width: int) -> None:
    if len(row) != fields:
        raise TraceError(f"trace row {n} has {len(row)} fields, expected {fields}")
    if len(trace) >= MAX_SAMPLES:
        raise TraceError(f"the trace has more than {MAX_SAMPLES} samples (the limit)")
    values: list[float | None] = [None] * width
    try:
        t = float(row[0])
        for i, text in zip(order, row[1:], strict=True):
            values[i] = float(text) if text != "" else None
    except ValueError:
        raise TraceError(f"trace row {n}: not a number") from None
    trace.add_row(t, values)


def _read_microsteps(trace: Trace, meta: dict[str, str]) -> None:
    for key, value in meta.items():
        if key.startswith("microsteps_"):
            try:
                u, f = (int(x) for x in value.split(","))
                trace.microsteps[int(key.split("_")[1])] = (u, f)
            except ValueError:
                raise TraceError(f"bad trace metadata line {'# ' + key + '=' + value!r}") from None


def _read_events(trace: Trace, lines: list[tuple[str, str]]) -> None:
    """The ``# events=``, ``# event=`` and ``# mark=`` lines into `trace`."""
    for key, value in lines:
        try:
            if key == "events" and trace.events is None:
                trace.events = []
            elif key == "mark":
                trace.marks.append(parse_mark(value))
            elif key == "fault":
                trace.faults.append(parse_fault(value))
            elif key == "event":
                if trace.events is None:
                    raise TraceError("a trace's '# event=' lines need '# events=recorded' before them")
                trace.events.append(parse_event(value))
        except TraceError:
            raise
        except ValueError:
            raise TraceError(f"bad trace metadata line {'# ' + key + '=' + value!r}") from None
