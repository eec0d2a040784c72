"""Replay in virtual time (capture/replay.py): what agrees, what diverges, tolerances, API, exit codes.

Captures here are recorded from one virtual module through the decoder (as the proxy does,
tests/capture/recorder.py) and then, where a test needs a divergence, one captured value is
changed by hand."""
from __future__ import annotations

import json

import pytest

import opentmcl
from opentmcl import VirtualModule
from opentmcl.capture import ReplayError, Tolerance, assert_replays, replay
from opentmcl.capture.decode import HOST, MODULE, Decoder
from opentmcl.protocol.frame import Request

from .helpers import Tool, cli
from .recorder import HEADER, edit, record

MOVE = [(0.1, (5, 4, 0, 51200)), (0.2, (4, 0, 0, 200000)), (2.0, (6, 1, 0, 0)), (2.1, (6, 3, 0, 0)),
        (2.2, (6, 6, 0, 0))]
"""SAP 4 = 51200 pps, MVP ABS 200000 (about 4.9 s), then GAP 1/3/6 while at constant speed."""


def test_a_module_agrees_with_its_own_capture(tmp_path):
    report = replay(record(tmp_path / "c.jsonl", MOVE), "TMCM-6212")
    assert report.ok and report.compared == 5 and report.divergences == []


def test_changed_constant_value_diverges_with_its_name(tmp_path):
    path = record(tmp_path / "c.jsonl", MOVE)
    edit(path, lambda r: r.get("kind") == "reply" and r.get("parameter") == "max_current", value=99)
    report = replay(path, "TMCM-6212")
    assert [d.parameter for d in report.divergences] == ["max_current"]
    assert "GAP 6, 0" in str(report.divergences[0]) and "captured 99" in str(report.divergences[0])


def test_position_agrees_within_the_twin_range_and_tolerances_only_widen_it(tmp_path):
    """Issue 30 "Interval comparison": at 51200 pps (TMCM-6212 AP4) the captured position agrees when
    it lies in the twins' range over the round trip (0.5 ms here, opened 2 ms earlier by the
    default clock lag; the twins start the move at either end of the MVP's window); the position
    tolerance widens that range by exactly its value (last valid and first invalid), and a time
    tolerance widens the interval (0.02 s = 1024 µsteps more)."""
    path = record(tmp_path / "c.jsonl", MOVE)
    actual = lambda r: r.get("kind") == "reply" and r.get("parameter") == "actual_position"  # noqa: E731
    captured = next(json.loads(x)["value"] for x in path.read_text().splitlines() if actual(json.loads(x)))
    assert replay(path, "TMCM-6212").ok
    edit(path, actual, value=captured + 1000)
    report = replay(path, "TMCM-6212")
    assert report.parameters == ["actual_position"]
    low, high = map(int, report.divergences[0].virtual.split(".."))
    # the read's window and the MVP's both span 2.5 ms; the twins act at either end of the MVP's
    assert low <= captured <= high and high - low == round(51200 * 2 * (0.0005 + 0.002))
    edit(path, actual, value=high + 1000)
    assert replay(path, "TMCM-6212", tolerance=["position=1000"]).ok
    assert not replay(path, "TMCM-6212", tolerance=["position=999"]).ok
    assert replay(path, "TMCM-6212", tolerance={"time": 0.02}).ok


def test_status_divergence_and_missing_reply(tmp_path):
    """Manual 3.2.1: status codes are compared; a reply the module sent but the capture lacks diverges."""
    path = record(tmp_path / "c.jsonl", [(0.1, (5, 4, 0, 51200)), (0.2, (6, 6, 0, 0))])
    edit(path, lambda r: r.get("kind") == "reply" and r.get("command") == 5, status=4)
    lines = [x for x in path.read_text().splitlines() if '"command": 6' not in x or '"dir": "host"' in x]
    path.write_text("\n".join(lines) + "\n")
    report = replay(path, "TMCM-6212")
    whats = [(d.what, d.parameter) for d in report.divergences]
    assert whats == [("status", "max_positioning_speed"), ("reply", "max_current")]


