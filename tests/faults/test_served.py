"""Every fault kind on a real served process (issue 34, "Every fault kind has a test on a real
served process ... checked through the wire"): ``opentmcl serve --faults FILE --fault-control
PATH`` with a PD86-1180 at address 1 and a TMCM-6212 at address 2 on one bus, served on TCP and on
a pty that stands for the RS-485 line; each fault triggered by name through the control socket
(server/control.py; `opentmcl fault`), its effect read back with the host library over the wire.

Real time: a request expected to get no reply waits a short time-out (`LOST`); every other waits
a generous one (`WAIT`), so that a busy machine only makes the tests slower; conditions are polled
with generous deadlines."""
from __future__ import annotations

import sys
import time

import pytest

import opentmcl
from opentmcl.host import TmclChecksumError, TmclStatusError, TmclTimeout
from opentmcl.server.control import ask

from ..capture.helpers import Tool, cli
from .helpers import GAP, MVP, SAP, STAP, plan_file

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals and Unix sockets need POSIX")

LOST = 0.3
"""Seconds a request whose reply the test expects to be lost waits for it."""
WAIT = 5.0
"""Seconds every other request may wait for its reply (also behind a late one)."""

PLAN = [
    {"name": "drop-request", "kind": "drop_request"},
    {"name": "drop-reply", "kind": "drop_reply"},
    {"name": "garble-request", "kind": "corrupt_request", "byte": 7},
    {"name": "garble-reply", "kind": "corrupt_reply", "byte": 7},
    {"name": "slow", "kind": "delay", "delay": 0.3},
    {"name": "slower", "kind": "delay", "delay": 1.0},
    {"name": "split", "kind": "split_request", "pieces": 3, "gap": 0.02},
    {"name": "split-lost", "kind": "split_request", "pieces": 3, "gap": 0.5},
    {"name": "split-reply", "kind": "split_reply", "pieces": 3, "gap": 0.1},
    {"name": "down", "kind": "link_down", "duration": 1.0},
    {"name": "power", "kind": "power_loss", "address": 1, "duration": 0.3},
    {"name": "hang", "kind": "hang", "address": 1, "duration": 1.0},
    {"name": "warm", "kind": "overtemperature", "address": 2, "level": "prewarning", "duration": 0.5},
    {"name": "hot", "kind": "overtemperature", "address": 2, "axis": 1, "duration": 1.0},
    {"name": "stuck", "kind": "stuck_switch", "address": 2, "switch": "left", "duration": 0.5},
    {"name": "bounce", "kind": "bouncing_switch", "address": 2, "switch": "home", "bounces": 2, "period": 0.5},
    {"name": "load", "kind": "step_loss", "address": 2, "axis": 2, "load": 3.0, "duration": 5.0},
]


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("served")
    control = tmp / "control.sock"
    tool = Tool("serve", "-m", "PD86-1180", "-a", "1", "-m", "TMCM-6212", "-a", "2", "--tcp", "127.0.0.1:0",
                "--pty", "--gap", "0.1", "--faults", str(plan_file(tmp, PLAN, seed=3)),
                "--fault-control", str(control))
    try:
        yield tool, str(control)
    finally:
        tool.stop()


@pytest.fixture
def tcp(served):
    tool, _ = served
    m = opentmcl.connect(tool.endpoint("tcp"), address=1, timeout=WAIT, profile="PD86-1180")
    yield m
    m.close()


def fire(served, name: str) -> None:
    out = ask(served[1], f"trigger {name}")
    assert out["ok"], out


def until(check, seconds: float = 10.0) -> None:
    deadline = time.monotonic() + seconds
    while not check():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.05)


def test_the_plan_is_announced(served):
    tool, _ = served
    assert any(line.startswith("faults: 17 armed, seed 3") for line in tool.lines)


def test_drop_request_and_drop_reply(served, tcp):
    """drop_request: the SAP never reaches the module (GAP reads the old value); drop_reply: the
    SAP is done but not answered."""
    tcp.request(SAP, 4, 0, 100)
    fire(served, "drop-request")
    with pytest.raises(TmclTimeout):
        tcp.request(SAP, 4, 0, 200, timeout=LOST)
    assert tcp.request(GAP, 4, 0).value == 100
    fire(served, "drop-reply")
    with pytest.raises(TmclTimeout):
        tcp.request(SAP, 4, 0, 300, timeout=LOST)
    assert tcp.request(GAP, 4, 0).value == 300


def test_garbled_request_and_reply(served, tcp):
    """A garbled request is answered with status 1 (wrong checksum) and not done; a garbled reply
    is a checksum error naming the request."""
    tcp.request(SAP, 4, 0, 100)
    fire(served, "garble-request")
    with pytest.raises(TmclStatusError) as info:
        tcp.request(SAP, 4, 0, 400)
    assert info.value.status == 1
    assert tcp.request(GAP, 4, 0).value == 100
    fire(served, "garble-reply")
    with pytest.raises(TmclChecksumError, match="GAP 4, 0"):
        tcp.request(GAP, 4, 0, timeout=LOST)
    assert tcp.request(GAP, 4, 0).value == 100


def test_delays(served, tcp):
    """A reply 0.3 s late still comes; one 1 s late is a time-out, and is not taken for the reply to
    the next request (sent while it is still on its way: the fence reads past it)."""
    fire(served, "slow")
    start = time.monotonic()
    assert tcp.request(GAP, 4, 0).status == 100
    assert time.monotonic() - start >= 0.3
    tcp.request(SAP, 4, 0, 111)
    fire(served, "slower")
    with pytest.raises(TmclTimeout):
        tcp.request(GAP, 5, 0, timeout=LOST)
    assert tcp.request(GAP, 4, 0).value == 111


