"""The virtual module's Python API (firmware/vm.py `VirtualModule`): the constructor's default
module, `request` with its defaults and its None for a suppressed reply, and `next_event_in`."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.firmware.interpreter import INSTRUCTION_TICKS
from opentmcl.motion import CLOCK_HZ

from .conftest import Host
from .test_program_support import T, module


def test_request_defaults_type_motor_and_value_to_0():
    """`VirtualModule.request(command, type=0, motor=0, value=0)`: GAP with only the command asks
    type 0 - TMCM-6212 4.1 AP0 "Target (next) position" - of motor 0, not AP1 actual position."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert vm.request(4, 0, 0, 1000).status == 100      # MVP ABS 1000: the target moves at once
    assert vm.request(6).value == 1000
    assert vm.request(6, 1).value == 0


def test_request_defaults_the_value_to_0():
    """`VirtualModule.request(command, type=0, motor=0, value=0)`: SIO 0, 2 with the value left out
    sets OUT_0 (TMCM-6212 3.6.12 SIO "<port number> (0...4), <bank number> (2), 0/1") to 0."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert vm.request(14, 0, 2, 1).status == 100
    assert vm.request(15, 0, 2).value == 1
    assert vm.request(14, 0, 2).status == 100
    assert vm.request(15, 0, 2).value == 0


def test_next_event_in_counts_seconds():
    """`VirtualModule.next_event_in()`: seconds to the next internal event. A program started with
    129 has its first instruction one slot later (docs/assumptions.md "Instruction rate": 1600
    ticks of the 16 MHz clock, 100 µs); a stopped program and standing motors have none."""
    w = module()
    assert w.vm.next_event_in() is None
    w.download([(27, 0, 0, 50), (28, 0, 0, 0)])
    w.run()
    assert w.vm.next_event_in() == INSTRUCTION_TICKS / CLOCK_HZ == 1e-4
    w.vm.advance(T)
    assert w.vm.next_event_in() == pytest.approx(0.5)


def test_a_module_built_without_a_name_is_a_tmcm_6212():
    """`VirtualModule(name="TMCM-6212", ...)` (firmware/vm.py): without a name the module is a
    TMCM-6212 - six motors (manual 3.6.6 GAP motor "0...5") at its factory address 1 (5.1 GP66)."""
    vm = VirtualModule()
    assert vm.profile.name == "TMCM-6212"
    h = Host(vm)
    assert h.ok(10, 66, 0) == 1
    assert h(6, 1, 5).status == 100
    assert h(6, 1, 6).status == 4


def test_request_gives_none_when_the_reply_is_suppressed():
    """3.6.7 GP255: "The reply in direct mode will be suppressed when this parameter is set to 1":
    the convenience `request` has no reply to decode and returns None."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert vm.request(9, 255, 0, 1) is None
    assert vm.request(6, 1, 0).status == 100  # GAP is never suppressed (docs/assumptions.md)
