"""Replay a capture against a virtual module in virtual time and compare every reply (docs/capture.md).

    report = opentmcl.replay("run.jsonl", module="PD86-1180")
    assert report.ok, report.text()

The captured host requests for one module address are sent to four fresh `VirtualModule`s, the
twins, each started from the module's state at capture start (the capture's snapshot, another
one given, or values inferred from the first reads: capture/initial.py). The module acted on each
request somewhere between the end of the request on the wire and the start of its reply
(capture/timing.py); the twins act at the ends that bracket what it can have done
(capture/twin.py). A reply agrees when its status and command agree with a twin's, and its value
lies in the twins' range of that value over the interval in which the module could have sampled
it, widened by the tolerances (capture/compare.py, capture/tolerance.py). Tolerances only widen:
the twins' runs do not depend on them. Divergences are grouped under their root causes
(capture/causes.py); moves are timed on both sides (capture/moves.py). The result is a
`ReplayReport` (capture/outcome.py).
"""
from __future__ import annotations

import os
from collections.abc import Callable
from typing import TYPE_CHECKING

from ..protocol.opcodes import MOTION_COMMANDS, Op
from .causes import Divergence, group
from .compare import Comparer
from .format import Capture, fault_notes, read_capture
from .identify import captured_module, first_address, virtual_module
from .initial import idle_time, starting_state
from .moves import acceleration_estimates, events_of, find_moves
from .outcome import ReplayReport
from .schedule import Schedule
from .snapshot import apply_snapshot
from .timing import CLOCK_LAG, Slot, module_starts, slots
from .tolerance import ReplayError, Tolerance, as_tolerance
from .twin import Twin, TwinRun

if TYPE_CHECKING:
    from ..firmware.vm import VirtualModule
    from ..modules.profile import ModuleProfile

__all__ = ["Divergence", "ReplayError", "ReplayReport", "Tolerance", "assert_replays", "replay"]

POLICIES = ("hi", "lo", "early", "late")
"""The twins (capture/twin.py): the highest and lowest positions, the earliest and latest actions."""


def replay(capture: str | os.PathLike | Capture, module: str | os.PathLike | None = None, *,
           address: int | None = None, eeprom: str | os.PathLike | None = None, scenario=None,
           tolerance: Tolerance | dict | list | None = None, initial_state=None,
           state_scope: str = "all", clock_lag: float = CLOCK_LAG) -> ReplayReport:
    """Replay `capture` (a path or a read `Capture`) against fresh virtual twins of `module` (a name
    or a profile file; default: the module the capture identified, else the built-in profile of
    the same module number). `initial_state`: a `Snapshot` or a file (a capture with a snapshot, a
    probed profile with [snapshot]); default: the capture's snapshot, else values inferred from
    the first reads. `state_scope` "state" starts the twins only where the module was (positions),
    not from its settings (`opentmcl conform`). `clock_lag`: seconds the module's clock may trail
    the host's (capture/timing.py; it shapes the twins' runs, so it is no tolerance). Returns a
    `ReplayReport`.
    Raises ReplayError (bad module, address, initial state or tolerance) or CaptureError (bad file)."""
    cap = capture if isinstance(capture, Capture) else read_capture(capture)
    tol = as_tolerance(tolerance)
    notes: list[str] = list(cap.warnings) + fault_notes(cap)
    if module is None:
        module = captured_module(cap, address, notes)
    address = _address(cap, address)
    if not 0 <= clock_lag < 1:
        raise ReplayError(f"clock lag must be 0 <= seconds < 1, got {clock_lag!r}")
    cap_slots = slots(cap, clock_lag)
    motion_axes = {s.rec["motor"] for s in cap_slots if _moves_an_axis(s.rec, address)}
    make_vm = _maker(module, address, eeprom, scenario)
    profile, runs = _run_twins(make_vm, cap, cap_slots, address, initial_state, state_scope, tol.time,
                               motion_axes, notes)
    _note_widened(cap_slots, notes)
    report = ReplayReport(cap.path, profile.name, address, link=cap.link, tolerance=tol, notes=notes)
    _compare(Comparer(cap, profile, address, tol, report), cap_slots, runs)
    real = _real_traces(cap_slots, address, motion_axes)
    report.traces = {m: {"module": real[m], "twin": runs[0].trace.get(m, [])} for m in sorted(motion_axes)}
    return report


def _address(cap: Capture, address: int | None) -> int:
    """`address`, else that of the capture's first answered request (ReplayError if none)."""
    if address is None:
        address = first_address(cap)
        if address is None:
            raise ReplayError(f"{cap.path}: no host request in the capture")
    return address


def _moves_an_axis(rec: dict, address: int) -> bool:
    return rec["kind"] == "request" and rec["address"] == address and rec["command"] in MOTION_COMMANDS


