"""Traces: the cost of a sample and the memory per hour of recording at 10 ms.

    python bench/bench_trace.py [--quick] [--cpu]

`speed()` (issue 33, "Speed where users are": "`Trace.sample` of six axes: at least 4x cheaper
than today. Measure it against the 54 GAP reads it stands for (`vm.request`) in the same run;
today a sample costs about half of them. A traced run at 10 ms is bounded by it"): a TMCM-6212
with all six axes moving back and forth in a world scenario (examples/scenarios/tmcm6212_stage.toml)
advances 10 ms at a time; after each advance one of these is timed, and the rate is that of the
median block of FLUSH_ROWS calls (steady on a busy machine; a block of samples holds one flush of
the samples into the columns):

- `Trace.sample(vm)` of the six axes (with its storage in compact columns);
- the 54 GAP reads it stands for, `vm.request(6, n, a)`: per axis the eight axis parameters of a
  sample (1, 3, 11, 10, 9, 206, 180, 209) and GAP 1 once more for the stage, which has no GAP of
  its own (the cheapest kind of read, so the yardstick is not flattered);
- the former sample (before issue 33), rebuilt here from the module's public calls: `vm.sync()`,
  `Axis.get` of each parameter (each world read syncing again), the stage through
  `physical_position`, the row as a dict and its values appended to compact columns.

Figures: samples per second next to groups of 54 GAP reads per second (goal: a sample costs at
most 1/8 of them, 4x better than the issue's "about half") and next to the former sample (goal:
4x), and a traced run at 10 ms in virtual seconds per second next to the same run untraced.

`measure()` records the same module, measured with tracemalloc, and returns MB (10^6 bytes) per
hour at 10 ms (360000 rows), extrapolated from the bytes per row of the rows recorded (issue 11:
"one hour at 10 ms must fit well under 100 MB"):

- the world trace (`Trace.sample`: `run --csv`, `demo --scenario`), compact columns, next to the
  dict-per-row layout it replaced, filled with the same rows;
- the plot trace (opentmcl.plot, `plot`, `plot --to`) of six axes through the host library, next
  to the list-per-channel layout it replaced, filled with the same values (the fixed cost of module
  and client is taken out: recordings of n/2 and n samples, twice the difference).
"""
from __future__ import annotations

import argparse
import gc
import statistics
import tracemalloc
from pathlib import Path

import figures
from figures import Figure, Goal, best_of
from opentmcl import VirtualModule
from opentmcl.columns import Column
from opentmcl.plot.virtual import run_virtual
from opentmcl.trace import FLUSH_ROWS, HOST_CHANNELS, Trace

SCENARIO = Path(__file__).resolve().parent.parent / "examples" / "scenarios" / "tmcm6212_stage.toml"
INTERVAL = 0.01
ROWS_PER_HOUR = round(3600 / INTERVAL)
SAMPLED = (1, 3, 11, 10, 9, 206, 180, 209)     # the axis parameters of a sample
GAP_READS = [(6, n, a) for a in range(6) for n in SAMPLED + (1,)]   # 54: the stage stands as GAP 1
TURN = 1000                                      # samples between two turns of the moves


def _moving_module() -> VirtualModule:
    vm = VirtualModule("TMCM-6212", scenario=SCENARIO)
    for a in range(6):
        vm.request(5, 4, a, 20000 + 3000 * a)   # max positioning speed, different per axis
        vm.request(4, 0, a, 200000)             # MVP ABS: off they go
    return vm


