"""CI runs a short version of every benchmark (DEVELOPERS.md: slow checks run short in CI).

No timing is asserted here: speed is measured by `python bench/run.py`, never in unit tests.
"""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_bench_quick_runs_and_reports_every_figure():
    out = subprocess.run([sys.executable, str(ROOT / "bench" / "run.py"), "--quick"], capture_output=True,
                         text=True, timeout=300, check=True).stdout
    for label in ("6212 six axes, 10-revolution moves", "PD86-1180 pulse_div=ramp_div=0",
                  "TMC429 fast vs per-tick speed-up", "in-process round trips per s",
                  "memory world trace MB per hour at 10 ms", "memory plot trace MB per hour at 10 ms",
                  "proxy added by the proxy, ms"):
        assert label in out
    figures = [float(line.rsplit(None, 1)[-1].replace(",", "")) for line in out.splitlines() if line.strip()]
    assert figures and all(f > 0 for f in figures)
