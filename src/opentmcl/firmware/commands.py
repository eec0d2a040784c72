"""Execution of TMCL commands (TMCM-6212 manual 3.6, PD86-1180 manual 4.6).

`execute()` answers one command with (status, value), special reply bytes,
or None when no reply is due. Status codes follow the manuals: 2 invalid
command, 3 wrong type, 4 invalid value, 5 EEPROM locked, 6 not available.
One rule for opcodes (docs/assumptions.md): a number that is not in the
module's own command set is an "Invalid command" (2), whatever another
module does with it; "Command not available" (6) is a command the module
has that cannot run in the present context (a control command met by a
running program).
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol

from ..protocol.frame import to_int32
from ..protocol.opcodes import Op
from ..protocol.replies import encode_version_string_reply
from ..protocol.status import Status
from .calc import last_operation
from .status import TmclStatus

if TYPE_CHECKING:
    from ..modules.profile import Param
    from .motor import Motor
    from .vm import VirtualModule

StatusReply = tuple[int, int]
"""(status, value) of a normal reply (manual 3.2.1)."""
Result = StatusReply | bytes | None
"""What a command answers: a normal reply, the raw bytes of a special reply (136 type 0, 134),
or None when no reply is due (137)."""


class CommandHandler(Protocol):
    """The signature every entry of HANDLERS has: the request's type, motor (or bank, port,
    coordinate number) and value fields, and whether a TMCL program runs the command; the
    handler answers a Result or raises TmclStatus (docs/architecture.md, "Request path")."""

    def __call__(self, vm: VirtualModule, type: int, motor: int, value: int, program: bool, /) -> Result: ...


OK = int(Status.OK)


def _axis(vm: VirtualModule, motor: int) -> Motor:
    if not 0 <= motor < len(vm.axes):
        raise TmclStatus(4)
    return vm.axes[motor]


# --- motion (3.6.1-3.6.4) --------------------------------------------------------
def _rotate(vm: VirtualModule, motor: int, value: int, sign: int) -> StatusReply:
    """ROR/ROL: the velocity within the command's own range where the manual prints one (profile
    key `rotate_range`; PD86-1180 4.6.1 "0… 2047"), and within AP2's range (3.6.1: "the velocity
    value is transferred to axis parameter #2")."""
    ax = _axis(vm, motor)
    rotate = vm.profile.extra.get("rotate_range")
    if rotate is not None and not rotate[0] <= value <= rotate[1]:
        raise TmclStatus(4)
    velocity = to_int32(sign * value)
    ax.check_value(ax.param(2), velocity)
    ax.rotate(velocity)
    return OK, 0


