"""Mutation testing of the protocol, firmware and lang layers with mutmut 3 (docs/mutation.md).

    python bench/mutation.py                          # every mutant of the three layers (hours)
    python bench/mutation.py --layer protocol         # one layer
    python bench/mutation.py --layer firmware --sample 300 --seed 12   # a reproducible sample
    python bench/mutation.py --report                 # only print the results already recorded
    python bench/mutation.py --layer protocol --retry survived   # after adding tests

mutmut reads [tool.mutmut] in pyproject.toml, copies the tree into mutants/ and records each
mutant's result there; mutants that have a result are not run again (unless --rerun), so an
interrupted run continues where it stopped. The script runs mutmut
under `nice -n 19` with one child (`--max-children`), then prints killed / survived / timeout and
the score (killed + timeout over all mutants that were tried) per layer, and the survivors.
Outside CI: a full run takes hours on a small machine.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MUTANTS = ROOT / "mutants" / "src" / "opentmcl"
LAYERS = ("protocol", "firmware", "lang")
MUTMUT = [str(Path(sys.executable).with_name("mutmut"))]  # the venv's console script, not -m

# mutmut's exit codes of a mutant run (mutmut/stats.py); anything else is "suspicious"
OUTCOME = {1: "killed", 3: "killed", 37: "killed", 0: "survived", 5: "no tests", 33: "no tests",
           34: "skipped", 36: "timeout", 24: "timeout", -24: "timeout", 152: "timeout", 255: "timeout",
           None: "not checked"}

# Mutant generation without a test run (mutmut 3 has no command for it): the steps `mutmut run`
# begins with, from mutmut's own module.
GENERATE = ("import os; from mutmut.__main__ import copy_src_dir, copy_also_copy_files, create_mutants; "
            "os.makedirs('mutants', exist_ok=True); copy_src_dir(); copy_also_copy_files(); create_mutants(1)")


def recorded(layer: str) -> dict[str, int | None]:
    """Mutant name -> exit code, as mutmut recorded them under mutants/ for `layer`."""
    out: dict[str, int | None] = {}
    for meta in sorted((MUTANTS / layer).glob("*.py.meta")):
        out.update(json.loads(meta.read_text())["exit_code_by_key"])
    return out


def generate() -> None:
    if not any(recorded(layer) for layer in LAYERS):
        subprocess.run([sys.executable, "-c", GENERATE], cwd=ROOT, check=True)


def _rank(seed: int, name: str) -> bytes:
    """A mutant's place in the draw of `seed`: a hash of its own name, so a change to one function
    swaps only that function's mutants in and out of a draw, and a draw of N is the first N of a
    larger one."""
    return hashlib.sha256(f"{seed}:{name}".encode()).digest()


def choose(layers: list[str], sample: int | None, seed: int) -> list[str]:
    """The mutant names to run: all of `layers`, or `sample` of each layer drawn with `seed`."""
    names: list[str] = []
    for layer in layers:
        pool = sorted(recorded(layer))
        if sample is not None and sample < len(pool):
            pool = sorted(sorted(pool, key=lambda name: _rank(seed, name))[:sample])
        names += pool
    return names


def pending(names: list[str], layers: list[str], retry: tuple[str, ...] = ()) -> list[str]:
    """The names among `names` that have no result yet, or whose outcome is in `retry` (e.g.
    "survived" after adding tests, "timeout" after raising the time limit; mutmut reruns every
    name it is given)."""
    codes = {k: v for layer in layers for k, v in recorded(layer).items()}
    return [n for n in names if codes.get(n) is None or OUTCOME.get(codes[n], "suspicious") in retry]


def run(names: list[str], layers: list[str], children: int, log: Path) -> int:
    """mutmut run on `names` (a whole untouched layer as one pattern), niced, output to `log`."""
    whole = [f"opentmcl.{layer}.*" for layer in layers]
    args = whole if len(names) == sum(len(recorded(layer)) for layer in layers) else names
    cmd = ["nice", "-n", "19", *MUTMUT, "run", "--max-children", str(children), *args]
    print(f"mutmut run: {len(names)} mutants, output in {log.relative_to(ROOT)}", flush=True)
    with log.open("w") as out:
        return subprocess.run(cmd, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT).returncode


def report(layers: list[str], only: set[str] | None) -> list[str]:
    """Print the outcome per layer (restricted to `only` when given); return the survivors."""
    survivors: list[str] = []
    print(f"{'layer':10} {'mutants':>7} {'tried':>6} {'killed':>7} {'survived':>8} {'timeout':>7}"
          f" {'no tests':>8} {'other':>5} {'score':>7}")
    for layer in layers:
        codes = {k: v for k, v in recorded(layer).items() if only is None or k in only}
        counts = Counter(OUTCOME.get(v, "suspicious") for v in codes.values())
        tried = len(codes) - counts["not checked"] - counts["skipped"]
        caught = counts["killed"] + counts["timeout"]
        other = tried - caught - counts["survived"] - counts["no tests"]
        score = f"{100 * caught / tried:6.1f}%" if tried else "     -"
        print(f"{layer:10} {len(codes):7} {tried:6} {counts['killed']:7} {counts['survived']:8} {counts['timeout']:7}"
              f" {counts['no tests']:8} {other:5} {score:>7}")
        survivors += sorted(k for k, v in codes.items() if OUTCOME.get(v) in ("survived", "no tests"))
    return survivors


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--layer", action="append", choices=LAYERS, help="layer to mutate (repeatable; default all)")
    ap.add_argument("--sample", type=int, metavar="N", help="run N mutants per layer, drawn with --seed")
    ap.add_argument("--seed", type=int, default=12, help="seed of the sample (default 12)")
    ap.add_argument("--max-children", type=int, default=1, help="parallel mutmut workers (default 1)")
    ap.add_argument("--report", action="store_true", help="print recorded results, run nothing")
    ap.add_argument("--rerun", action="store_true", help="run mutants that already have a result again")
    ap.add_argument("--retry", action="append", default=[], choices=("survived", "timeout", "no tests"),
                    help="run the mutants with this recorded outcome again (repeatable)")
    ap.add_argument("--survivors", action="store_true", help="list the surviving mutants")
    args = ap.parse_args(argv)
    if args.sample is not None and args.sample < 1:
        ap.error("--sample must be at least 1")
    layers = args.layer or list(LAYERS)
    generate()
    names = choose(layers, args.sample, args.seed)
    todo = names if args.rerun else pending(names, layers, tuple(args.retry))
    if todo and not args.report:
        code = run(todo, layers, args.max_children, ROOT / "mutants" / "mutation-run.log")
        if code:
            print(f"mutmut exited with {code}; see mutants/mutation-run.log", file=sys.stderr)
            return code
    survivors = report(layers, set(names) if args.sample is not None else None)
    if args.survivors:
        print("\n".join(["", "survivors (`mutmut show NAME` prints the diff):", *survivors]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
