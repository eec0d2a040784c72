"""Process-time A/B of the TMC429 fast core between two source trees (a loaded machine makes the
wall-clock figures of bench/run.py useless for small differences; CPU time of this process is not).

    python bench/ab_tmc429.py /tmp/old /path/to/repo      # alternates the trees, five rounds

Each round runs, in a fresh interpreter per tree, bench_tmc429's cold-braking move at A_MAX=4,
the six-move arrival run and the PD86-1180 engine run, and prints their CPU milliseconds.
"""
from __future__ import annotations

import subprocess
import sys

CHILD = """
import sys, time
sys.path[:0] = [sys.argv[1] + "/src", sys.argv[1] + "/bench"]
import bench_tmc429 as b
def cpu(f, *a):
    t = time.process_time(); f(*a); return (time.process_time() - t) * 1000
print(f"{sys.argv[1]}: A_MAX=4 cold braking {cpu(b._small_a_max_move_ms, 4, 3_000_000):.1f} ms, "
      f"6 arrivals {cpu(b._fast_arrivals, 6, 50_000):.2f} ms, "
      f"engine run {cpu(b._engine_run, 20.0, 20_000):.0f} ms (CPU)")
"""


def main() -> None:
    trees = sys.argv[1:] or ["."]
    for _ in range(5):
        for tree in trees:
            subprocess.run([sys.executable, "-c", CHILD, tree], check=True)


if __name__ == "__main__":
    main()
