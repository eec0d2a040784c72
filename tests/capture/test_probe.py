"""`opentmcl profile probe URL` (issue 13 item 5) over a real pty, through `opentmcl proxy` so that the
capture proves it sent reading commands only: GAP (6), GGP (10), GIO (15), 136 (TMCM-6212 manual 3.6.6,
3.6.8, 3.6.13, 3.6.36)."""
from __future__ import annotations

import json
import sys

import pytest

from opentmcl.modules.profile import load_profile

from .helpers import Tool, cli

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")


def readable(prof):
    return ({n for n, p in prof.axis_parameters.items() if p.readable},
            {k for k, p in prof.global_parameters.items() if p.readable},
            {k for k, p in prof.io.items() if "R" in p.access})


@pytest.mark.parametrize("name", ["TMCM-6212", "PD28-1021", "PD86-1180"])
def test_probe_reproduces_the_readable_parameter_set(name, tmp_path):
    out, log = tmp_path / "probed.toml", tmp_path / "probe.jsonl"
    with Tool("serve", "--module", name, "--pty") as served:
        proxy = Tool("proxy", "--to", f"serial://{served.endpoint('pty')}", "--pty", "--log", str(log))
        try:
            done = cli("profile", "probe", f"serial://{proxy.endpoint('pty')}", "-o", str(out), timeout=300)
        finally:
            proxy.stop()
    assert done.returncode == 0, done.stderr
    progress = done.stderr.splitlines()
    assert any(line.startswith("probe: axis 0:") for line in progress) and progress[-1] == f"probe: wrote {out}"
    builtin = load_profile(name)
    probed = load_profile(str(out))
    assert probed.axes == builtin.axes and probed.firmware_version == builtin.firmware_version
    assert readable(probed) == readable(builtin)
    assert out.read_text().splitlines()[1].startswith("# UNVERIFIED")
    assert cli("profile", "check", str(out)).returncode == 0
    sent = {json.loads(x)["command"] for x in log.read_text().splitlines() if '"kind":"request"' in x}
    assert sent == {6, 10, 15, 136}


def test_probe_extends_the_closest_builtin_and_notes_what_differs(tmp_path):
    """A module whose firmware string shares the module number (6212) extends that profile; a
    writable value that differs from the default becomes an override."""
    custom = tmp_path / "custom.toml"
    custom.write_text('extends = "TMCM-6212"\n[module]\nname = "X"\nfirmware_version = "6212V200"\n'
                      "[[axis_parameter]]\nnumber = 6\ndefault = 77\n[remove]\naxis_parameter = [206]\n")
    with Tool("serve", "--module", str(custom), "--tcp", "127.0.0.1:0") as served:
        done = cli("profile", "probe", served.endpoint("tcp"), timeout=300)
    assert done.returncode == 0, done.stderr
    text = done.stdout
    assert 'extends = "TMCM-6212"' in text and 'firmware_version = "6212V200"' in text
    assert "[[axis_parameter]]\nnumber = 6\ndefault = 77" in text
    assert "axis_parameter = [206]" in text


def test_probe_is_bounded_in_time_and_fails_in_one_line(tmp_path):
    """On an RS-485 line nobody answers address 9 (docs/endpoints.md: only frames for GP66/GP87 are
    answered); on USB the module answers every address with its own (GP66 = 1), so the 136 type 1
    reply comes from module 1 and the probe says so in one line. (Merged code: `serve --pty` became
    USB for one module, and the probe ended with the client's bare time-out message.)"""
    with Tool("serve", "--module", "PD86-1180", "--pty", "--interface", "rs485") as served:
        slow = cli("profile", "probe", f"serial://{served.endpoint('pty')}", "--max-seconds", "0.05")
        nobody = cli("profile", "probe", f"serial://{served.endpoint('pty')}", "--address", "9", "--timeout", "0.2")
    with Tool("serve", "--module", "PD86-1180", "--pty", "--interface", "usb") as served:
        usb = cli("profile", "probe", f"serial://{served.endpoint('pty')}", "--address", "9", "--timeout", "0.2")
    assert slow.returncode == 3 and "longer than its time limit" in slow.stderr.splitlines()[-1]
    assert nobody.returncode == 3 and "does not answer command 136" in nobody.stderr.splitlines()[-1]
    assert usb.returncode == 3 and len(usb.stderr.splitlines()) == 1   # 3: no reply (docs/cli.md)
    assert "not type 1 at this address" in usb.stderr and "give that --address" in usb.stderr
    bad = cli("profile", "probe", "nope://x")
    assert bad.returncode == 2 and len(bad.stderr.splitlines()) == 1
