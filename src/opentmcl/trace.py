"""Traces of a virtual module in its world: position, velocity, switches, load value, current.

    trace = Trace()                 # all axes
    trace.sample(vm)                # one row at vm.time (call as often as you like)
    trace.to_csv("run.csv")         # or trace.to_csv() -> str
    print(trace.table())

A row is a dict: ``time`` (virtual seconds) and, per axis n, ``pos<n>`` (AP1), ``vel<n>`` (AP3),
``left<n>``/``right<n>``/``home<n>`` (AP11/AP10/AP9, logical states), ``load<n>`` (AP206),
``current<n>`` (AP180, 0..31), ``encoder<n>`` (AP209) and ``stage<n>`` (the physical position
of the slider in the world). Values a module does not have are empty. Rows are kept as compact
columns (opentmcl.columns, about 140 bytes per row of a TMCM-6212) and built as dicts only when
read; at most MAX_ROWS rows (TraceFull beyond).
"""
from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, overload

from .atomicfile import open_atomic
from .columns import Column

if TYPE_CHECKING:
    from .firmware.vm import VirtualModule

Row = dict[str, float | int | None]
"""One sample: column name -> value (None: the module has no such value)."""

FIELDS = (("pos", 1), ("vel", 3), ("left", 11), ("right", 10), ("home", 9), ("load", 206),
          ("current", 180), ("encoder", 209))
MAX_ROWS = 1_000_000   # about 2.8 hours at 10 ms; `run` takes at most this many looks


def check_interval(seconds: float, interval: float) -> None:
    """ValueError unless `interval` is a finite number > 0 and `seconds` one >= 0 (NaN too)."""
    if not 0 < interval < math.inf or not 0 <= seconds < math.inf:
        raise ValueError("interval must be a finite number > 0 and seconds a finite number >= 0")


class TraceFull(ValueError):
    """A trace that already holds max_rows rows."""


class _Rows(Sequence[Row]):
    """The rows of a Trace as dicts, made on demand from its columns."""

    def __init__(self, trace: Trace) -> None:
        self._t = trace

    def __len__(self) -> int:
        return len(self._t._data[0]) if self._t._data else 0

    @overload
    def __getitem__(self, i: int) -> Row: ...

    @overload
    def __getitem__(self, i: slice) -> list[Row]: ...

    def __getitem__(self, i: int | slice) -> Row | list[Row]:
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        names, data = self._t._names, self._t._data
        if not data:
            raise IndexError("trace row index out of range")
        return {n: c[i] for n, c in zip(names, data, strict=True)}


class Trace:
    def __init__(self, axes: Iterable[int] | None = None, *, max_rows: int = MAX_ROWS) -> None:
        self.axes = None if axes is None else list(axes)
        self.max_rows = max_rows
        self._names: list[str] = []
        self._data: list[Column] = []

    @property
    def rows(self) -> _Rows:
        """The recorded rows (a read-only sequence of dicts)."""
        return _Rows(self)

    def nbytes(self) -> int:
        """Bytes held by the values (column arrays)."""
        return sum(c.nbytes() for c in self._data)

    def _axes(self, vm: VirtualModule) -> list[int]:
        n = len(vm.axes)
        if self.axes is None:
            return list(range(n))
        bad = [a for a in self.axes if not 0 <= a < n]
        if bad:
            raise ValueError(f"{vm.profile.name} has no axis {bad[0]}")
        return self.axes

    def columns(self, vm: VirtualModule) -> list[str]:
        cols = ["time"]
        for a in self._axes(vm):
            cols += [f"{name}{a}" for name, _ in FIELDS] + [f"stage{a}"]
        return cols

    def sample(self, vm: VirtualModule) -> Row:
        """Read one row from the virtual module at its present time (no time passes)."""
        from .firmware.status import TmclStatus

        vm.sync()
        row: dict[str, float | int | None] = {"time": round(vm.time, 9)}
        for a in self._axes(vm):
            axis = vm.axes[a]
            for name, number in FIELDS:
                try:
                    row[f"{name}{a}"] = axis.get(number) if number in axis.params else None
                except TmclStatus:
                    row[f"{name}{a}"] = None
            world = getattr(vm, "world", None)
            row[f"stage{a}"] = world.axis(a).physical_position if world is not None else None
        self._append(row)
        return row

    def _append(self, row: Row) -> None:
        if not self._data:
            self._names, self._data = list(row), [Column() for _ in row]
        elif list(row) != self._names:
            raise ValueError("a trace row must have the columns of the first row")
        if len(self._data[0]) >= self.max_rows:
            raise TraceFull(f"the trace holds {self.max_rows} rows already (the limit)")
        for col, v in zip(self._data, row.values(), strict=True):
            col.append(v)

    def record(self, vm: VirtualModule, seconds: float, interval: float) -> _Rows:
        """Sample now and every `interval` virtual seconds for `seconds` (advances the module)."""
        check_interval(seconds, interval)
        steps = round(seconds / interval)
        if len(self.rows) + steps + 1 > self.max_rows:
            raise TraceFull(f"{steps + 1} more rows would pass the limit of {self.max_rows} rows")
        self.sample(vm)
        for _ in range(steps):
            vm.advance(interval)
            self.sample(vm)
        return self.rows

    def to_csv(self, target: str | os.PathLike[str] | None = None) -> str:
        """The rows as CSV text; written to `target` when given."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self._names or ["time"])
        for row in zip(*self._data, strict=True):
            w.writerow(["" if v is None else v for v in row])
        text = buf.getvalue()
        if target is not None:
            with open_atomic(target, text=True) as f:
                f.write(text)
        return text

    def table(self) -> str:
        """The rows as an aligned text table."""
        if not self.rows:
            return ""
        cols = list(self.rows[0])
        cells = [[("" if r[c] is None else (f"{r[c]:.3f}" if c == "time" else str(r[c]))) for c in cols]
                 for r in self.rows]
        widths = [max(len(c), *(len(row[i]) for row in cells)) for i, c in enumerate(cols)]
        lines = [" ".join(c.rjust(w) for c, w in zip(cols, widths, strict=True))]
        lines += [" ".join(v.rjust(w) for v, w in zip(row, widths, strict=True)) for row in cells]
        return "\n".join(lines)
