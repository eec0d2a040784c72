"""Non-volatile storage of a virtual module (docs/architecture.md "Errors").

The EEPROM holds what the manuals say survives power-off: stored axis
parameters (STAP), bank-0 global parameters (auto-stored) and stored user
variables (STGP), coordinates (SCO ..., 255 forms / GP84) and the TMCL
program. In memory by default; with a path it is a JSON file written
atomically (temp file, fsync, rename), so a killed process leaves either the
old or the new file, never a torn one.
"""
from __future__ import annotations

import json
import os
import threading
from collections.abc import Callable
from pathlib import Path

from ..atomicfile import remove_stale, write_atomic
from ..limits import TEXT_MAX, InputTooLarge, read_text

FORMAT = "opentmcl-eeprom"
VERSION = 1


class EepromError(Exception):
    """The EEPROM file exists but cannot be used (not ours, unreadable)."""


def _int(v: object, lo: int = -(2 ** 31), hi: int = 2 ** 31 - 1) -> bool:
    return type(v) is int and lo <= v <= hi


def _flat(d: object) -> bool:
    return isinstance(d, dict) and all(_int(v) for v in d.values())


def _whole(raw: dict) -> bool:
    """Every section has the shape `flush` writes: {"n": {"m": int}} for axis/global/coord,
    {"n": int} for user variables, [[command, type, motor, value], ...] for the program."""
    nested = all(isinstance(raw.get(k, {}), dict) and all(_flat(v) for v in raw.get(k, {}).values())
                 for k in ("axis", "global", "coord"))
    program = raw.get("program", [])
    return (nested and _flat(raw.get("user", {})) and isinstance(program, list)
            and all(isinstance(ins, list) and len(ins) == 4 and all(_int(x, 0, 255) for x in ins[:3])
                    and _int(ins[3]) for ins in program))


def _empty() -> dict:
    return {"axis": {}, "global": {}, "user": {}, "coord": {}, "program": []}


