"""Issue 30 "Done when", on real processes: a "real" module is played by `opentmcl serve` with a
profile that plants four differences from the TMCM-6212 (tests/capture/recorder.py PLANTED: a
changed default, a narrower range, another firmware string, a ramp that does not follow AP5);
`opentmcl conform --allow-motion` and its report name exactly those, with no false divergence,
over a pty paced at 9600 baud and over TCP, and the same run against an unchanged twin agrees
everywhere. Also: read-only by default, and MST to every axis on an error and on Ctrl-C."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import pytest

from opentmcl import VirtualModule
from opentmcl.capture import read_capture

from .helpers import Tool, cli
from .recorder import PLANTED

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")

MOTION = ["--module", "TMCM-6212", "--allow-motion", "--max-travel", "20000", "--axes", "0",
          "--max-speed", "40000", "--max-accel", "204800", "--clock-lag", "0.05"]
"""Moves of up to 20000 µsteps at up to 40000 pps and 204800 pps^2, four times the 51200 pps^2
the planted module's ramp keeps to. A served module answers from a clock up to 2 ms behind the
wall clock, more while a loaded machine keeps its process waiting: 50 ms allowed."""
CAUSES = ["identity: 136 0 (firmware string): firmware string",
          "parameters: axis 0: GAP 194, 0 [reference_search_speed]: value",
          "status codes: axis 0: SAP 4, 0, 7999774 [max_positioning_speed]: status"]


def stood(url: str) -> str:
    """Wait until the served module has stood past its power-down delay (TMCM-6212 AP214: 2 s) and
    reads the standby current a real module that was switched on a while ago reads (AP180; the
    twins then stand too, docs/capture.md): a condition, polled up to 30 s."""
    vm = VirtualModule("TMCM-6212", address=1)
    vm.advance(10)
    standby = str(vm.request(6, 180, 0, 0).value)
    deadline = time.monotonic() + 30
    while cli("send", "GAP 180, 0", "--plain", "--to", url).stdout.strip() != standby:
        assert time.monotonic() < deadline, "the served module never reached its standby current"
    return url


def conform(url: str, tmp, name: str, *extra: str):
    done = cli("conform", url, *MOTION, "--capture", str(tmp / f"{name}.jsonl"), "--report",
               str(tmp / f"{name}.json"), *extra, timeout=600)
    assert done.returncode in (0, 1), done.stdout + done.stderr
    return done, json.loads((tmp / f"{name}.json").read_text())


def assert_planted(done, data) -> None:
    """Exactly the four planted differences, every other divergence a repeat or knock-on of them."""
    assert done.returncode == 1
    titles = [c["title"] for c in data["causes"]]
    assert [t.split(" (")[0] if t.endswith("times)") else t for t in titles[:3]] == CAUSES and len(titles) == 4, titles
    assert titles[3].startswith("move durations: axis 0: MVP ABS, 0, 20000: duration"), titles
    module, twin = data["accelerations"]["0"]["acceleration"].values()
    assert module < twin / 2 and "acceleration about" in data["causes"][3]["note"]   # 51200 against 204800
    assert data["causes"][0]["root"]["captured"] == "'6212V200'"
    assert sum(1 + len(c["repeats"]) + len(c["knock_on"]) for c in data["causes"]) == len(data["divergences"])
    moves = [m for m in data["moves"] if m["request"] == "MVP ABS, 0, 20000"]
    assert moves and all(m["percent"] > 20 and not m["ok"] for m in moves)   # measurably longer
    assert data["areas"]["parameters"]["agree"] == data["areas"]["parameters"]["checks"] - 2   # AP194 twice
    assert "agreement" not in done.stderr and "capture: " in done.stdout


@pytest.fixture(scope="module")
def planted(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("conform")
    (tmp / "planted.toml").write_text(PLANTED)
    return tmp


def test_conform_over_a_pty_paced_at_9600_baud_names_exactly_the_planted_differences(planted):
    """The one long run (about 30 s): every frame takes 9.375 ms on the wire each way."""
    with Tool("serve", "--module", str(planted / "planted.toml"), "--pty", "--pace") as served:
        url = stood(f"serial://{served.endpoint('pty')}?baud=9600")
        done, data = conform(url, planted, "pty", "--html", str(planted / "html"))
    assert_planted(done, data)
    cap = read_capture(planted / "pty.jsonl")
    assert cap.link == {"interface": "serial", "baud": 9600, "frame_time": 0.009375}
    assert [m["phase"] for m in cap.marks][:5] == ["identity", "survey", "survey", "edges", "edges"]
    assert (planted / "html" / "index.html").exists()
    writes = [r for r in cap.frames if r["kind"] == "request" and r["command"] == 5 and r["type"] in (4, 5, 17)]
    first = {r["type"]: r for r in reversed(writes)}
    reads = {r["type"]: r["n"] for r in cap.frames if r["kind"] == "request" and r["command"] == 6}
    assert writes[-1]["t"] > cap.marks[-1]["t"] and cap.marks[-1]["phase"] == "restore"
    assert {r["type"]: r["value"] for r in writes[-3:]} == {4: 51200, 5: 51200, 17: 51200}  # as found
    assert first and reads


def test_conform_over_tcp_planted_and_unchanged(planted):
    """Over TCP (no wire time known) the same four differences; against an unchanged TMCM-6212 the
    same run agrees in every area (exit 0)."""
    with Tool("serve", "--module", str(planted / "planted.toml"), "--tcp", "127.0.0.1:0", "--idle-timeout", "0") as served:
        done, data = conform(stood(served.endpoint("tcp")), planted, "tcp")
    assert_planted(done, data)
    with Tool("serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--idle-timeout", "0") as served:
        done, data = conform(stood(served.endpoint("tcp")), planted, "same")
    assert done.returncode == 0, done.stdout
    assert data["ok"] and not data["causes"] and "all replies agree" in done.stdout
    assert all(a["agree"] == a["checks"] for a in data["areas"].values())
    assert all(data["areas"][area]["checks"] for area in ("identity", "parameters", "status codes",
                                                           "move durations", "ramp shape", "programs"))


def test_conform_is_read_only_by_default(tmp_path):
    """Without --allow-writes or --allow-motion only 136, GAP, GGP and GIO are sent."""
    with Tool("serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--idle-timeout", "0") as served:
        done = cli("conform", stood(served.endpoint("tcp")), "--module", "TMCM-6212", "--capture",
                   str(tmp_path / "r.jsonl"))
    assert done.returncode == 0, done.stdout + done.stderr
    sent = {r["command"] for r in read_capture(tmp_path / "r.jsonl").frames if r["kind"] == "request"}
    assert sent == {6, 10, 15, 136}
    bad = cli("conform", served.endpoint("tcp"), "--module", "TMCM-6212", "--allow-motion")
    assert bad.returncode == 2 and len(bad.stderr.splitlines()) == 1 and "--max-travel" in bad.stderr


def _stops_after(cap, t: float) -> list[int]:
    return [r["motor"] for r in cap.frames if r["kind"] == "request" and r["command"] == 3 and r["t"] >= t]


def test_an_error_or_ctrl_c_sends_mst_to_every_axis_first(tmp_path):
    """A program already running is an error before anything moves; Ctrl-C (SIGINT) in the middle
    of the moves. Either way MST goes to all six axes (TMCM-6212 manual 3.6.3) before the settings
    are restored; exit 2 with one line, and 130 after Ctrl-C."""
    with Tool("serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--idle-timeout", "0") as served:
        url = served.endpoint("tcp")
        for text in ("132 0, 0, 0", "WAIT TICKS, 0, 1000", "28 0, 0, 0", "133 0, 0, 0", "129 0, 0, 0"):
            assert cli("send", text, "--to", url).returncode == 0, text
        done = cli("conform", url, *MOTION, "--capture", str(tmp_path / "e.jsonl"))
        assert done.returncode == 2 and "a TMCL program is running" in done.stderr.splitlines()[-1]
        cap = read_capture(tmp_path / "e.jsonl")
        assert _stops_after(cap, 0.0) == [0, 1, 2, 3, 4, 5] and [m["phase"] for m in cap.marks] == ["identity",
                                                                                                   "restore"]
        assert cli("send", "128 0, 0, 0", "--to", url).returncode == 0   # stop the program
        log = tmp_path / "c.jsonl"
        # a first move far longer than the wait for its mark, so the Ctrl-C lands inside the run
        # even on a busy machine (with MOTION's 20000 µsteps the run could end before it)
        long = [("2000000" if a == "20000" else a) for a in MOTION]
        # SIGINT as at a terminal: a shell that starts jobs in the background (CI's, `nohup ... &`)
        # hands them SIGINT ignored, and a Python started so keeps it ignored
        proc = subprocess.Popen([sys.executable, "-m", "opentmcl", "conform", url, *long, "--capture", str(log)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        deadline = time.monotonic() + 60
        while not (log.exists() and '"phase":"move"' in log.read_text()):
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=60)
    assert proc.returncode == 130
    cap = read_capture(log)
    move = next(m["t"] for m in cap.marks if m["phase"] == "move")
    stops = _stops_after(cap, move)
    assert stops[-6:] == [0, 1, 2, 3, 4, 5]
