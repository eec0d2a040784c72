"""The state of a module at capture start: read with reading commands only, replayed into the twin.

    snap = take_snapshot(ask, profile, address=1)        # GAP, GGP, GIO (and 134 on request)
    records = snapshot_records(snap, t=0.0)               # capture records (docs/capture.md)
    notes = apply_snapshot(vm, snap, scope="all")         # the twin starts from it (SAP, SGP, SIO, 132)

`ask(command, type, motor, value)` returns the reply's value, None when the module refuses the
request (an error status), and raises on a link error. A snapshot covers every readable axis
parameter of every axis, every readable global parameter (user variables included) and I/O port of
the profile (scope "full"), or only the values that say where the module is (scope "state",
modules/state.py). The program memory is read with command 134 only when asked.
"""
from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..modules.state import SET_STATE, UNREPRODUCIBLE, is_state
from ..protocol.opcodes import ENTER_DOWNLOAD_MODE, EXIT_DOWNLOAD_MODE, Op

if TYPE_CHECKING:
    from ..modules.profile import ModuleProfile
    from .format import Capture

# plain ints for the requests of a snapshot (`Client.request` keeps plain-int requests ready)
_GAP, _GGP, _GIO, _SAP, _SGP, _SIO = int(Op.GAP), int(Op.GGP), int(Op.GIO), int(Op.SAP), int(Op.SGP), int(Op.SIO)
_MST, _MVP = int(Op.MST), int(Op.MVP)
USER_VARIABLE_BANK = 2
OUTPUT_BANK = 2
ROWS_PER_RECORD = 100
"""Rows per snapshot record: a record line stays far below the reader's 4096 bytes."""
INSTRUCTIONS_PER_RECORD = 64
EMPTY_RUN = 64
"""The program read (134) stops after this many empty (all-zero) instructions in a row."""
KEEP = frozenset({(0, 65), (0, 66), (0, 69), (0, 70), (0, 71), (0, 76), (0, 81), (0, 83), (0, 87), (0, 255)})
"""Global parameters a snapshot never writes into the twin: the link (baud rates, addresses, CAN
IDs, host address), code protection (its change erases the program) and suppress reply; the
replay talks to the twin at the capture's address."""

Ask = Callable[[int, int, int, int], "int | None"]


class SnapshotError(ValueError):
    """A snapshot file that cannot be used (one line)."""


@dataclass
class Snapshot:
    """Values read from one module: axis[motor][number], globals[(bank, number)], io[(bank, port)],
    program[index] = (command, type, motor, value)."""

    address: int
    t: float = 0.0
    firmware_version: str | None = None
    module: str | None = None
    axis: dict[int, dict[int, int]] = field(default_factory=dict)
    globals: dict[tuple[int, int], int] = field(default_factory=dict)
    io: dict[tuple[int, int], int] = field(default_factory=dict)
    program: dict[int, tuple[int, int, int, int]] | None = None
    complete: bool = True
    source: str = ""

    def count(self) -> int:
        return (sum(len(v) for v in self.axis.values()) + len(self.globals) + len(self.io)
                + len(self.program or {}))


def _axis_numbers(profile: ModuleProfile, scope: str) -> list[int]:
    return [n for n, p in sorted(profile.axis_parameters.items())
            if p.readable and (scope == "full" or is_state(p.name))]


def _global_keys(profile: ModuleProfile, scope: str) -> list[tuple[int, int]]:
    keys = [k for k, p in sorted(profile.global_parameters.items())
            if p.readable and (scope == "full" or is_state(p.name))]
    if scope == "full":
        keys += [(USER_VARIABLE_BANK, n) for n in range(profile.user_variables)
                 if (USER_VARIABLE_BANK, n) not in profile.global_parameters]
    return keys


def take_snapshot(ask: Ask, profile: ModuleProfile, address: int, *, scope: str = "full",
                  program: bool = False, read_memory: Callable[[int], tuple[int, int, int, int] | None] | None = None,
                  version: str | None = None) -> Snapshot:
    """Read the module's state with GAP, GGP and GIO (and 134 with `program`): see the module doc."""
    snap = Snapshot(address, firmware_version=version, module=profile.name)
    for motor in range(profile.axes):
        values = {}
        for number in _axis_numbers(profile, scope):
            v = ask(_GAP, number, motor, 0)
            if v is not None:
                values[number] = v
        snap.axis[motor] = values
    for bank, number in _global_keys(profile, scope):
        v = ask(_GGP, number, bank, 0)
        if v is not None:
            snap.globals[(bank, number)] = v
    if scope == "full":
        for (bank, port), p in sorted(profile.io.items()):
            if "R" in p.access:
                v = ask(_GIO, port, bank, 0)
                if v is not None:
                    snap.io[(bank, port)] = v
    if program and read_memory is not None:
        snap.program = _read_program(read_memory, profile.program_memory)
    return snap


