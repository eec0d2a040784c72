"""The capture file: JSON Lines, one header record, then one record per frame (docs/capture.md).

Writing is line by line with a flush, so a proxy that is killed leaves a readable file. Reading is
bounded: a file larger than `MAX_CAPTURE_BYTES` or a line longer than `MAX_LINE_BYTES` is refused
with a one-line `CaptureError` naming the file and line.
"""
from __future__ import annotations

import datetime
import json
import os
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any, TextIO

from ..limits import open_regular

FORMAT = "opentmcl-capture"
VERSION = 1
MAX_CAPTURE_BYTES = 64 * 1024 * 1024
"""Largest capture file read (about 200,000 round trips)."""
MAX_LINE_BYTES = 4096
"""Longest record line read (a frame record is about 300 bytes)."""


FAULT = "fault"
"""The record kind of a fault that fired (docs/faults.md "Seeing what fired")."""


def fault_record(t: float, fired: Any) -> dict:
    """The capture record of a fault that fired `t` seconds after the capture started (`fired`:
    an opentmcl.faults `Fired`)."""
    return {"record": FAULT, "t": round(t, 6), "kind": fired.kind, "name": fired.name, "detail": fired.detail}


def fault_notes(capture: Capture) -> list[str]:
    """One line per fault the capture records (a replay report lists them: a reply the link lost
    or a module that lost its power is no divergence of the twin)."""
    return [f"fault at {f['t']:.3f} s: {f.get('name') or f['kind']} ({f['kind']}): {f['detail']}"
            for f in capture.faults]


class CaptureError(ValueError):
    """A capture file that cannot be read: one line, with the file and line number."""


class CaptureWriter:
    """Appends records to a JSON Lines file; thread-safe; `close()` writes the end record."""

    def __init__(self, path: str | os.PathLike, *, target: str, gap: float, tool: str,
                 link: dict | None = None) -> None:
        self._fh: TextIO | None = open(path, "w", encoding="utf-8")  # noqa: SIM115 - closed by close()
        self._lock = threading.Lock()
        self.frames = 0
        self.size = 0
        self.limit = MAX_CAPTURE_BYTES - 2 * MAX_LINE_BYTES  # room for the end records
        self.truncated = False
        header = {"record": "header", "format": FORMAT, "version": VERSION, "tool": tool, "target": target,
                  "start": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="milliseconds"),
                  "gap": gap}
        if link is not None:
            header["link"] = link
        self.write(header)

    def write(self, record: dict) -> None:
        """Append one record. Every record counts against the size cap (`limit`): past it, records
        are dropped and one `truncated` record says so; the `end` record always fits, in the room
        kept for it and the note (the relay goes on; a file is never written larger than
        `read_capture` reads)."""
        line = json.dumps(record, ensure_ascii=True, separators=(",", ":")) + "\n"
        with self._lock:
            if self._fh is None:
                return
            if record.get("record") != "end":
                if self.truncated or self.size + len(line) > self.limit:
                    if not self.truncated:
                        self.truncated = True
                        note = {"record": "truncated", "t": record.get("t"), "frames": self.frames}
                        self._put(json.dumps(note, separators=(",", ":")) + "\n")
                    return
                if record.get("record") == "frame":
                    self.frames += 1
            self._put(line)

    def _put(self, line: str) -> None:
        assert self._fh is not None
        self._fh.write(line)
        self._fh.flush()
        self.size += len(line)

    def close(self, t: float) -> None:
        self.write({"record": "end", "t": round(t, 6), "frames": self.frames})
        with self._lock:
            if self._fh is not None:
                self._fh.close()
                self._fh = None


@dataclass
class Capture:
    """A capture read back: its header, the frame records in order, the identities seen."""

    path: str
    header: dict
    frames: list[dict] = field(default_factory=list)
    identities: list[dict] = field(default_factory=list)
    truncated: float | None = None
    """When the proxy stopped capturing at the size cap (its `truncated` record), else None."""
    snapshots: list[dict] = field(default_factory=list)
    """The `snapshot` records (capture/snapshot.py `snapshot_of` assembles them)."""
    marks: list[dict] = field(default_factory=list)
    """The `mark` records: the phases of a conformance run (`opentmcl conform`)."""
    faults: list[dict] = field(default_factory=list)
    """The `fault` records: faults that fired while the capture ran (docs/faults.md)."""
    warnings: list[str] = field(default_factory=list)
    """What was skipped while reading (a torn last line), one line each."""

    @property
    def link(self) -> dict:
        """The link the capture was taken on: interface, baud (None if unknown) and the seconds one
        9-byte frame takes on the wire (0 when unknown: the timestamps alone then bound each window)."""
        link = self.header.get("link")
        out = {"interface": "unknown", "baud": None, "frame_time": 0.0}
        if isinstance(link, dict):
            out.update(link)
        return out

    def module_name(self) -> str | None:
        """The built-in module the host identified (command 136), if any."""
        for ident in self.identities:
            if ident.get("module"):
                return ident["module"]
        return None


