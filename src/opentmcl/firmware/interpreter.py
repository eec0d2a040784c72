"""The TMCL program interpreter: standalone mode in virtual time
(TMCM-6212 manual 3.3, 3.5.3-3.5.6, 3.6.14-3.6.33, 3.6.36, 7; PD86-1180 manual 4.6, 8;
PD28-1021 manual 3.5 for the extended command set).

Time: every instruction takes INSTRUCTION_TICKS of the 16 MHz clock (100 µs, i.e.
10000 TMCL instructions per second) and takes effect at the end of its slot; a
WAIT ends at its condition or timeout and the next instruction follows one slot
later; dispatching an interrupt and returning from it (RETI) take one slot each.
`VirtualModule.advance_to` asks `own_event()` when the program next needs
service (timers are the module's) and calls `service()` at every event tick,
so a run is deterministic.

Registers live on the virtual module: vm.accumulator, vm.x_register, vm.flags
(flags.py), vm.program_counter, vm.application_status. Direct-mode commands go
through commands.execute(program=False) and never reach this class, so a host
talking to the module never disturbs a running program (manual 7.6).

An instruction that the module answers with an error status in direct mode
(invalid motor, wrong type, ...) has no effect in a program and execution goes
on with the next instruction; the last such error is kept in `last_error` for
the debugger.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from ..protocol.frame import to_int32
from ..protocol.status import Status
from . import ahead, calc, flags, wait
from .ahead import OTHER, PURE_KIND, READ_KIND, RETI_KIND
from .commands import execute
from .dispatch import USER_BANK, program_read, program_store
from .program import RESET, RUNNING, STEPPING, STOPPED
from .status import TmclStatus

if TYPE_CHECKING:
    from .vm import VirtualModule

INSTRUCTION_TICKS = 1600      # 100 µs at 16 MHz per TMCL instruction
STACK_DEPTH = 8               # "The number of entries in the internal stack is limited to 8."
AGP = 35
READS_VALUE = frozenset({6, 10, 15, 31})  # GAP, GGP, GIO, GCO (and RFS STATUS) load the accumulator
CALL = 80                     # PD28-1021 3.7.44 (not in its Table 5; number from public TMCL headers)
# Instructions that neither read nor change anything outside the program's registers, flags,
# stack and user variables (SGP/GGP/AGP on bank 2), or only the outputs (SIO): they may run
# ahead of the motors (_run_ahead).
PURE = frozenset({14, 19, 20, 21, 22, 23, 24, 33, 40, 41, 42, 43, 44, 45, 48, 49, 55, 56, 57, CALL})
PURE_ON_BANK_2 = frozenset({9, 10, 35})
# Reads that may also run ahead, at their own tick (_run_ahead): GAP (not of world-computed
# parameters nor AP207, which clears the error flags when read), the tick timer GGP 132, GIO (an
# input the world drives, e.g. analog, changes between events: it is read at the instruction's
# tick). Other GGPs read RAM and registers only: they are pure.
READS_AHEAD = frozenset({6, 10, 15})
TICK_TIMER = (132, 0)
# After any other instruction (SAP, SGP, motion, EI/DI/VECT, WAIT, STOP, ...) the module's
# cached next event (VirtualModule._limit_event) is looked up again: it may have moved.
RETI = 38


@dataclass(slots=True)
class Context:
    """What an interrupt saves and RETI restores (manual 3.5.6.2, 3.6.33)."""

    pc: int
    accumulator: int
    x_register: int
    flags: int
    wait: wait.Wait | None


class FlowHandler(Protocol):
    """The signature every entry of FLOW has: an Interpreter method taking the instruction's
    type, motor (or variable) and value fields. True: the handler set the program counter
    itself (jump, WAIT, STOP); False or None: the program goes on with the next instruction."""

    def __call__(self, interpreter: Interpreter, type: int, motor: int, value: int, /) -> bool | None: ...


Entry = tuple[int, FlowHandler, int, int, int, int]
"""Interpreter._entry: (kind, handler, type, motor, value, command) of an instruction."""
Bound = tuple[Callable[..., Any], list[Any] | None]
"""Interpreter._bound: a pre-bound read or store and the engines a read looks at."""


class Interpreter:
    run_ahead = True  # batch pure instructions (see _run_ahead); False: one event per instruction
    ja_watch: Callable[[int, int], None] | None = None
    """Called with (program counter, target) before every JA executes (plot.program.JumpWatch)."""

    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm
        self.stack: list[int] = []
        self.wait: wait.Wait | None = None
        self.next_time: int | None = None   # tick of the next instruction (None: not scheduled)
        self.saved: Context | None = None   # context of the interrupted program while in an ISR
        self.last_error: tuple[int, int, int] | None = None  # (pc, command, status)
        self.executed = 0                   # instructions executed since power-up
        self._t: int | None = None          # tick of an instruction run ahead of vm.now
        self._entries: dict[tuple[int, int, int, int], Entry] = {}  # instruction -> _entry
        self._nested = False                # taking an event inside _run_ahead (_fold)
        self._quiet: bool | None = None     # World.quiet() while the run-ahead limit holds
        self._steps: dict[tuple[int, int, int, int], ahead.Step] = {}  # instruction -> ahead.compile_step
        self._steps_of: object = None       # the vm._program_ops the steps were compiled with

    @property
    def waiting(self) -> bool:
        return self.wait is not None

    # --- hooks called by VirtualModule ----------------------------------------------------
    def power_up(self) -> None:
        """GP77 auto start mode: 1 starts the stored program after power-up (manual 5.1)."""
        if self.vm.globals.get_raw(0, 77) == 1 and self.vm.program.length:
            self.run(0)

    def own_event(self) -> int | None:
        """The program's own next tick (instruction, WAIT timeout or check, dispatch from a
        WAIT), > vm.now, or None; timers are the module's (`VirtualModule._limit_event`)."""
        vm = self.vm
        now = vm.now
        status = vm.application_status
        if status not in (RUNNING, STEPPING):
            return None
        w = self.wait
        if w is None:
            t = self.next_time
            if status != RUNNING or t is None:
                return None
            return t if t > now else now + 1
        candidates = []
        if w.deadline is not None:
            candidates.append(w.deadline)
        if status == RUNNING and vm.interrupts.next_dispatch() is not None:
            candidates.append(now + 1)
        if wait.satisfied(vm, w):  # met outside an event: host command, after RETI
            candidates.append(now + 1)
        if not candidates:
            return None
        return max(min(candidates), now + 1)

    def service(self) -> None:
        """Execute what is due at vm.now: finish a WAIT, take an interrupt, run one instruction."""
        vm = self.vm
        now = vm.now
        vm.interrupts.poll(now, refresh=not vm._limit_ok)  # periods are written only by commands
        if vm.application_status not in (RUNNING, STEPPING):
            return
        if self.wait is not None:
            self._check_wait(self.wait)
        if vm.application_status != RUNNING:
            return
        if self.wait is not None or (self.next_time is not None and self.next_time <= now):
            if self._dispatch_interrupt():
                self._run_ahead()
                return
        if self.wait is None and self.next_time is not None and self.next_time <= now:
            self._execute_next()
            self._run_ahead()

    def _run_ahead(self) -> None:
        """Execute pure instructions (PURE) at their own ticks without stopping the motors'
        clock, up to the next event of anything else (`VirtualModule._limit_event`) and never
        past the end of the current `advance` (vm.horizon). The result is the same as one event
        per instruction: nothing a pure instruction reads can change in between, and no host
        command arrives during an `advance`. A tight polling loop then costs one event per loop
        pass, not per instruction.

        Reads (READS_AHEAD: GAP of a parameter the world does not compute, the tick timer, GIO
        of an input the world drives) and RETI run ahead too when the world does nothing
        between its events (`World.quiet`): time moves
        to the read's tick and the engines follow it there, exactly as an event would; no
        engine, world, heartbeat or timer event lies before the limit, so such an event would
        only run the instruction.

        What cannot run ahead (the limit is reached, an interrupt is to be entered, any other
        instruction) is the module's next event: it is taken here, as `advance_to`'s loop would
        take it (`_fold`), and the run goes on after it."""
        vm = self.vm
        horizon = getattr(vm, "horizon", None) if self.run_ahead and not self._nested else None
        if horizon is None:
            return
        code = vm.program.code
        size = len(code)
        ints = vm.interrupts
        self._quiet = None
        try:
            while True:  # what runs ahead changes neither the WAIT nor the status: only a fold can
                t = self.next_time
                if t is None or t >= horizon or self.wait is not None or vm.application_status != RUNNING:
                    return
                limit = self._ahead_limit(horizon)
                steps = self._steps_now()
                while t is not None and t < limit:
                    pc = vm.program_counter
                    if not 0 <= pc < size or (ints.pending and ints.next_dispatch() is not None):
                        break
                    ins = code[pc]
                    step = steps.get(ins) or self._step(ins)
                    if not step(t):
                        break
                    t = self.next_time
                if t is None:
                    return
                tick = t if t < limit else limit
                if tick >= horizon or tick <= vm.now:
                    return
                self._fold(tick)  # (erasing the program, GP81, resets it: the loop ends above)
        finally:
            self._t = None

    def _steps_now(self) -> dict[tuple[int, int, int, int], ahead.Step]:
        """The compiled steps (ahead.py), dropped with the program's reads (`_bound`)."""
        ops = self.vm._program_ops
        if self._steps_of is not ops:
            self._steps_of = ops
            self._steps = {}
        return self._steps

    def _step(self, ins: tuple[int, int, int, int]) -> ahead.Step:
        step = self._steps[ins] = ahead.compile_step(self, self._entries.get(ins) or self._entry(ins), INSTRUCTION_TICKS)
        return step

    def __getstate__(self) -> dict[str, Any]:
        """A copy (copy.deepcopy, pickle) makes its own entries and steps (the steps are bound to
        this module, the handlers of the entries are local functions: no pickle) and has no
        `ja_watch`; it starts outside a run."""
        state = self.__dict__.copy()
        state.update(_entries={}, _steps={}, _steps_of=None, _t=None, _nested=False, _quiet=None)
        state.pop("ja_watch", None)  # an observer of this module's program
        return state

    def _ahead_limit(self, horizon: int) -> int:
        """The tick before which instructions may run ahead: the module's next event (all but
        the program's own), `horizon` if none or later, vm.now while a heartbeat is up but not yet fired
        (it stops the motors at the next event), the next instruction's tick when the world is not
        quiet (`World.quiet`: it checks something at every event)."""
        vm = self.vm
        if not vm._limit_ok or vm._engines_dirty:  # a write since the last look-up: World.quiet may differ
            self._quiet = None
        nxt = vm._limit_event()
        hb = vm._heartbeat_deadline()
        if hb is not None and hb <= vm.now:
            return vm.now
        limit = horizon if nxt is None or nxt > horizon else nxt
        t = self.next_time
        if t is not None and t < limit and not self._world_quiet():
            return t  # the world acts at every event: each instruction is one, as in the reference
        return limit

    def _ahead_ok(self, entry: Entry, t: int) -> bool:
        """May the instruction of `entry` (not pure) run ahead at tick t? A read moves time there."""
        kind = entry[0]
        if kind == OTHER or (kind == RETI_KIND and (self.saved is None or self.saved.wait is not None)):
            return False
        vm = self.vm
        if kind == READ_KIND and entry[5] == 15 and not vm.io.sources:  # GIO of undriven inputs: pure
            return True
        if not self._world_quiet():
            return False
        if kind != RETI_KIND:
            vm.now = t              # the read's own tick: the engines follow there
        return True

    def _fold(self, tick: int) -> None:
        """Take the module's event at `tick` here (`VirtualModule._event_at`); the program's part
        of it does not run ahead again (`_nested`). At a tick before every event but the timers'
        (`VirtualModule._limit_other`, nothing written since it was looked up) in a quiet world the
        engines, the world and the heartbeats have nothing to do: only the program is served."""
        vm = self.vm
        self._t = None
        self._nested = True
        try:
            other = vm._limit_other
            if vm._limit_ok and not vm._engines_dirty and (other is None or tick < other) and self._world_quiet():
                vm.now = tick
                self.service()
            else:
                vm._event_at(tick)
        finally:
            self._nested = False

    def _world_quiet(self) -> bool:
        """World.quiet(), kept while the run-ahead limit holds (`_ahead_limit`)."""
        quiet = self._quiet
        if quiet is None:
            quiet = self._quiet = self.vm.world.quiet()
        return quiet

    # --- control commands 128-131 (manual 3.6.36) ------------------------------------------
    def run(self, address: int | None) -> None:
        """129: from the current address (None) or from `address` (a fresh start there:
        subroutine stack and interrupt context are dropped)."""
        vm = self.vm
        if address is not None:
            vm.program_counter = address
            self.stack.clear()
            self.saved = None
            vm.interrupts.active = None
            self.wait = None
        vm.application_status = RUNNING
        if self.wait is None:
            self.next_time = vm.now + INSTRUCTION_TICKS

    def stop(self) -> None:
        """128: the program stops before its next instruction; an unfinished WAIT is
        abandoned (continuing executes the WAIT again)."""
        vm = self.vm
        if vm.application_status in (RUNNING, STEPPING):
            vm.application_status = STOPPED
        self.wait = None
        self.next_time = None

    def step(self) -> None:
        """130: execute the next instruction now and pause. A pending interrupt is entered
        instead (that step only moves the PC to the handler). A WAIT that is not yet satisfied
        goes on waiting; the program pauses after it."""
        vm = self.vm
        vm.application_status = STEPPING
        vm.interrupts.poll(vm.now)
        if self.wait is not None:
            return
        if self._dispatch_interrupt():
            self.next_time = None
            return
        self._execute_next()

    def reset(self) -> None:
        """131: stop; program counter, stack, A, X and all flags to zero; interrupts off."""
        vm = self.vm
        vm.application_status = RESET
        vm.program_counter = 0
        vm.accumulator = 0
        vm.x_register = 0
        vm.flags = 0
        self.stack.clear()
        self.wait = None
        self.saved = None
        self.next_time = None
        vm.interrupts.reset()

    def status(self, type: int) -> int:
        """135: 0 mode/wait/memory pointer, 1 mode/wait/program counter, 2 A, 3 X; any
        other type is status 3 (the table lists only these four). Types 0 and 1 pack the
        mode in bits 24-31, the wait flag in bits 16-23 and the address in bits 0-15 (the
        manual is silent on the layout)."""
        vm = self.vm
        if type == 2:
            return vm.accumulator
        if type == 3:
            return vm.x_register
        if type not in (0, 1):
            raise TmclStatus(3)
        address = vm.download_pointer if type == 0 else vm.program_counter
        return (vm.application_status << 24) | (int(self.waiting) << 16) | (address & 0xFFFF)

    # --- error flags for the physical-world model -------------------------------------------
    def set_error_flag(self, flag: int) -> None:
        """Set EAL/EDV/EPO/ESD (flags.py) when the condition occurs (cleared by CLE)."""
        self.vm.flags |= flag & flags.ERROR_MASK

    # --- execution ---------------------------------------------------------------------------
    def _pause_or_continue(self) -> None:
        """After an instruction: schedule the next one, or pause when single-stepping."""
        vm = self.vm
        if vm.application_status == RUNNING:
            self.next_time = (vm.now if self._t is None else self._t) + INSTRUCTION_TICKS
        else:
            self.next_time = None

    def _check_wait(self, w: wait.Wait) -> None:
        """End the WAIT `w` (the one in progress) when its condition is met or it timed out."""
        vm = self.vm
        if wait.satisfied(vm, w):
            pass
        elif wait.expired(vm, w):
            if w.condition != wait.TICKS:
                vm.flags |= flags.ETO
        else:
            return
        self.wait = None
        vm.program_counter += 1
        self._pause_or_continue()

    def _dispatch_interrupt(self) -> bool:
        vm = self.vm
        ints = vm.interrupts
        number = ints.next_dispatch()
        if number is None:
            return False
        ints.pending.discard(number)
        ints.active = number
        self.saved = Context(vm.program_counter, vm.accumulator, vm.x_register, vm.flags, self.wait)
        self.wait = None
        vm.program_counter = ints.vectors[number]
        self._pause_or_continue()
        return True

    def _fail(self, command: int, status: int) -> None:
        self.last_error = (self.vm.program_counter, command, status)

    def _execute_next(self) -> None:
        vm = self.vm
        pc = vm.program_counter
        if not 0 <= pc < vm.program.size:  # ran off the end of program memory
            vm.application_status = STOPPED
            self.next_time = None
            return
        ins = vm.program.code[pc]
        t = self._t
        self._run(self._entries.get(ins) or self._entry(ins), pc, vm.now if t is None else t)

    def _run(self, entry: Entry, pc: int, t: int) -> None:
        """Execute the instruction at `pc` (its `_entry`) taking effect at tick t."""
        vm = self.vm
        kind, handler, type, motor, value, command = entry
        self.executed += 1
        dirty = vm._engines_dirty
        try:
            if handler(self, type, motor, value):  # True: the handler set the PC itself
                return
        except TmclStatus as exc:
            self._fail(command, exc.status)
        finally:
            if kind:  # the engines at most followed to now: their plans and events stay
                vm._engines_dirty = dirty
            else:
                vm._limit_ok = False
        if vm.application_status == RESET:  # the instruction erased the program (GP81): PC 0 stays
            self.next_time = None
            return
        vm.program_counter = pc + 1
        self.next_time = t + INSTRUCTION_TICKS if vm.application_status == RUNNING else None  # _pause_or_continue

    def _entry(self, ins: tuple[int, int, int, int]) -> Entry:
        """(kind, handler, type, motor, value, command) of an instruction, kept per instruction
        (it depends on the module's command set and axes only)."""
        command, type, motor, value = ins
        vm = self.vm
        if command not in vm.opcodes:  # not in this module's command set (commands.py)
            handler = _refused(int(Status.INVALID_COMMAND))
        elif command in FLOW:
            handler = FLOW[command]
        elif command >= 128:  # a control command of this module, direct mode only (3.6.36)
            handler = _refused(int(Status.NOT_AVAILABLE))
        elif command in READS_AHEAD or command == AGP:
            handler = _bound_or_direct(command)
        else:
            handler = _direct(command)
        entry = self._entries[ins] = (self._kind(command, type, motor), handler, type, motor, value, command)
        return entry

    def _kind(self, command: int, type: int, bank: int) -> int:
        """OTHER, or what keeps every event but the program's own where it was: PURE, READ (the
        reads that may run ahead), or RETI_KIND."""
        if command in PURE or (command in PURE_ON_BANK_2 and bank == 2) or (command == 10 and (type, bank) != TICK_TIMER):
            return PURE_KIND
        if command in READS_AHEAD and (command != 6 or (type not in self.vm.world.axis_numbers and type != 207)):
            return READ_KIND
        return RETI_KIND if command == RETI else OTHER

    def _generic(self, command: int, type: int, motor: int, value: int) -> None:
        """Motion, parameter, I/O and coordinate commands: the direct-mode handler, then the
        value of a reading command goes to the accumulator (manual 3.5.5)."""
        vm = self.vm
        out = execute(vm, command, type, motor, value, program=True)
        if not isinstance(out, tuple):
            return
        status, result = out
        if status != Status.OK:
            raise TmclStatus(status)
        reads = command in READS_VALUE or (command == 13 and type == 2)
        if command == 31 and motor == 255:  # GCO n, 255: EEPROM -> RAM copy, nothing read
            reads = False
        if reads:
            self._load(result)

    def _bound(self, command: int, type: int, motor: int) -> Bound | None:
        """The pre-bound read (GAP, GGP, GIO: dispatch.program_read) or user-variable store (AGP:
        dispatch.program_store) of an instruction and the engines the read looks at (a GAP: its
        axis's), or None where `execute` must run it; kept until the module drops its tables
        (`VirtualModule.forget_requests`)."""
        ops = self.vm._program_ops
        key = (command, type, motor)
        try:
            return ops[key]
        except KeyError:
            vm = self.vm
            op: Callable[..., Any] | None
            engines: list[Any] | None = vm._engines
            if command == AGP:
                op, engines = program_store(vm, type, motor), None
            else:
                op = program_read(vm, command, type, motor)
                if command == 6 and op is not None:
                    engines = [vm.axes[motor].engine]
                elif command == 10 and motor == USER_BANK:
                    engines = []
            bound = ops[key] = None if op is None else (op, engines)
            return bound

    def _load(self, value: int) -> None:
        vm = self.vm
        a = vm.accumulator = value if -0x8000_0000 <= value <= 0x7FFF_FFFF else to_int32(value)
        vm.flags = (vm.flags & ~flags.ZERO) | (flags.ZERO if a == 0 else 0)  # the zero flag follows a load (3.5.6.4)

    def _jump(self, address: int) -> bool:
        """Set the PC (a jump outside program memory is ignored: status 4 in `last_error`)."""
        vm = self.vm
        if not 0 <= address < vm.program.size:
            raise TmclStatus(4)
        vm.program_counter = address
        if vm.application_status == RUNNING:  # _pause_or_continue
            t = self._t
            self.next_time = (vm.now if t is None else t) + INSTRUCTION_TICKS
        else:
            self.next_time = None
        return True

    # --- flow and calculation commands ---------------------------------------------------------
    def _calc(self, type: int, motor: int, value: int) -> None:  # 19 CALC (3.6.14)
        vm = self.vm
        if not calc.ADD <= type <= calc.LOAD:
            raise TmclStatus(3)
        self._load(self._calc_into(type, vm.accumulator, value))

    def _comp(self, type: int, motor: int, value: int) -> None:  # 20 COMP (3.6.15)
        vm = self.vm
        vm.flags = flags.after_compare(vm.flags, vm.accumulator, to_int32(value))

    def _condition(self, type: int) -> bool:
        met = flags.condition(self.vm.flags, type)
        if met is None:
            raise TmclStatus(3)
        return met

    def _jc(self, type: int, motor: int, value: int) -> bool:  # 21 JC (3.6.16)
        if self._condition(type):
            return self._jump(value)
        return False

    def _ja(self, type: int, motor: int, value: int) -> bool:  # 22 JA (3.6.17)
        watch = self.ja_watch
        if watch is not None:
            watch(self.vm.program_counter, value)
        return self._jump(value)

    def _csub(self, type: int, motor: int, value: int) -> bool:  # 23 CSUB (3.6.18): ignored when the stack is full
        vm = self.vm
        if len(self.stack) >= STACK_DEPTH:
            return False
        if not 0 <= value < vm.program.size:
            raise TmclStatus(4)
        self.stack.append(vm.program_counter + 1)
        return self._jump(value)

    def _rsub(self, type: int, motor: int, value: int) -> bool:  # 24 RSUB (3.6.19): ignored when the stack is empty
        if not self.stack:
            return False
        return self._jump(self.stack.pop())

    def _wait(self, type: int, motor: int, value: int) -> bool:  # 27 WAIT (3.6.20)
        vm = self.vm
        w = wait.start(vm, type, motor, value)
        self.wait = w
        self.next_time = None
        if w.condition == wait.TICKS and w.deadline is not None and w.deadline <= vm.now:  # WAIT TICKS, 0, 0
            self.wait = None
            return False
        if wait.satisfied(vm, w):
            self.wait = None
            return False
        return True  # the PC stays at the WAIT

    def _stop(self, type: int, motor: int, value: int) -> bool:  # 28 STOP (3.6.21): the PC stays at the STOP
        self.vm.application_status = STOPPED
        self.next_time = None
        return True

    def _calcx(self, type: int, motor: int, value: int) -> None:  # 33 CALCX (3.6.26)
        vm = self.vm
        a, x = vm.accumulator, vm.x_register
        if type == calc.NOT:          # "logical invert X register"
            vm.x_register = to_int32(~x)
        elif type == calc.LOAD:       # "copy accumulator to X register"
            vm.x_register = a
        elif type == calc.SWAP:
            vm.x_register = a
            self._load(x)
        elif calc.ADD <= type <= calc.XOR:
            self._load(self._calc_into(type, a, x))
        else:
            raise TmclStatus(3)

    def _reti(self, type: int, motor: int, value: int) -> bool:  # 38 RETI (3.6.33); ignored outside an ISR
        vm = self.vm
        ctx = self.saved
        if ctx is None:
            return False
        self.saved = None
        vm.interrupts.active = None
        vm.program_counter = ctx.pc
        vm.accumulator, vm.x_register, vm.flags = ctx.accumulator, ctx.x_register, ctx.flags
        self.wait = ctx.wait
        self._pause_or_continue()
        if self.wait is not None:
            self.next_time = None
        return True

    # --- PD28-1021 extended set (manual 3.5 Table 5; semantics: docs/assumptions.md) -------
    def _var(self, index: int) -> int:
        if not 0 <= index < len(self.vm.user_vars):
            raise TmclStatus(3)
        return index

    def _calc_into(self, op: int, dst: int, src: int | None) -> int:
        """`dst <op> src` for the CALCxx family: LOAD copies src, NOT inverts dst."""
        if op == calc.SWAP or src is None and op != calc.NOT:
            raise TmclStatus(3)
        result = calc.binary(op, dst, 0 if src is None else src)
        if result is None:
            raise TmclStatus(3)
        return result

    def _calc_vv(self, op: int, v1: int, v2: int) -> None:  # 40 CALCVV op, var1, var2: var1 = var1 op var2
        vm, a, b = self.vm, self._var(v1), self._var(v2)
        if op == calc.SWAP:
            vm.user_vars[a], vm.user_vars[b] = vm.user_vars[b], vm.user_vars[a]
        else:
            vm.user_vars[a] = self._calc_into(op, vm.user_vars[a], vm.user_vars[b])

    def _calc_va(self, op: int, var: int, value: int) -> None:  # 41 CALCVA op, var: var = var op A
        vm, v = self.vm, self._var(var)
        if op == calc.SWAP:
            a = vm.accumulator
            self._load(vm.user_vars[v])
            vm.user_vars[v] = a
        else:
            vm.user_vars[v] = self._calc_into(op, vm.user_vars[v], vm.accumulator)

    def _calc_av(self, op: int, var: int, value: int) -> None:  # 42 CALCAV op, var: A = A op var
        vm, v = self.vm, self._var(var)
        if op == calc.SWAP:
            return self._calc_va(op, var, value)
        self._load(self._calc_into(op, vm.accumulator, vm.user_vars[v]))

    def _calc_vx(self, op: int, var: int, value: int) -> None:  # 43 CALCVX op, var: var = var op X
        vm, v = self.vm, self._var(var)
        if op == calc.SWAP:
            vm.user_vars[v], vm.x_register = vm.x_register, vm.user_vars[v]
        else:
            vm.user_vars[v] = self._calc_into(op, vm.user_vars[v], vm.x_register)

    def _calc_xv(self, op: int, var: int, value: int) -> None:  # 44 CALCXV op, var: X = X op var
        vm, v = self.vm, self._var(var)
        if op == calc.SWAP:
            return self._calc_vx(op, var, value)
        vm.x_register = self._calc_into(op, vm.x_register, vm.user_vars[v])

    def _calc_v(self, op: int, var: int, value: int) -> None:  # 45 CALCV op, var, value: var = var op value
        vm, v = self.vm, self._var(var)
        vm.user_vars[v] = self._calc_into(op, vm.user_vars[v], value)

    def _with_accu(self, command: int, type: int, motor: int) -> None:
        self._generic(command, type, motor, self.vm.accumulator)

    def _mvpa(self, type: int, motor: int, value: int) -> None:  # 46 MVPA ABS|REL|COORD, motor: MVP with A
        self._with_accu(4, type, motor)

    def _rola(self, type: int, motor: int, value: int) -> None:  # 50 ROLA motor
        self._with_accu(2, 0, motor)

    def _rora(self, type: int, motor: int, value: int) -> None:  # 51 RORA motor
        self._with_accu(1, 0, motor)

    def _rst(self, type: int, motor: int, value: int) -> bool:  # 48 RST label: restart there, stack and ISR dropped
        vm = self.vm
        if not 0 <= value < vm.program.size:
            raise TmclStatus(4)
        self.stack.clear()
        self.saved = None
        vm.interrupts.active = None
        return self._jump(value)

    def _djnz(self, var: int, motor: int, value: int) -> bool:  # 49 DJNZ var, label: var -= 1, jump unless 0
        vm, v = self.vm, self._var(var)
        vm.user_vars[v] = to_int32(vm.user_vars[v] - 1)
        if vm.user_vars[v] != 0:
            return self._jump(value)
        return False

    def _call(self, type: int, motor: int, value: int) -> bool:  # 80 CALL cond, label: CSUB if the JC condition holds
        if self._condition(type):
            return self._csub(type, motor, value)
        return False

    def _siv(self, type: int, motor: int, value: int) -> None:  # 55 SIV value: variable[X] = value
        vm = self.vm
        vm.user_vars[self._var(vm.x_register)] = to_int32(value)

    def _giv(self, type: int, motor: int, value: int) -> None:  # 56 GIV: A = variable[X]
        vm = self.vm
        self._load(vm.user_vars[self._var(vm.x_register)])

    def _aiv(self, type: int, motor: int, value: int) -> None:  # 57 AIV: variable[X] = A
        vm = self.vm
        vm.user_vars[self._var(vm.x_register)] = vm.accumulator


