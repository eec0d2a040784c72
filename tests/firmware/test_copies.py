"""Copies of a module that has bound its requests and compiled its program (copy.deepcopy, pickle):
a copy binds its own handlers, reads, stores and steps, so it reads its own axes and the original
is left alone (firmware/vm.py `VirtualModule.__getstate__`, interpreter.py `Interpreter.__getstate__`).

TMCM-6212 manual 3.6.6 GAP 1 (actual position), 3.6.5 SAP 1 (set the actual position), 3.6.35 AGP
(user variables, bank 2), 3.5.6.4 (timer interrupt)."""
from __future__ import annotations

import copy
import pickle

import pytest

from opentmcl import VirtualModule

from .test_program_support import Wire

PROGRAM = """
    VECT 0, T
    SGP 0, 3, 1
    EI 0
    EI 255
L:  GAP 1, 0
    AGP 0, 2
    JA L
T:  RETI"""


def running() -> Wire:
    """A module whose program stores GAP 1 of motor 0 in user variable 0, and whose host has read
    GAP 1 and GGP 0, 2 (both pre-bound) once."""
    w = Wire(VirtualModule("TMCM-6212", address=1))
    w.load(PROGRAM)
    w.run()
    w.vm.advance(0.01)
    w.ok(6, 1, 0)
    w.ok(10, 0, 2)
    return w


@pytest.mark.parametrize("how", ["deepcopy", "pickle"])
def test_a_copy_reads_its_own_axis(how):
    """SAP 1, 0, 5000 on the copy: the copy's host GAP 1 and its program (user variable 0) see
    5000, the original still 0; the same on the original gives the same answers and counts."""
    w = running()
    vm = copy.deepcopy(w.vm) if how == "deepcopy" else pickle.loads(pickle.dumps(w.vm))
    c = Wire(vm)
    c.ok(5, 1, 0, 5000)
    vm.advance(0.01)
    assert (c.ok(6, 1, 0), c.ok(10, 0, 2)) == (5000, 5000)
    assert (w.ok(6, 1, 0), w.vm.user_vars[0]) == (0, 0)
    w.ok(5, 1, 0, 5000)
    w.vm.advance(0.01)
    assert (w.ok(6, 1, 0), w.ok(10, 0, 2), w.vm.interpreter.executed, w.vm.now) == \
        (c.ok(6, 1, 0), c.ok(10, 0, 2), vm.interpreter.executed, vm.now)