def _lines(path: str) -> Iterator[tuple[int, bytes]]:
    """(line number, line) of a capture file: a regular file (limits.open_regular) of at most
    MAX_CAPTURE_BYTES, lines of at most MAX_LINE_BYTES."""
    try:
        with open_regular(path) as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > MAX_CAPTURE_BYTES:
                raise CaptureError(f"{path}: {size} bytes, larger than the {MAX_CAPTURE_BYTES} bytes "
                                   "a capture may have")
            number = 0
            while line := fh.readline(MAX_LINE_BYTES + 1):
                number += 1
                if len(line) > MAX_LINE_BYTES:
                    raise CaptureError(f"{path}:{number}: line longer than {MAX_LINE_BYTES} bytes")
                yield number, line
    except OSError as exc:
        raise CaptureError(f"{path}: cannot read: {exc.strerror or exc}") from None


_FRAME_KEYS: dict[str, type | tuple[type, ...]] = {"t": (int, float), "dir": str, "kind": str, "raw": str}
_KIND_KEYS = {  # the decoded fields replay and `log show` rely on, per kind (all integers)
    "request": ("address", "command", "type", "motor", "value"),
    "reply": ("address", "status", "command", "value"),
    "event": ("address", "status", "command", "value"),
    "version": ("address",), "memory": ("address",),
}


def _record(line: bytes, path: str, number: int) -> dict[str, Any]:
    """One line as a JSON object."""
    try:
        rec = json.loads(line)
    except (ValueError, UnicodeDecodeError):
        raise CaptureError(f"{path}:{number}: not a JSON record") from None
    except RecursionError:   # e.g. 4000 "[": no record of this format nests at all
        raise CaptureError(f"{path}:{number}: not a capture record (arrays or objects nested too deeply)") from None
    if not isinstance(rec, dict):
        raise CaptureError(f"{path}:{number}: not a JSON object")
    return rec


def _check_header(rec: dict[str, Any], path: str, number: int) -> None:
    """The first record: the header of a capture of this format version."""
    if rec.get("record") != "header" or rec.get("format") != FORMAT:
        raise CaptureError(f"{path}:{number}: not an {FORMAT} file (the first record must be its header)")
    if rec.get("version") != VERSION:
        raise CaptureError(f"{path}:{number}: capture format version {rec.get('version')!r}, "
                           f"this tool reads version {VERSION}")


def _check_frame(rec: dict[str, Any], path: str, number: int) -> None:
    """A frame record with the keys replay and `log show` rely on; adds its `bytes`."""
    for key, types in _FRAME_KEYS.items():
        if not isinstance(rec.get(key), types) or isinstance(rec.get(key), bool):
            raise CaptureError(f"{path}:{number}: frame record without a valid {key!r}")
    if not 0 <= rec["t"] < float("inf"):  # also NaN: seconds since the proxy started
        raise CaptureError(f"{path}:{number}: 't' must be a finite number of seconds >= 0, got {rec['t']!r}")
    for key in _KIND_KEYS.get(rec["kind"], ()):
        if type(rec.get(key)) is not int:
            raise CaptureError(f"{path}:{number}: {rec['kind']} record without an integer {key!r}")
    if "request" in rec and type(rec["request"]) is not int:
        raise CaptureError(f"{path}:{number}: 'request' is not a record number")
    if rec["dir"] not in ("host", "module"):
        raise CaptureError(f"{path}:{number}: 'dir' must be \"host\" or \"module\"")
    try:
        rec["bytes"] = bytes.fromhex(rec["raw"])
    except ValueError:
        raise CaptureError(f"{path}:{number}: 'raw' is not hex") from None


_IDENTITY_KEYS: dict[str, tuple[type, str]] = {"address": (int, "an address"), "module": (str, "a module name"),
                                               "firmware_version": (str, "a firmware string")}


def _check_identity(rec: dict[str, Any], path: str, number: int) -> None:
    """An identity record: its address, module and firmware string, where given, of their types."""
    for key, (kind, what) in _IDENTITY_KEYS.items():
        if key in rec and type(rec[key]) is not kind:
            raise CaptureError(f"{path}:{number}: identity record: {key!r} is not {what}")


