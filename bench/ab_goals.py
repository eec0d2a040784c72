"""Issue 16's goals, old trees against this one, interleaved (docs/performance.md).

    git archive aafd556 | tar -x -C /tmp/old
    python bench/ab_goals.py aafd556=/tmp/old/src now=src [--rounds 4] [--only poll,bus]

Each round runs every tree once, each in a process of its own (PYTHONPATH=<tree>), measuring in CPU
time the host polling GAP 8 + GAP 1 of six moving TMCM-6212 axes every 10 ms (bench_polling.py),
the served bus of 8 modules (bench_bus.py) and the four interpreter loops (bench_interp.py:
standing or moving axis, without or with a 1 ms timer interrupt), best of 3 each. On a shared
machine single runs vary by tens of per cent; the rounds interleave the trees so that a slow spell
hits all of them. Prints every round's figures and the best and median per tree, and the ratios
against the first.
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parent
FIGURES = {  # name: the expression measuring it (virtual s or instructions per CPU s)
    "poll": "bench_polling.poll_handle(6, 0.01, 1.0)",
    "bus": "bench_bus.served(8, 1.0)",
    "interp": "bench_interp.rate(False, False, 0.4)",
    "interp-moving": "bench_interp.rate(False, True, 0.4)",
    "interp-timer": "bench_interp.rate(True, False, 0.4)",
    "interp-timer-moving": "bench_interp.rate(True, True, 0.4)",
}

_MEASURE = """
import sys, time, json
sys.path.insert(0, {bench!r})
import figures
figures.clock = time.process_time
import bench_polling, bench_bus, bench_interp
print(json.dumps([{exprs}]))
"""


def measure(src: str, names: list[str]) -> list[float]:
    exprs = ", ".join(f"max({FIGURES[n]} for _ in range(3))" for n in names)
    code = _MEASURE.format(bench=str(BENCH), exprs=exprs)
    out = subprocess.run([sys.executable, "-c", code], env={"PYTHONPATH": src, "PATH": "/usr/bin:/bin"},
                         capture_output=True, text=True, check=True).stdout
    return [float(x) for x in json.loads(out)]


def tree(text: str) -> tuple[str, str]:
    name, sep, path = text.partition("=")
    if not sep or not Path(path, "opentmcl").is_dir():
        raise argparse.ArgumentTypeError(f"expected NAME=PATH to a tree's src directory, got {text!r}")
    return name, str(Path(path).resolve())


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("trees", nargs="+", type=tree, metavar="NAME=SRC")
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--only", default=",".join(FIGURES), help=f"comma-separated figures of {', '.join(FIGURES)}")
    args = ap.parse_args(argv)
    names = [n for n in args.only.split(",") if n]
    unknown = [n for n in names if n not in FIGURES]
    if unknown or not names:
        ap.error(f"unknown figure(s) {', '.join(unknown) or '(none)'}; choose from {', '.join(FIGURES)}")
    results: dict[str, list[list[float]]] = {name: [] for name, _ in args.trees}
    for r in range(args.rounds):
        for name, src in args.trees:
            results[name].append(measure(src, names))
            got = ", ".join(f"{n} {v:,.0f}" for n, v in zip(names, results[name][-1], strict=True))
            print(f"round {r + 1} {name}: {got}", flush=True)
    first = args.trees[0][0]
    base = [statistics.median(x[i] for x in results[first]) for i in range(len(names))]
    for i, figure in enumerate(names):
        print(f"\n{figure:22} {'best':>12} {'median':>12} {'x first':>8}")
        for name, rows in results.items():
            med = statistics.median(x[i] for x in rows)
            best = max(x[i] for x in rows)
            print(f"  {name:20} {best:12,.0f} {med:12,.0f} {med / base[i]:8.2f}")


if __name__ == "__main__":
    main()
