"""Issue 34, "Done when": "An unmodified PyTrinamic script, served on a pty with 1 % of replies
dropped, shows its own timeout handling." The cookbook's script (examples/faults/) talks to
`opentmcl serve --pty --faults examples/faults/drop_1_percent.toml`; each reply the server drops is
one PyTrinamic time-out ("TMCL datagram timed out"), which the script retries."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import pytrinamic  # noqa: F401  (a test dependency, pyproject.toml [test]: missing, the test must not pass)

from opentmcl.server.control import ask

from ..capture.helpers import Tool

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "faults"


def test_pytrinamic_shows_its_own_timeout_handling(tmp_path):
    control = tmp_path / "control.sock"
    with Tool("serve", "-m", "TMCM-6212", "--pty", "--faults", str(EXAMPLES / "drop_1_percent.toml"),
              "--fault-control", str(control)) as served:
        run = subprocess.run([sys.executable, str(EXAMPLES / "pytrinamic_timeouts.py"), served.endpoint("pty")],
                             capture_output=True, text=True, timeout=120)
        fired = [line for line in ask(control, "list")["fired"] if "(drop_reply)" in line or "drop_reply:" in line]
    assert run.returncode == 0, run.stdout + run.stderr
    timeouts = int(run.stdout.split()[-1])
    assert timeouts == len(fired) > 0