def _refused(status: int) -> FlowHandler:
    """The handler of an instruction this module does not execute in a program: `status`."""
    def refused(interpreter: Interpreter, type: int, motor: int, value: int) -> None:
        raise TmclStatus(status)
    return refused


_DIRECT: dict[int, FlowHandler] = {}


def _direct(command: int) -> FlowHandler:
    """The handler of a command that runs as in direct mode (`Interpreter._generic`)."""
    handler = _DIRECT.get(command)
    if handler is None:
        def handler(interpreter: Interpreter, type: int, motor: int, value: int) -> None:
            interpreter._generic(command, type, motor, value)
        _DIRECT[command] = handler
    return handler


_BOUND: dict[int, FlowHandler] = {}


def _bound_or_direct(command: int) -> FlowHandler:
    """The handler of GAP, GGP, GIO (`read`) or AGP (`store`): the pre-bound read or user-variable
    store (`Interpreter._bound`) where there is one, else as in direct mode."""
    handler = _BOUND.get(command)
    if handler is not None:
        return handler

    def store(interpreter: Interpreter, type: int, motor: int, value: int) -> None:
        bound = interpreter._bound(command, type, motor)
        if bound is None:
            interpreter._generic(command, type, motor, value)
        else:  # `execute` syncs the engines first; a user variable touches none
            bound[0](interpreter.vm.accumulator)

    def read(interpreter: Interpreter, type: int, motor: int, value: int) -> None:
        bound = interpreter._bound(command, type, motor)
        if bound is None:
            interpreter._generic(command, type, motor, value)
            return
        op, engines = bound
        vm = interpreter.vm
        if vm._synced_at != vm.now:  # as `execute` does for a read, for the engines it reads
            vm.sync_for_read(engines)
        v = op()
        interpreter._load(int(v) if v.__class__ is bool else v)  # AP8: Axis.get answers int()
    handler = _BOUND[command] = store if command == AGP else read
    return handler


FLOW: dict[int, FlowHandler] = {
    19: Interpreter._calc, 20: Interpreter._comp, 21: Interpreter._jc, 22: Interpreter._ja,
    23: Interpreter._csub, 24: Interpreter._rsub, 27: Interpreter._wait, 28: Interpreter._stop,
    33: Interpreter._calcx, 38: Interpreter._reti,
    40: Interpreter._calc_vv, 41: Interpreter._calc_va, 42: Interpreter._calc_av, 43: Interpreter._calc_vx,
    44: Interpreter._calc_xv, 45: Interpreter._calc_v, 46: Interpreter._mvpa, 48: Interpreter._rst,
    49: Interpreter._djnz, 50: Interpreter._rola, 51: Interpreter._rora, 55: Interpreter._siv,
    56: Interpreter._giv, 57: Interpreter._aiv, CALL: Interpreter._call,
}
