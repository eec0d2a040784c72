"""The Access column of every parameter, generated from the profiles and sent over the wire.

TMCM-6212 Table 15 / 17 / 19 "Meaning of the Letters in the Access Column" (PD86-1180 5 and 6 have
the same legend):

    R  GGP          Parameter readable
    W  SGP, AGP     Parameter writable
    E  STGP, RSGP   Parameter can be stored in the EEPROM
    A  SGP          Automatically stored in the EEPROM

(for axis parameters GAP, SAP, STAP and RSAP). TMCM-6212 5.1: "The parameters with numbers between
64 and 128 are automatically stored in the EEPROM" — bank-0 parameters 64..127 behave as A.
Statuses (TMCM-6212 3.2.1 Table 4): a command the access letters do not allow is answered with
"3 Wrong type", the reading of docs/assumptions.md ("Firmware (direct mode)": "a write to a
read-only parameter: 3 (wrong type)"; "STAP on a non-storable axis parameter" is status 3).

Checked for every axis parameter on every motor and every bank-0/bank-3 parameter of each module:
R -> GAP/GGP status 100, no R -> status 3; no W -> SAP/SGP status 3 and the value is unchanged;
W -> the written value reads back; E/A -> STAP/STGP and RSAP/RSGP status 100 and the value survives
a power cycle; neither -> those four commands status 3 and a power cycle brings the default back.

Not round-tripped (their value is not a plain stored number; each is tested elsewhere): the motion
parameters 0-3 and the world's inputs (writing them starts a move or is overwritten by the world,
tests/firmware/test_parameters.py), GP64 (PD86-1180 6.1 "another value than $E4 re-initialises" the
EEPROM at the next power-up), GP73 (lock codes 1234/4321), GP132/GP133 (timer tick and random number,
live values) and GP255 (3.6.7 "The reply in direct mode will be suppressed when this parameter is set
to 1").
"""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.modules.profile import Param, load_profile
from opentmcl.protocol.frame import Reply, Request

MODULES = ["TMCM-6212", "PD86-1180", "PD28-1021"]
SAP, GAP, STAP, RSAP, SGP, GGP, STGP, RSGP = 5, 6, 7, 8, 9, 10, 11, 12
NOT_ROUND_TRIPPED_GLOBALS = {(0, 64), (0, 73), (0, 132), (0, 133), (0, 255)}


def _request(vm: VirtualModule, command: int, number: int, bank: int, value: int = 0) -> Reply:
    raw = vm.handle(Request(vm.address, command, number, bank, value).encode())
    assert len(raw) == 9, f"no reply to {command} {number} {bank} {value}"
    return Reply.decode(raw)


def _storable(key: tuple[int, int], p: Param) -> bool:
    """The legend's E or A, or a bank-0 parameter 64..127 (5.1 "automatically stored")."""
    bank, number = key
    return p.storable or (bank == 0 and 64 <= number < 128 and number != 255)


def _two_values(p: Param) -> tuple[int, int]:
    """v, w: accepted values, v not the default and w not v (a round trip that can fail)."""
    pool = [v for v in dict.fromkeys(p.values or (p.min, p.max, p.min + 1, p.max - 1, p.default))
            if p.accepts(v) and -2**31 <= v < 2**31]
    v = next(x for x in pool if x != p.default)
    return v, next(x for x in pool if x != v)


def _axes_round_tripped(vm: VirtualModule) -> dict[int, Param]:
    skip = {0, 1, 2, 3} | vm.world.axis_numbers
    return {n: p for n, p in vm.profile.axis_parameters.items() if p.writable and n not in skip}


def _globals_round_tripped(vm: VirtualModule) -> dict[tuple[int, int], Param]:
    return {k: p for k, p in vm.profile.global_parameters.items()
            if p.writable and k not in NOT_ROUND_TRIPPED_GLOBALS}


@pytest.mark.parametrize("name", MODULES)
def test_the_r_letter_decides_whether_gap_and_ggp_answer(name):
    """R "Parameter readable": GAP on every motor / GGP on its bank is status 100 exactly for the
    parameters with R, status 3 for the others."""
    vm = VirtualModule(name, address=1)
    prof = vm.profile
    wrong = {}
    for motor in range(prof.axes):
        for n, p in prof.axis_parameters.items():
            if (status := _request(vm, GAP, n, motor).status) != (100 if p.readable else 3):
                wrong[("axis", motor, n)] = status
    for (bank, n), p in prof.global_parameters.items():
        if (status := _request(vm, GGP, n, bank).status) != (100 if p.readable else 3):
            wrong[("global", bank, n)] = status
    assert wrong == {}


@pytest.mark.parametrize("name", MODULES)
def test_parameters_without_w_refuse_sap_and_sgp_with_status_3(name):
    """W "Parameter writable": SAP/SGP on a parameter without W answers status 3 (wrong type) and
    the parameter reads what an untouched module reads."""
    prof = load_profile(name)
    wrong = {}
    for motor in range(prof.axes):
        for n, p in prof.axis_parameters.items():
            if p.writable:
                continue
            vm, twin = VirtualModule(name, address=1), VirtualModule(name, address=1)
            status = _request(vm, SAP, n, motor, p.max).status
            if status != 3 or _request(vm, GAP, n, motor).value != _request(twin, GAP, n, motor).value:
                wrong[("axis", motor, n)] = status
    for (bank, n), p in prof.global_parameters.items():
        if p.writable:
            continue
        vm, twin = VirtualModule(name, address=1), VirtualModule(name, address=1)
        status = _request(vm, SGP, n, bank, p.max).status
        if status != 3 or _request(vm, GGP, n, bank).value != _request(twin, GGP, n, bank).value:
            wrong[("global", bank, n)] = status
    assert wrong == {}


