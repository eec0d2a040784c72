"""A benchmark figure next to its reference, and the timing helpers the scenarios share.

A figure is (name, value, reference, goal): `reference` is measured in the same run (a yardstick
such as the minimal handler, or the slower path the figure is compared with), so `ratio` =
value / reference does not depend on how loaded the machine was. `value` None means "n/a" (the
code under test lacks the API the scenario needs). A `Goal` says what the value or the ratio
should reach, and so whether this run met it; a goal given as text is shown but not judged (it
compares with another tree: bench/ab_goals.py).
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

clock: Callable[[], float] = time.perf_counter
"""What the in-process scenarios time with: wall time (default), or this process's CPU time
(`bench/run.py --cpu`, `use_cpu_time()`), which on a shared machine leaves out the time other
processes had the core. Scenarios across processes (TCP, pty, proxy) always use wall time."""


def use_cpu_time() -> None:
    global clock
    clock = time.process_time


@dataclass(frozen=True)
class Goal:
    """What a figure should reach: its value (or, `on_ratio`, value / reference) `op` `bound`, with
    `op` ">=" (at least) or "<" (below). `text` is how the table shows it (default "op bound")."""

    op: str
    bound: float
    on_ratio: bool = False
    text: str = ""

    def __post_init__(self) -> None:
        if self.op not in (">=", "<"):
            raise ValueError(f"a goal is '>=' or '<' a bound, not {self.op!r}")

    def __str__(self) -> str:
        return self.text or f"{self.op} {self.bound:g}"

    def met(self, value: float | None, ratio: float | None) -> bool | None:
        """Whether the figure reaches the goal; None when what it is judged on was not measured."""
        got = ratio if self.on_ratio else value
        if got is None:
            return None
        return got >= self.bound if self.op == ">=" else got < self.bound


@dataclass
class Figure:
    name: str
    value: float | None
    reference: float | None = None
    goal: Goal | str = ""
    reference_name: str = ""

    @property
    def ratio(self) -> float | None:
        if self.value is None or not self.reference:
            return None
        return self.value / self.reference

    @property
    def met(self) -> bool | None:
        """True or False for a `Goal` this run reached or missed; None without one (or n/a)."""
        return self.goal.met(self.value, self.ratio) if isinstance(self.goal, Goal) else None

    def verdict(self) -> str:
        """The goal column's verdict: "pass", "FAIL", "n/a" (not measured), "-" (a goal another
        run judges), "" (no goal)."""
        if isinstance(self.goal, Goal):
            return {True: "pass", False: "FAIL", None: "n/a"}[self.met]
        return "-" if self.goal else ""

    def as_json(self) -> dict:
        return {"value": self.value, "reference": self.reference, "reference_name": self.reference_name,
                "ratio": self.ratio, "goal": str(self.goal), "met": self.met}


def figures_of(label: str, values: dict[str, float]) -> list[Figure]:
    """The figures of an older benchmark that reports plain values (no reference)."""
    return [Figure(f"{label} {key}", value) for key, value in values.items()]


def timed(step: Callable[[], float], budget: float) -> float:
    """Call `step()` (which returns the units of work it did) until `budget` wall seconds have
    passed; return units per wall second."""
    step()  # warm-up, not counted
    done = 0.0
    start = clock()
    while True:
        done += step()
        elapsed = clock() - start
        if elapsed >= budget:
            return done / elapsed


def best_of(rounds: int, measures: list[Callable[[], float | None]]) -> list[float | None]:
    """Best result of each measure over `rounds` interleaved rounds: on a busy machine the best
    round is the least disturbed one, and interleaving puts every measure under the same load.
    A measure that returns None (n/a) stays None."""
    best: list[float | None] = [None] * len(measures)
    for _ in range(rounds):
        for i, measure in enumerate(measures):
            got = measure()
            if got is not None:
                prev = best[i]
                best[i] = got if prev is None else max(prev, got)
    return best


def print_figures(measure: Callable[[bool], list[Figure]], description: str) -> None:
    """The command line of a bench_*.py of its own: `[--quick] [--cpu]`, one figure per line with
    its ratio and verdict."""
    import argparse

    ap = argparse.ArgumentParser(description=description.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--cpu", action="store_true", help="time the in-process scenarios in CPU time (`use_cpu_time`)")
    args = ap.parse_args()
    if args.cpu:
        use_cpu_time()
    for f in measure(args.quick):
        ratio = "-" if f.ratio is None else f"{f.ratio:.3f}"
        value = "n/a" if f.value is None else f"{f.value:,.0f}"
        print(f"{f.name}: {value}  ratio {ratio} ({f.reference_name or '-'})  goal {f.goal or '-'}  {f.verdict()}")
