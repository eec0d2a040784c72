"""OpenTMCL benchmarks: one command, figures measured side by side in one run.

    python bench/run.py                      # full run (a few minutes on a busy machine)
    python bench/run.py --quick              # short run, as CI does it (tests/test_bench.py)
    python bench/run.py --json PATH          # where the table goes as JSON (default bench/results/latest.json)
    python bench/run.py --compare OLD.json   # also print OLD next to this run, with new / old
    python bench/run.py --check              # exit status 1 when a goal was missed (else 0 either way)

Every figure has a name, a value, the reference it is compared with (measured in the same run;
"-" where a figure has none), the ratio value / reference, the goal (docs/performance.md) and
whether this run met it ("pass", "FAIL"; "-" for a goal against an older tree, bench/ab_goals.py),
with a summary line at the end:

- the request path of a polling host (bench_polling.py): the minimal-handler floor against
  `vm.handle`; `connect("sim://")` `Module.request` against `vm.handle`; a host polling GAP 8 + GAP 1
  of 1 or 6 moving TMCM-6212 axes every 10 ms or 500 ms of virtual time through `vm.handle`,
  `Module.request` and `Module.request_many` (issue 16);
- the served bus of 1/2/4/8 modules (bench_bus.py) and the interpreter with GAP in its loop, with
  and without a 1 ms timer interrupt (bench_interp.py);
- virtual seconds per wall second, TMCM-6212 with six axes doing back-and-forth MVP moves (target >= 3600);
- virtual seconds per wall second, PD86-1180 at pulse_div = ramp_div = 0 (target >= 100);
- speed-up of the event-driven TMC429 engine over the per-tick reference model (exact agreement checked);
- in-process round trips per second through VirtualModule.handle (target >= 50,000);
- the engines alone (bench_sixpoint.py, bench_tmc429.py);
- round trips through TCP and the pseudo-terminal next to a bare echo server on the same transport,
  each server in a process of its own (target: ours >= 50 % of echo), and our client against
  PyTrinamic on the same module (target >= 1) (bench_endpoints.py);
- `Trace.sample` of six moving axes next to the 54 GAP reads it stands for (goal: >= 8x as many
  samples as groups of 54 reads per second, 4x the former 2x) and next to the former sample (goal:
  >= 4x), and a run traced at 10 ms next to the same run untraced (bench_trace.py `speed`);
- memory of the world and plot traces in MB per hour of recording at 10 ms, compact columns next to
  the old dict-per-row / list-per-channel layouts (target < 100 MB; bench_trace.py).
- the round-trip time `opentmcl proxy` adds on loopback, next to a direct connection to the same served
  module in the same run (target: < 1 ms added; bench_proxy.py).
"""
from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # for tests.motion (the per-tick oracle)
sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_bus  # noqa: E402
import bench_endpoints  # noqa: E402
import bench_interp  # noqa: E402
import bench_polling  # noqa: E402
import bench_proxy  # noqa: E402
import bench_sixpoint  # noqa: E402
import bench_tmc429  # noqa: E402
import bench_trace  # noqa: E402
import figures as figures_module  # noqa: E402
import opentmcl  # noqa: E402
from figures import Figure, Goal, figures_of, use_cpu_time  # noqa: E402
from opentmcl import VirtualModule  # noqa: E402
from opentmcl.motion import CLOCK_HZ  # noqa: E402
from opentmcl.protocol.frame import Request  # noqa: E402


def back_and_forth(vm: VirtualModule, virtual_seconds: float, distance: int) -> float:
    """Every axis moves between 0 and `distance` (MVP ABS); the host hears of each arrival through
    command 138 and sends the next move at once. Returns virtual seconds per wall second."""
    axes = range(vm.profile.axes)
    targets = dict.fromkeys(axes, distance)
    vm.request(138, 1, 0, (1 << vm.profile.axes) - 1)
    for a in axes:
        vm.request(4, 0, a, distance)
    end = vm.now + round(virtual_seconds * CLOCK_HZ)
    start = time.perf_counter()
    while vm.now < end:
        step = vm.next_event_in()
        vm.advance_to(end if step is None else min(end, vm.now + max(1, round(step * CLOCK_HZ))))
        for raw in vm.drain_events():
            axis = raw[7].bit_length() - 1
            targets[axis] = 0 if targets[axis] else distance
            vm.request(4, 0, axis, targets[axis])
    return virtual_seconds / (time.perf_counter() - start)


def bench_6212(seconds: float) -> float:
    """Six axes at factory ramp settings (51200 pps, 51200 pps^2: one revolution per second at 256
    microsteps and 200 full steps), each moving back and forth over ten revolutions (512000 µsteps),
    axes 1-5 with slightly higher speeds so that their events do not coincide."""
    vm = VirtualModule("TMCM-6212")
    for a in range(1, 6):
        vm.request(5, 4, a, 51200 + 5000 * a)
    return back_and_forth(vm, seconds, 512000)


