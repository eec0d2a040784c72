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


def test_probe_keeps_state_out_of_the_defaults_and_writes_a_snapshot_section(tmp_path):
    """Issue 30 item 6: a probed module that has been used reads AP0/AP1/AP209 = 51200, a running
    tick timer (GP132) and a random number (GP133) (TMCM-6212 manual 4.1, 5.1): those are state, so
    the skeleton overrides no default with them and lists them under [snapshot]; a setting that
    differs (AP6 = 100) still overrides its default. `replay --module probed.toml --initial-state
    probed.toml` starts a twin from the section: a capture that begins there agrees."""
    import tomllib

    from opentmcl.capture import replay
    from opentmcl.host.connect import open_bus
    from opentmcl.host.probe import probe, skeleton

    from .recorder import Recorder, edit

    client = open_bus("sim://TMCM-6212")
    for fields in [(5, 5, 0, 1_000_000), (5, 4, 0, 400_000), (4, 0, 0, 51200), (5, 6, 0, 100), (9, 133, 0, 4711)]:
        client.request(*fields)
    client.sleep(3.0)
    text = skeleton(probe(client), "sim://TMCM-6212")
    client.close()
    out = tmp_path / "probed.toml"
    out.write_text(text)
    assert cli("profile", "check", str(out)).returncode == 0
    data = tomllib.loads(text)
    assert {e["number"]: e.get("default") for e in data["axis_parameter"]} == {6: 100, 4: 400_000, 5: 1_000_000}
    assert not [e for e in data.get("global_parameter", []) if e["number"] in (132, 133)]
    rows = {tuple(row[:2]): row[2] for row in data["snapshot"]["axis_parameter"]}
    assert rows[(0, 0)] == rows[(0, 1)] == rows[(0, 209)] == 51200 and rows[(1, 1)] == 0
    globals_ = {tuple(row[:2]): row[2] for row in data["snapshot"]["global_parameter"]}
    assert globals_[(0, 132)] >= 3000 and (0, 133) in globals_
    rec = Recorder()
    for fields in [(5, 5, 0, 1_000_000), (5, 4, 0, 400_000), (4, 0, 0, 51200)]:
        rec.vm.request(*fields)   # the state the module was in before the capture
    for t, fields in [(5.0, (6, 1, 0, 0)), (5.01, (4, 1, 0, 1000)), (9.0, (6, 1, 0, 0)), (9.01, (6, 209, 0, 0))]:
        rec.request(t, fields)
    path = rec.write(tmp_path / "c.jsonl")
    assert replay(path, out, initial_state=out).ok   # the probed profile from its own snapshot
    edit(path, lambda r: r.get("kind") == "reply" and r.get("parameter") == "encoder_position", value=0)
    assert replay(path, out, initial_state=out).parameters == ["encoder_position"]   # AP209 came from it