def cmd_ror(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    return _rotate(vm, motor, value, 1)


def cmd_rol(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    return _rotate(vm, motor, value, -1)


def cmd_mst(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    _axis(vm, motor).stop()
    return OK, 0


def cmd_mvp(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    ax = _axis(vm, motor)
    if type == 0:
        target = value
    elif type == 1:
        target = ax.relative_origin() + value
    elif type == 2:
        if not 0 <= value <= vm.profile.coordinates:
            raise TmclStatus(4)
        target = vm.coords[motor][value]
    else:
        raise TmclStatus(3)
    ax.move_to(to_int32(target))
    vm.arm_position_event(motor)
    return OK, 0


# --- axis parameters (3.6.5, 3.6.6; STAP/RSAP PD86-1180 4.6.7, 4.6.8) -----------------
def cmd_sap(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    _axis(vm, motor).set(type, value)
    return OK, 0


def cmd_gap(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    return OK, _axis(vm, motor).get(type)


def _storable_axis_param(vm: VirtualModule, type: int, motor: int) -> tuple[Motor, Param]:
    ax = _axis(vm, motor)
    p = ax.param(type)
    if not p.storable:
        raise TmclStatus(3)
    return ax, p


def cmd_stap(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    ax, p = _storable_axis_param(vm, type, motor)
    if vm.globals.eeprom_locked:
        raise TmclStatus(5)
    vm.eeprom.set_axis(motor, type, ax.ram.get(type, p.default))
    return OK, 0


def cmd_rsap(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    ax, p = _storable_axis_param(vm, type, motor)
    stored = vm.eeprom.get_axis(motor, type)
    ax.set(type, p.default if stored is None else stored)
    return OK, 0


# --- global parameters (3.6.7-3.6.10) -----------------------------------------------
def _bank(vm: VirtualModule, bank: int) -> int:
    if bank not in vm.profile.global_banks:
        raise TmclStatus(4)
    return bank


def cmd_sgp(vm: VirtualModule, type: int, bank: int, value: int, program: bool) -> Result:
    vm.globals.set(_bank(vm, bank), type, value)
    return OK, 0


def cmd_ggp(vm: VirtualModule, type: int, bank: int, value: int, program: bool) -> Result:
    return OK, vm.globals.get(_bank(vm, bank), type)


def cmd_stgp(vm: VirtualModule, type: int, bank: int, value: int, program: bool) -> Result:
    vm.globals.store(_bank(vm, bank), type)
    return OK, 0


def cmd_rsgp(vm: VirtualModule, type: int, bank: int, value: int, program: bool) -> Result:
    vm.globals.restore(_bank(vm, bank), type)
    return OK, 0


# --- reference search (3.6.11) --------------------------------------------------------
def cmd_rfs(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    ax = _axis(vm, motor)
    if type == 0:
        vm.reference_search(ax).start()
    elif type == 1:
        vm.reference_search(ax).stop()
    elif type == 2:
        return OK, vm.reference_search(ax).status()
    else:
        raise TmclStatus(3)
    return OK, 0


# --- I/O (3.6.12, 3.6.13) ----------------------------------------------------------------
def cmd_sio(vm: VirtualModule, port: int, bank: int, value: int, program: bool) -> Result:
    vm.io.set(port, bank, value)
    return OK, 0


def cmd_gio(vm: VirtualModule, port: int, bank: int, value: int, program: bool) -> Result:
    return OK, vm.io.get(port, bank)


# --- coordinates (3.6.22-3.6.25) ------------------------------------------------------------
def _coord(vm: VirtualModule, number: int, lowest: int = 0) -> int:
    if not lowest <= number <= vm.profile.coordinates:
        raise TmclStatus(3)
    return number


def _eeprom_coords(vm: VirtualModule, number: int) -> Sequence[int]:
    """The coordinates selected by `number` for the 255 forms: 0 = all (except #0)."""
    if number == 0:
        return range(1, vm.profile.coordinates + 1)
    return [_coord(vm, number, 1)]


def _set_coord(vm: VirtualModule, number: int, motor: int, value: int) -> None:
    vm.coords[motor][number] = to_int32(value)
    if number and vm.globals.get_raw(0, 84) == 1:  # GP84: coordinates always also in EEPROM
        vm.eeprom.set_coord(motor, number, vm.coords[motor][number])


def cmd_sco(vm: VirtualModule, number: int, motor: int, value: int, program: bool) -> Result:
    if motor == 255:  # "SCO <n>, 255, 0": copy RAM -> EEPROM
        for c in _eeprom_coords(vm, number):
            for a in range(len(vm.axes)):
                vm.eeprom.set_coord(a, c, vm.coords[a][c])
        return OK, 0
    _axis(vm, motor)
    _set_coord(vm, _coord(vm, number), motor, value)
    return OK, 0


def cmd_gco(vm: VirtualModule, number: int, motor: int, value: int, program: bool) -> Result:
    if motor == 255:  # "GCO <n>, 255, 0": copy EEPROM -> RAM
        for c in _eeprom_coords(vm, number):
            for a in range(len(vm.axes)):
                stored = vm.eeprom.get_coord(a, c)
                vm.coords[a][c] = 0 if stored is None else stored
        return OK, 0
    _axis(vm, motor)
    return OK, vm.coords[motor][_coord(vm, number)]


def cmd_cco(vm: VirtualModule, number: int, motor: int, value: int, program: bool) -> Result:
    ax = _axis(vm, motor)
    position = ax.engine.position
    _set_coord(vm, _coord(vm, number), motor, position)
    return OK, position


def cmd_aco(vm: VirtualModule, number: int, motor: int, value: int, program: bool) -> Result:
    _axis(vm, motor)
    _set_coord(vm, _coord(vm, number), motor, vm.accumulator)
    return OK, 0


# --- accumulator to parameter (3.6.27, 3.6.28) ------------------------------------------------
def cmd_aap(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    _axis(vm, motor).set(type, vm.accumulator)
    return OK, 0


def cmd_agp(vm: VirtualModule, type: int, bank: int, value: int, program: bool) -> Result:
    vm.globals.set(_bank(vm, bank), type, vm.accumulator)
    return OK, 0


# --- error flags and interrupts (3.6.29-3.6.33) ------------------------------------------------
def cmd_cle(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    if not 0 <= type <= 5:
        raise TmclStatus(3)
    vm.clear_error_flags(type)
    return OK, 0


def cmd_ei(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    vm.interrupts.enable(type, True)
    return OK, 0


def cmd_di(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    vm.interrupts.enable(type, False)
    return OK, 0


def cmd_vect(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    vm.interrupts.set_vector(type, value)
    return OK, 0


def cmd_calc(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """CALC in direct mode: the accumulator is untouched, the reply carries "the operand"
    (TMCM-6212 3.6.14, reply example 02 01 64 13 FF FF EC 78 DC for CALC MUL, -5000)."""
    if not 0 <= type <= 9:  # ADD .. LOAD
        raise TmclStatus(3)
    return OK, to_int32(value)


def cmd_no_effect(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """Program-flow and accumulator commands sent in direct mode: accepted,
    without touching the program's accumulator or flow (TMCM-6212 manual 7.6)."""
    return OK, 0


def cmd_calcx(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """CALCX and the PD28-1021's CALCVV ... CALCXV in direct mode: no effect (7.6), but an operation
    beyond the list (TMCM-6212 3.6.26: types 0 ADD ... 10 SWAP) is "3 Wrong type" (Table 4), as
    CALC's type beyond LOAD is and as the same instruction in a program is."""
    return _operation(type, last_operation(Op.CALCX))


def cmd_calcv(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """The PD28-1021's CALCV in direct mode: as CALCX, but its operations end at LOAD (it has no
    second register to SWAP with; calc.last_operation)."""
    return _operation(type, last_operation(Op.CALCV))


def _operation(type: int, last: int) -> Result:
    if not 0 <= type <= last:
        raise TmclStatus(3)
    return OK, 0


# --- control commands (3.6.35, 3.6.36) --------------------------------------------------------
def cmd_138(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    if type not in (0, 1):
        raise TmclStatus(3)
    mask = value & ((1 << len(vm.axes)) - 1)
    # TMCM-6212 3.6.35: a bit vector of the motors; PD86-1180 4.6.37 (one motor): value "1"
    if value != mask or (len(vm.axes) == 1 and mask != 1):
        raise TmclStatus(4)
    vm.event_mask = mask
    vm.event_permanent = mask if type == 1 else 0
    return OK, mask


def cmd_136(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    if type == 0:  # special reply: host address + 8 characters, no checksum
        return encode_version_string_reply(vm.host_address & 0xFF, vm.profile.firmware_version[:8].ljust(8))
    if type == 1:
        return OK, vm.profile.firmware_binary
    raise TmclStatus(3)


def cmd_137(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    if value != 1234:
        raise TmclStatus(4)
    vm.restore_factory_defaults()
    return None


def cmd_139(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    vm.ascii_mode = True
    return OK, 0
