"""The steps of the run ahead (`Interpreter._run_ahead`): one closure per instruction that executes
it at tick t and answers True, or answers False where it cannot run ahead now (the interpreter then
takes it as an event). JA, JC, CALC ADD/SUB/LOAD and the other valid CALCs, COMP, GGP and AGP on
user variables, pre-bound GAPs and RETI are written out here, with the same effect as the interpreter's
handlers (TMCM-6212 manual 3.6.14 CALC, 3.6.15 COMP, 3.6.16 JC, 3.6.17 JA, 3.6.6 GAP, 3.6.11 GGP,
3.6.35 AGP, 3.6.33 RETI); every other instruction runs through `Interpreter._run`. The reference (`run_ahead`
False) runs every instruction through the handlers: the tests compare the two.

Errors are the handlers' business: an instruction that would fail (a jump outside program memory,
an unknown condition or operation) is not written out."""
from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from ..protocol.frame import to_int32
from . import calc, flags
from .dispatch import USER_BANK

if TYPE_CHECKING:
    from .interpreter import Entry, Interpreter

Step = Callable[[int], bool]
OTHER, PURE_KIND, READ_KIND, RETI_KIND = 0, 1, 2, 3   # Interpreter._kind
CALC, COMP, JC, JA, GAP, GGP, AGP, RETI = 19, 20, 21, 22, 6, 10, 35, 38
_LOW, _HIGH = -0x8000_0000, 0x7FFF_FFFF
_ZERO = flags.ZERO


def _never(t: int) -> bool:
    return False


def compile_step(interpreter: Interpreter, entry: Entry, slot: int) -> Step:
    """The step of the instruction `entry` describes (`Interpreter._entry`); `slot` is the length
    of an instruction in ticks."""
    kind, command = entry[0], entry[5]
    if not kind:
        return _never
    make = _WRITTEN_OUT.get(command) if command in interpreter.vm.opcodes else None
    step = None if make is None else make(interpreter, entry, slot)
    if step is not None:
        return step
    if kind == PURE_KIND:
        return _through_handler(interpreter, entry, guarded=False)
    return _through_handler(interpreter, entry, guarded=True)


def _through_handler(interpreter: Interpreter, entry: Entry, guarded: bool) -> Step:
    """`Interpreter._run` at tick t; `guarded`: only where `Interpreter._ahead_ok` allows it."""
    vm = interpreter.vm
    run, ok = interpreter._run, interpreter._ahead_ok

    def step(t: int) -> bool:
        if guarded and not ok(entry, t):
            return False
        interpreter._t = t
        run(entry, vm.program_counter, t)
        return True
    return step


def _jump_target(interpreter: Interpreter, address: int) -> bool:
    return 0 <= address < interpreter.vm.program.size


def _ja(interpreter: Interpreter, entry: Entry, slot: int) -> Step | None:
    address = entry[4]
    if not _jump_target(interpreter, address):
        return None
    vm = interpreter.vm

    def ja(t: int) -> bool:
        watch = interpreter.ja_watch
        if watch is not None:
            watch(vm.program_counter, address)
        interpreter.executed += 1
        vm.program_counter = address
        interpreter.next_time = t + slot
        return True
    return ja


def _jc(interpreter: Interpreter, entry: Entry, slot: int) -> Step | None:
    address, test = entry[4], flags.CONDITIONS.get(entry[2])
    if test is None or not _jump_target(interpreter, address):
        return None
    bits, when_set = test
    vm = interpreter.vm

    def jc(t: int) -> bool:
        interpreter.executed += 1
        if bool(vm.flags & bits) == when_set:
            vm.program_counter = address
        else:
            vm.program_counter += 1
        interpreter.next_time = t + slot
        return True
    return jc


def _load(vm: object, a: int) -> None:  # Interpreter._load for a value already in 32 bits
    vm.accumulator = a  # type: ignore[attr-defined]
    vm.flags = (vm.flags & ~_ZERO) | (_ZERO if a == 0 else 0)  # type: ignore[attr-defined]


