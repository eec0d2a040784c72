"""Recording a program run: instruction marks, loop passes and when to stop.

Each sample also reads the application status (command 135 type 1: mode and program counter,
TMCM-6212 manual 3.6.36), so the trace knows which instruction ran when (at sample resolution:
the instruction the program was at, usually a WAIT). A *loop* is the body of an unconditional
jump back (JA to an address at or before its own, TMCM-6212 manual 3.6.17). On an in-process
virtual module a *loop pass* is each executed JA back (`JumpWatch`); on another module it is
counted when the program counter comes back to the first address inside such a body that it came
back to (the anchor). Loops that end by themselves (JC, DJNZ: polling, counting) are waited out
like a WAIT; a JA to itself is a halt (the program counts as stopped there). docs/plots.md.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable

from ..protocol.opcodes import GET_APPLICATION_STATUS, Op
from ..trace import MAX_SAMPLES, FaultMark, Mark, Trace
from .events import EngineWatch
from .recording import Sampler, record

SETTLE_SAMPLES = 5      # samples of standstill after the program stopped before the recording ends
AUTO_SECONDS = 300.0    # hard cap of a recording whose length comes from the program
AUTO_LOOPS = 2          # ... which ends once the program has looped this often
DEFAULT_SECONDS = 10.0  # a recording without a program to derive its length from
MAX_MARKS = 10_000      # program marks kept (a tight loop changes the PC at every sample)
RUNNING = 1             # 135 mode: 0 stop, 1 run, 2 step, 3 reset


def auto_seconds(interval: float) -> float:
    """The cap of a derived recording: AUTO_SECONDS, or less when the interval would give more
    than MAX_SAMPLES samples."""
    return min(AUTO_SECONDS, MAX_SAMPLES * interval)


EXITS = frozenset({Op.JC, Op.DJNZ})
"""Conditional jumps that may leave a loop (TMCM-6212 manual 3.6.16; PD28-1021 manual 3.5)."""


def loop_bodies(program) -> list[tuple[int, int]]:
    """(first, last) address of every loop: a JA whose target is at or before its own address,
    unless a JC or DJNZ inside it jumps out (a polling loop: it ends by itself, like a WAIT)."""
    code = list(program)

    def leaves(first: int, last: int) -> bool:
        return any(code[a][0] in EXITS and not first <= code[a][3] <= last for a in range(first, last + 1))

    return [(ins[3], address) for address, ins in enumerate(code)
            if ins[0] == Op.JA and 0 <= ins[3] <= address and not leaves(ins[3], address)]


def instruction_texts(program) -> dict[int, str]:
    """Address -> TMCL source text of each instruction (lang disassembler, plain numbers)."""
    from ..lang.disassembler import disassemble

    texts = {}
    try:
        source = disassemble(list(program), comments=True)
    except (TypeError, ValueError):
        return {}
    for line in source.splitlines():
        text, sep, addr = line.rpartition("//")
        if sep and addr.strip().isdigit():
            texts[int(addr)] = " ".join(text.split())
    return texts


class JumpWatch:
    """Counts the backward JA jumps an in-process virtual module executes, per JA address: each is
    one pass through that loop, however short the loop or wherever it spends its time (a
    subroutine, an interrupt). Listens through the interpreter's `ja_watch`."""

    def __init__(self, vm, loops: Iterable[int] | None = None) -> None:
        self.vm = vm
        wanted = None if loops is None else set(loops)   # the JA addresses that count
        self.interpreter = vm.interpreter
        self.passes: dict[int, int] = {}

        def seen(pc: int, address: int) -> None:
            if 0 <= address < pc and (wanted is None or pc in wanted):  # JA to itself: a halt
                self.passes[pc] = self.passes.get(pc, 0) + 1

        self.interpreter.ja_watch = seen

    def loops(self) -> int:
        """Passes of the loop that ran most often."""
        return max(self.passes.values(), default=0)

    def close(self) -> None:
        self.interpreter.ja_watch = None


