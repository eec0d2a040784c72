"""Copies of a module during a reference search (issue 28 item 5: "`deepcopy`/pickle of a module
during a reference search raises TypeError").

A copy (copy.deepcopy, pickle) taken at any moment of a search goes on exactly as the original
does from that moment: the same positions, speeds and RFS STATUS at every step, the same phases
in the search log, the same reference point, AP196 and AP197 - and the original is left alone.
Modes: TMCM-6212 manual 6.1 (1-7, +64, +128 inverted home switch), PD86-1180 manual 7.1 (1-3);
RFS START/STATUS: TMCM-6212 manual 3.6.11.
"""
from __future__ import annotations

import copy
import pickle

import pytest

from opentmcl import VirtualModule

from .test_reference import STAGE

STEP = 0.002         # virtual seconds between looks: several in each calibration move
LIMIT = 100_000      # steps: 200 virtual seconds, as Rig.search
STAGE_1180 = {"axis": {"0": {"left": {"position": -20000}, "right": {"position": 30000},
                             "home": {"position": 5000, "width": 1000}}}}
INVERTED_HOME = {"axis": {"0": {"left": {"position": -20000},
                                "home": {"position": 5000, "width": 1000, "inverted": True}}}}

CASES = [("TMCM-6212", mode, STAGE) for mode in (1, 2, 3, 4, 5, 6, 7, 65, 66, 67, 68)] \
    + [("TMCM-6212", 5 + 128, INVERTED_HOME), ("TMCM-1021", 2, STAGE)] \
    + [("TMCM-1180", mode, STAGE_1180) for mode in (1, 2, 3)]


def ok(vm: VirtualModule, command: int, type_: int, value: int = 0) -> int:
    reply = vm.request(command, type_, 0, value)
    assert reply.status == 100, (command, type_, reply.status)
    return reply.value


def look(vm: VirtualModule) -> tuple:
    """What a host and the world see of axis 0: time, GAP 1 (actual position), GAP 3 (actual
    speed), RFS STATUS, the slider's physical position."""
    return (vm.now, ok(vm, 6, 1), ok(vm, 6, 3), ok(vm, 13, 2), vm.world.axis(0).physical_position)


def finish(vm: VirtualModule, steps: int = LIMIT) -> list[tuple]:
    """Looks after each step until RFS STATUS reads 0 (the search has ended)."""
    seen = []
    for _ in range(steps):
        vm.advance(STEP)
        seen.append(look(vm))
        if seen[-1][3] == 0:
            return seen
    raise AssertionError("reference search did not end")


def result(vm: VirtualModule) -> tuple:
    """The search log, the reference point and AP196/AP197 (TMCM-6212 4.1) after the search."""
    return (vm.reference_search(vm.axes[0]).log, vm.world.axis(0).physical_position,
            ok(vm, 6, 1), ok(vm, 6, 196), ok(vm, 6, 197))


def searching(module: str, mode: int, scenario: dict) -> VirtualModule:
    vm = VirtualModule(module, scenario=scenario)
    ok(vm, 5, 193, mode)
    ok(vm, 13, 0)
    return vm


def duplicate(vm: VirtualModule, how: str) -> VirtualModule:
    return copy.deepcopy(vm) if how == "deepcopy" else pickle.loads(pickle.dumps(vm))


@pytest.mark.parametrize(("module", "mode", "scenario"), CASES)
def test_a_copy_taken_at_each_phase_finishes_the_search_as_the_original(module, mode, scenario):
    """Copies at the start and just after every change of phase (a switch found, left or
    entered; a stop, a reversal; the drive to the reference point), by deepcopy and pickle in
    turn: each copy's looks from then on and its result equal the original's."""
    vm = searching(module, mode, scenario)
    reference = searching(module, mode, scenario)
    expected = finish(reference)
    copies: list[tuple[int, VirtualModule]] = [(0, duplicate(vm, "pickle"))]
    phase: tuple = ()
    for i, seen in enumerate(expected, 1):
        vm.advance(STEP)
        assert look(vm) == seen
        now = (len(vm.reference_search(vm.axes[0]).log), vm.world.axis(0).watch is None, (seen[2] > 0) - (seen[2] < 0))
        if now != phase and seen[3]:
            phase = now
            copies.append((i, duplicate(vm, "deepcopy" if len(copies) % 2 else "pickle")))
    assert len(copies) >= 4
    final = result(vm)
    assert final == result(reference)
    for i, twin in copies:
        assert finish(twin) == expected[i:], f"copy after step {i}"
        assert result(twin) == final, f"copy after step {i}"


@pytest.mark.parametrize("how", ["deepcopy", "pickle"])
def test_a_copy_of_a_copy_and_a_stopped_copy_leave_the_original_alone(how):
    """A copy of a copy taken before it has run goes on as the original; RFS STOP on a copy
    (TMCM-6212 3.6.11: "stop a running reference search") stops that copy only."""
    vm = searching("TMCM-6212", 3, STAGE)
    for _ in range(30):
        vm.advance(STEP)
    assert ok(vm, 13, 2) != 0
    first = duplicate(vm, how)
    second = duplicate(first, "pickle" if how == "deepcopy" else "deepcopy")
    stopped = duplicate(vm, how)
    ok(stopped, 13, 1)
    stopped.advance(5)
    assert ok(stopped, 13, 2) == 0 and ok(stopped, 6, 3) == 0
    expected = finish(vm)
    assert finish(second) == expected and finish(first) == expected
    assert result(second) == result(first) == result(vm)
    assert result(vm)[1] == -21500        # mode 3: the middle of the left switch (test_reference.py)
