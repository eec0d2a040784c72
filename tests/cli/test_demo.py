"""`opentmcl demo`: the main job of the README's first command."""
import os
import pathlib
import subprocess
import sys

SCENARIOS = pathlib.Path(__file__).resolve().parents[2] / "examples" / "scenarios"


def opentmcl(*args):
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], capture_output=True, text=True, timeout=120)


def blocks(stdout):
    """The demo table as {axis: [(time, pos, vel), ...]}, read from every block of the wrapped table."""
    lines = stdout.splitlines()
    found = {}
    for i, line in enumerate(lines):
        if not line.startswith("time/s"):
            continue
        names = line.split()[1:]
        axes = [int(n[4:]) for n in names if n.startswith("axis")]
        for row in lines[i + 2:]:
            if not row.strip() or not row.split()[0].replace(".", "").isdigit():
                break
            cells = row.split()
            for k, axis in enumerate(axes):
                found.setdefault(axis, []).append((float(cells[0]), int(cells[1 + 2 * k]), int(cells[2 + 2 * k])))
    return found


def test_demo_prints_a_table_of_all_six_axes():
    """Issue #2 item 1: a virtual TMCM-6212 runs a few moves in virtual time and prints a readable table
    (time, per-axis position/velocity) — no arguments needed. Issue 15 item 7: the six axes wrap into
    blocks that fit 80 columns, each block with the time column."""
    out = opentmcl("demo")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert "TMCM-6212" in lines[0]
    table = blocks(out.stdout)
    assert sorted(table) == list(range(6))
    times = [t for t, _, _ in table[0]]
    assert times[:3] == [0.0, 0.1, 0.2] and times[-1] == 2.0
    assert all(len(rows) == len(times) for rows in table.values())
    assert all(rows[0][1:] == (0, 0) for rows in table.values())   # everything starts at rest at 0
    assert table[0][-1][1] == 12000                                 # axis 0 arrived at its MVP target
    assert table[2][-1][1] > 0 and table[2][-1][2] > 0              # axis 2 rotates (ROR)
    assert "position reached" in lines[-1]


def widths(*args):
    env = {k: v for k, v in os.environ.items() if k != "COLUMNS"}
    out = subprocess.run([sys.executable, "-m", "opentmcl", "demo", *args], capture_output=True, text=True,
                         timeout=120, env=env)
    assert out.returncode == 0, out.stderr
    return [len(line) for line in out.stdout.splitlines()], out.stdout


def test_demo_fits_an_80_column_terminal():
    """Issue 15: "`demo --scenario` prints 330-character lines"; every line now fits 80 columns
    (79 characters, so that a full line never makes the terminal wrap), with and without a scenario."""
    for args in ([], ["--module", "PD86-1180"], ["--scenario", str(SCENARIOS / "tmcm6212_stage.toml")],
                 ["--scenario", str(SCENARIOS / "pd86_1180_three_switch.toml"), "--duration", "0.5"]):
        lengths, text = widths(*args)
        assert max(lengths) <= 79, (args, max(lengths))
        assert len(lengths) > 5
    # the wrapped world trace still has each trace column (docs/scenarios.md) exactly once
    _, text = widths("--scenario", str(SCENARIOS / "tmcm6212_stage.toml"), "--duration", "0.2")
    heads = [line.split() for line in text.splitlines() if line.split()[:1] == ["time"]]
    columns = [c for head in heads for c in head[1:]]
    assert len(heads) > 1 and len(columns) == len(set(columns)) == 6 * 9   # pos, vel, ..., stage per axis


def test_demo_axes_selects_the_axes_shown():
    """`--axes 0,2`: only those axes (all six still move)."""
    out = opentmcl("demo", "--axes", "2,0", "--duration", "0.3")
    assert out.returncode == 0, out.stderr
    assert sorted(blocks(out.stdout)) == [0, 2]
    last = opentmcl("demo", "--axes", "5", "--duration", "0.1")            # the last axis of a TMCM-6212
    assert last.returncode == 0 and sorted(blocks(last.stdout)) == [5]
    bad = opentmcl("demo", "--axes", "6")                                   # the first axis it lacks
    assert bad.returncode == 2 and "axes 0..5" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1


def test_demo_other_module():
    out = opentmcl("demo", "--module", "PD86-1180", "--duration", "0.5")
    assert out.returncode == 0 and "PD86-1180" in out.stdout


def test_demo_bad_input_is_one_line_and_nonzero():
    """DEVELOPERS.md: bad input gets non-zero exit and a one-line message, never a traceback."""
    for args in (["--module", "TMCM-9999"], ["--interval", "0"], ["--duration", "nan"],
                 ["--duration", "inf"], ["--interval", "1e-9"]):
        out = opentmcl("demo", *args)
        assert out.returncode == 2
        assert len(out.stderr.strip().splitlines()) == 1 and "Traceback" not in out.stderr
