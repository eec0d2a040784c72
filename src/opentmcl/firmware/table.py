"""The command table: what the firmware does with each TMCL command (docs/architecture.md
"Request path"), built on the command set of protocol/opcodes.py.

For every command the table gives:

- `handler`: what the command does in direct mode (commands.py), answering (status, value);
- `effect`: what it may change, for the scheduler's caches (effects.py), refined by type and
  motor/bank where that matters (`effect_of`): a GAP of a parameter the world computes reads
  through the world, an SGP to the user variables (bank 2) touches nothing the time loop reads;
- `loads`: whether a program's instruction loads the accumulator with the value (manual 3.5.5);
- `binds`: "read" for the reads the request path and programs bind ahead (GAP, GGP, GIO), "write"
  for the writes the request path binds (SAP, SGP to user variables), "store" for the program's
  bound store of the accumulator (AGP), "" otherwise;
- `engines`: for a bound read, the engines it brings to now (`read_engines`; all by default);
- `step`: its behaviour as a program step (steps.py), or None: it runs as in direct mode;
  `returns`: the step returns from an interrupt (RETI: it may run ahead back to a program that
  was not in a WAIT); `accumulator`: the direct-mode command it runs with the accumulator as value
  and the type it passes on (MVPA, ROLA, RORA);
- which modules have it: the profile's command set (`available`).

Direct mode (`execute`), programs (Interpreter), ASCII mode (ascii.py) and the run ahead all
dispatch through this table.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import TYPE_CHECKING

from ..protocol.opcodes import (
    ALWAYS_ANSWERED,
    COMMANDS,
    ENTER_DOWNLOAD_MODE,
    EXIT_DOWNLOAD_MODE,
    Command,
    Op,
    is_control,
)
from ..protocol.status import Status
from . import commands as c
from . import program as p
from . import steps as s
from .effects import ALL, WRITE, Effect
from .status import TmclStatus
from .world import World

if TYPE_CHECKING:
    from ..motion.base import RampEngine as Engine
    from .commands import CommandHandler, Result
    from .vm import VirtualModule

USER_BANK, INTERRUPT_BANK = 2, 3
TICK_TIMER = (0, 132)
_NONE, _READ = Effect.NONE, Effect.READ
_CONTROL = Effect.PROGRAM | Effect.EVENTS | Effect.REQUESTS
_OK, _INVALID, _NOT_AVAILABLE = int(Status.OK), int(Status.INVALID_COMMAND), int(Status.NOT_AVAILABLE)
_DOWNLOAD = (ENTER_DOWNLOAD_MODE, EXIT_DOWNLOAD_MODE)


@dataclass(frozen=True, slots=True)
class Spec:
    """One command of the table."""

    command: Command
    handler: CommandHandler
    effect: Effect
    refine: Callable[[int, int], Effect] | None = None
    loads: Callable[[int, int], bool] | None = None
    binds: str = ""
    step: s.Compiler | None = None
    engines: Callable[[VirtualModule, int, int], list[Engine] | None] | None = None
    returns: bool = False
    accumulator: tuple[int, Callable[[int], int]] | None = None

    @property
    def number(self) -> int:
        return self.command.number

    def effect_of(self, type: int, motor: int) -> Effect:
        """The effect of this command with these type and motor/bank fields."""
        refine = self.refine
        return self.effect if refine is None else refine(type, motor)

    def read_engines(self, vm: VirtualModule, type: int, motor: int) -> list[Engine] | None:
        """The engines a bound read of this command needs at now; None: every engine."""
        engines = self.engines
        return None if engines is None else engines(vm, type, motor)

    def loads_accumulator(self, type: int, motor: int) -> bool:
        loads = self.loads
        return loads is not None and loads(type, motor)


# --- refinements ---------------------------------------------------------------------------------
def _gap(type: int, motor: int) -> Effect:
    """A parameter the world computes is read through it (the world brings the engines to now and
    follows the stage there): not a pure read. AP207, cleared by the read, is one: nothing any next
    event depends on reads it."""
    return WRITE if type in World.axis_numbers else _READ


def _global_write(type: int, bank: int) -> Effect:
    """SGP, RSGP, AGP by bank: user variables touch nothing the time loop reads; bank 3 configures
    interrupts and timers; bank 0 holds addresses, reply suppression, the heartbeats, GP81."""
    if bank == USER_BANK:
        return _NONE
    if bank == INTERRUPT_BANK:
        return Effect.EVENTS
    return WRITE | Effect.REQUESTS | Effect.PROGRAM


def _ggp(type: int, bank: int) -> Effect:
    """The tick timer GP132 reads the clock; every other GGP reads RAM or registers."""
    return _READ if (bank, type) == TICK_TIMER else _NONE


def _rfs(type: int, motor: int) -> Effect:
    return _READ if type == 2 else WRITE  # RFS STATUS only reads (3.6.11)


def _axis_engine(vm: VirtualModule, type: int, motor: int) -> list[Engine] | None:
    """GAP reads one axis: only its engine is brought to now."""
    return [vm.axes[motor].engine]


def _bank_engines(vm: VirtualModule, type: int, bank: int) -> list[Engine] | None:
    """GGP of a user variable reads no engine; the other banks may (every engine)."""
    return [] if bank == USER_BANK else None


def _reads_value(type: int, motor: int) -> bool:
    return True


def _gco_reads(type: int, motor: int) -> bool:
    return motor != 255  # GCO n, 255 copies the EEPROM to RAM and reads nothing


def _rfs_reads(type: int, motor: int) -> bool:
    return type == 2


def _spec(number: int, handler: CommandHandler, effect: Effect, **more: object) -> Spec:
    return Spec(COMMANDS[number], handler, effect, **more)  # type: ignore[arg-type]


def _mvpa_type(type: int) -> int:
    return type


def _rotate_type(type: int) -> int:
    return 0


_NO, _CX = c.cmd_no_effect, c.cmd_calcx
_SPECS = (
    # motion, parameters, I/O (TMCM-6212 3.6.1-3.6.13, PD86-1180 4.6.1-4.6.15)
    _spec(Op.ROR, c.cmd_ror, WRITE), _spec(Op.ROL, c.cmd_rol, WRITE), _spec(Op.MST, c.cmd_mst, WRITE),
    _spec(Op.MVP, c.cmd_mvp, WRITE), _spec(Op.SAP, c.cmd_sap, WRITE, binds="write"),
    _spec(Op.GAP, c.cmd_gap, _READ, refine=_gap, loads=_reads_value, binds="read", engines=_axis_engine),
    _spec(Op.STAP, c.cmd_stap, _NONE), _spec(Op.RSAP, c.cmd_rsap, WRITE),
    _spec(Op.SGP, c.cmd_sgp, WRITE, refine=_global_write, binds="write"),
    _spec(Op.GGP, c.cmd_ggp, _NONE, refine=_ggp, loads=_reads_value, binds="read", engines=_bank_engines),
    _spec(Op.STGP, c.cmd_stgp, _NONE), _spec(Op.RSGP, c.cmd_rsgp, WRITE, refine=_global_write),
    _spec(Op.RFS, c.cmd_rfs, WRITE, refine=_rfs, loads=_rfs_reads), _spec(Op.SIO, c.cmd_sio, _NONE),
    _spec(Op.GIO, c.cmd_gio, _READ, loads=_reads_value, binds="read"),
    # calculation and flow (3.6.14-3.6.21): no effect in direct mode (manual 7.6) but CALC's reply
    _spec(Op.CALC, c.cmd_calc, _NONE, step=s.calc_), _spec(Op.COMP, _NO, _NONE, step=s.comp),
    _spec(Op.JC, _NO, _NONE, step=s.jc), _spec(Op.JA, _NO, _NONE, step=s.ja), _spec(Op.CSUB, _NO, _NONE, step=s.csub),
    _spec(Op.RSUB, _NO, _NONE, step=s.rsub), _spec(Op.EI, c.cmd_ei, Effect.EVENTS),
    _spec(Op.DI, c.cmd_di, Effect.EVENTS), _spec(Op.WAIT, _NO, Effect.EVENTS, step=s.wait_),
    _spec(Op.STOP, _NO, Effect.EVENTS | Effect.PROGRAM, step=s.stop),
    # coordinates, X register, accumulator transfers, interrupts (3.6.22-3.6.33)
    _spec(Op.SCO, c.cmd_sco, _NONE), _spec(Op.GCO, c.cmd_gco, _NONE, loads=_gco_reads),
    _spec(Op.CCO, c.cmd_cco, _READ), _spec(Op.CALCX, _CX, _NONE, step=s.calcx), _spec(Op.AAP, c.cmd_aap, WRITE),
    _spec(Op.AGP, c.cmd_agp, WRITE, refine=_global_write, binds="store"), _spec(Op.CLE, c.cmd_cle, _NONE),
    _spec(Op.VECT, c.cmd_vect, Effect.EVENTS), _spec(Op.RETI, _NO, Effect.EVENTS, step=s.reti, returns=True),
    _spec(Op.ACO, c.cmd_aco, _NONE),
    # the PD28-1021's extended set (PD28-1021 manual 3.5, Table 5)
    _spec(Op.CALCVV, _CX, _NONE, step=s.calc_vv), _spec(Op.CALCVA, _CX, _NONE, step=s.calc_va),
    _spec(Op.CALCAV, _CX, _NONE, step=s.calc_av), _spec(Op.CALCVX, _CX, _NONE, step=s.calc_vx),
    _spec(Op.CALCXV, _CX, _NONE, step=s.calc_xv), _spec(Op.CALCV, c.cmd_calcv, _NONE, step=s.calc_v),
    _spec(Op.MVPA, _NO, WRITE, accumulator=(Op.MVP, _mvpa_type)),
    _spec(Op.RST, _NO, Effect.EVENTS, step=s.rst), _spec(Op.DJNZ, _NO, _NONE, step=s.djnz),
    _spec(Op.ROLA, _NO, WRITE, accumulator=(Op.ROL, _rotate_type)),
    _spec(Op.RORA, _NO, WRITE, accumulator=(Op.ROR, _rotate_type)),
    _spec(Op.SIV, _NO, _NONE, step=s.siv), _spec(Op.GIV, _NO, _NONE, step=s.giv), _spec(Op.AIV, _NO, _NONE, step=s.aiv),
    _spec(Op.CALL, _NO, _NONE, step=s.call),
    # user functions (3.6.34): accepted, nothing to do in a virtual module
    *(_spec(n, _NO, _NONE) for n in range(Op.UF0, Op.UF7 + 1)),
    # control commands, direct mode only (3.6.35, 3.6.36; PD86-1180 4.6.39)
    _spec(Op.STOP_APPLICATION, p.stop_application, _CONTROL), _spec(Op.RUN_APPLICATION, p.run_application, _CONTROL),
    _spec(Op.STEP_APPLICATION, p.step_application, _CONTROL),
    _spec(Op.RESET_APPLICATION, p.reset_application, _CONTROL),
    _spec(Op.ENTER_DOWNLOAD_MODE, p.enter_download_mode, _CONTROL),
    _spec(Op.EXIT_DOWNLOAD_MODE, p.exit_download_mode, _CONTROL),
    _spec(Op.READ_PROGRAM_MEMORY, p.read_program_memory, _NONE),
    _spec(Op.GET_APPLICATION_STATUS, p.get_application_status, _NONE),
    _spec(Op.GET_FIRMWARE_VERSION, c.cmd_136, _NONE), _spec(Op.RESTORE_FACTORY_SETTINGS, c.cmd_137, ALL),
    _spec(Op.REQUEST_TARGET_REACHED_EVENT, c.cmd_138, Effect.EVENTS), _spec(Op.ENTER_ASCII_MODE, c.cmd_139, Effect.REQUESTS),
)

TABLE: Mapping[int, Spec] = MappingProxyType({spec.number: spec for spec in _SPECS})
"""Every TMCL command the firmware knows, by number."""


def available(vm: VirtualModule, number: int) -> Spec | None:
    """The command's entry if the module has it (the profile's command set), else None."""
    return TABLE.get(number) if number in vm.opcodes else None


def execute(vm: VirtualModule, command: int, type: int, motor: int, value: int, *, program: bool,
            direct: bool = False) -> Result:
    """Run one command in direct mode (or a program's command that acts as in direct mode). In
    download mode (132) the commands other than control commands (`opcodes.is_control`; 138 is
    none) are stored instead (status 101, 3.6.36). A number the module's command set lacks is an
    "Invalid command" (2).

    `direct`: the request comes from a host that did not open the download under way (another link
    of a served module, docs/endpoints.md "Several hosts"). It is executed as in direct mode, never
    stored; that download is not its own to start again or end: its 132 is "Command not available"
    (6), its 133 does nothing (as in direct mode)."""
    try:
        if vm.download_mode and not program:
            if direct:
                if command in _DOWNLOAD:
                    return _not_own_download(command)
            elif not is_control(command):
                return vm.store_instruction(command, type, motor, value)
        spec = available(vm, command)
        if spec is None:
            return _INVALID, 0
        vm.scheduler.prepare(spec.effect_of(type, motor))
        return spec.handler(vm, type, motor, value, program)
    except TmclStatus as exc:
        return exc.status, 0


def _not_own_download(command: int) -> Result:
    """132 or 133 of a host whose requests are `direct` during another host's download."""
    return (_NOT_AVAILABLE if command == ENTER_DOWNLOAD_MODE else _OK), 0


def suppressible(command: int) -> bool:
    """May GP255 = 1 suppress the reply? "The reply will not be suppressed for GAP, GGP and GIO
    commands" (TMCM-6212 manual 5.1, `opcodes.ALWAYS_ANSWERED`, the rule the host reads too)."""
    return command not in ALWAYS_ANSWERED


def _ok(status: int) -> bool:
    return status == _OK