def test_events_are_compared_in_order(tmp_path):
    """Manual 3.6.35: 138 then MVP: one event with the motor mask when the target is reached; the
    captured event agrees when the twin's arrival lies at most the event latency (0.05 s) before it."""
    steps = [(0.1, (138, 0, 0, 1)), (0.2, (4, 0, 0, 1000)), (3.0, (6, 1, 0, 0))]
    path = record(tmp_path / "c.jsonl", steps)
    report = replay(path, "TMCM-6212")
    assert report.ok and report.events == 1
    event_t = next(json.loads(x)["t"] for x in path.read_text().splitlines() if '"event"' in x)
    edit(path, lambda r: r.get("kind") == "event", t=event_t + 0.06)
    assert [d.what for d in replay(path, "TMCM-6212").divergences] == ["event time"]
    assert replay(path, "TMCM-6212", tolerance=["latency=0.07"]).ok
    edit(path, lambda r: r.get("kind") == "event", t=event_t, value=2)
    assert [d.what for d in replay(path, "TMCM-6212").divergences] == ["event"]
    lines = [x for x in path.read_text().splitlines() if '"event"' not in x]
    path.write_text("\n".join(lines) + "\n")
    report = replay(path, "TMCM-6212")
    assert [(d.what, d.captured) for d in report.divergences] == [("event", "no event")]


def test_an_address_without_requests_is_bad_input_not_agreement(tmp_path):
    """docs/capture.md: exit 0 means "all agree"; a replay that compared nothing (a mistyped
    --address) proves nothing, so it is bad input: ReplayError, exit 2 with one line naming the
    addresses the capture has. (Old code: 0 replies compared, "all replies agree", exit 0.)"""
    path = record(tmp_path / "c.jsonl", MOVE)
    with pytest.raises(ReplayError, match=r"no request to address 2 .*requests go to 1\)"):
        replay(path, "TMCM-6212", address=2)
    done = cli("replay", str(path), "--module", "TMCM-6212", "--address", "2")
    assert done.returncode == 2 and done.stdout == "" and len(done.stderr.splitlines()) == 1
    assert "no request to address 2" in done.stderr


@pytest.mark.parametrize("spec", ["speed=1", "position", "position=-1", "position=inf", "time=x", "latency=nan"])
def test_bad_tolerances(spec, tmp_path):
    with pytest.raises(ReplayError):
        Tolerance.parse([spec])
    key, _, value = spec.partition("=")
    with pytest.raises(ReplayError):
        replay(record(tmp_path / "d.jsonl", MOVE), "TMCM-6212", tolerance={key: value})
    done = cli("replay", str(record(tmp_path / "c.jsonl", MOVE)), "-m", "TMCM-6212", "--tolerance", spec)
    assert done.returncode == 2 and len(done.stderr.splitlines()) == 1


def test_api_helper_and_unknown_module(tmp_path):
    path = record(tmp_path / "c.jsonl", MOVE)
    assert opentmcl.replay is replay
    assert assert_replays(path, "TMCM-6212").ok
    edit(path, lambda r: r.get("parameter") == "max_current" and r["dir"] == "module", value=1)
    with pytest.raises(AssertionError, match=r"max_current"):
        assert_replays(path, "TMCM-6212")
    with pytest.raises(ReplayError, match="unknown module"):
        replay(path, "TMCM-9999")
    with pytest.raises(ReplayError, match="does not identify"):
        replay(path)
    done = cli("replay", str(path), "--module", "TMCM-9999")
    assert done.returncode == 2 and "unknown module" in done.stderr


def test_eeprom_file_gives_the_replayed_module_its_stored_state(tmp_path):
    """PD86-1180 manual 4.6.7 (STAP): a stored axis parameter is restored at power-up; a capture of a
    module with max_current stored as 77 agrees only with a twin that powers up from that EEPROM."""
    eeprom = tmp_path / "module.eeprom"
    vm = VirtualModule("PD86-1180", address=1, eeprom=eeprom)
    assert vm.request(5, 6, 0, 77).status == 100 and vm.request(7, 6, 0, 0).status == 100
    vm.close()
    path = record(tmp_path / "c.jsonl", [(0.1, (6, 6, 0, 0))], name="PD86-1180")
    edit(path, lambda r: r.get("kind") == "reply", value=77)  # what the module with that EEPROM said
    assert replay(path, "PD86-1180").parameters == ["max_current"]
    done = cli("replay", str(path), "--module", "PD86-1180", "--eeprom", str(eeprom))
    assert done.returncode == 0, done.stdout + done.stderr


