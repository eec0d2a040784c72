"""TMCL instructions as program steps: the one implementation of what each instruction does in a
program (TMCM-6212 manual 3.5, 3.6.14-3.6.33; PD28-1021 manual 3.5 Table 5 for 40-57 and CALL).

The interpreter compiles each stored instruction once into a step, a function of the tick `t` at
which the instruction takes effect: it does the instruction's work and answers the address of the
next instruction, which the interpreter schedules one slot later; or None when the step has set the
program counter and the schedule itself (WAIT, STOP, RETI). The same
step runs whether the instruction is taken as an event of the scheduler or run ahead of it
(Interpreter.run_ahead); which instructions may run ahead is the command table's business
(table.py: the effect of each command).

An instruction that fails (a wrong type, a jump outside program memory, an unknown condition, a
command the module lacks) has no effect: the step records the status in `last_error` and the
program goes on with the next instruction (docs/assumptions.md). Commands that act as in direct
mode (motion, parameters, I/O, coordinates) go through the command table's `execute`; a reading
command's value goes to the accumulator (manual 3.5.5).
"""
from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING, Any

from ..protocol.frame import to_int32
from ..protocol.status import Status
from . import calc, flags, wait
from .program import RESET, RUNNING, STOPPED
from .status import TmclStatus

if TYPE_CHECKING:
    from .interpreter import Interpreter

Step = Callable[[int], int | None]
Compiler = Callable[["Interpreter", int, int, int, int], Step]
"""Makes the step of one instruction from its (command, type, motor, value) fields."""
SLOT = 1600
"""Ticks of the 16 MHz clock one TMCL instruction takes: 100 µs, 10000 instructions per second."""
STACK_DEPTH = 8  # "The number of entries in the internal stack is limited to 8."
_LOW, _HIGH = -0x8000_0000, 0x7FFF_FFFF
_ZERO = flags.ZERO
_SIGN = {calc.ADD: 1, calc.SUB: -1}


def _load(vm: Any, value: int) -> None:
    """A value to the accumulator; the zero flag follows it (3.5.6.4)."""
    a = vm.accumulator = value if _LOW <= value <= _HIGH else to_int32(value)
    vm.flags = (vm.flags & ~_ZERO) | (_ZERO if a == 0 else 0)


def failing(ip: Interpreter, command: int, status: int) -> Step:
    """The step of an instruction the program cannot execute: it fails with `status`."""
    vm = ip.vm

    def step(t: int) -> int:
        ip.executed += 1
        pc = vm.program_counter
        ip.last_error = (pc, command, status)
        return pc + 1
    return step


def refused(status: int) -> Compiler:
    """The compiler of a command that never runs in a program: 2 when the module lacks it, 6
    ("command not available") for a control command."""
    def compile_(ip: Interpreter, command: int, type: int, motor: int, value: int) -> Step:
        return failing(ip, command, status)
    return compile_


# --- jumps and subroutines (3.6.16-3.6.19; RST, DJNZ, CALL of the PD28-1021) --------------------
def _go(ip: Interpreter, command: int, address: int) -> Step:
    """Jump to `address`; outside program memory the jump fails (status 4) and the program goes on
    with the next instruction."""
    if 0 <= address < ip.vm.program.size:
        def go(t: int) -> int:
            return address
        return go
    return partial(_fail, ip, command, 4)


def _fail(ip: Interpreter, command: int, status: int, t: int) -> int:
    pc = ip.vm.program_counter
    ip.last_error = (pc, command, status)
    return pc + 1


def ja(ip: Interpreter, command: int, type: int, motor: int, address: int) -> Step:
    vm = ip.vm
    go = _go(ip, command, address)

    def step(t: int) -> int | None:
        watch = ip.ja_watch
        if watch is not None:
            watch(vm.program_counter, address)
        ip.executed += 1
        return go(t)
    return step


def jc(ip: Interpreter, command: int, condition: int, motor: int, address: int) -> Step:
    test = flags.CONDITIONS.get(condition)
    if test is None:
        return failing(ip, command, 3)
    bits, when_set = test
    vm = ip.vm
    go = _go(ip, command, address)

    def step(t: int) -> int | None:
        ip.executed += 1
        if bool(vm.flags & bits) == when_set:
            return go(t)
        return vm.program_counter + 1
    return step


def csub(ip: Interpreter, command: int, type: int, motor: int, address: int) -> Step:
    """CSUB: ignored when the stack is full (3.6.18)."""
    vm = ip.vm
    ok = 0 <= address < vm.program.size

    def step(t: int) -> int:
        ip.executed += 1
        pc = vm.program_counter
        if len(ip.stack) >= STACK_DEPTH:
            return pc + 1
        if not ok:
            return _fail(ip, command, 4, t)
        ip.stack.append(pc + 1)
        return address
    return step