def _read_program(read_memory: Callable[[int], tuple[int, int, int, int] | None],
                  size: int) -> dict[int, tuple[int, int, int, int]]:
    """Instructions up to the first run of `EMPTY_RUN` empty ones (or a refused read: protected)."""
    out: dict[int, tuple[int, int, int, int]] = {}
    empty = 0
    for index in range(size):
        ins = read_memory(index)
        if ins is None:
            break
        out[index] = ins
        empty = empty + 1 if not any(ins) else 0
        if empty >= EMPTY_RUN:
            break
    while out and not any(out[max(out)]):
        del out[max(out)]
    return out


# -- records ---------------------------------------------------------------------------------
def _chunks(rows: list, size: int) -> Iterable[list]:
    for start in range(0, len(rows), size):
        yield rows[start:start + size]


def snapshot_records(snap: Snapshot, t: float) -> list[dict]:
    """The snapshot as capture records: `begin`, rows by axis, bank and program, `done`."""
    head = {"record": "snapshot", "t": round(t, 6), "address": snap.address}
    out = [{**head, "part": "begin", "firmware_version": snap.firmware_version, "module": snap.module}]
    for motor, values in sorted(snap.axis.items()):
        for rows in _chunks(sorted([n, v] for n, v in values.items()), ROWS_PER_RECORD):
            out.append({**head, "part": "axis", "motor": motor, "values": rows})
    banks = sorted({b for b, _ in snap.globals})
    for bank in banks:
        rows_all = sorted([n, v] for (b, n), v in snap.globals.items() if b == bank)
        for rows in _chunks(rows_all, ROWS_PER_RECORD):
            out.append({**head, "part": "global", "bank": bank, "values": rows})
    for bank in sorted({b for b, _ in snap.io}):
        rows = sorted([p, v] for (b, p), v in snap.io.items() if b == bank)
        out.append({**head, "part": "io", "bank": bank, "values": rows})
    if snap.program is not None:
        items = sorted(snap.program.items())
        for start in range(0, len(items), INSTRUCTIONS_PER_RECORD):
            chunk = items[start:start + INSTRUCTIONS_PER_RECORD]
            out.append({**head, "part": "program", "start": chunk[0][0], "values": [list(i) for _, i in chunk]})
        if not items:
            out.append({**head, "part": "program", "start": 0, "values": []})
    out.append({**head, "part": "done"})
    return out


def snapshot_of(capture: Capture, address: int | None) -> Snapshot | None:
    """The snapshot the capture holds for `address` (the first one if None), else None."""
    recs = [r for r in capture.snapshots if address is None or r["address"] == address]
    if not recs:
        return None
    address = recs[0]["address"]
    snap = Snapshot(address, t=float(recs[0].get("t") or 0.0), complete=False, source=capture.path)
    for rec in recs:
        add = _PARTS.get(rec["part"])
        if rec["address"] == address and add is not None:
            add(snap, rec)
    return snap


def _text(rec: dict, key: str) -> str | None:
    value = rec.get(key)
    return value if isinstance(value, str) else None


def _begin(snap: Snapshot, rec: dict) -> None:
    snap.firmware_version = _text(rec, "firmware_version")
    snap.module = _text(rec, "module")


def _axis(snap: Snapshot, rec: dict) -> None:
    snap.axis.setdefault(rec["motor"], {}).update({n: v for n, v in rec["values"]})


def _global(snap: Snapshot, rec: dict) -> None:
    snap.globals.update({(rec["bank"], n): v for n, v in rec["values"]})


def _io(snap: Snapshot, rec: dict) -> None:
    snap.io.update({(rec["bank"], p): v for p, v in rec["values"]})


def _program(snap: Snapshot, rec: dict) -> None:
    prog = snap.program if snap.program is not None else {}
    for i, ins in enumerate(rec["values"]):
        prog[rec["start"] + i] = (ins[0], ins[1], ins[2], ins[3])
    snap.program = prog