def test_the_replayed_module_follows_a_new_address(tmp_path):
    """TMCM-6212 manual 3.6.7 example: SGP 66, 0, 3 gives the module address 3; the next requests go
    to address 3 and must be replayed, not skipped."""
    vm = VirtualModule("TMCM-6212", address=1)
    decoder = Decoder(lambda a: vm.profile)
    out = [HEADER]
    for t, (address, fields) in enumerate([(1, (9, 66, 0, 3)), (3, (6, 6, 0, 0)), (1, (6, 6, 0, 0))]):
        frame = Request(address, *fields).encode()
        out += [{"record": "frame", **r} for r in decoder.feed(t, HOST, frame)]
        out += [{"record": "frame", **r} for r in decoder.feed(t + 0.001, MODULE, vm.handle(frame))]
    path = tmp_path / "c.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in out))
    report = replay(path, "TMCM-6212")
    assert report.ok and report.compared == 2 and report.skipped == 1
    edit(path, lambda r: r.get("kind") == "reply" and r.get("address") == 3, value=1)
    assert replay(path, "TMCM-6212").parameters == ["max_current"]


def test_capture_of_a_sim_profile_file_replays_against_that_file(tmp_path):
    """docs/capture.md: "default: the module the capture identified". Behind
    `proxy --to sim:///path/my.toml` the identity is the file's module name, which no built-in has;
    the default is then the target's file (old code: "unknown module 'MY-6212'", exit 2). A changed
    default of AP 4 (TMCM-6212 manual 3.6.6 GAP) in the file is seen, with its firmware string (manual 3.6.36: 136)."""
    profile = tmp_path / "my.toml"
    profile.write_text('extends = "TMCM-6212"\n[module]\nname = "MY-6212"\nfirmware_version = "6212V999"\n'
                       '[[axis_parameter]]\nnumber = 4\ndefault = 1234\n')
    with Tool("proxy", "--to", f"sim://{profile}", "--tcp", "127.0.0.1:0", "--log", str(tmp_path / "c.jsonl")) as px:
        assert cli("send", "136 0, 0, 0", "--plain", "--to", px.endpoint("tcp")).stdout.strip() == "6212V999"
        assert cli("send", "GAP 4, 0", "--plain", "--to", px.endpoint("tcp")).stdout.strip() == "1234"
    done = cli("replay", str(tmp_path / "c.jsonl"))
    assert done.returncode == 0 and "against MY-6212 at address 1" in done.stdout, done.stdout + done.stderr
    assert cli("replay", str(tmp_path / "c.jsonl"), "--module", "TMCM-6212").returncode == 1


@pytest.mark.parametrize("firmware, binary, note", [
    ("6212V999", None, "firmware '6212V999' matches no built-in profile"),
    ("ABCDV999", 0x18440999, "firmware 'ABCDV999' matches no built-in profile"),
])
def test_replay_without_module_falls_back_to_the_module_number(tmp_path, firmware, binary, note):
    """Issue 30 item 7: `replay` without --module takes the built-in profile of the same module
    number, as `profile probe` does: the digits before "V" of the firmware string (136 type 0), else
    the upper 16 bits of the binary version (136 type 1: 0x1844 = 6212; TMCM-6212 manual 3.6.36).
    The replay says so and still compares the firmware string (a divergence by name)."""
    profile = tmp_path / "other.toml"
    extra = f"firmware_binary = {binary}\n" if binary is not None else ""
    profile.write_text(f'extends = "TMCM-6212"\n[module]\nname = "OTHER"\nfirmware_version = "{firmware}"\n{extra}')
    path = record(tmp_path / "c.jsonl", [(0.1, (136, 0, 0, 0)), (0.2, (136, 1, 0, 0)), (0.3, (6, 4, 0, 0))],
                  name=str(profile))
    done = cli("replay", str(path))
    assert done.returncode == 1, done.stdout + done.stderr
    assert f"note: {note}: replaying against TMCM-6212, the same module number" in done.stdout
    roots = [line for line in done.stdout.splitlines() if line.startswith("t=")]
    assert f"firmware string: captured '{firmware}', virtual '6212V105'" in roots[0]
    nothing = tmp_path / "none.toml"
    nothing.write_text('extends = "TMCM-6212"\n[module]\nname = "NONE"\nfirmware_version = "ABCDV999"\n'
                       "firmware_binary = 0x12340001\n")
    path = record(tmp_path / "n.jsonl", [(0.1, (136, 0, 0, 0)), (0.2, (136, 1, 0, 0))], name=str(nothing))
    with pytest.raises(ReplayError, match="does not identify its module"):
        replay(path)
