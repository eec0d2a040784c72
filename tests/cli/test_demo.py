"""`opentmcl demo`: the main job of the README's first command."""
import subprocess
import sys


def opentmcl(*args):
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], capture_output=True, text=True, timeout=120)


def test_demo_prints_a_table_of_all_six_axes():
    """Issue #2 item 1: a virtual TMCM-6212 runs a few moves in virtual time and prints a readable table
    (time, per-axis position/velocity) — no arguments needed."""
    out = opentmcl("demo")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert "TMCM-6212" in lines[0]
    assert all(f"axis{a} pos" in lines[1] for a in range(6))
    rows = [line.split() for line in lines[3:] if line[:8].strip().replace(".", "").isdigit()]
    assert [float(r[0]) for r in rows][:3] == [0.0, 0.1, 0.2] and float(rows[-1][0]) == 2.0
    assert rows[0][1:] == ["0"] * 12                      # everything starts at rest at 0
    assert int(rows[-1][1]) == 12000                      # axis 0 arrived at its MVP target
    assert int(rows[-1][5]) > 0 and int(rows[-1][6]) > 0  # axis 2 rotates (ROR)
    assert "position reached" in lines[-1]


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