def test_split_frames_and_the_frame_gap(served, tcp):
    """A request in pieces 20 ms apart is assembled (the server's --gap is 0.1 s); 0.5 s apart the
    partial frame is dropped: no reply, nothing done. A reply in pieces is read whole."""
    fire(served, "split")
    assert tcp.request(SAP, 4, 0, 222).status == 100
    fire(served, "split-lost")
    with pytest.raises(TmclTimeout):
        tcp.request(SAP, 4, 0, 333, timeout=0.8)
    # The last piece reaches the module 1 s after the request was sent; bytes sent right behind it
    # (the next request's fence) would complete that partial frame, torn, as on a real line: wait
    # until the partial has been silent for more than the gap.
    time.sleep(0.5)
    fire(served, "split-reply")
    assert tcp.request(GAP, 4, 0).value == 222


def test_link_down_on_the_rs485_pty(served):
    """link_down for 1 s on every link: a request on the pty (RS-485, module 2) is lost, then it
    answers again."""
    tool, _ = served
    m = opentmcl.connect(f"serial://{tool.endpoint('pty')}", address=2, timeout=WAIT, profile="TMCM-6212")
    try:
        assert m.request(10, 66, 0).value == 2
        fire(served, "down")
        with pytest.raises(TmclTimeout):
            m.request(10, 66, 0, timeout=LOST)
        time.sleep(1.0)
        assert m.request(10, 66, 0).value == 2
    finally:
        m.close()


def test_power_loss(served, tcp):
    """Power lost for 0.3 s: nothing answers meanwhile; then RAM parameters are back to their
    stored values (AP4: not stored, back to its default; AP5: STAP'd)."""
    default = tcp.axes[0].param(4).default
    tcp.request(SAP, 4, 0, default - 5)
    tcp.request(SAP, 5, 0, 777)
    tcp.request(STAP, 5, 0)
    fire(served, "power")
    with pytest.raises(TmclTimeout):
        tcp.request(GAP, 4, 0, timeout=0.1)
    time.sleep(0.4)
    assert tcp.request(GAP, 4, 0).value == default
    assert tcp.request(GAP, 5, 0).value == 777


def test_hang(served, tcp):
    """The firmware answers nothing for 1 s, then answers again."""
    fire(served, "hang")
    with pytest.raises(TmclTimeout):
        tcp.request(10, 66, 0, timeout=0.3)
    until(lambda: _answers(tcp), 10)


def _answers(m) -> bool:
    try:
        return m.request(10, 66, 0, timeout=0.2).value == 1
    except TmclTimeout:
        return False


@pytest.fixture
def six(served):
    tool, _ = served
    m = opentmcl.connect(tool.endpoint("tcp"), address=2, timeout=WAIT, profile="TMCM-6212")
    yield m
    m.close()


def test_overtemperature(served, six):
    """Pre-warning: AP208 bit 2 only, for 0.5 s. Shutdown on axis 1: bits 1 and 2, and the driver is
    off: the encoder (AP209) stands while the counter (AP1) runs on; the flags clear once cooled."""
    fire(served, "warm")
    assert six.request(GAP, 208, 0).value & 0x06 == 0x04
    until(lambda: six.request(GAP, 208, 0).value & 0x06 == 0)
    six.request(1, 0, 1, 20000)   # ROR 1, 20000
    fire(served, "hot")
    assert six.request(GAP, 208, 1).value & 0x06 == 0x06
    encoder, counter = six.request(GAP, 209, 1).value, six.request(GAP, 1, 1).value
    until(lambda: six.request(GAP, 1, 1).value > counter + 2000)
    assert six.request(GAP, 209, 1).value == encoder
    six.request(3, 0, 1)          # MST 1
    until(lambda: six.request(GAP, 208, 1).value & 0x06 == 0)


def test_switches(served, six):
    """The left switch stuck at 1 for 0.5 s (AP11), the home switch bouncing (AP9: 1, then 0)."""
    fire(served, "stuck")
    assert six.request(GAP, 11, 0).value == 1
    until(lambda: six.request(GAP, 11, 0).value == 0)
    fire(served, "bounce")
    assert six.request(GAP, 9, 0).value == 1
    until(lambda: six.request(GAP, 9, 0).value == 0)


def test_lost_steps(served, six):
    """A load beyond the motor's torque on axis 2 while it moves: the deviation check (AP212) sees
    the encoder fall behind and stops the motor (AP207 bit 2 "deviation error")."""
    six.request(SAP, 212, 2, 2000)
    fire(served, "load")
    six.request(MVP, 0, 2, 10_000_000)
    until(lambda: six.request(GAP, 207, 2).value & 2)   # reading AP207 clears it: read until it is set
    assert six.request(GAP, 3, 2).value == 0
    assert six.request(GAP, 1, 2).value - six.request(GAP, 209, 2).value > 2000


def test_the_cli_triggers_and_lists(served, tcp):
    """`opentmcl fault NAME --control PATH` fires it; `--list` shows it; an unknown name is one line
    and exit 2."""
    out = cli("fault", "drop-reply", "--control", served[1])
    assert out.returncode == 0 and out.stdout.strip() == "drop-reply: fired"
    with pytest.raises(TmclTimeout):
        tcp.request(GAP, 4, 0, timeout=LOST)
    listed = cli("fault", "--list", "--control", served[1])
    assert listed.returncode == 0 and "drop-reply (drop_reply): reply to GAP 4, 0 dropped" in listed.stdout
    bad = cli("fault", "no-such", "--control", served[1])
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "no fault named 'no-such'" in bad.stderr