def _calc(interpreter: Interpreter, entry: Entry, slot: int) -> Step | None:
    op, operand = entry[2], to_int32(entry[4])
    if not calc.ADD <= op <= calc.LOAD:  # the handler refuses the others (status 3)
        return None
    vm = interpreter.vm
    sign = {calc.ADD: 1, calc.SUB: -1}.get(op)
    binary = calc.binary

    def add(t: int) -> bool:  # ADD and SUB: the accumulator is in 32 bits already
        a = vm.accumulator + operand * sign  # type: ignore[operator]
        if not _LOW <= a <= _HIGH:
            a = to_int32(a)
        interpreter.executed += 1
        _load(vm, a)
        vm.program_counter += 1
        interpreter.next_time = t + slot
        return True

    def other(t: int) -> bool:
        interpreter.executed += 1
        _load(vm, binary(op, vm.accumulator, operand))  # type: ignore[arg-type]
        vm.program_counter += 1
        interpreter.next_time = t + slot
        return True
    return add if sign is not None else other


def _comp(interpreter: Interpreter, entry: Entry, slot: int) -> Step | None:
    operand = to_int32(entry[4])
    vm = interpreter.vm
    after = flags.after_compare

    def comp(t: int) -> bool:
        interpreter.executed += 1
        vm.flags = after(vm.flags, vm.accumulator, operand)
        vm.program_counter += 1
        interpreter.next_time = t + slot
        return True
    return comp


def _user_variable(interpreter: Interpreter, entry: Entry, slot: int) -> Step | None:
    """GGP (load) or AGP (store) of a user variable (bank 2) that the pre-bound path serves."""
    index, bank = entry[2], entry[3]
    if bank != USER_BANK or interpreter._bound(entry[5], index, bank) is None:
        return None
    vm = interpreter.vm
    variables = vm.user_vars

    def ggp(t: int) -> bool:
        interpreter.executed += 1
        _load(vm, variables[index])
        vm.program_counter += 1
        interpreter.next_time = t + slot
        return True

    def agp(t: int) -> bool:
        interpreter.executed += 1
        variables[index] = vm.accumulator
        vm.program_counter += 1
        interpreter.next_time = t + slot
        return True
    return ggp if entry[5] == GGP else agp


def _gap(interpreter: Interpreter, entry: Entry, slot: int) -> Step | None:
    bound = interpreter._bound(GAP, entry[2], entry[3]) if entry[0] == READ_KIND else None
    if bound is None:
        return None
    read, engines = bound
    vm = interpreter.vm
    quiet = interpreter._world_quiet

    def gap(t: int) -> bool:
        q = interpreter._quiet
        if not (quiet() if q is None else q):  # Interpreter._ahead_ok
            return False
        vm.now = t  # the read's own tick: its engines follow there
        if vm._synced_at != t:
            vm.sync_for_read(engines)
        v = read()  # 32 bits: RAM values lie in their parameter's range, engine positions wrap
        if v.__class__ is bool:  # AP8: Axis.get answers int()
            v = int(v)
        interpreter.executed += 1
        _load(vm, v)
        vm.program_counter += 1
        interpreter.next_time = t + slot
        return True
    return gap


def _reti(interpreter: Interpreter, entry: Entry, slot: int) -> Step | None:
    """RETI (3.6.33) back to a program that was not in a WAIT (`Interpreter._ahead_ok`)."""
    vm = interpreter.vm
    ints = vm.interrupts
    quiet = interpreter._world_quiet

    def reti(t: int) -> bool:
        ctx = interpreter.saved
        q = interpreter._quiet
        if ctx is None or ctx.wait is not None or not (quiet() if q is None else q):
            return False
        interpreter.executed += 1
        interpreter.saved = None
        ints.active = None
        vm.program_counter = ctx.pc
        vm.accumulator, vm.x_register, vm.flags = ctx.accumulator, ctx.x_register, ctx.flags
        interpreter.next_time = t + slot
        return True
    return reti


_WRITTEN_OUT: dict[int, Callable[[Interpreter, Entry, int], Step | None]] = {
    JA: _ja, JC: _jc, CALC: _calc, COMP: _comp, GGP: _user_variable, AGP: _user_variable, GAP: _gap, RETI: _reti,
}
