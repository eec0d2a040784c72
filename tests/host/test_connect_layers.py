"""DESIGN.md "Layers": host talks bytes and never imports the firmware, except lazily in sim://."""
from __future__ import annotations

import subprocess
import sys


def test_importing_the_host_library_does_not_import_the_firmware():
    code = ("import sys, opentmcl.host, opentmcl.host.transports.inprocess, opentmcl.cli.send; "
            "print(sorted(m for m in sys.modules if m.startswith('opentmcl.firmware')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