def bench_6212_short(seconds: float) -> float:
    """The same with short, fast moves (51200 µsteps at up to 200000 pps): the cost per move."""
    vm = VirtualModule("TMCM-6212")
    for a in range(6):
        vm.request(5, 4, a, 100000 + 20000 * a)
        vm.request(5, 5, a, 200000)
    return back_and_forth(vm, seconds, 51200)


def bench_1180(seconds: float) -> float:
    vm = VirtualModule("PD86-1180")
    vm.request(5, 154, 0, 0)
    vm.request(5, 153, 0, 0)
    vm.request(5, 4, 0, 2047)
    vm.request(5, 5, 0, 1000)
    return back_and_forth(vm, seconds, 200000)


def bench_round_trips(n: int) -> float:
    vm = VirtualModule("TMCM-6212")
    frames = [Request(1, 6, 1, a % 6, 0).encode() for a in range(64)]
    start = time.perf_counter()
    for i in range(n):
        vm.handle(frames[i & 63])
    return n / (time.perf_counter() - start)


RESULTS = Path(__file__).resolve().parent / "results" / "latest.json"

# Figures of the older benchmarks that have a yardstick in the same run: figure -> (its
# reference among the figures, goal of the ratio).
HALF_OF_ECHO = Goal(">=", 0.5, on_ratio=True, text=">= 0.5 of echo")
PAIRS: dict[str, tuple[str, Goal | str]] = {
    "endpoints TCP round trips/s: ours": ("endpoints TCP bare echo round trips/s", HALF_OF_ECHO),
    "endpoints pty round trips/s: ours": ("endpoints pty bare echo round trips/s", HALF_OF_ECHO),
    "endpoints TCP round trips/s: our client (opentmcl.connect)": ("endpoints TCP round trips/s: PyTrinamic client",
                                                                   Goal(">=", 1, on_ratio=True, text=">= 1x PyTrinamic")),
    "proxy through the proxy (capture on), median ms": ("proxy direct round trip, median ms", ""),
}
GOALS = {  # the older figures' targets, in the goal column
    "proxy added by the proxy, ms (target < 1)": Goal("<", 1, text="< 1 ms"),
    "memory world trace MB per hour at 10 ms, 6 axes, compact columns (target < 100)": Goal("<", 100, text="< 100 MB"),
    "memory plot trace MB per hour at 10 ms, 6 axes, compact columns (target < 100)": Goal("<", 100, text="< 100 MB"),
}


def pair(figures: list[Figure]) -> None:
    by_name = {f.name: f for f in figures}
    for name, (ref, goal) in PAIRS.items():
        f, r = by_name.get(name), by_name.get(ref)
        if f is not None and r is not None:
            f.reference, f.reference_name, f.goal = r.value, r.name, goal
    for f in figures:
        f.goal = GOALS.get(f.name, f.goal)


def measure(quick: bool) -> list[Figure]:
    scale = 0.1 if quick else 1.0
    out = bench_polling.measure(quick) + bench_bus.measure(quick) + bench_interp.measure(quick)
    out += bench_trace.speed(quick)
    out += [Figure("6212 six axes, 10-revolution moves, virtual s per wall s (target >= 3600)",
                   bench_6212(3600 * scale), goal=Goal(">=", 3600)),
            Figure("6212 six axes, short fast moves, virtual s per wall s", bench_6212_short(300 * scale)),
            Figure("PD86-1180 pulse_div=ramp_div=0, virtual s per wall s (target >= 100)", bench_1180(20 * scale),
                   goal=Goal(">=", 100))]
    for label, older in (("engine", bench_sixpoint.measure), ("TMC429", bench_tmc429.measure),
                         ("endpoints", bench_endpoints.measure), ("memory", bench_trace.measure),
                         ("proxy", bench_proxy.measure)):
        out += figures_of(label, older(quick=quick))
    out.append(Figure("in-process round trips per s (target >= 50000)", bench_round_trips(int(200000 * scale)),
                      goal=Goal(">=", 50_000, text=">= 50,000")))
    pair(out)
    return out


def commit() -> str:
    """The commit of the opentmcl package measured (not of this script), or why it is unknown."""
    where = Path(opentmcl.__file__).resolve().parent
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=where, capture_output=True, text=True,
                              timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "."], cwd=where, capture_output=True,
                               text=True, timeout=10, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return f"unknown ({where} is not a git checkout)"
    return head + (" (uncommitted changes)" if dirty else "")