def _check_link(rec: dict[str, Any], path: str, number: int) -> None:
    """The header's `link`: interface, baud rate and wire time per frame, of their types."""
    link = rec.get("link")
    if link is None:
        return
    frame_time = link.get("frame_time") if isinstance(link, dict) else None
    if not isinstance(link, dict) or not isinstance(link.get("interface"), str) \
            or not (link.get("baud") is None or type(link.get("baud")) is int) \
            or not isinstance(frame_time, (int, float)) or isinstance(frame_time, bool) \
            or not 0 <= frame_time < 1:
        raise CaptureError(f"{path}:{number}: header 'link' must give interface, baud and frame_time "
                           "(seconds, 0 <= frame_time < 1)")


def _int_rows(rows: Any, width: int) -> bool:
    return isinstance(rows, list) and all(
        isinstance(row, list) and len(row) == width and all(type(x) is int for x in row) for row in rows)


_SNAPSHOT_PARTS = {"axis": ("motor", 2), "global": ("bank", 2), "io": ("bank", 2), "program": ("start", 4),
                   "begin": (None, 0), "done": (None, 0)}


def _check_snapshot(rec: dict[str, Any], path: str, number: int) -> None:
    """A snapshot record: its address, part and rows of integers (capture/snapshot.py)."""
    part = _SNAPSHOT_PARTS.get(rec.get("part"))  # type: ignore[arg-type]
    if part is None or type(rec.get("address")) is not int:
        raise CaptureError(f"{path}:{number}: snapshot record without an integer 'address' and a 'part' "
                           f"({', '.join(_SNAPSHOT_PARTS)})")
    key, width = part
    if key is not None and (type(rec.get(key)) is not int or not _int_rows(rec.get("values"), width)):
        raise CaptureError(f"{path}:{number}: snapshot {rec['part']} record needs an integer {key!r} "
                           f"and 'values' rows of {width} integers")


def _check_mark(rec: dict[str, Any], path: str, number: int) -> None:
    t = rec.get("t")
    if not isinstance(t, (int, float)) or isinstance(t, bool) or not 0 <= t < float("inf") \
            or not isinstance(rec.get("phase"), str):
        raise CaptureError(f"{path}:{number}: mark record without a time 't' and a 'phase'")


def _check_fault(rec: dict[str, Any], path: str, number: int) -> None:
    t = rec.get("t")
    if not isinstance(t, (int, float)) or isinstance(t, bool) or not 0 <= t < float("inf") \
            or not isinstance(rec.get("kind"), str) or not isinstance(rec.get("detail"), str) \
            or not (rec.get("name") is None or isinstance(rec.get("name"), str)):
        raise CaptureError(f"{path}:{number}: fault record without a time 't', a 'kind' and a 'detail'")


def _torn(line: bytes, path: str, number: int) -> str | None:
    """The warning for a last line cut before its end (no newline, not a JSON object), else None."""
    if line.endswith(b"\n"):
        return None
    try:
        json.loads(line)
    except (ValueError, UnicodeDecodeError, RecursionError):
        return f"{path}:{number}: torn last line skipped ({len(line)} bytes without an end: the capture was cut off)"
    return None


def read_capture(path: str | os.PathLike[str]) -> Capture:
    """Read and check a capture file; CaptureError (one line) if it is not one. A last line cut
    before its end (a pulled cable, a full disk) is skipped with a warning (`Capture.warnings`);
    a broken line anywhere else is an error naming its line."""
    path = os.fspath(path)
    capture: Capture | None = None
    warning = None
    for number, line in _lines(path):
        if not line.strip():
            continue
        warning = _torn(line, path, number)   # only the last line can lack its newline
        if warning is not None:
            continue
        rec = _record(line, path, number)
        if capture is None:
            _check_header(rec, path, number)
            _check_link(rec, path, number)
            capture = Capture(path, rec)
        elif rec.get("record") == "frame":
            _check_frame(rec, path, number)
            capture.frames.append(rec)
        elif rec.get("record") == "identity":
            _check_identity(rec, path, number)
            capture.identities.append(rec)
        elif rec.get("record") == "truncated" and capture.truncated is None:
            t = rec.get("t")
            capture.truncated = float(t) if isinstance(t, (int, float)) and not isinstance(t, bool) else 0.0
        elif rec.get("record") == "snapshot":
            _check_snapshot(rec, path, number)
            capture.snapshots.append(rec)
        elif rec.get("record") == "mark":
            _check_mark(rec, path, number)
            capture.marks.append(rec)
        elif rec.get("record") == FAULT:
            _check_fault(rec, path, number)
            capture.faults.append(rec)
    if capture is None:
        raise CaptureError(f"{path}: empty, not a capture file" if warning is None else
                           f"{path}:1: not a capture file (its only line is cut off)")
    if warning is not None:
        capture.warnings.append(warning)
    return capture