def _maker(module, address: int, eeprom, scenario) -> Callable[[], VirtualModule]:
    """Builds a fresh twin of `module` at `address` on each call."""
    return lambda: virtual_module(module, address, eeprom, scenario)


def _run_twins(make_vm: Callable[[], VirtualModule], cap: Capture, cap_slots: list[Slot], address: int,
               initial_state, state_scope: str, tau: float, motion_axes: set[int],
               notes: list[str]) -> tuple[ModuleProfile, list[TwinRun]]:
    """Each twin's run through the capture, from the starting state (the notes say which): the
    profile of the twins and one `TwinRun` per policy, in POLICIES order."""
    vms = [make_vm() for _ in POLICIES]
    profile = vms[0].profile
    runs: list[TwinRun] = []
    try:
        snap = starting_state(cap, cap_slots, profile, address, initial_state, notes)
        # the state applies from its own instant in this capture, else from the start; never after a request
        start = min([snap.t if initial_state is None else 0.0, *(s.e for s in cap_slots[:1])])
        idle = idle_time(make_vm, snap, start, state_scope, notes)
        for vm, policy in zip(vms, POLICIES, strict=True):
            twin = Twin(vm, policy, tau, motion_axes, idle)
            twin.start(start)
            applied = apply_snapshot(vm, snap, scope=state_scope)
            if policy == POLICIES[0]:
                notes.extend(applied)
            runs.append(Schedule(twin, cap_slots).run())
    finally:
        for vm in vms:
            vm.close()
    return profile, runs


def _note_widened(cap_slots: list[Slot], notes: list[str]) -> None:
    widened = sum(1 for s in cap_slots if s.widened)
    if widened:
        notes.append(f"{widened} round trips were shorter than the link's wire time: their window is the whole "
                     "round trip (a pty or USB port that ignores the baud rate?)")


def _compare(comparer: Comparer, cap_slots: list[Slot], runs: list[TwinRun]) -> None:
    """Replies, events and moves against the twins', grouped into causes (ReplayError when no
    request to the address was compared: nothing checked is no evidence)."""
    cap, report, address = comparer.cap, comparer.report, comparer.address
    for slot in cap_slots:
        comparer.slot(slot, runs)
    if report.compared == 0:
        seen = sorted({r["address"] for r in cap.frames if r["kind"] == "request" and "address" in r})
        raise ReplayError(f"{cap.path}: no request to address {address} in the capture "
                          f"(requests go to {', '.join(map(str, seen)) or 'no address'})")
    starts = module_starts(cap)
    comparer.events(starts, runs)
    report.moves = find_moves(cap_slots, events_of(cap.frames, starts, address), runs, address, comparer.tol.time)
    comparer.moves(report.moves)
    report.accelerations = acceleration_estimates(report.moves)
    report.divergences.sort(key=lambda d: d.t)
    report.causes = group(comparer.checks)
    _diagnose(report)


def _real_traces(cap_slots: list[Slot], address: int, axes: set[int]) -> dict[int, dict[str, list]]:
    """The module's positions and speeds as the host read them (middle of each window)."""
    out: dict[int, dict[str, list]] = {m: {"position": [], "speed": []} for m in axes}
    for slot in cap_slots:
        rec, reply = slot.rec, slot.reply
        if rec["kind"] != "request" or rec["address"] != address or rec["command"] != Op.GAP or reply is None \
                or reply.get("status") != 100 or rec["motor"] not in out or rec["type"] not in (1, 3):
            continue
        key = "position" if rec["type"] == 1 else "speed"
        out[rec["motor"]][key].append(((slot.e + slot.s) / 2, int(reply["value"])))
    return out


def _diagnose(report: ReplayReport) -> None:
    """A note on motion causes: the accelerations measured on both sides and the move durations."""
    for cause in report.causes:
        axis = cause.root.axis
        if cause.area not in ("ramp shape", "move durations") or axis is None:
            continue
        parts = []
        for kind, (real, twin) in sorted(report.accelerations.get(axis, {}).items()):
            if twin and abs(real - twin) / twin > 0.05:
                parts.append(f"{kind} about {real:.0f} pps^2 on the module, {twin:.0f} on the twin")
        durations = [m.percent for m in report.moves if m.axis == axis and m.percent is not None and not m.ok]
        if durations:
            parts.append(f"moves {sum(durations) / len(durations):+.0f}% on average")
        cause.note = "; ".join(parts)


def assert_replays(capture, module=None, **kwargs) -> ReplayReport:
    """For a user's own tests: replay and fail with every divergence listed."""
    report = replay(capture, module, **kwargs)
    if not report.ok:
        raise AssertionError(report.text())
    return report
