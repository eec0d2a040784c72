"""Where the twins start: the module's state at capture start and how long they stood before
(docs/capture.md "Replay").

The state is a given `Snapshot` or file, else the capture's snapshot, else the positions the host
read before anything moved or set an axis (inferred, and said so in the notes).
"""
from __future__ import annotations

import os
from collections.abc import Callable

from ..modules.state import moving_class
from ..protocol.opcodes import CONTROL_FIRST, MOTION_COMMANDS, Op
from .format import Capture
from .snapshot import Snapshot, SnapshotError, apply_snapshot, snapshot_from_file, snapshot_of
from .timing import Slot
from .tolerance import ReplayError

IDLE = 10.0
"""Seconds a twin may stand before the capture: longer than the longest power-down delay of the
profiles (TMCM-6212 AP214: 4.17 s), after which a standing motor gets its standby current."""
INFERRED = {(Op.GAP, 0): "target_position", (Op.GAP, 1): "actual_position", (Op.GAP, 209): "encoder_position"}
"""The reads a state is inferred from (AP0, AP1, AP209)."""


def inferred_state(cap_slots: list[Slot], profile, address: int) -> tuple[Snapshot, list[str]]:
    """Without a snapshot: the positions (AP0, AP1, AP209) an axis reported before anything moved
    or set it, taken as its state at capture start; the notes say which."""
    snap = Snapshot(address, source="inferred")
    touched: set[int] = set()
    notes = []
    for slot in cap_slots:
        rec, reply = slot.rec, slot.reply
        if rec["kind"] != "request" or rec["address"] != address:
            continue
        motor = rec["motor"]
        if rec["command"] in MOTION_COMMANDS or rec["command"] == Op.SAP or rec["command"] >= CONTROL_FIRST:
            touched.add(motor if rec["command"] < CONTROL_FIRST else -1)
            continue
        if -1 in touched or motor in touched or motor >= profile.axes:
            continue
        key = (rec["command"], rec["type"])
        if key in INFERRED and reply is not None and reply.get("status") == 100 \
                and rec["type"] not in snap.axis.get(motor, {}):
            snap.axis.setdefault(motor, {})[rec["type"]] = int(reply["value"])
            if reply["value"]:
                notes.append(f"axis {motor} {INFERRED[key]} = {reply['value']} (inferred from its first "
                             f"read at t={float(rec['t']):.3f} s)")
    return snap, notes


def starting_state(cap: Capture, cap_slots: list[Slot], profile, address: int,
                   initial_state, notes: list[str]) -> Snapshot:
    """The state the twins start from (module doc); the notes say where it came from."""
    if isinstance(initial_state, Snapshot):
        notes.append(f"initial state: {initial_state.source or 'given'} ({initial_state.count()} values)")
        return initial_state
    if initial_state is not None:
        try:
            snap = snapshot_from_file(initial_state, address)
        except SnapshotError as exc:
            raise ReplayError(str(exc)) from None
        notes.append(f"initial state: {os.fspath(initial_state)} ({snap.count()} values)")
        return snap
    found = snapshot_of(cap, address)
    if found is not None:
        part = "" if found.complete else ", cut off before its end"
        notes.append(f"initial state: the capture's snapshot at t={found.t:.3f} s ({found.count()} values{part})")
        return found
    snap, inferred = inferred_state(cap_slots, profile, address)
    notes.append("no snapshot in the capture: the twin starts from power-up"
                 + (" with values inferred from the first reads" if inferred else ""))
    notes.extend(inferred)
    return snap


def _readings(snap: Snapshot, vm) -> tuple[int, int]:
    """(read-only axis values of the snapshot the twin reads alike, those it reads otherwise)."""
    same = other = 0
    for motor, values in snap.axis.items():
        for number, value in values.items():
            p = vm.profile.axis_parameters.get(number)
            if p is None or p.writable or motor >= vm.profile.axes or moving_class(p.name) not in ("load", "flag"):
                continue
            reply = vm.request(Op.GAP, number, motor, 0)
            if reply is not None and reply.status == 100:
                same, other = (same + 1, other) if reply.value == value else (same, other + 1)
    return same, other


def idle_time(make_vm: Callable, snap: Snapshot, start: float, scope: str, notes: list[str]) -> float:
    """How long the twins stand before the capture: 0, or IDLE when the snapshot's read-only
    readings (load, flags: a motor at standby current, AP180) agree better with a twin that has
    stood that long. A capture seldom starts right after power-up; the snapshot says which."""
    if not any(snap.axis.values()):
        return 0.0
    scores = []
    for idle in (0.0, IDLE):
        vm = make_vm()
        try:
            vm.advance(idle + start)
            apply_snapshot(vm, snap, scope=scope)
            scores.append(_readings(snap, vm))
        finally:
            vm.close()
    if scores[1][1] < scores[0][1]:
        notes.append(f"the twins stood {IDLE:g} s before the capture: the snapshot's readings (standby "
                     f"current, flags) agree with that in {scores[1][0]} of {sum(scores[1])} values")
        return IDLE
    return 0.0
