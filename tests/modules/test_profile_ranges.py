"""The Range column of every writable parameter, generated from the profiles and sent over the wire.

TMCM-6212 3.2.1 / PD86-1180 4.2 status code "4 Invalid value"; PD86-1180 5 and 6 (the tables the
profiles transcribe, docs/assumptions.md): for each parameter SAP/SGP accept the first and last
value of the range and refuse the value one beyond each end with status 4, leaving the parameter
unchanged; enumerations accept exactly their values; values inside a range that the manual forbids
(PD86-1180 7.2 "The values 1, 2, 4, and 16 must not be used for <p>") are refused too.

Exceptions, each one written in docs/assumptions.md ("Value ranges"):
- GP73 takes the codes 1234/4321 (6.1 "Write: 1234 to lock the EEPROM, 4321 to unlock it"); 0/1
  are what it reads back.
- Parameters whose range is unsigned 32 bit (bank-3 timer periods, GP132): the 32-bit value field
  cannot carry a value beyond either end (-1 on the wire is 4294967295).
- GP255 = 1 suppresses the reply of the SGP itself (3.6.7 GP255 "The reply in direct mode will be
  suppressed when this parameter is set to 1").
"""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.modules.profile import Param, load_profile
from opentmcl.protocol.frame import Reply, Request

MODULES = ["TMCM-6212", "PD86-1180", "PD28-1021"]
INT32 = (-2**31, 2**31 - 1)
SAP, GAP, SGP, GGP = 5, 6, 9, 10


def _cases(p: Param) -> list[tuple[int, bool]]:
    """(value, accepted) pairs from the profile row: both ends, one beyond each, enumerations
    and forbidden values with their neighbours."""
    if p.values:
        gaps = [v for v in range(p.min - 1, p.max + 2) if v not in p.values]
        return [(v, True) for v in p.values] + [(v, False) for v in gaps[:64]]
    cases = [(p.min, True), (p.max, True)]
    if p.max <= INT32[1]:  # an unsigned 32-bit range has nothing beyond it on the wire
        cases += [(p.min - 1, False), (p.max + 1, False)]
    for v in p.excluded:
        cases += [(v, False), (v - 1, v - 1 not in p.excluded), (v + 1, v + 1 not in p.excluded)]
    return [(v, ok) for v, ok in cases if INT32[0] <= v <= INT32[1] or p.max > INT32[1]]


def _wire(value: int) -> int:
    return value - 2**32 if value > INT32[1] else value


def _read(vm, command, number, bank):
    raw = vm.handle(Request(vm.address, command + 1, number, bank, 0).encode())
    return Reply.decode(raw).value if raw else None


def _send(name: str, command: int, number: int, bank: int, value: int) -> tuple[int | None, bool]:
    """(status of the write, whether the value read back equals that of a twin module that got no
    write); fresh modules, as a write may move a motor or change the address, and live values
    (AP180 current, GP133 random number) are compared with the twin rather than the default."""
    vm, twin = VirtualModule(name, address=1), VirtualModule(name, address=1)
    raw = vm.handle(Request(1, command, number, bank, _wire(value)).encode())
    status = Reply.decode(raw).status if raw else None
    return status, _read(vm, command, number, bank) == _read(twin, command, number, bank)


def _check(name, command, number, bank, p: Param) -> dict:
    wrong = {}
    for value, ok in _cases(p):
        status, unchanged = _send(name, command, number, bank, value)
        if ok and status not in (100, None):
            wrong[value] = status
        elif not ok and (status != 4 or not unchanged):
            wrong[value] = (status, unchanged)
    return wrong


@pytest.mark.parametrize("name", MODULES)
def test_axis_parameter_ranges(name):
    """SAP with each end of every writable axis parameter's range is accepted (status 100), one
    beyond is status 4 and GAP reads what an untouched module reads; PD86-1180 AP210 refuses 1, 2, 4, 16."""
    prof = load_profile(name)
    wrong = {n: w for n, p in prof.axis_parameters.items() if p.writable
             and (w := _check(name, SAP, n, 0, p))}
    assert wrong == {}


@pytest.mark.parametrize("name", MODULES)
def test_global_parameter_ranges(name):
    """SGP with each end of every writable bank-0/bank-3 parameter's range is accepted, one beyond
    is status 4 and GGP reads what an untouched module reads (exceptions in the module docstring)."""
    prof = load_profile(name)
    wrong = {(b, n): w for (b, n), p in prof.global_parameters.items()
             if p.writable and (b, n) != (0, 73) and (w := _check(name, SGP, n, b, p))}
    assert wrong == {}


@pytest.mark.parametrize("name", ["PD86-1180", "PD28-1021"])
def test_encoder_prescaler_values_the_manual_forbids(name):
    """PD86-1180 7.2: "The values 1, 2, 4, and 16 must not be used for <p>" (taken for the
    PD28-1021, whose 6.2 is cut off): status 4, AP210 keeps its value; 0, 3, 5, 15, 17 and the
    table's 800 and 6400 + 4 (clear at the next null channel) are accepted."""
    got = {v: _send(name, SAP, 210, 0, v)[0] for v in (0, 1, 2, 3, 4, 5, 15, 16, 17, 800, 6404)}
    assert got == {0: 100, 1: 4, 2: 4, 3: 100, 4: 4, 5: 100, 15: 100, 16: 4, 17: 100, 800: 100, 6404: 100}


@pytest.mark.parametrize("name", ["PD86-1180", "PD28-1021"])
def test_event_request_value_is_the_one_motor(name):
    """PD86-1180 4.6.37 binary representation: "138 | 0/1 | (don't care) | 1": the value of a
    one-motor module is 1; 0 and 2 are status 4."""
    got = {v: _send(name, 138, 1, 0, v)[0] for v in (0, 1, 2)}
    assert got == {0: 4, 1: 100, 2: 4}
