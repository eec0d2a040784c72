"""Issue 33: the slowest PD86-1180 `advance(0.5)` call during a move, this tree against 716168a.

    git archive 716168a | tar -x -C /tmp/base716          # the release before the ramp fidelity work
    python bench/pd86_advance.py [--old /tmp/base716] [--new .] [--rounds 5] [--quick]

Goal (issue 33, "Speed where users are"): during MVP ABS moves of 5 000 to 200 000 steps the
slowest `advance(0.5)` costs at most 3x that of 716168a, measured in the same run. A move: a fresh
VirtualModule("PD86-1180"), SAP 4 / SAP 5 of the setting (none: the profile's defaults AP4 = 1000,
AP5 = 100, AP153 = 7, AP154 = 3), MVP ABS, then `vm.advance(0.5)` until GAP 8 reads 1; each
advance call is timed alone in CPU time of the process (`time.process_time_ns`, so that a busy
machine taking the CPU away does not count), after one untimed warm-up move (MVP ABS 3000) in the
same process, as in a long-running `serve`, and with the garbage collector paused during the move
(collected before it): a collection lands on whichever call allocates at that moment, the same
call in every round, and would time the process's history instead of the call. Each round runs every tree once, each in a process of
its own with its `src` first on the path and OPENTMCL_PURE=1 (no compiled accelerator), the trees
interleaved so that a slow spell hits both. A move's figure is the least over the rounds of its
slowest call; the goal compares the slowest move of each tree over the goal settings (the
profile's defaults, AP4 = 500 as in the manual's example program, AP4 = 2047, AP5 = 10,
AP5 = 1000, AP4 = AP5 = 2047); the table also gives the ratio move by move, and a stress
setting (AP4 = 2047, AP5 = 200) outside the goal.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
from io import BytesIO
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BASE = "716168a"
GOAL = 3.0

SETTINGS: list[tuple[str, list[tuple[int, int]]]] = [   # (label, [(axis parameter, value)])
    ("defaults", []),
    ("AP4=500", [(4, 500)]),                             # the manual's example program (8.2)
    ("AP4=2047", [(4, 2047)]),
    ("AP5=10", [(5, 10)]),
    ("AP5=1000", [(5, 1000)]),
    ("AP4=2047 AP5=2047", [(4, 2047), (5, 2047)]),
]
STRESS: list[tuple[str, list[tuple[int, int]]]] = [
    ("AP4=2047 AP5=200", [(4, 2047), (5, 200)]),         # ~1 500 velocity levels in one call
]
"""Shown after the goal rows, not part of the goal: the fastest braking over the most velocity
levels we know, where one 0.5 s call walks about 1 500 of them (docs/performance.md)."""
DISTANCES = [5_000, 20_000, 50_000, 100_000, 200_000]
QUICK_DISTANCES = [5_000, 50_000]

CHILD = """
import gc, json, os, sys, time
sys.path[:0] = [sys.argv[1]]
from opentmcl import VirtualModule
clock = time.process_time_ns
warm = VirtualModule("PD86-1180")          # the code paths of a move run once, untimed
warm.request(4, 0, 0, 3000)
while warm.request(6, 8, 0).value != 1:
    warm.advance(0.5)
out = []
for sets, distance in json.loads(sys.argv[2]):
    gc.collect()
    gc.disable()
    vm = VirtualModule("PD86-1180")
    for number, value in sets:
        vm.request(5, number, 0, value)
    vm.request(4, 0, 0, distance)
    slowest = calls = 0
    while True:
        t = clock()
        vm.advance(0.5)
        slowest = max(slowest, clock() - t)
        calls += 1
        if vm.request(6, 8, 0).value == 1 or calls > 10_000:
            break
    gc.enable()
    out.append([slowest, calls, vm.request(6, 1, 0).value])
