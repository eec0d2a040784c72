"""Issue 15 item 7: progress bars on a terminal only (docs/cli.md "Progress").

stderr is a real pseudo-terminal (pty.openpty) for the "bar appears" half and a pipe for the
"no bar" half; -q hides the bar on a terminal too.
"""
from __future__ import annotations

import os
import select
import subprocess
import sys
import time

import pytest

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")

SIM = "sim://TMCM-6212"
BAR = "%|"   # tqdm draws "desc:  40%|####      | 4/10 ..."


def on_terminal(*args: str, timeout: float = 120) -> tuple[int, str, str]:
    """Run opentmcl with stderr on a pty; (status, stdout, what the terminal showed)."""
    import pty

    master, slave = pty.openpty()
    env = {k: v for k, v in os.environ.items() if k != "COLUMNS"}
    proc = subprocess.Popen([sys.executable, "-m", "opentmcl", *args], stdout=subprocess.PIPE,
                            stderr=slave, stdin=subprocess.DEVNULL, env=env)
    os.close(slave)
    shown = b""
    deadline = time.monotonic() + timeout
    try:
        while time.monotonic() < deadline:
            ready, _, _ = select.select([master], [], [], 0.2)
            if ready:
                try:
                    chunk = os.read(master, 65536)
                except OSError:   # EIO: every holder of the slave closed it
                    break
                if not chunk:
                    break
                shown += chunk
            elif proc.poll() is not None:
                break
        out = proc.stdout.read().decode()
        return proc.wait(timeout=30), out, shown.decode(errors="replace")
    finally:
        os.close(master)
        if proc.poll() is None:
            proc.kill()


def in_a_pipe(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], capture_output=True, text=True, timeout=120)


@pytest.fixture
def program(tmp_path):
    """400 instructions: a download and read-back that a bar can show."""
    path = tmp_path / "long.tmc"
    path.write_text("".join(f"SAP 4, 0, {1000 + i}\n" for i in range(399)) + "STOP\n")
    return path


def test_load_shows_a_bar_on_a_terminal_only(program):
    """`load`: every instruction written, then read back (command 134): twice as many steps."""
    code, out, shown = on_terminal("load", str(program), "--to", SIM)
    count = int(out.split()[1])
    assert code == 0 and out.startswith("loaded") and out.endswith("verified\n") and count >= 400
    assert "load:" in shown and BAR in shown and f"/{2 * count}" in shown
    piped = in_a_pipe("load", str(program), "--to", SIM)
    assert piped.returncode == 0 and piped.stderr == ""
    quiet_code, _, quiet = on_terminal("load", str(program), "--to", SIM, "-q")
    assert quiet_code == 0 and BAR not in quiet


def test_run_shows_its_seconds_on_a_terminal_only(tmp_path):
    """`run`: the bar counts the module's seconds up to --seconds."""
    prog = tmp_path / "wait.tmc"
    prog.write_text("loop: JA loop\n")
    code, out, shown = on_terminal("run", str(prog), "-t", "2", "--sample", "0.1")
    assert code == 0 and "program still running" in out
    assert "run:" in shown and BAR in shown
    piped = in_a_pipe("run", str(prog), "-t", "2", "--sample", "0.1")
    assert piped.returncode == 0 and piped.stderr == ""


def test_probe_shows_a_bar_on_a_terminal_and_lines_in_a_pipe():
    """`profile probe`: its per-axis lines stay (docs/profiles.md), the bar is extra on a terminal."""
    code, out, shown = on_terminal("profile", "probe", "sim://PD28-1021")
    assert code == 0 and out.startswith("#")
    assert "probe:" in shown and BAR in shown and "probe: axis 0:" in shown
    piped = in_a_pipe("profile", "probe", "sim://PD28-1021")
    assert piped.returncode == 0 and BAR not in piped.stderr and "probe: axis 0:" in piped.stderr


def test_plot_to_shows_its_recording_on_a_terminal_only(tmp_path):
    """`plot - --to URL` records what the module does for --seconds: the bar counts them."""
    out = tmp_path / "rec.png"
    code, text, shown = on_terminal("plot", "-", "--to", SIM, "--seconds", "1", "-o", str(out))
    assert code == 0 and text.startswith(f"wrote {out}")
    assert "recording:" in shown and BAR in shown
    piped = in_a_pipe("plot", "-", "--to", SIM, "--seconds", "1", "-o", str(out))
    assert piped.returncode == 0 and piped.stderr == ""