@pytest.mark.parametrize("name", MODULES)
def test_a_written_parameter_reads_back_what_was_written(name):
    """W with R: after SAP/SGP of a value of the range, GAP/GGP on the same motor/bank reads it (the
    last motor here; motor 0 is tests/firmware/test_parameters.py)."""
    vm = VirtualModule(name, address=1)
    last = vm.profile.axes - 1
    wrong = {}
    for n, p in _axes_round_tripped(vm).items():
        for v in _two_values(p):
            _request(vm, SAP, n, last, v)
            if (got := _request(vm, GAP, n, last).value) != v:
                wrong[("axis", n, v)] = got
    for (bank, n), p in _globals_round_tripped(vm).items():
        for v in _two_values(p):
            _request(vm, SGP, n, bank, v)
            if (got := _request(vm, GGP, n, bank).value) != v:
                wrong[("global", bank, n, v)] = got
    assert wrong == {}


@pytest.mark.parametrize("name", MODULES)
def test_store_and_restore_answer_by_the_e_letter(name, tmp_path):
    """E "Parameter can be stored in the EEPROM" (STAP/RSAP, STGP/RSGP): status 100 for a parameter
    with E or A (or bank 0 64..127), status 3 for every other parameter, on every motor. The
    TMCM-6212 has no STAP/RSAP (3.5 command list; its axis table has no E): "2 Invalid command"."""
    vm = VirtualModule(name, address=1, eeprom=tmp_path / "ee.json")
    prof = vm.profile
    wrong = {}
    for motor in range(prof.axes):
        for n, p in prof.axis_parameters.items():
            want = tuple((100 if p.storable else 3) if c in prof.opcodes else 2 for c in (STAP, RSAP))
            got = (_request(vm, STAP, n, motor).status, _request(vm, RSAP, n, motor).status)
            if got != want:
                wrong[("axis", motor, n)] = got
    for (bank, n), p in prof.global_parameters.items():
        want = 100 if _storable((bank, n), p) else 3
        got = (_request(vm, STGP, n, bank).status, _request(vm, RSGP, n, bank).status)
        if got != (want, want):
            wrong[("global", bank, n)] = got
    assert wrong == {}


@pytest.mark.parametrize("name", MODULES)
def test_only_storable_parameters_survive_a_power_cycle(name, tmp_path):
    """E: SAP/SGP v, STAP/STGP, then a new module on the same EEPROM reads v; A and bank 0 64..127
    survive without STGP; a parameter with neither letter is back at its default (its STAP/STGP was
    refused, so nothing was stored)."""
    path = tmp_path / "ee.json"
    vm = VirtualModule(name, address=1, eeprom=path)
    last = vm.profile.axes - 1
    axes, glob = _axes_round_tripped(vm), _globals_round_tripped(vm)
    written = {}
    for n, p in axes.items():
        v = written[("axis", n)] = _two_values(p)[0]
        _request(vm, SAP, n, last, v)
        _request(vm, STAP, n, last)
    for (bank, n), p in glob.items():
        v = written[("global", bank, n)] = _two_values(p)[0]
        _request(vm, SGP, n, bank, v)
        if p.storable and not p.auto_stored and not 64 <= n < 128:
            _request(vm, STGP, n, bank)
    again = VirtualModule(name, eeprom=path)
    wrong = {}
    for n, p in axes.items():
        want = written[("axis", n)] if p.storable else p.default
        if (got := _request(again, GAP, n, last).value) != want:
            wrong[("axis", n)] = (got, want)
    for (bank, n), p in glob.items():
        want = written[("global", bank, n)] if _storable((bank, n), p) else p.default
        if (got := _request(again, GGP, n, bank).value) != want:
            wrong[("global", bank, n)] = (got, want)
    assert wrong == {}


@pytest.mark.parametrize("name", MODULES)
def test_rsap_and_rsgp_bring_back_the_stored_value(name, tmp_path):
    """RSAP/RSGP (PD86-1180 4.6.8 "restores the value from the EEPROM"): SAP v, STAP, SAP w, RSAP
    reads v again, for every parameter with E on the last motor and every bank-0 parameter with E
    outside 64..127 (those are stored by the SGP itself, so RSGP gives w)."""
    vm = VirtualModule(name, address=1, eeprom=tmp_path / "ee.json")
    last = vm.profile.axes - 1
    wrong = {}
    for n, p in _axes_round_tripped(vm).items():
        if not p.storable:
            continue
        v, w = _two_values(p)
        for command, value in ((SAP, v), (STAP, 0), (SAP, w), (RSAP, 0)):
            _request(vm, command, n, last, value)
        if (got := _request(vm, GAP, n, last).value) != v:
            wrong[("axis", n)] = got
    for (bank, n), p in _globals_round_tripped(vm).items():
        if not _storable((bank, n), p):
            continue
        v, w = _two_values(p)
        auto = p.auto_stored or (bank == 0 and 64 <= n < 128)
        for command, value in ((SGP, v), (STGP, 0), (SGP, w), (RSGP, 0)):
            _request(vm, command, n, bank, value)
        if (got := _request(vm, GGP, n, bank).value) != (w if auto else v):
            wrong[("global", bank, n)] = got
    assert wrong == {}
