"""The TMCL program interpreter: standalone mode in virtual time
(TMCM-6212 manual 3.3, 3.5.3-3.5.6, 3.6.14-3.6.33, 3.6.36, 7; PD86-1180 manual 4.6, 8;
PD28-1021 manual 3.5 for the extended command set).

Time: every instruction takes `steps.SLOT` ticks of the 16 MHz clock (100 µs, i.e. 10000 TMCL
instructions per second) and takes effect at the end of its slot; a WAIT ends at its condition or
timeout and the next instruction follows one slot later; dispatching an interrupt and returning
from it (RETI) take one slot each. The scheduler asks `own_event()` when the program next needs
service (timers are the module's) and calls `service()` at every event tick.

Each stored instruction is compiled once into a step (steps.py) through the command table
(table.py); its effect decides whether it may run ahead of the scheduler's events (`run_ahead`):
one that changes nothing any next event depends on runs at its own tick without an event, a pure
read too while the world does nothing between its events (time moves to the read's tick), and
anything else is the module's next event, taken in place (`Scheduler.fold`).

Registers live on the virtual module: vm.accumulator, vm.x_register, vm.flags (flags.py),
vm.program_counter, vm.application_status. Direct-mode commands never reach this class, so a host
talking to the module never disturbs a running program (manual 7.6).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..protocol.status import Status
from . import steps, wait
from .effects import Effect
from .program import RESET, RUNNING, STEPPING, STOPPED
from .requests import reader, store
from .status import TmclStatus
from .table import Spec, available, execute

if TYPE_CHECKING:
    from .vm import VirtualModule

INSTRUCTION_TICKS = steps.SLOT
STACK_DEPTH = steps.STACK_DEPTH
FLAGGED = 0x1F  # the error flags (flags.ERROR_MASK)
PURE, READ, RETURN, EVENT = 0, 1, 2, 3
"""How an instruction may run ahead: always; as a read at its own tick in a quiet world; RETI back
to a program that was not in a WAIT; never (it is an event of the scheduler)."""
Compiled = tuple[int, Effect, steps.Step]
"""(how it may run ahead, its effect, its step)."""


@dataclass(slots=True)
class Context:
    """What an interrupt saves and RETI restores (manual 3.5.6.2, 3.6.33)."""

    pc: int
    accumulator: int
    x_register: int
    flags: int
    wait: wait.Wait | None


def _kind(effect: Effect, spec: Spec) -> int:
    if spec.returns:
        return RETURN
    if effect == Effect.NONE:
        return PURE
    if effect == Effect.READ:
        return READ
    return EVENT


class Interpreter:
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
        self._compiled: dict[tuple[int, int, int, int], Compiled] = {}
        self._nested = False                # taking an event inside the run ahead (Scheduler.fold)
        vm.scheduler.register("program steps", Effect.REQUESTS | Effect.PROGRAM, self.forget)

    def forget(self) -> None:
        """Drop the compiled steps (they bind reads of the module's axes and banks)."""
        self._compiled.clear()

    @property
    def waiting(self) -> bool:
        return self.wait is not None

    # --- compiling ------------------------------------------------------------------------------
    def compiled(self, ins: tuple[int, int, int, int]) -> Compiled:
        """The step of a stored instruction (kept per instruction until the module's state changes)."""
        found = self._compiled.get(ins)
        if found is None:
            found = self._compiled[ins] = self._compile(*ins)
        return found

    def _compile(self, command: int, type: int, motor: int, value: int) -> Compiled:
        vm = self.vm
        spec = available(vm, command)
        if spec is None:  # not in this module's command set
            return PURE, Effect.NONE, steps.failing(self, command, int(Status.INVALID_COMMAND))
        if not spec.command.program:  # a control command: direct mode only (3.6.36)
            return PURE, Effect.NONE, steps.failing(self, command, int(Status.NOT_AVAILABLE))
        effect = spec.effect_of(type, motor)
        kind = _kind(effect, spec)
        if spec.step is not None:
            return kind, effect, spec.step(self, command, type, motor, value)
        if spec.accumulator is not None:
            direct, type_of = spec.accumulator
            return kind, effect, steps.with_accumulator(direct, type_of)(self, command, type, motor, value, execute)
        if spec.binds == "read":
            read = reader(vm, command, type, motor)
            if read is not None:
                return kind, effect, steps.bound_read(self, read, spec.read_engines(vm, type, motor))
        if spec.binds == "store":
            put = store(vm, type, motor)
            if put is not None:
                return kind, effect, steps.bound_store(self, put)
        loads = spec.loads_accumulator(type, motor)
        return kind, effect, steps.direct(self, command, type, motor, value, loads, execute)

    # --- scheduling -----------------------------------------------------------------------------
    def go_on(self, address: int, t: int) -> None:
        """The instruction at tick `t` is done: the one at `address` follows one slot later, if
        the program runs (single-stepping pauses)."""
        vm = self.vm
        vm.program_counter = address
        self.next_time = t + steps.SLOT if vm.application_status == RUNNING else None

    # --- hooks called by the module and its scheduler --------------------------------------------
    def power_up(self) -> None:
        """GP77 auto start mode: 1 starts the stored program after power-up (manual 5.1)."""
        if self.vm.globals.get_raw(0, 77) == 1 and self.vm.program.length:
            self.run(0)

    def own_event(self) -> int | None:
        """The program's own next tick (instruction, WAIT timeout or check, dispatch from a
        WAIT), > now, or None; timers are the module's."""
        vm = self.vm
        now = vm.scheduler.now
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
        """Execute what is due now: finish a WAIT, take an interrupt, run one instruction."""
        vm = self.vm
        sched = vm.scheduler
        now = sched.now
        vm.interrupts.poll(now, refresh=not sched.limit_held())  # periods are written only by commands
        if vm.application_status not in (RUNNING, STEPPING):
            return
        if self.wait is not None:
            self._check_wait(self.wait, now)
        if vm.application_status != RUNNING:
            return
        if self.wait is not None or (self.next_time is not None and self.next_time <= now):
            if self._dispatch_interrupt(now):
                self.run_ahead()
                return
        if self.wait is None and self.next_time is not None and self.next_time <= now:
            self._execute_next(now)
            self.run_ahead()

    def run_ahead(self) -> None:
        """Run the instructions that may run ahead at their own ticks, up to the scheduler's next
        event and never past the end of the `advance` in progress; what cannot run ahead (the limit
        reached, an interrupt to enter, an instruction that is an event) is taken as the module's
        next event in place (`Scheduler.fold`), and the run goes on after it. The result is the
        same as one event per instruction (the tests' oracle)."""
        vm = self.vm
        sched = vm.scheduler
        horizon = sched.horizon
        if horizon is None or self._nested:
            return
        while True:  # what runs ahead changes neither the WAIT nor the status: only a fold can
            t = self.next_time
            if t is None or t >= horizon or self.wait is not None or vm.application_status != RUNNING:
                return
            limit = sched.ahead_limit(horizon, t)
            t = self._steps_before(t, limit)
            if t is None:
                return
            tick = t if t < limit else limit
            if tick >= horizon or tick <= sched.now:
                return
            self._nested = True
            try:
                sched.fold(tick)  # (erasing the program, GP81, resets it: the loop ends above)
            finally:
                self._nested = False

    def _steps_before(self, t: int | None, limit: int) -> int | None:
        """Run the instructions that may run ahead from tick `t` on, up to `limit`; the tick of the
        next instruction (None: none is scheduled)."""
        vm = self.vm
        sched = vm.scheduler
        code = vm.program.code
        size = len(code)
        ints = vm.interrupts
        compiled = self._compiled
        slot = steps.SLOT
        while t is not None and t < limit:  # the program runs: what runs ahead does not change that
            pc = vm.program_counter
            if not 0 <= pc < size or (ints.pending and ints.next_dispatch() is not None):
                break
            ins = code[pc]
            kind, _effect, step = compiled.get(ins) or self.compiled(ins)
            if kind:
                if kind == EVENT or not sched.world_quiet():
                    break
                if kind == RETURN:
                    if self.saved is None or self.saved.wait is not None:
                        break
                else:
                    sched.now = t  # the read's own tick: the engines follow there
            address = step(t)
            if address is None:
                t = self.next_time
            else:
                vm.program_counter = address
                t = self.next_time = t + slot
        return t

    def __getstate__(self) -> dict[str, Any]:
        """A copy (copy.deepcopy, pickle) compiles its own steps (they are bound to this module)
        and has no `ja_watch`; it starts outside a run."""
        state = {k: v for k, v in self.__dict__.items() if k != "ja_watch"}
        state.update(_compiled={}, _nested=False)
        return state

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
            self.next_time = vm.scheduler.now + steps.SLOT

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
        now = vm.scheduler.now
        vm.application_status = STEPPING
        vm.interrupts.poll(now)
        if self.wait is not None:
            return
        if self._dispatch_interrupt(now):
            self.next_time = None
            return
        self._execute_next(now)

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
        self.vm.flags |= flag & FLAGGED

    # --- execution ---------------------------------------------------------------------------
    def _check_wait(self, w: wait.Wait, now: int) -> None:
        """End the WAIT `w` (the one in progress) when its condition is met or it timed out."""
        vm = self.vm
        if wait.satisfied(vm, w):
            pass
        elif wait.expired(vm, w):
            if w.condition != wait.TICKS:
                vm.flags |= 1  # ETO (flags.py)
        else:
            return
        self.wait = None
        self.go_on(vm.program_counter + 1, now)

    def _dispatch_interrupt(self, now: int) -> bool:
        vm = self.vm
        ints = vm.interrupts
        number = ints.next_dispatch()
        if number is None:
            return False
        ints.pending.discard(number)
        ints.active = number
        self.saved = Context(vm.program_counter, vm.accumulator, vm.x_register, vm.flags, self.wait)
        self.wait = None
        self.go_on(ints.vectors[number], now)
        return True

    def _execute_next(self, now: int) -> None:
        """The next instruction as an event of the scheduler, at `now`."""
        vm = self.vm
        pc = vm.program_counter
        if not 0 <= pc < vm.program.size:  # ran off the end of program memory
            vm.application_status = STOPPED
            self.next_time = None
            return
        kind, effect, step = self.compiled(vm.program.code[pc])
        address = step(now)
        if address is not None:
            self.go_on(address, now)
        if kind == EVENT:
            vm.scheduler.invalidate(effect | Effect.EVENTS)