def rsub(ip: Interpreter, command: int, type: int, motor: int, value: int) -> Step:
    """RSUB: ignored when the stack is empty (3.6.19)."""
    vm = ip.vm
    size = vm.program.size

    def step(t: int) -> int:
        ip.executed += 1
        if not ip.stack:
            return vm.program_counter + 1
        address = ip.stack.pop()
        if 0 <= address < size:
            return address
        return _fail(ip, command, 4, t)  # back past the end of program memory
    return step


def call(ip: Interpreter, command: int, condition: int, motor: int, address: int) -> Step:
    """CALL cond, label: CSUB when the JC condition holds."""
    test = flags.CONDITIONS.get(condition)
    if test is None:
        return failing(ip, command, 3)
    bits, when_set = test
    sub = csub(ip, command, 0, 0, address)
    vm = ip.vm

    def step(t: int) -> int | None:
        if bool(vm.flags & bits) == when_set:
            return sub(t)
        ip.executed += 1
        return vm.program_counter + 1
    return step


def rst(ip: Interpreter, command: int, type: int, motor: int, address: int) -> Step:
    """RST label: restart there; stack and interrupt context are dropped."""
    vm = ip.vm
    if not 0 <= address < vm.program.size:
        return failing(ip, command, 4)

    def step(t: int) -> int:
        ip.executed += 1
        ip.stack.clear()
        ip.saved = None
        vm.interrupts.active = None
        return address
    return step


def djnz(ip: Interpreter, command: int, var: int, motor: int, address: int) -> Step:
    """DJNZ var, label: var -= 1, jump unless it is 0."""
    vm = ip.vm
    variables = vm.user_vars
    if not 0 <= var < len(variables):
        return failing(ip, command, 3)
    go = _go(ip, command, address)

    def step(t: int) -> int | None:
        ip.executed += 1
        v = variables[var] = to_int32(variables[var] - 1)
        if v != 0:
            return go(t)
        return vm.program_counter + 1
    return step


# --- calculation (3.6.14, 3.6.15, 3.6.26) ---------------------------------------------------------
def calc_(ip: Interpreter, command: int, op: int, motor: int, value: int) -> Step:
    """CALC op, value: A = A op value (ADD .. LOAD)."""
    if not calc.ADD <= op <= calc.LOAD:
        return failing(ip, command, 3)
    vm = ip.vm
    operand = to_int32(value)
    sign = _SIGN.get(op)
    binary = calc.binary

    def add(t: int) -> int:  # ADD and SUB: the accumulator is in 32 bits already
        ip.executed += 1
        a = vm.accumulator + operand * sign  # type: ignore[operator]
        _load(vm, a if _LOW <= a <= _HIGH else to_int32(a))
        return vm.program_counter + 1

    def other(t: int) -> int:
        ip.executed += 1
        _load(vm, binary(op, vm.accumulator, operand))  # type: ignore[arg-type]
        return vm.program_counter + 1
    return add if sign is not None else other


def comp(ip: Interpreter, command: int, type: int, motor: int, value: int) -> Step:
    vm = ip.vm
    operand = to_int32(value)
    after = flags.after_compare

    def step(t: int) -> int:
        ip.executed += 1
        vm.flags = after(vm.flags, vm.accumulator, operand)
        return vm.program_counter + 1
    return step


def _calc_into(op: int, dst: int, src: int | None) -> int | None:
    """`dst <op> src` for the CALCxx family: LOAD copies src, NOT inverts dst; None: refused."""
    if op == calc.SWAP or src is None and op != calc.NOT:
        return None
    return calc.binary(op, dst, 0 if src is None else src)


def _simple(ip: Interpreter, command: int, work: Callable[[], int | None]) -> Step:
    """A step whose work answers a failing status or None."""
    vm = ip.vm

    def step(t: int) -> int:
        ip.executed += 1
        status = work()
        if status is not None:
            ip.last_error = (vm.program_counter, command, status)
        return vm.program_counter + 1
    return step


def calcx(ip: Interpreter, command: int, op: int, motor: int, value: int) -> Step:
    """CALCX op: A = A op X; NOT inverts X, LOAD copies A to X, SWAP exchanges them (3.6.26)."""
    vm = ip.vm

    def work() -> int | None:
        a, x = vm.accumulator, vm.x_register
        if op == calc.NOT:
            vm.x_register = to_int32(~x)
        elif op == calc.LOAD:
            vm.x_register = a
        elif op == calc.SWAP:
            vm.x_register = a
            _load(vm, x)
        elif calc.ADD <= op <= calc.XOR:
            _load(vm, calc.binary(op, a, x))  # type: ignore[arg-type]
        else:
            return 3
        return None
    return _simple(ip, command, work)