print(json.dumps(out))
"""


def extract(commit: str, into: Path) -> Path:
    """`git archive commit | tar -x -C into` (only src/ is needed)."""
    data = subprocess.run(["git", "-C", str(ROOT), "archive", commit, "src"], check=True,
                          capture_output=True).stdout
    with tarfile.open(fileobj=BytesIO(data)) as tar:
        tar.extractall(into, filter="data")
    return into


def moves(quick: bool) -> list[tuple[str, list[tuple[int, int]], int, bool]]:
    """(label, settings, distance, part of the goal) of every move measured."""
    distances = QUICK_DISTANCES if quick else DISTANCES
    settings = [(label, sets, True) for label, sets in SETTINGS]
    settings += [(label, sets, False) for label, sets in STRESS]
    if quick:
        settings = settings[:1] + settings[-1:]
    return [(label, sets, d, goal) for label, sets, goal in settings for d in distances]


def run_tree(src: Path, plan: list) -> list[list[int]]:
    """One process on the tree `src`: [slowest call ns, calls, final AP1] per move."""
    env = {**os.environ, "OPENTMCL_PURE": "1", "PYTHONPATH": str(src)}
    arg = json.dumps([[sets, d] for _label, sets, d, _goal in plan])
    out = subprocess.run([sys.executable, "-c", CHILD, str(src), arg], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)


def measure(old: Path, new: Path, rounds: int, quick: bool = False,
            echo: bool = True) -> dict[str, object]:
    """Interleaved rounds; returns per move (label, distance, old ms, new ms) and the totals."""
    plan = moves(quick)
    best: dict[str, list[float]] = {"old": [float("inf")] * len(plan), "new": [float("inf")] * len(plan)}
    for r in range(rounds):
        for name, tree in (("old", old), ("new", new)) if r % 2 == 0 else (("new", new), ("old", old)):
            rows = run_tree(tree, plan)
            for i, (slowest, _calls, position) in enumerate(rows):
                if position != plan[i][2]:
                    raise RuntimeError(f"{name}: {plan[i][0]} MVP {plan[i][2]} ended at {position}")
                best[name][i] = min(best[name][i], slowest / 1e6)
        if echo:
            print(f"round {r + 1}/{rounds}: slowest call old {max(best['old']):.3f} ms, "
                  f"new {max(best['new']):.3f} ms", flush=True)
    rows = [(label, d, goal, o, n) for (label, _sets, d, goal), o, n
            in zip(plan, best["old"], best["new"], strict=True)]
    slow_old = max(o for _l, _d, goal, o, _n in rows if goal)
    slow_new = max(n for _l, _d, goal, _o, n in rows if goal)
    stress = [n / o for _l, _d, goal, o, n in rows if not goal]
    return {"moves": rows, "old_ms": slow_old, "new_ms": slow_new, "ratio": slow_new / slow_old,
            "stress_ratio": max(n for _l, _d, goal, _o, n in rows if not goal) / slow_old
            if stress else None}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", type=Path, help=f"a tree of {BASE} (default: extracted to a temporary dir)")
    ap.add_argument("--new", type=Path, default=ROOT, help="the tree to measure (default: this one)")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="two settings, two distances")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        old = args.old if args.old is not None else extract(BASE, Path(tmp))
        result = measure(old / "src", args.new / "src", args.rounds, args.quick)
    print(f"\n{'setting':<20} {'MVP ABS':>8} {BASE + ' ms':>12} {'this ms':>9} {'ratio':>6}")
    for label, d, goal, o, n in result["moves"]:  # type: ignore[union-attr]
        print(f"{label:<20} {d:>8} {o:>12.3f} {n:>9.3f} {n / o:>6.2f}{'' if goal else '  (stress)'}")
    ratio = result["ratio"]
    print(f"\nslowest advance(0.5) call: {BASE} {result['old_ms']:.3f} ms, this tree "
          f"{result['new_ms']:.3f} ms, ratio {ratio:.2f} (goal <= {GOAL:g}: "
          f"{'met' if ratio <= GOAL else 'MISSED'})")
    if result["stress_ratio"] is not None:
        print(f"stress rows (not in the goal): slowest call / {BASE}'s slowest = "
              f"{result['stress_ratio']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
