"""The interpreter (issue 16): a TMCL program whose loop reads GAP 1 in every iteration.

    python bench/bench_interp.py [--quick]

The program (TMCL-IDE syntax, assembled by opentmcl.lang, downloaded with 132 / the
instructions / 133 and started with 129, TMCM-6212 manual 3.6.36) counts its loop passes in user
variable 0 (GGP/CALC/AGP on bank 2) and reads the actual position of motor 0 (GAP 1, 0), on a
standing axis and on a moving one (MVP far away). The timer variant also runs timer 0 every 1 ms
(bank 3 parameter 0 = period in ms; VECT, EI, manual 3.5.6.4 and 3.8) with a handler that only
RETIs. The host lets virtual time pass with `vm.advance` and never sends a request meanwhile.

The instruction count is exact: the interpreter's own counter of executed instructions
(`vm.interpreter.executed`), checked against what the program itself counted: setup + 5 per
counted pass + the position in the current pass (global parameter 130, program counter), and
for the timer variant one RETI per interrupt (one per virtual millisecond). Where the counter
does not exist the main loop's count from the variable is used (RETIs left out).
Reference: the minimal-handler floor (bench_polling.py) in the same run. Both are timed with
CPU time (issue 33: at least 1 M instructions per CPU second).
"""
from __future__ import annotations

import time

import figures
from bench_polling import FAR, floor_rate
from figures import Figure, Goal, best_of, print_figures
from opentmcl import VirtualModule
from opentmcl.lang import assemble
from opentmcl.protocol.frame import Reply, Request

TIMER = """\
#include Interrupts.inc
    VECT TI_TIMER0, Tick
    SGP TI_TIMER0, 3, 1         // timer 0 period: 1 ms
    EI TI_TIMER0
    EI TI_GLOBAL
"""
LOOP = """\
Loop:
    GGP 0, 2                    // A = pass count (user variable 0)
    CALC ADD, 1
    AGP 0, 2                    // pass count = A
    GAP 1, 0                    // A = actual position of motor 0
    JA Loop
Tick:
    RETI
"""
BODY = 5          # instructions per loop pass
COUNTED_AT = 3    # the pass is counted once its first 3 instructions have run
CHUNK = 0.05      # virtual seconds per advance


class Wire:
    """Direct-mode requests to one module through its frames."""

    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm

    def __call__(self, command: int, type: int = 0, motor: int = 0, value: int = 0) -> Reply:
        raw = self.vm.handle(Request(1, command, type, motor, value).encode())
        reply = Reply.decode(raw)
        if reply.status not in (100, 101):
            raise RuntimeError(f"status {reply.status} for {command} {type} {motor} {value}")
        return reply


def prepared(timer: bool, moving: bool) -> tuple[VirtualModule, Wire, int, int]:
    """A module running the program; returns (vm, wire, address of Loop, address of Tick)."""
    vm = VirtualModule("TMCM-6212", address=1)
    wire = Wire(vm)
    program = assemble((TIMER if timer else "") + LOOP, module="TMCM-6212")
    if moving:
        wire(5, 4, 0, 20000)
        wire(4, 0, 0, FAR)
    wire(132, 0, 0, 0)
    for ins in program.instructions:
        wire(ins.command, ins.type, ins.motor, ins.value)
    wire(133)
    wire(129)
    return vm, wire, program.labels["Loop"], program.labels["Tick"]


def program_count(wire: Wire, loop: int, tick: int) -> int | None:
    """Main-program instructions executed so far, from the program's own count and its program
    counter; None while the handler runs (the interrupted position is not visible)."""
    pc = wire(10, 130, 0).value
    if pc == tick:
        return None
    passes = wire(10, 0, 2).value
    into = pc - loop
    return loop + BODY * (passes - (1 if into >= COUNTED_AT else 0)) + into


def rate(timer: bool, moving: bool, budget: float) -> float:
    vm, wire, loop, tick = prepared(timer, moving)
    interpreter = vm.interpreter
    exact = hasattr(interpreter, "executed")

    def count() -> int:
        if exact:
            return interpreter.executed
        got = program_count(wire, loop, tick)
        while got is None:  # leave the handler (one slot) before counting
            vm.advance(0.0001)
            got = program_count(wire, loop, tick)
        return got

    vm.advance(CHUNK)  # warm-up
    first, t0 = count(), vm.time
    start = figures.clock()
    while True:
        vm.advance(CHUNK)
        elapsed = figures.clock() - start
        if elapsed >= budget:
            break
    done = count() - first
    if exact:
        check(vm, wire, loop, tick, timer, t0)
    if moving and wire(6, 8, 0).value:
        raise RuntimeError("the axis reached its far target: the interpreter scenario ran out of travel")
    return done / elapsed


def check(vm: VirtualModule, wire: Wire, loop: int, tick: int, timer: bool, t0: float) -> None:
    """The interpreter's counter against what the program counted (see the module docstring)."""
    main = program_count(wire, loop, tick)
    if main is None:
        return
    rets = vm.interpreter.executed - main
    interrupts = round(vm.time * 1000) if timer else 0
    if not 0 <= interrupts - rets <= 2:
        raise RuntimeError(f"instruction count disagrees: {vm.interpreter.executed} executed, "
                           f"{main} counted by the program, {interrupts} timer interrupts")


A_MILLION = Goal(">=", 1_000_000, text=">= 1,000,000")  # instructions per CPU s (issue 33)


def measure(quick: bool = False) -> list[Figure]:
    """The four loops and the floor, timed with this process's CPU time (issue 33's goal is per
    CPU second), whatever clock the other figures use."""
    rounds, budget = (1, 0.05) if quick else (3, 0.4)
    out = []
    clock = figures.clock
    figures.clock = time.process_time
    try:
        for timer in (False, True):
            for moving in (False, True):
                floor, got = best_of(rounds, [lambda: floor_rate(budget / 2),
                                              lambda t=timer, m=moving: rate(t, m, budget)])
                what = (f"interpreter GAP loop, {'moving' if moving else 'standing'} axis"
                        f"{', 1 ms timer interrupt' if timer else ''}, instructions/CPU s")
                out.append(Figure(what, got, floor, A_MILLION, "floor calls/CPU s"))
    finally:
        figures.clock = clock
    return out


def main() -> None:
    print_figures(measure, __doc__ or "")


if __name__ == "__main__":
    main()