def number(value: float | None) -> str:
    if value is None:
        return "n/a"
    return f"{value:,.2f}" if abs(value) < 100 else f"{value:,.0f}"


def table(rows: list[list[str]], left: int = 1) -> str:
    """Columns: the first and the last `left` ones flush left, the others right."""
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = []
    for r in rows:
        cells = [c.ljust(w) if i == 0 or i >= len(r) - left else c.rjust(w)
                 for i, (c, w) in enumerate(zip(r, widths, strict=True))]
        lines.append("  ".join(cells).rstrip())
    return "\n".join(lines)


def report(figures: list[Figure]) -> str:
    rows = [["figure", "value", "reference", "ratio", "goal", "verdict"]]
    for f in figures:
        rows.append([f.name, number(f.value), "-" if f.reference is None else number(f.reference),
                     "-" if f.ratio is None else f"{f.ratio:.3f}", str(f.goal), f.verdict()])
    return table(rows, left=2)


def summary(figures: list[Figure]) -> str:
    """One line: how many goals this run met and missed, and how many it cannot judge; then each
    missed figure on a line of its own."""
    judged = [f for f in figures if f.goal]
    missed = [f for f in judged if f.met is False]
    met = sum(1 for f in judged if f.met)
    line = f"goals: {met} of {len(judged)} met, {len(missed)} missed"
    if len(judged) - met - len(missed):
        line += (f", {len(judged) - met - len(missed)} not judged in this run "
                 "(n/a, or against an older tree: bench/ab_goals.py)")
    return "\n".join([line] + [f"  missed: {f.name}: value {number(f.value)}, ratio "
                                f"{'-' if f.ratio is None else f'{f.ratio:.3f}'}, goal {f.goal}" for f in missed])


def exit_status(figures: list[Figure], check: bool) -> int:
    """0, or with --check 1 when a goal was missed."""
    return 1 if check and any(f.met is False for f in figures) else 0


def document(figures: list[Figure], quick: bool, commit_id: str | None = None) -> dict:
    return {"commit": commit_id or commit(), "python": platform.python_version(), "implementation": platform.python_implementation(),
            "opentmcl": str(Path(opentmcl.__file__).resolve().parent), "quick": quick,
            "clock": "cpu" if figures_module.clock is time.process_time else "wall",
            "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "figures": {f.name: f.as_json() for f in figures}}


def compare(old: dict, new: dict) -> str:
    """Old next to new for every figure of either run, with new / old; then each run's ratio
    value / reference, which does not depend on the load of the machine during that run."""
    rows = [["figure", "old", "new", "new/old", "old ratio", "new ratio"]]
    names = list(new["figures"]) + [n for n in old["figures"] if n not in new["figures"]]
    for name in names:
        a, b = old["figures"].get(name, {}), new["figures"].get(name, {})
        va, vb = a.get("value"), b.get("value")
        ra, rb = a.get("ratio"), b.get("ratio")
        rows.append([name, number(va), number(vb), f"{vb / va:.2f}" if va and vb is not None else "-",
                     "-" if ra is None else f"{ra:.3f}", "-" if rb is None else f"{rb:.3f}"])
    return f"old: {old.get('commit')}\nnew: {new.get('commit')}\n" + table(rows)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="short run")
    ap.add_argument("--json", type=Path, default=RESULTS, metavar="PATH", help="write the figures here as JSON")
    ap.add_argument("--compare", type=Path, metavar="OLD.json", help="print an earlier run next to this one")
    ap.add_argument("--cpu", action="store_true", help="time the in-process scenarios (polling, bus, interpreter) "
                    "with this process's CPU time instead of wall time: steadier on a shared machine")
    ap.add_argument("--commit", metavar="TEXT", help="the commit to record, where the measured opentmcl is not a "
                    "git checkout (a `git archive` tree)")
    ap.add_argument("--check", action="store_true", help="exit with status 1 when a goal was missed "
                    "(without it the status is 0 either way)")
    args = ap.parse_args(argv)
    old = None
    if args.compare is not None:
        try:
            old = json.loads(args.compare.read_text())
            old["figures"]
        except (OSError, ValueError, KeyError, TypeError) as exc:
            ap.error(f"--compare {args.compare}: not a results file of bench/run.py ({exc})")
    if args.cpu:
        use_cpu_time()
    figures = measure(args.quick)
    if args.cpu:
        print("in-process scenarios timed with CPU time: read 'wall s' in their names as 'CPU s'")
    print(report(figures))
    doc = document(figures, args.quick, args.commit)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(doc, indent=1) + "\n")
    print(f"\nwritten to {args.json}")
    if old is not None:
        print()
        print(compare(old, doc))
    print()
    print(summary(figures))
    return exit_status(figures, args.check)


if __name__ == "__main__":
    sys.exit(main())