def _variable(ip: Interpreter, index: int) -> bool:
    return 0 <= index < len(ip.vm.user_vars)


def calc_vv(ip: Interpreter, command: int, op: int, v1: int, v2: int) -> Step:
    """CALCVV op, var1, var2: var1 = var1 op var2 (SWAP exchanges them)."""
    vm = ip.vm
    variables = vm.user_vars

    def work() -> int | None:
        if not (_variable(ip, v1) and _variable(ip, v2)):
            return 3
        if op == calc.SWAP:
            variables[v1], variables[v2] = variables[v2], variables[v1]
            return None
        return _store(variables, v1, _calc_into(op, variables[v1], variables[v2]))
    return _simple(ip, command, work)


def _store(variables: list[int], index: int, value: int | None) -> int | None:
    if value is None:
        return 3
    variables[index] = value
    return None


def calc_va(ip: Interpreter, command: int, op: int, var: int, value: int) -> Step:
    """CALCVA op, var: var = var op A (SWAP exchanges var and A)."""
    vm = ip.vm
    variables = vm.user_vars

    def work() -> int | None:
        if not _variable(ip, var):
            return 3
        if op == calc.SWAP:
            a = vm.accumulator
            _load(vm, variables[var])
            variables[var] = a
            return None
        return _store(variables, var, _calc_into(op, variables[var], vm.accumulator))
    return _simple(ip, command, work)


def calc_av(ip: Interpreter, command: int, op: int, var: int, value: int) -> Step:
    """CALCAV op, var: A = A op var (SWAP as CALCVA)."""
    if op == calc.SWAP:
        return calc_va(ip, command, op, var, value)
    vm = ip.vm

    def work() -> int | None:
        if not _variable(ip, var):
            return 3
        result = _calc_into(op, vm.accumulator, vm.user_vars[var])
        if result is None:
            return 3
        _load(vm, result)
        return None
    return _simple(ip, command, work)


def calc_vx(ip: Interpreter, command: int, op: int, var: int, value: int) -> Step:
    """CALCVX op, var: var = var op X (SWAP exchanges var and X)."""
    vm = ip.vm
    variables = vm.user_vars

    def work() -> int | None:
        if not _variable(ip, var):
            return 3
        if op == calc.SWAP:
            variables[var], vm.x_register = vm.x_register, variables[var]
            return None
        return _store(variables, var, _calc_into(op, variables[var], vm.x_register))
    return _simple(ip, command, work)


def calc_xv(ip: Interpreter, command: int, op: int, var: int, value: int) -> Step:
    """CALCXV op, var: X = X op var (SWAP as CALCVX)."""
    if op == calc.SWAP:
        return calc_vx(ip, command, op, var, value)
    vm = ip.vm

    def work() -> int | None:
        if not _variable(ip, var):
            return 3
        result = _calc_into(op, vm.x_register, vm.user_vars[var])
        if result is None:
            return 3
        vm.x_register = result
        return None
    return _simple(ip, command, work)


def calc_v(ip: Interpreter, command: int, op: int, var: int, value: int) -> Step:
    """CALCV op, var, value: var = var op value."""
    variables = ip.vm.user_vars

    def work() -> int | None:
        if not _variable(ip, var):
            return 3
        return _store(variables, var, _calc_into(op, variables[var], value))
    return _simple(ip, command, work)


def siv(ip: Interpreter, command: int, type: int, motor: int, value: int) -> Step:
    """SIV value: variable[X] = value."""
    vm = ip.vm
    v = to_int32(value)

    def work() -> int | None:
        if not _variable(ip, vm.x_register):
            return 3
        vm.user_vars[vm.x_register] = v
        return None
    return _simple(ip, command, work)


def giv(ip: Interpreter, command: int, type: int, motor: int, value: int) -> Step:
    """GIV: A = variable[X]."""
    vm = ip.vm

    def work() -> int | None:
        if not _variable(ip, vm.x_register):
            return 3
        _load(vm, vm.user_vars[vm.x_register])
        return None
    return _simple(ip, command, work)


def aiv(ip: Interpreter, command: int, type: int, motor: int, value: int) -> Step:
    """AIV: variable[X] = A."""
    vm = ip.vm

    def work() -> int | None:
        if not _variable(ip, vm.x_register):
            return 3
        vm.user_vars[vm.x_register] = vm.accumulator
        return None
    return _simple(ip, command, work)