class ProgramWatch:
    """`until(trace)` of a program run: records marks, counts loop passes, says when to stop.

    Stops when `loops` passes were seen (None: never for that reason), or - with `stop_when_idle` -
    once the program no longer runs and every axis of the trace had actual speed 0 for
    SETTLE_SAMPLES samples."""

    def __init__(self, loader, texts: dict[int, str], *, stop_when_idle: bool = True,
                 loops: int | None = None, vm=None, bodies: Iterable[tuple[int, int]] = ()) -> None:
        self.loader = loader
        self.texts = texts
        self.bodies = list(bodies)
        self.halts = {first for first, last in self.bodies if first == last}   # JA to itself
        self.stop_when_idle = stop_when_idle
        self.loops_wanted = loops
        self.vm = vm
        self.loops = 0
        self.anchor: int | None = None
        self._seen: set[int] = set()
        self._pc: int | None = None
        self._executed: int | None = None
        has_vm = hasattr(vm, "interpreter") and hasattr(vm, "program")
        self.jumps = JumpWatch(vm, [last for _, last in self.bodies]) if has_vm else None

    def __call__(self, trace: Trace) -> bool:
        word = self.loader.request(GET_APPLICATION_STATUS, 1).value & 0xFFFFFFFF
        mode, pc = word >> 24, word & 0xFFFF
        executed = getattr(getattr(self.vm, "interpreter", None), "executed", None)
        if self.jumps is not None:
            self.loops = self.jumps.loops()
        else:
            self._count(pc, executed)
        if pc != self._pc and len(trace.marks) < MAX_MARKS:
            trace.marks.append(Mark(trace.time[-1], pc, self.texts.get(pc, "")))
        self._pc, self._executed = pc, executed
        if self.loops_wanted is not None and self.loops >= self.loops_wanted:
            return True
        running = mode == RUNNING and pc not in self.halts   # "End: JA End" is a STOP that spins
        return not running and self.stop_when_idle and idle(trace)

    def close(self) -> None:
        if self.jumps is not None:
            self.jumps.close()

    def _count(self, pc: int, executed: int | None) -> None:
        if self._pc is None:
            self._seen.add(pc)
            return
        ran = executed is not None and self._executed is not None and executed > self._executed
        back = (pc != self._pc and pc in self._seen) or (pc == self._pc and ran)
        self._seen.add(pc)
        if not back:
            return
        if self.anchor is None and pc not in self.halts and any(first <= pc <= last for first, last in self.bodies):
            self.anchor = pc
        if pc == self.anchor:
            self.loops += 1


def idle(trace: Trace) -> bool:
    """Every axis of the trace had actual speed 0 (or none) for the last SETTLE_SAMPLES samples."""
    if len(trace) < SETTLE_SAMPLES:
        return False
    return all(v in (0, None) for ax in trace.axes for v in trace.column(ax, "velocity")[-SETTLE_SAMPLES:])


def record_program(module, program=None, axes=(0,), seconds: float | None = None, interval: float = 0.01,
                   *, stop_when_idle: bool = True, loops: int | None = None, download_progress=None,
                   sample_progress=None) -> Trace:
    """Download `program` (instructions; None: record what runs) to a host `Module`, start it
    (129 from address 0) and record `axes`.

    `seconds=None` derives the length from the program: until it stops (and the axes stand still)
    or has looped AUTO_LOOPS times, at most `auto_seconds(interval)`; without a program
    DEFAULT_SECONDS. On an in-process virtual module the trace also gets the module's origin
    writes and hard stops (`Trace.events`). `download_progress(done, total)` follows the download,
    `sample_progress(seconds, total)` the recording (total: the longest it may take)."""
    from ..host.loader import Loader

    if seconds is None:
        seconds = auto_seconds(interval) if program is not None else DEFAULT_SECONDS
        if program is not None and loops is None:
            loops = AUTO_LOOPS
    axes = list(axes)
    sampler = Sampler(module, axes)
    vm = module.client.transport.local_module(module.address)
    watch = EngineWatch(vm, sampler.to_pps) if vm is not None and hasattr(vm, "axes") else None
    start: list[float] = []
    program_watch: ProgramWatch | None = None
    try:   # the watches come off the module however the run ends
        until: Callable[[Trace], bool] | None = idle if stop_when_idle else None
        if program is not None:
            loader = Loader(module)
            code = loader.download(program, progress=download_progress)
            until = program_watch = ProgramWatch(loader, instruction_texts(code), stop_when_idle=stop_when_idle,
                                                 loops=loops, vm=vm, bodies=loop_bodies(code))
            loader.run(0)
        inner = until

        def first_sample(trace: Trace) -> bool:   # the module's clock at the trace's time 0
            if not start and vm is not None:
                start.append(vm.time - trace.time[-1])
            if sample_progress is not None:
                sample_progress(round(trace.time[-1], 2), seconds)
            return inner(trace) if inner is not None else False

        trace = record(module, axes, seconds, interval, until=first_sample, sampler=sampler)
    finally:
        if watch is not None:
            watch.close()
        if program_watch is not None:
            program_watch.close()
    if watch is not None and start:
        trace.events = watch.events(start[0], axes)
    if vm is not None and start:
        trace.faults = fault_marks(vm, start[0], trace)
    return trace


def fault_marks(vm, start: float, trace: Trace) -> list[FaultMark]:
    """The faults that fired on the in-process module `vm` while `trace` was recorded (its time 0
    is `start` on the module's clock), at trace time (docs/faults.md "Seeing what fired")."""
    log = getattr(getattr(vm, "faults", None), "log", None)
    if log is None or not len(trace):
        return []
    end = start + trace.time[-1] + 1e-9
    return [FaultMark(round(f.t - start, 9), f.kind, f.name or "", f.detail)
            for f in log.since(0) if start - 1e-9 <= f.t <= end]