def _done(snap: Snapshot, rec: dict) -> None:
    snap.complete = True


_PARTS: dict[str, Callable[[Snapshot, dict], None]] = {
    "begin": _begin, "axis": _axis, "global": _global, "io": _io, "program": _program, "done": _done}
"""What each part of a snapshot record adds to the snapshot (docs/capture.md)."""


def snapshot_from_file(path: str | os.PathLike[str], address: int | None) -> Snapshot:
    """`replay --initial-state FILE`: the snapshot of a capture file, or the `[snapshot]` section of
    a probed profile (`profile probe`). SnapshotError (one line) if the file has none."""
    from ..modules.profile_file import ProfileError, read_toml
    from .format import CaptureError, read_capture

    path = os.fspath(path)
    if path.lower().endswith(".toml"):
        from pathlib import Path

        from ..modules.state import snapshot_errors

        try:
            data = read_toml(Path(path))
        except ProfileError as exc:
            raise SnapshotError(str(exc)) from None
        table = data.get("snapshot")
        if table is None:
            raise SnapshotError(f"{path}: no [snapshot] section (write one with opentmcl profile probe)")
        errors = snapshot_errors(table)
        if errors:
            raise SnapshotError(f"{path}: {errors[0]}")
        snap = Snapshot(address if address is not None else 1, source=path,
                        firmware_version=table.get("firmware_version"))
        for motor, number, value in table.get("axis_parameter", []):
            snap.axis.setdefault(motor, {})[number] = value
        snap.globals = {(b, n): v for b, n, v in table.get("global_parameter", [])}
        snap.io = {(b, p): v for b, p, v in table.get("io", [])}
        return snap
    try:
        cap = read_capture(path)
    except CaptureError as exc:
        raise SnapshotError(str(exc)) from None
    found = snapshot_of(cap, address)
    if found is None:
        raise SnapshotError(f"{path}: the capture holds no snapshot"
                            + (f" of address {address}" if address is not None else ""))
    return found


# -- into the twin ---------------------------------------------------------------------------
def _differs(vm, command: int, type_: int, motor: int, value: int) -> bool:
    reply = vm.request(command, type_, motor, 0)
    return reply is None or reply.status != 100 or reply.value != value


def _differing(vm, snap: Snapshot) -> list[str]:
    """The settings of the snapshot that differ from the twin's power-up values, one text each."""
    prof = vm.profile
    out = []
    for motor, values in sorted(snap.axis.items()):
        for number, value in sorted(values.items()):
            p = prof.axis_parameters.get(number)
            if p is not None and p.writable and not is_state(p.name) and motor < prof.axes:
                reply = vm.request(_GAP, number, motor, 0)
                if reply is not None and reply.status == 100 and reply.value != value:
                    out.append(f"axis {motor} {p.name} {value} (profile {reply.value})")
    for (bank, number), value in sorted(snap.globals.items()):
        p = prof.global_parameters.get((bank, number))
        name = p.name if p is not None else f"user variable {number}" if bank == USER_VARIABLE_BANK else None
        if name is None or (p is not None and (not p.writable or is_state(p.name))):
            continue
        reply = vm.request(_GGP, number, bank, 0)
        if reply is not None and reply.status == 100 and reply.value != value:
            out.append(f"{name} {value} (profile {reply.value})")
    return out


def _set(vm, notes: list[str], what: str, command: int, type_: int, motor: int, value: int) -> None:
    reply = vm.request(command, type_, motor, value)
    if reply is not None and reply.status != 100:
        notes.append(f"{what} = {value}: the twin refuses it (status {reply.status})")


def _apply_config(vm, snap: Snapshot, notes: list[str]) -> None:
    """Every writable setting that differs: global parameters, axis parameters, outputs."""
    _apply_globals(vm, snap, notes)
    _apply_axis_settings(vm, snap, notes)
    _apply_outputs(vm, snap, notes)


def _apply_globals(vm, snap: Snapshot, notes: list[str]) -> None:
    """Writable global parameters (but KEEP) and the profile's user variables."""
    prof = vm.profile
    for (bank, number), value in sorted(snap.globals.items()):
        p = prof.global_parameters.get((bank, number))
        user = bank == USER_VARIABLE_BANK and p is None and number < prof.user_variables
        if (bank, number) in KEEP or not (user or (p is not None and p.writable and not is_state(p.name))):
            continue
        if _differs(vm, _GGP, number, bank, value):
            _set(vm, notes, f"GP {bank}:{number}", _SGP, number, bank, value)


