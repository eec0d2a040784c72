"""Issue 16's two polling goals, old trees against this one, interleaved (docs/performance.md).

    git archive aafd556 | tar -x -C /tmp/old
    python bench/ab_goals.py aafd556=/tmp/old/src now=src [--rounds 4]

Each round runs every tree once, each in a process of its own (PYTHONPATH=<tree>), measuring in CPU
time the host polling GAP 8 + GAP 1 of six moving TMCM-6212 axes every 10 ms (bench_polling.py)
and the served bus of 8 modules (bench_bus.py), best of 3 each. On a shared machine single runs
vary by tens of per cent; the rounds interleave the trees so that a slow spell hits all of them.
Prints every round's figures and the best and median per tree, and the ratios against the first.
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parent

_MEASURE = """
import sys, time, json
sys.path.insert(0, {bench!r})
import figures
figures.clock = time.process_time
import bench_polling, bench_bus
poll = max(bench_polling.poll_handle(6, 0.01, 1.0) for _ in range(3))
bus = max(bench_bus.served(8, 1.0) for _ in range(3))
print(json.dumps([poll, bus]))
"""


def measure(src: str) -> tuple[float, float]:
    code = _MEASURE.format(bench=str(BENCH))
    out = subprocess.run([sys.executable, "-c", code], env={"PYTHONPATH": src, "PATH": "/usr/bin:/bin"},
                         capture_output=True, text=True, check=True).stdout
    poll, bus = json.loads(out)
    return poll, bus


def tree(text: str) -> tuple[str, str]:
    name, sep, path = text.partition("=")
    if not sep or not Path(path, "opentmcl").is_dir():
        raise argparse.ArgumentTypeError(f"expected NAME=PATH to a tree's src directory, got {text!r}")
    return name, str(Path(path).resolve())


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("trees", nargs="+", type=tree, metavar="NAME=SRC")
    ap.add_argument("--rounds", type=int, default=4)
    args = ap.parse_args(argv)
    results: dict[str, list[tuple[float, float]]] = {name: [] for name, _ in args.trees}
    for r in range(args.rounds):
        for name, src in args.trees:
            results[name].append(measure(src))
            print(f"round {r + 1} {name}: poll {results[name][-1][0]:.0f}, bus {results[name][-1][1]:.1f}", flush=True)
    first = args.trees[0][0]
    base = [statistics.median(x[i] for x in results[first]) for i in (0, 1)]
    print(f"{'tree':10} {'poll best':>10} {'median':>8} {'x first':>8} {'bus best':>9} {'median':>8} {'x first':>8}")
    for name, rows in results.items():
        med = [statistics.median(x[i] for x in rows) for i in (0, 1)]
        best = [max(x[i] for x in rows) for i in (0, 1)]
        print(f"{name:10} {best[0]:10.0f} {med[0]:8.0f} {med[0] / base[0]:8.2f}"
              f" {best[1]:9.1f} {med[1]:8.1f} {med[1] / base[1]:8.2f}")


if __name__ == "__main__":
    main()