# --- WAIT, STOP, RETI (3.6.20, 3.6.21, 3.6.33) ---------------------------------------------------
def wait_(ip: Interpreter, command: int, condition: int, motor: int, ticks: int) -> Step:
    """WAIT: the PC stays at the WAIT until its condition or timeout (Interpreter.check_wait)."""
    vm = ip.vm
    start, satisfied = wait.start, wait.satisfied

    def step(t: int) -> int | None:
        ip.executed += 1
        try:
            w = start(vm, condition, motor, ticks)
        except TmclStatus as exc:  # a wrong condition or motor
            ip.last_error = (vm.program_counter, command, exc.status)
            return vm.program_counter + 1
        if (w.condition == wait.TICKS and w.deadline is not None and w.deadline <= vm.now) or satisfied(vm, w):
            return vm.program_counter + 1  # WAIT TICKS, 0, 0; or the condition holds already
        ip.wait = w
        ip.next_time = None
        return None
    return step


def stop(ip: Interpreter, command: int, type: int, motor: int, value: int) -> Step:
    """STOP: the program stops; the PC stays at the STOP."""
    vm = ip.vm

    def step(t: int) -> None:
        ip.executed += 1
        vm.application_status = STOPPED
        ip.next_time = None
    return step


def reti(ip: Interpreter, command: int, type: int, motor: int, value: int) -> Step:
    """RETI: back to where the interrupt came in, registers and flags restored; ignored outside
    an interrupt routine."""
    vm = ip.vm
    ints = vm.interrupts

    def step(t: int) -> int | None:
        ip.executed += 1
        ctx = ip.saved
        if ctx is None:
            return vm.program_counter + 1
        ip.saved = None
        ints.active = None
        vm.program_counter = ctx.pc
        vm.accumulator, vm.x_register, vm.flags = ctx.accumulator, ctx.x_register, ctx.flags
        ip.wait = ctx.wait
        ip.next_time = t + SLOT if vm.application_status == RUNNING and ip.wait is None else None
        return None
    return step


# --- reads and stores bound to their object (GAP, GGP, GIO; AGP to a user variable) -------------
def bound_read(ip: Interpreter, read: Callable[[], int], engines: list[Any] | None) -> Step:
    """GAP, GGP or GIO whose read is bound (the request path's readers): the engines it looks at
    (`engines`; None: all) are brought to the present tick, and the value goes to the accumulator."""
    vm = ip.vm
    sync = vm.scheduler.sync_for_read

    def step(t: int) -> int:
        sync(engines)
        ip.executed += 1
        value = read()
        _load(vm, int(value) if value.__class__ is bool else value)  # AP8, a flag: 1 or 0
        return vm.program_counter + 1
    return step


def bound_store(ip: Interpreter, store: Callable[[int], None]) -> Step:
    """AGP to a user variable (bank 2): the accumulator is copied there."""
    vm = ip.vm

    def step(t: int) -> int:
        ip.executed += 1
        store(vm.accumulator)
        return vm.program_counter + 1
    return step


# --- commands that act as in direct mode ------------------------------------------------------
def direct(ip: Interpreter, command: int, type: int, motor: int, value: int, loads: bool,
           execute: Callable[..., Any]) -> Step:  # noqa: PLR0913
    """A motion, parameter, I/O or coordinate command run by `execute` as in direct mode, at the
    present tick; a reading command's value goes to the accumulator."""
    vm = ip.vm
    ok = int(Status.OK)

    def step(t: int) -> int | None:
        ip.executed += 1
        pc = vm.program_counter
        out = execute(vm, command, type, motor, value, program=True)
        if out.__class__ is tuple:
            status, result = out
            if status != ok:
                ip.last_error = (pc, command, status)
            elif loads:
                _load(vm, result)
        if vm.application_status == RESET:  # the instruction erased the program (GP81): PC 0 stays
            ip.next_time = None
            return None
        return pc + 1
    return step


def with_accumulator(command: int, type_of: Callable[[int], int]) -> Callable[..., Step]:
    """MVPA, ROLA, RORA: the direct-mode command `command` with the accumulator as its value."""
    def compile_(ip: Interpreter, own: int, type: int, motor: int, value: int, execute: Callable[..., Any]) -> Step:
        vm = ip.vm
        ok = int(Status.OK)
        t_ = type_of(type)

        def step(t: int) -> int:
            ip.executed += 1
            out = execute(vm, command, t_, motor, vm.accumulator, program=True)
            if out.__class__ is tuple and out[0] != ok:
                ip.last_error = (vm.program_counter, own, out[0])
            return vm.program_counter + 1
        return step
    return compile_