def _apply_axis_settings(vm, snap: Snapshot, notes: list[str]) -> None:
    """Writable axis parameters that are settings, not state."""
    prof = vm.profile
    for motor, values in sorted(snap.axis.items()):
        for number, value in sorted(values.items()):
            p = prof.axis_parameters.get(number)
            if p is None or not p.writable or is_state(p.name) or motor >= prof.axes:
                continue
            if _differs(vm, _GAP, number, motor, value):
                _set(vm, notes, f"axis {motor} {p.name}", _SAP, number, motor, value)


def _apply_outputs(vm, snap: Snapshot, notes: list[str]) -> None:
    """Writable outputs (bank 2)."""
    for (bank, port), value in sorted(snap.io.items()):
        p = vm.profile.io.get((bank, port))
        if bank == OUTPUT_BANK and p is not None and "W" in p.access and _differs(vm, _GIO, port, bank, value):
            _set(vm, notes, f"output {port}", _SIO, port, bank, value)


def _apply_program(vm, program: dict[int, tuple[int, int, int, int]], notes: list[str]) -> None:
    """Download the read instructions (132 ... 133) where they were read."""
    if not program:
        return
    reply = vm.request(ENTER_DOWNLOAD_MODE, 0, 0, min(program))
    if reply is None or reply.status != 100:
        notes.append("the twin refuses the program download (132)")
        return
    for index in range(min(program), max(program) + 1):
        command, type_, motor, value = program.get(index, (0, 0, 0, 0))
        vm.request(command, type_, motor, value)
    vm.request(EXIT_DOWNLOAD_MODE, 0, 0, 0)


def _apply_position(vm, motor: int, values: dict[int, int], notes: list[str]) -> None:
    """Target and actual position (AP0, AP1) without a move: the actual position is set to the
    target, MVP ABS goes there (which makes it the target MVP REL counts from, manual 3.6.4), and
    when the axis stood elsewhere (after ROR and MST) MST and the actual position follow. A moving
    axis starts at rest."""
    target, actual = values.get(0), values.get(1)
    speed = values.get(3, 0)
    if speed:
        notes.append(f"axis {motor} was moving at the snapshot ({speed}): the twin starts it at rest (inferred)")
    if actual is None:
        return
    target = actual if target is None else target
    _set(vm, notes, f"axis {motor} actual_position", _SAP, 1, motor, target)
    _set(vm, notes, f"axis {motor} target_position", _MVP, 0, motor, target)
    if target != actual:
        vm.request(_MST, 0, motor, 0)
        _set(vm, notes, f"axis {motor} actual_position", _SAP, 1, motor, actual)


def apply_snapshot(vm, snap: Snapshot, *, scope: str = "all") -> list[str]:
    """Start the twin `vm` from `snap` over its wire API (SAP, SGP, SIO, 132/133, MST). Scope "all":
    settings, program and state; "state": only where the module is (positions, encoder, tick
    timer). Returns notes on what could not be reproduced."""
    notes: list[str] = []
    prof = vm.profile
    differing = _differing(vm, snap)
    if differing:
        shown = ", ".join(differing[:8]) + (f" and {len(differing) - 8} more" if len(differing) > 8 else "")
        verb = "the twin takes them" if scope == "all" else "the twin keeps the profile's (settings from the profile)"
        notes.append(f"{len(differing)} settings at capture start differ from the profile's: {shown}; {verb}")
    if scope == "all":
        _apply_config(vm, snap, notes)
        if snap.program:
            _apply_program(vm, snap.program, notes)
    for motor, values in sorted(snap.axis.items()):
        if motor >= prof.axes:
            continue
        _apply_position(vm, motor, values, notes)
        for number, value in sorted(values.items()):
            p = prof.axis_parameters.get(number)
            if p is not None and number not in (0, 1, 2) and p.name in SET_STATE and p.writable \
                    and _differs(vm, _GAP, number, motor, value):
                _set(vm, notes, f"axis {motor} {p.name}", _SAP, number, motor, value)
    for (bank, number), value in sorted(snap.globals.items()):
        p = prof.global_parameters.get((bank, number))
        if p is not None and p.name in SET_STATE and p.name not in UNREPRODUCIBLE and p.writable:
            _set(vm, notes, f"GP {bank}:{number} {p.name}", _SGP, number, bank, value)
    return notes
