"""Process-time A/B of the TMC429 fast core between source trees (a loaded machine makes the
wall-clock figures of bench/run.py useless for small differences; CPU time of this process is not).

    python bench/ab_tmc429.py /tmp/old /path/to/repo      # alternates the trees, five rounds
    python bench/ab_tmc429.py --rounds 15 /tmp/old .      # more rounds on a busy machine

Each round runs, in a fresh interpreter per tree and with that tree's `src` first on the path,
the cold-braking move at A_MAX=4 (bench_tmc429's last row), the six-move arrival run and the
PD86-1180 engine run, and prints their CPU milliseconds; the end prints each tree's best and median.
The workloads are written here, not imported from the tree's bench/, so that trees older than a
bench row still run the same code.
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys

CHILD = """
import sys, time
sys.path[:0] = [sys.argv[1] + "/src"]
from opentmcl.motion import CLOCK_HZ, tmc429
from opentmcl.motion.pmulpdiv import registers_for
from opentmcl.motion.tmc429 import Tmc429Ramp
from opentmcl.motion.tmc429_engine import Tmc429Engine

def ramp(a_max):
    pmul, pdiv = registers_for(a_max, 0, 0)
    r = Tmc429Ramp(position_bits=32)
    r.set(pulse_div=0, ramp_div=0, v_max=2047, v_min=1, a_max=a_max, pmul=pmul, pdiv=pdiv)
    return r

def cold_braking():
    r = ramp(4)
    r.set(x_target=3_000_000)
    forget = getattr(tmc429, "clear_memos", None)     # trees before issue 33: _FOLLOW_MEMO
    forget() if forget else getattr(tmc429, "_FOLLOW_MEMO", {}).clear()
    while (e := r.next_event()) is not None:
        r.advance(e)
    assert r.x_actual == 3_000_000 and r.position_reached

def arrivals():
    r, target = ramp(1000), 50_000
    for _ in range(6):
        r.set(x_target=target)
        while (e := r.next_event()) is not None:
            r.advance(e)
        target = 50_000 - target

def engine_run():
    e = Tmc429Engine()
    e.configure(pulse_divisor=0, ramp_divisor=0, max_positioning_speed=2047,
                max_acceleration=1000, minimum_speed=1)
    horizon, target = int(20.0 * CLOCK_HZ), 20_000
    e.move_to(target)
    while e.now < horizon:
        t = e.next_event()
        if t is None:
            target = 20_000 - target
            e.move_to(target)
            continue
        e.advance(min(t, horizon))

def cpu(f):
    t = time.process_time(); f(); return (time.process_time() - t) * 1000

print(cpu(cold_braking), cpu(arrivals), cpu(engine_run))
"""

NAMES = ("A_MAX=4 cold braking", "6 arrivals", "engine run")


def _run(tree: str) -> list[float]:
    out = subprocess.run([sys.executable, "-c", CHILD, tree], check=True, capture_output=True,
                         text=True).stdout
    return [float(x) for x in out.split()]


def _line(figures: list[float]) -> str:
    return ", ".join(f"{name} {ms:.2f} ms" for name, ms in zip(NAMES, figures, strict=True))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("trees", nargs="*", default=["."])
    args = ap.parse_args()
    trees = args.trees
    seen: dict[str, list[list[float]]] = {tree: [] for tree in trees}
    for _ in range(args.rounds):
        for tree in trees:
            figures = _run(tree)
            seen[tree].append(figures)
            print(f"{tree}: {_line(figures)} (CPU)", flush=True)
    for tree, rounds in seen.items():
        columns = list(zip(*rounds, strict=True))
        print(f"{tree}: best   {_line([min(c) for c in columns])}")
        print(f"{tree}: median {_line([statistics.median(c) for c in columns])}")


if __name__ == "__main__":
    main()