def _turn(vm: VirtualModule, i: int) -> None:
    if i % TURN == TURN - 1:                     # turn round now and then
        for a in range(6):
            vm.request(4, 0, a, 0 if (i // TURN) % 2 else 200000)


def _record(trace: Trace, vm: VirtualModule, rows: int) -> Trace:
    for i in range(rows):
        _turn(vm, i)
        vm.advance(INTERVAL)
        trace.sample(vm)
    assert trace.nbytes()      # (the last samples, at most FLUSH_ROWS, go into the columns too)
    return trace


# --- the cost of a sample ---------------------------------------------------------------------------

class FormerSample:
    """The sample before issue 33: `vm.sync()`, then `Axis.get` per parameter (a world parameter's
    read syncs again) and `physical_position`, as a row dict appended to compact columns."""

    def __init__(self) -> None:
        self.columns: list[Column] = []

    def __call__(self, vm: VirtualModule) -> None:
        vm.sync()
        row: dict[str, float | int | None] = {"time": round(vm.time, 9)}
        for a, axis in enumerate(vm.axes):
            for n in SAMPLED:
                row[f"{n}_{a}"] = axis.get(n) if n in axis.params else None
            row[f"stage{a}"] = vm.world.axis(a).physical_position
        if not self.columns:
            self.columns = [Column() for _ in row]
        for col, v in zip(self.columns, row.values(), strict=True):
            col.append(v)


def _timed(action, samples: int) -> float:
    """Calls of `action(vm)` per second (figures.clock), each after a 10 ms advance of the moving
    module; only the calls are timed. The rate is that of the median block of FLUSH_ROWS calls (a
    block holds one flush of a trace's samples into its columns): a block another process broke
    into on a busy machine does not count."""
    vm = _moving_module()
    clock, blocks, spent = figures.clock, [], 0.0
    action(vm)                                   # first-use caches
    for i in range(samples):
        _turn(vm, i)
        vm.advance(INTERVAL)
        start = clock()
        action(vm)
        spent += clock() - start
        if i % FLUSH_ROWS == FLUSH_ROWS - 1:
            blocks.append(spent)
            spent = 0.0
    return FLUSH_ROWS / statistics.median(blocks)


def _gap_reads(vm: VirtualModule) -> None:
    request = vm.request
    for r in GAP_READS:
        request(*r)


def _traced_run(samples: int, traced: bool) -> float:
    """Virtual seconds per second of the moving module advanced in 10 ms steps, sampled or not."""
    vm = _moving_module()
    trace = Trace()
    clock = figures.clock
    start = clock()
    for i in range(samples):
        _turn(vm, i)
        vm.advance(INTERVAL)
        if traced:
            trace.sample(vm)
    return samples * INTERVAL / (clock() - start)


def speed(quick: bool = False) -> list[Figure]:
    rounds, samples = (3, 5 * FLUSH_ROWS) if quick else (5, 16 * FLUSH_ROWS)
    sample, gaps, former, traced, untraced = best_of(rounds, [
        lambda: _timed(Trace().sample, samples), lambda: _timed(_gap_reads, samples),
        lambda: _timed(FormerSample(), samples), lambda: _traced_run(samples, True),
        lambda: _traced_run(samples, False)])
    return [
        Figure("trace Trace.sample of 6 moving axes, samples/s", sample, gaps,
               Goal(">=", 8, on_ratio=True, text=">= 8x: 4x the former 2x"), "54 GAP reads (vm.request) per s"),
        Figure("trace Trace.sample of 6 moving axes against the former sample, samples/s", sample, former,
               Goal(">=", 4, on_ratio=True, text=">= 4x the former"), "former samples per s"),
        Figure("trace run of 6 moving axes sampled every 10 ms, virtual s/s", traced, untraced, "",
               "the same run untraced"),
    ]


# --- memory --------------------------------------------------------------------------------------------

def _traced(build) -> tuple[object, int]:
    """(result of build(), bytes it still holds) measured with tracemalloc."""
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    result = build()
    gc.collect()
    held = tracemalloc.get_traced_memory()[0] - before
    tracemalloc.stop()
    return result, held


def _per_hour(nbytes: int, rows: int) -> float:
    return nbytes / rows * ROWS_PER_HOUR / 1e6


def world(rows: int) -> dict[str, float]:
    vm = _moving_module()
    _record(Trace(), vm, 10)                      # first-use caches of the module, not of the trace
    trace = Trace()
    _, new_bytes = _traced(lambda: _record(trace, vm, rows))
    old, old_bytes = _traced(lambda: [dict(r) for r in trace.rows])   # the former layout: a dict per row
    assert isinstance(old, list) and len(old) == rows
    return {"world trace MB per hour at 10 ms, 6 axes, compact columns (target < 100)": _per_hour(new_bytes, rows),
            "world trace MB per hour at 10 ms, 6 axes, old dict per row": _per_hour(old_bytes, rows),
            "world trace old / compact memory ratio": old_bytes / new_bytes}


def plot(rows: int) -> dict[str, float]:
    program = [(5, 4, a, 20000 + 3000 * a) for a in range(6)] + [(4, 0, a, 200000) for a in range(6)]
    program.append((28, 0, 0, 0))
    axes = list(range(6))
    run_virtual(program, axes=axes, seconds=0.1, interval=INTERVAL, scenario=SCENARIO)   # warm caches

    def held(n: int):   # what a recording of n samples keeps, with the module and client around it
        vm = VirtualModule("TMCM-6212", scenario=SCENARIO)
        def build() -> Trace:
            trace = run_virtual(program, axes=axes, seconds=(n - 1) * INTERVAL, interval=INTERVAL, vm=vm,
                                stop_when_idle=False)
            assert trace.nbytes()  # (the last samples, at most FLUSH_ROWS, go into the columns too)
            return trace
        return _traced(build)

    (_, short_bytes), (trace, new_bytes) = held(rows // 2), held(rows)
    new_bytes = (new_bytes - short_bytes) * 2      # the cost of the samples alone: 2 x (n - n/2)
    assert isinstance(trace, Trace)

    def old_layout():   # the former Trace: a list for the time and one list per (axis, channel)
        return list(trace.time), {(a, ch): trace.column(a, ch) for a in axes for ch in HOST_CHANNELS}

    _, old_bytes = _traced(old_layout)
    return {"plot trace MB per hour at 10 ms, 6 axes, compact columns (target < 100)": _per_hour(new_bytes, rows),
            "plot trace MB per hour at 10 ms, 6 axes, old lists per channel": _per_hour(old_bytes, rows),
            "plot trace old / compact memory ratio": old_bytes / new_bytes}


def measure(quick: bool = False) -> dict[str, float]:
    """Memory. Full run: 5000 rows of the world trace (50 virtual s), 1000 samples of the plot
    trace; quick: 500 and 150."""
    return {**world(500 if quick else 5_000), **plot(150 if quick else 1_000)}


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--cpu", action="store_true", help="time with this process's CPU time (steadier on a shared machine)")
    args = ap.parse_args()
    if args.cpu:
        figures.use_cpu_time()
    for f in speed(args.quick):
        print(f"{f.name:<80} {f.value:>12,.1f}  reference {f.reference:>12,.1f}  ratio {f.ratio:6.2f}  "
              f"goal {f.goal or '-'}: {f.verdict() or '-'}")
    for key, value in measure(args.quick).items():
        print(f"{key:<80} {value:>10,.2f}")
