"""Issue 30 items 1 and 2: a moving value is compared over the whole interval in which the module
could have sampled it, and each request acts inside the window the capture's timestamps and link
speed give (capture/timing.py, capture/twin.py; docs/capture.md "Replay").

Captures are recorded from a virtual module (tests/capture/recorder.py) that samples or acts at a
chosen instant inside the round trip, as a real module would; the twins do not know that instant."""
from __future__ import annotations

import json

from opentmcl import VirtualModule
from opentmcl.capture import replay
from opentmcl.capture.timing import link_record

from .recorder import CLOCK_HZ, Recorder, edit, reply_of

SETUP = [(0.0, (5, 5, 0, 204800)), (0.01, (5, 4, 0, 51200))]
"""SAP 5 (max acceleration) 204800 pps^2, SAP 4 (max positioning speed) 51200 pps; AP17 (max
deceleration) keeps its 51200 pps^2 default (TMCM-6212 manual 4.1)."""
LINK_9600 = link_record("serial", 9600)


def turning_time(start: float, reverse: float) -> float:
    """When the axis stops to turn back: MVP ABS 30000 at `start`, MVP ABS -30000 at `reverse`."""
    vm = VirtualModule("TMCM-6212", address=1)
    for t, fields in [*SETUP, (start, (4, 0, 0, 30000)), (reverse, (4, 0, 0, -30000))]:
        vm.advance_to(round(t * CLOCK_HZ))
        vm.request(*fields)
    while vm.request(6, 3, 0, 0).value > 0:
        vm.advance(vm.next_event_in())
    return vm.time


def test_a_turning_point_inside_the_round_trip_is_part_of_the_range(tmp_path):
    """Problem 1: values checked at three instants missed peaks. The module samples the position at
    the turning point of a reversal (TMCM-6212 manual 3.6.4 MVP ABS while moving) inside a 0.3 s
    round trip: that peak agrees; one µstep beyond it diverges (the last valid and the first
    invalid value). The module reversed at the late end of its window, where the twin that
    reaches furthest reverses too, so the twins' highest value is exactly the module's peak."""
    turn = turning_time(0.02, 0.2205)
    rec = Recorder()
    for t, fields in [*SETUP, (0.02, (4, 0, 0, 30000))]:
        rec.request(t, fields)
    rec.request(0.22, (4, 0, 0, -30000), act=0.0005)   # the reversal as late as its window allows
    rec.request(0.85, (6, 1, 0, 0), act=turn - 0.85, rtt=0.3)
    path = rec.write(tmp_path / "c.jsonl")
    read = lambda r: r.get("parameter") == "actual_position"  # noqa: E731
    peak = reply_of(path, read)["value"]
    assert replay(path, "TMCM-6212", clock_lag=0).ok
    edit(path, lambda r: r.get("kind") == "reply" and read(r), value=peak + 1)
    report = replay(path, "TMCM-6212", clock_lag=0)
    assert report.parameters == ["actual_position"] and report.divergences[0].virtual.endswith(f"..{peak}")


def test_the_top_speed_of_a_short_move_is_part_of_the_range(tmp_path):
    """A move too short to reach AP4 turns from acceleration to deceleration at its top speed
    (manual 4.1, AP3 actual speed); the module reads AP3 there, inside a 0.2 s round trip."""
    probe = VirtualModule("TMCM-6212", address=1)
    for t, fields in [*SETUP, (0.1, (4, 0, 0, 4000))]:
        probe.advance_to(round(t * CLOCK_HZ))
        probe.request(*fields)
    probe.advance(probe.next_event_in())   # the end of the acceleration: the top speed
    top_at, top = probe.time, probe.request(6, 3, 0, 0).value
    rec = Recorder()
    for t, fields in [*SETUP, (0.1, (4, 0, 0, 4000))]:
        rec.request(t, fields)
    rec.request(0.11, (6, 3, 0, 0), act=top_at - 0.11, rtt=0.2)
    path = rec.write(tmp_path / "c.jsonl")
    assert reply_of(path, lambda r: r.get("parameter") == "actual_speed")["value"] == top > 0
    assert replay(path, "TMCM-6212").ok
    edit(path, lambda r: r.get("parameter") == "actual_speed" and r.get("kind") == "reply", value=top + 1)
    assert replay(path, "TMCM-6212").parameters == ["actual_speed"]


def test_the_window_starts_when_the_request_has_crossed_the_wire(tmp_path):
    """The module cannot sample before the request's last byte arrived: at 9600 baud (9 bytes of
    10 bits, 9.375 ms) a position the axis had when the request's first byte left the proxy, 480
    µsteps earlier at 51200 pps, diverges; without a recorded link speed the window is the whole
    round trip and it agrees (clock lag 0: the module's clock is the host's)."""
    rec = Recorder(link=LINK_9600)
    for t, fields in [*SETUP, (0.02, (4, 0, 0, 200000))]:
        rec.request(t, fields, act=0.0094, rtt=0.03)
    rec.request(2.0, (6, 1, 0, 0), act=0.0, rtt=0.03)   # sampled too early for this link
    path = rec.write(tmp_path / "c.jsonl")
    assert replay(path, "TMCM-6212", clock_lag=0).parameters == ["actual_position"]
    lines = [json.loads(x) for x in path.read_text().splitlines()]
    lines[0].pop("link")
    path.write_text("".join(json.dumps(r) + "\n" for r in lines))
    assert replay(path, "TMCM-6212", clock_lag=0).ok


def test_an_mst_takes_effect_where_the_module_could_have_stopped(tmp_path):
    """Problem 2: an MST whose reply took 92 ms (TMCM-6212 manual 3.6.3) stopped the axis somewhere
    in that window; the twins stop it at both ends, so the resting position the host reads later
    agrees wherever the module acted, and one µstep beyond the later end diverges. At 9600 baud a
    module that acted 2 ms after the first byte, before the frame could have arrived, diverges."""
    steps = [*SETUP, (0.02, (1, 0, 0, 20000))]
    for act in (0.0, 0.03, 0.092):
        rec = Recorder()
        for t, fields in steps:
            rec.request(t, fields)
        rec.request(1.0, (3, 0, 0, 0), act=act, rtt=0.092)
        rec.request(2.0, (6, 1, 0, 0))
        path = rec.write(tmp_path / f"mst{act}.jsonl")
        assert replay(path, "TMCM-6212", clock_lag=0).ok, act
    rest = reply_of(path, lambda r: r.get("parameter") == "actual_position")["value"]
    edit(path, lambda r: r.get("kind") == "reply" and r.get("parameter") == "actual_position", value=rest + 1)
    report = replay(path, "TMCM-6212", clock_lag=0)
    assert report.parameters == ["actual_position"] and report.divergences[0].virtual.endswith(f"..{rest}")
    rec = Recorder(link=LINK_9600)
    for t, fields in steps:
        rec.request(t, fields, act=0.0094, rtt=0.03)
    rec.request(1.0, (3, 0, 0, 0), act=0.002, rtt=0.03)
    rec.request(2.0, (6, 1, 0, 0), act=0.0094, rtt=0.03)
    assert replay(rec.write(tmp_path / "early.jsonl"), "TMCM-6212", clock_lag=0).parameters == ["actual_position"]
