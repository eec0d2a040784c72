"""Memory of traces per hour of recording at 10 ms (issue 11: "one hour at 10 ms must fit well
under 100 MB").

    python bench/bench_trace.py [--quick]

`measure()` records a TMCM-6212 with all six axes moving back and forth in a world scenario
(examples/scenarios/tmcm6212_stage.toml), measured with tracemalloc, and returns MB (10^6 bytes)
per hour at 10 ms (360000 rows), extrapolated from the bytes per row of the rows recorded:

- the world trace (opentmcl.trace, `run --csv`, `demo --scenario`), compact columns, next to the
  dict-per-row layout it replaced, recorded in the same run from the same module;
- the plot trace (opentmcl.plot, `plot`, `plot --to`) of six axes through the host library, next
  to the list-per-channel layout it replaced, filled with the same values (the fixed cost of module
  and client is taken out: recordings of n/2 and n samples, twice the difference).
"""
from __future__ import annotations

import argparse
import gc
import tracemalloc
from pathlib import Path

from opentmcl import VirtualModule
from opentmcl.plot.trace import RECORDED
from opentmcl.plot.virtual import run_virtual
from opentmcl.trace import Trace

SCENARIO = Path(__file__).resolve().parent.parent / "examples" / "scenarios" / "tmcm6212_stage.toml"
INTERVAL = 0.01
ROWS_PER_HOUR = round(3600 / INTERVAL)


class DictRowTrace(Trace):
    """The old layout: every row kept as the dict `sample` builds."""

    def __init__(self) -> None:
        super().__init__()
        self.dict_rows: list[dict] = []

    def _append(self, row: dict) -> None:
        self.dict_rows.append(row)


def _moving_module() -> VirtualModule:
    vm = VirtualModule("TMCM-6212", scenario=SCENARIO)
    for a in range(6):
        vm.request(5, 4, a, 20000 + 3000 * a)   # max positioning speed, different per axis
        vm.request(4, 0, a, 200000)             # MVP ABS: off they go
    return vm


def _record(trace: Trace, vm: VirtualModule, rows: int) -> None:
    for i in range(rows):
        if i % 1000 == 999:                     # turn round now and then
            for a in range(6):
                vm.request(4, 0, a, 0 if (i // 1000) % 2 else 200000)
        vm.advance(INTERVAL)
        trace.sample(vm)


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
    vm_new, vm_old = _moving_module(), _moving_module()
    _record(Trace(), vm_new, 10)                  # first-use caches of the module, not of the trace
    _record(DictRowTrace(), vm_old, 10)
    new, old = Trace(), DictRowTrace()
    _, new_bytes = _traced(lambda: _record(new, vm_new, rows))
    _, old_bytes = _traced(lambda: _record(old, vm_old, rows))
    assert [dict(r) for r in new.rows[-3:]] == old.dict_rows[-3:]   # same rows, two layouts
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
        return _traced(lambda: run_virtual(program, axes=axes, seconds=(n - 1) * INTERVAL,
                                           interval=INTERVAL, vm=vm, stop_when_idle=False))

    (_, short_bytes), (trace, new_bytes) = held(rows // 2), held(rows)
    new_bytes = (new_bytes - short_bytes) * 2      # the cost of the samples alone: 2 x (n - n/2)
    def old_layout():   # the former Trace: a list for the time and one list per (axis, channel)
        return list(trace.time), {(a, ch): list(trace.data[(a, ch)]) for a in axes for ch in RECORDED}

    _, old_bytes = _traced(old_layout)
    return {"plot trace MB per hour at 10 ms, 6 axes, compact columns (target < 100)": _per_hour(new_bytes, rows),
            "plot trace MB per hour at 10 ms, 6 axes, old lists per channel": _per_hour(old_bytes, rows),
            "plot trace old / compact memory ratio": old_bytes / new_bytes}


def measure(quick: bool = False) -> dict[str, float]:
    """Full run: 5000 rows of the world trace (50 virtual s), 1000 samples of the plot trace;
    quick: 500 and 150."""
    return {**world(500 if quick else 5_000), **plot(150 if quick else 1_000)}


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    for key, value in measure(ap.parse_args().quick).items():
        print(f"{key:<80} {value:>10,.2f}")