class Eeprom:
    """Dictionary-shaped EEPROM image; `flush()` persists it when file-backed."""

    def __init__(self, path: str | os.PathLike[str] | None = None, module: str = "") -> None:
        self.path = Path(path) if path is not None else None
        self.module = module
        self.data = _empty()
        self.dirty = False
        self.deferred = False
        self.on_change: Callable[[], None] | None = None
        """Called instead of `flush` after a change: a server's writer thread writes the file
        outside the bus lock (server/eeprom_writer.py)."""
        self._write_lock = threading.Lock()
        self._taken = 0    # snapshots taken
        self._program_json: tuple[list, str] | None = None  # (the program list, its JSON)
        self._written = 0  # the latest snapshot written
        if self.path is not None:
            remove_stale(self.path)   # temp files of a writer killed mid-write (atomicfile)
        if self.path is not None and self.path.exists():
            self.data = self._read(self.path)
        elif self.path is not None:  # a new file: fail now, not at the first store
            self.dirty = True
            try:
                self.flush()
            except OSError as exc:
                raise EepromError(f"cannot create EEPROM file {self.path}: {exc.strerror or exc}") from None

    def __getstate__(self) -> dict[str, object]:
        """A copy (deepcopy, pickle) is nobody's to write through a server's thread."""
        state = self.__dict__.copy()
        del state["_write_lock"]
        state["on_change"] = None
        return state

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__dict__.update(state)
        self._write_lock = threading.Lock()

    def _read(self, path: Path) -> dict:
        try:
            raw = json.loads(read_text(path, TEXT_MAX, "EEPROM image"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, InputTooLarge,
                RecursionError) as exc:   # RecursionError: nesting too deep for json
            raise EepromError(f"cannot read EEPROM file {path}: {exc}") from None
        if not isinstance(raw, dict) or raw.get("format") != FORMAT:
            raise EepromError(f"{path} is not an OpenTMCL EEPROM file")
        if self.module and raw.get("module") not in (None, self.module):
            raise EepromError(f"{path} belongs to a {raw.get('module')}, not a {self.module}")
        if raw.get("version", VERSION) != VERSION:
            raise EepromError(f"{path}: EEPROM file format version {raw.get('version')!r}; "
                              f"this OpenTMCL reads version {VERSION}")
        if not _whole(raw):
            raise EepromError(f"{path}: damaged EEPROM file (a section or value is not what OpenTMCL "
                              "writes); left unchanged")
        data = _empty()
        for key in data:
            if key in raw:
                data[key] = raw[key]
        return data

    # --- typed access (JSON keys are strings) -----------------------------
    def get_axis(self, axis: int, number: int) -> int | None:
        return self.data["axis"].get(str(axis), {}).get(str(number))

    def set_axis(self, axis: int, number: int, value: int) -> None:
        self.data["axis"].setdefault(str(axis), {})[str(number)] = int(value)
        self._changed()

    def get_global(self, bank: int, number: int) -> int | None:
        return self.data["global"].get(str(bank), {}).get(str(number))

    def set_global(self, bank: int, number: int, value: int) -> None:
        self.data["global"].setdefault(str(bank), {})[str(number)] = int(value)
        self._changed()

    def get_user(self, number: int) -> int | None:
        return self.data["user"].get(str(number))

    def set_user(self, number: int, value: int) -> None:
        self.data["user"][str(number)] = int(value)
        self._changed()

    def get_coord(self, axis: int, number: int) -> int | None:
        return self.data["coord"].get(str(axis), {}).get(str(number))

    def set_coord(self, axis: int, number: int, value: int) -> None:
        self.data["coord"].setdefault(str(axis), {})[str(number)] = int(value)
        self._changed()

    @property
    def program(self) -> list[list[int]]:
        return self.data["program"]

    def set_program(self, program: list[list[int]]) -> None:
        self.data["program"] = [list(map(int, ins)) for ins in program]
        self._changed()

    def clear(self) -> None:
        """Factory state (command 137): everything erased."""
        self.data = _empty()
        self._changed()

    # --- persistence --------------------------------------------------------
    def _changed(self) -> None:
        self.dirty = True
        if not self.deferred:
            if self.on_change is not None:
                self.on_change()
            else:
                self.flush()

    def flush(self) -> None:
        """Write the image now if it changed."""
        snap = self.snapshot()
        if snap is not None:
            self.write(snap)

    def snapshot(self) -> tuple[int, dict] | None:
        """A copy of the image if it changed since the last snapshot (it then counts as written),
        else None; the caller holds what guards the module (the bus lock). Cheap: the sections are
        copied one level deep, the program list is shared (it is only ever replaced, never changed
        in place); `write` encodes it."""
        if self.path is None or not self.dirty:
            self.dirty = False
            return None
        data = self.data
        copy = {key: {k: dict(v) for k, v in data[key].items()} for key in ("axis", "global", "coord")}
        copy["user"] = dict(data["user"])
        copy["program"] = data["program"]
        self.dirty = False
        self._taken += 1
        return self._taken, copy

    def _encode(self, data: dict) -> str:
        """The file's JSON (keys sorted, compact); the program's part is encoded once per program
        (up to 65536 instructions: 30 ms, during which no other thread runs) and kept."""
        program = data["program"]
        if self._program_json is None or self._program_json[0] is not program:
            self._program_json = (program, json.dumps(program, separators=(",", ":")))
        fields = {"format": FORMAT, "version": VERSION, "module": self.module, **data}
        return "{" + ",".join(
            json.dumps(key) + ":" + (self._program_json[1] if key == "program" else
                                     json.dumps(value, separators=(",", ":"), sort_keys=True))
            for key, value in sorted(fields.items())) + "}"

    def write(self, snap: tuple[int, dict]) -> None:
        """Write a `snapshot` atomically, unless a later one is written already (two writers may
        race); an OSError leaves the image marked changed."""
        number, data = snap
        with self._write_lock:
            if number <= self._written or self.path is None:
                return
            try:
                write_atomic(self.path, self._encode(data).encode("utf-8"))
            except OSError:
                self.dirty = True
                raise
            self._written = number
