"""Compact columns for traces: one `array` per quantity instead of a Python object per value.

A column starts as signed 8-bit and widens (16, 32, 64 bit, then double) when a value does not
fit, so a switch costs 1 byte per sample, a 32-bit position 4 and a float 8. None (a value the
module does not have) is stored as the type's smallest value (-128, -32768, ...) in an integer
column and as NaN in a float column; a real value equal to that sentinel widens the column.
Values read back as int from integer columns and as float from float columns.
"""
from __future__ import annotations

import math
import struct
from array import array
from collections.abc import Iterable, Iterator, Sequence
from typing import cast

_INTS = ("b", "h", "i", "q")
_LIMITS = {code: 1 << (array(code).itemsize * 8 - 1) for code in _INTS}   # 2**(bits-1)
_SENTINEL_BYTES = {code: array(code, [-half]).tobytes() for code, half in _LIMITS.items()}
"""The None sentinel of each integer type as stored: where its bytes are not in a block, no value
of the block is the sentinel (a find of bytes, not a look at every value)."""


def _packer(code: str, n: int) -> struct.Struct:
    """The native struct of `n` items of array type `code` (the same sizes as the array's)."""
    packer = _PACKERS.get((code, n))
    if packer is None:
        if len(_PACKERS) >= 64:
            _PACKERS.clear()
        packer = _PACKERS[(code, n)] = struct.Struct(f"{n}{code}")
    return packer


_PACKERS: dict[tuple[str, int], struct.Struct] = {}


def _array(code: str, values: Iterable[float] = ()) -> array[float]:
    """An array of type `code` ("b" ... "q" or "d"); typed array[float], which holds ints too."""
    return array(code, values)


class Column:
    """A growing sequence of int / float / None values."""

    __slots__ = ("_a",)

    def __init__(self, values: Iterable[float | int | None] = ()) -> None:
        self._a = _array("b")
        for v in values:
            self.append(v)

    @property
    def typecode(self) -> str:
        return self._a.typecode

    def _fits(self, v: int) -> bool:
        half = _LIMITS[self._a.typecode]
        return -half < v < half            # -half is the None sentinel

    def _widen(self, code: str) -> None:
        old, none = self._a, -_LIMITS[self._a.typecode]
        new_none = math.nan if code == "d" else -_LIMITS[code]
        self._a = _array(code, (new_none if x == none else x for x in old))

    def append(self, v: float | int | None) -> None:
        a = self._a
        if v is None:
            a.append(math.nan if a.typecode == "d" else -_LIMITS[a.typecode])
            return
        if a.typecode != "d":
            if isinstance(v, float) or not -_LIMITS["q"] < v < _LIMITS["q"]:
                self._widen("d")
            else:
                while not self._fits(v):
                    self._widen(_INTS[_INTS.index(self._a.typecode) + 1])
        self._a.append(v)

    def extend(self, values: Sequence[float | int | None]) -> None:
        """Append `values`. Values that fit the column as it is (no None, no float in an integer
        column, none equal to its None sentinel) are copied in one go; a run of 64-bit integers
        widens the column at most once, to the narrowest type that holds all of them."""
        a = self._a
        code = a.typecode
        try:   # packed, then copied in: several times cheaper than array(code, values)
            same = array(code, _packer(code, len(values)).pack(*values))
        except struct.error:   # None, a float in an integer column, a value too wide for it
            same = None
        if same is not None and (code == "d" or _SENTINEL_BYTES[code] not in same.tobytes()
                                 or -_LIMITS[code] not in same):
            a.extend(same)
            return
        try:
            ints: array[int] = array("q", cast("Sequence[int]", values))
        except (TypeError, OverflowError):     # None, a float, or an integer beyond 64 bits
            for v in values:
                self.append(v)
            return
        if not ints:
            return
        lo, hi = min(ints), max(ints)
        while self._a.typecode != "d" and not (self._fits(lo) and self._fits(hi)):
            code = self._a.typecode
            self._widen("d" if code == "q" else _INTS[_INTS.index(code) + 1])
        if self._a.typecode == "q":
            self._a.extend(ints)
        else:
            self._a.extend(_array(self._a.typecode, ints))

    def _get(self, x: float) -> float | int | None:
        if self._a.typecode == "d":
            return None if x != x else x
        return None if x == -_LIMITS[self._a.typecode] else x

    def __len__(self) -> int:
        return len(self._a)

    def __getitem__(self, i: int) -> float | int | None:
        return self._get(self._a[i])

    def __iter__(self) -> Iterator[float | int | None]:
        get = self._get
        return (get(x) for x in self._a)

    def tolist(self) -> list[float | int | None]:
        return list(self)

    def nbytes(self) -> int:
        return self._a.buffer_info()[1] * self._a.itemsize
