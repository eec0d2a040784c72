"""Issue 29 ("Fidelity, third pass"), items 1, 3-8 and 10, against served modules: an in-process
`Server` with a real pseudo-terminal (a client speaking 9-byte frames through pyserial), or
`opentmcl serve` in a subprocess. Each test quotes the manual it pins. Item 2 (odemis) is
tests/server/test_odemis.py, item 9 (documents) docs/tmcl-assembler.md and docs/assumptions.md.
"""
from __future__ import annotations

import re
import sys
import time

import pytest
import serial

from opentmcl import VirtualModule
from opentmcl.lang import assemble
from opentmcl.protocol.frame import Reply, Request
from opentmcl.server import PtyServer, Server

from ..capture.helpers import cli

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")

WAIT = 30.0  # seconds a condition may take on a loaded machine; nothing here is timed
MST, MVP, SAP, GAP, SGP, GGP, GIO = 3, 4, 5, 6, 9, 10, 15
RUN, DOWNLOAD, END_DOWNLOAD, READ_MEMORY, STATUS, VERSION = 129, 132, 133, 134, 135, 136


class Link:
    """A host on the served port: whole 9-byte frames out, replies in (pyserial on the pty)."""

    def __init__(self, path: str, address: int = 1) -> None:
        self.port = serial.Serial(path, 9600, timeout=0.2)
        self.address = address
        self.unsolicited: list[Reply] = []

    def send(self, command: int, type_: int = 0, motor: int = 0, value: int = 0, address: int | None = None) -> None:
        self.port.write(Request(self.address if address is None else address, command, type_, motor,
                                value).encode())

    def read(self, n: int = 9) -> bytes:
        deadline, buf = time.monotonic() + WAIT, b""
        while len(buf) < n and time.monotonic() < deadline:
            buf += self.port.read(n - len(buf))
        assert len(buf) == n, f"wanted {n} bytes, got {buf!r}"
        return buf

    def reply(self) -> Reply:
        """The next reply; unsolicited ones (status 128, command 138) are set aside."""
        while True:
            r = Reply.decode(self.read())
            if r.status != 128:
                return r
            self.unsolicited.append(r)

    def ask(self, command: int, type_: int = 0, motor: int = 0, value: int = 0) -> Reply:
        self.send(command, type_, motor, value)
        r = self.reply()
        assert r.command == command
        return r

    def value(self, command: int, type_: int = 0, motor: int = 0, value: int = 0) -> int:
        r = self.ask(command, type_, motor, value)
        assert r.status == 100, r
        return r.value

    def until(self, command: int, type_: int, motor: int, want) -> int:
        deadline = time.monotonic() + WAIT
        while True:
            got = self.value(command, type_, motor)
            if want(got) or time.monotonic() > deadline:
                return got
            time.sleep(0.01)

    def download(self, source: str, module: str) -> list:
        """132, the assembled instructions (each status 101), 133 (manual 3.6.36)."""
        program = assemble(source, module=module).instructions
        assert self.ask(DOWNLOAD).status == 100
        for ins in program:
            assert self.ask(ins.command, ins.type, ins.motor, ins.value).status == 101, ins
        assert self.ask(END_DOWNLOAD).status == 100
        return program

    def close(self) -> None:
        self.port.close()


@pytest.fixture
def link():
    """`link(name, **vm args)`: a module served alone on a pty (USB when its profile has USB)."""
    started = []

    def serve(name: str, **kw) -> Link:
        server = Server([VirtualModule(name, address=1, **kw)])
        pty = server.add(PtyServer(server.bus))
        server.start()
        started.append((server, Link(pty.path)))
        return started[-1][1]

    yield serve
    for server, lk in started:
        lk.close()
        server.stop()


# --- item 1: AP8 after a stop ------------------------------------------------------------------
@pytest.mark.parametrize(("name", "ramp_mode"), [("PD86-1180", 0), ("PD86-1180", 1), ("TMCM-6212", None)])
def test_position_reached_after_mst_on_the_target(link, name, ramp_mode):
    """PD86-1180 manual ch. 5 AP8 "Target pos. reached": "Indicates that the actual position
    equals the target position" (TMCM-6212 4.1: "always set when target position and actual
    position are equal"). MVP ABS 0, 2000 in position mode (AP138 = 0) or soft mode (1), arrival,
    MST, which selects velocity mode (AP138 = 2, "Automatically set when using ROR, ROL, MST and
    MVP"): AP0 = AP1 = 2000 at rest, so GAP 8 reads 1 in every ramp mode (the PD86-1180 read 0 in
    velocity mode), and a program's MST; WAIT POS ends."""
    lk = link(name)
    if ramp_mode is not None:
        assert lk.ask(SAP, 138, 0, ramp_mode).status == 100
        assert lk.ask(SAP, 5, 0, 2047).status == 100      # AP5: a short soft-mode approach
    assert lk.ask(MVP, 0, 0, 2000).status == 100
    assert lk.until(GAP, 8, 0, lambda v: v == 1) == 1
    if ramp_mode is not None:
        assert lk.value(GAP, 138, 0) == ramp_mode
    assert lk.ask(MST).status == 100
    assert [lk.value(GAP, n) for n in (0, 1, 3, 8)] == [2000, 2000, 0, 1]
    if ramp_mode is not None:
        assert lk.value(GAP, 138, 0) == 2
    lk.download("    MST 0\n    WAIT POS, 0, 0\n    SGP 7, 2, 1\n", name)
    assert lk.ask(RUN, 1, 0, 0).status == 100
    assert lk.until(GGP, 7, 2, lambda v: v == 1) == 1   # past the WAIT POS


@pytest.mark.parametrize("name", ["PD86-1180", "TMCM-6212"])
def test_no_position_reached_after_mst_elsewhere(link, name):
    """The other side of AP8 (PD86-1180 ch. 5: "the actual position equals the target position"):
    an MST during a move stops the motor short of AP0, which the stop leaves alone, so GAP 8 reads
    0 at rest."""
    lk = link(name)
    assert lk.ask(MVP, 0, 0, 10**8).status == 100
    lk.until(GAP, 1, 0, lambda v: v >= 100)
    assert lk.ask(MST).status == 100
    assert lk.until(GAP, 3, 0, lambda v: v == 0) == 0
    target, actual = lk.value(GAP, 0), lk.value(GAP, 1)
    assert target == 10**8 and 0 < actual < target
    assert lk.value(GAP, 8) == 0


# --- item 3: GP255 suppresses the version string too --------------------------------------------
def test_gp255_suppresses_the_reply_of_136(link):
    """TMCM-6212 manual 5.1 GP255: "The reply in direct mode will be suppressed when this parameter
    is set to 1. ... The reply will not be suppressed for GAP, GGP and GIO commands." 136 type 0
    (special reply) and type 1 get no reply; a GGP sent after them is the next reply on the line."""
    lk = link("TMCM-6212")
    lk.send(SGP, 255, 0, 1)                      # its own reply is suppressed already
    lk.send(VERSION, 0)
    lk.send(VERSION, 1)
    r = lk.ask(GGP, 255, 0)
    assert (r.status, r.value) == (100, 1)
    lk.send(SGP, 255, 0, 0)
    assert lk.reply().command == SGP            # replies again
    lk.send(VERSION, 0)
    assert lk.read(9) == b"\x02" + b"6212V105"   # host address + 8 characters (special format)


# --- item 4: 138 is direct mode only -----------------------------------------------------------
def test_a_stored_138_arms_no_event(link):
    """TMCM-6212 manual 3.6.35: "This instruction can only be used in direct mode (in standalone
    mode, it is covered by the WAIT command)". 3.6.36: in download mode "All following commands
    (except control commands) are not executed but stored"; 138 is none of Table 13's control
    commands, so it is stored (status 101). The program skips it: its MVP brings no status-128
    "position reached" reply, while 138 sent in direct mode before an MVP does."""
    lk = link("TMCM-6212")
    lk.download("    RAW 138, 1, 0, 1\n    MVP ABS, 0, 500\n    WAIT POS, 0, 0\n    SGP 7, 2, 1\n", "TMCM-6212")
    lk.send(READ_MEMORY, 0, 0, 0)                # special reply: host address, then the stored
    raw = lk.reply()                              # instruction's command, type, motor, value
    assert (raw.module_address, raw.status, raw.command, raw.value) == (138, 1, 0, 1)
    assert lk.ask(RUN, 1, 0, 0).status == 100
    assert lk.until(GGP, 7, 2, lambda v: v == 1) == 1
    lk.value(GGP, 7, 2)
    assert lk.unsolicited == []
    assert lk.ask(138, 0, 0, 1).status == 100     # direct mode: the next MVP reports its arrival
    assert lk.ask(MVP, 0, 0, 0).status == 100
    lk.until(GAP, 8, 0, lambda v: v == 1)
    deadline = time.monotonic() + WAIT
    while not lk.unsolicited and time.monotonic() < deadline:
        lk.value(GAP, 8, 0)
    assert [(r.status, r.command, r.value) for r in lk.unsolicited] == [(128, 138, 1)]


def test_the_assembler_says_138_is_direct_mode_only(tmp_path):
    """3.6.35 "This instruction can only be used in direct mode": `asm --module` warns, as it warns of
    what the module would refuse (docs/tmcl-assembler.md "Checking against a module"); --strict
    refuses (exit 2, nothing written). `asm` without --module warns too: no module runs it."""
    src = tmp_path / "p.tmc"
    src.write_text("    MVP ABS, 0, 500\n    RAW 138, 1, 0, 1\n")
    out = tmp_path / "p.bin"
    r = cli("asm", str(src), "-o", str(out), "--module", "TMCM-6212")
    warning = f"{src}:2:9: warning: command 138 can only be used in direct mode: in a program the module skips it (status 6)"
    assert (r.returncode, r.stderr.strip()) == (0, warning)
    out.unlink()
    r = cli("asm", str(src), "-o", str(out), "--module", "TMCM-6212", "--strict")
    assert r.returncode == 2 and not out.exists()
    r = cli("asm", str(src), "-o", str(out))    # no module: 138 is direct mode only on every one
    assert (r.returncode, r.stderr.strip()) == (0, warning)


# --- item 5: CALCX type 11 ---------------------------------------------------------------------
@pytest.mark.parametrize(("name", "command"), [("TMCM-6212", 33), ("PD86-1180", 33), ("PD28-1021", 40)])
def test_calcx_beyond_swap_is_wrong_type(link, name, command):
    """TMCM-6212 manual 3.6.26 CALCX: types "0 ADD ... 10 SWAP"; Table 4 "3 Wrong type". In direct
    mode CALCX has no effect (status 100 up to SWAP) and type 11 is status 3, as CALC's type 10
    is (3.6.14 lists 0...9). The PD28-1021's CALCVV (Table 5) takes the same operations."""
    lk = link(name)
    got = {t: lk.ask(command, t, 0, 0).status for t in (0, 10, 11, 255)}
    assert got == {0: 100, 10: 100, 11: 3, 255: 3}
    assert (lk.ask(19, 9, 0, 1).status, lk.ask(19, 10, 0, 1).status) == (100, 3)


def test_calcv_ends_at_load(link):
    """PD28-1021 Table 5 CALCV (45): "Arithmetical operation between user variable and direct
    value": a constant cannot be swapped, so its last operation is 9 LOAD and 10 SWAP is "3 Wrong
    type" (Table 4), in direct mode as in a program (docs/assumptions.md "PD28-1021 extended set")."""
    lk = link("PD28-1021")
    assert [lk.ask(45, t, 0, 1).status for t in (0, 9, 10, 11)] == [100, 100, 3, 3]
    lk.download("    CALCV SWAP, 3, 1\n    SGP 4, 2, 1\n", "PD28-1021")
    assert lk.ask(RUN, 1, 0, 0).status == 100
    assert lk.until(GGP, 4, 2, lambda v: v == 1) == 1  # the program went on past it
    assert lk.value(GGP, 3, 2) == 0                    # the refused CALCV changed nothing


# --- item 6: AP21 in velocity mode -------------------------------------------------------------
AP21_PROGRAM = """
    SAP 5, 0, 500000      // AMAX: ramps of 0.1 s
    SAP 21, 0, 65535      // ramp wait time: 65535 * 0.000032 s = 2097.12 ms
    ROR 0, 50000
Up: GAP 3, 0
    COMP 50000
    JC NE, Up
    ROL 0, 50000          // a direction inversion
Down: GAP 3, 0
    COMP 0
    JC GT, Down
    GGP 132, 0            // the tick at which the speed reached zero
    AGP 0, 2
Rest: GAP 3, 0
    COMP 0
    JC GE, Rest
    GGP 132, 0            // the tick at which the motor turned left
    AGP 1, 2
    SGP 2, 2, 1
"""


def test_ramp_wait_time_before_a_direction_inversion(link):
    """TMCM-6212 manual 4.1 AP21 "Ramp wait time": "waiting time after ramping down to zero
    velocity before next movement or direction inversion can start", 0.000032 s per unit. ROR then
    ROL with AP21 = 65535: the motor ramps down, stands 2097.12 ms, then turns left. A program on
    the module times it with its own clock (GP132 tick timer, "incremented by one every
    millisecond"), so the host's speed does not enter: whole ms 2097, plus at most one for the poll."""
    lk = link("TMCM-6212")
    lk.download(AP21_PROGRAM, "TMCM-6212")
    assert lk.ask(RUN, 1, 0, 0).status == 100
    assert lk.until(GGP, 2, 2, lambda v: v == 1) == 1
    rest, moving = lk.value(GGP, 0, 2), lk.value(GGP, 1, 2)
    assert 2097 <= moving - rest <= 2099


# --- item 7: ranges of the PD86-1180 -----------------------------------------------------------
def test_pd86_1180_ror_rol_range_and_tick_timer(link):
    """PD86-1180 manual 4.6.1/4.6.2 ROR/ROL: "<velocity> 0… 2047", "This makes possible choosing a
    velocity between 0 and 2047": 0 and 2047 are accepted, -1 and 2048 "4 Invalid value". Chapter
    6 GP132 tick timer: "A 32 bit counter that gets incremented by one every millisecond", range
    "0… 2^32": -1 on the wire is 2^32 - 1, inside the range, and the counter goes on from there."""
    lk = link("PD86-1180")
    got = {(c, v): lk.ask(c, 0, 0, v).status for c in (1, 2) for v in (0, 2047, -1, 2048)}
    assert got == {(1, 0): 100, (1, 2047): 100, (1, -1): 4, (1, 2048): 4,
                   (2, 0): 100, (2, 2047): 100, (2, -1): 4, (2, 2048): 4}
    assert lk.ask(SGP, 132, 0, -1).status == 100
    since = (lk.value(GGP, 132, 0) - 0xFFFFFFFF) % 2**32        # ms counted since the SGP, wrapped
    assert since < 10000


def test_tmcm6212_tick_timer_range(link):
    """TMCM-6212 manual 5.1 GP132 "TMCL tick timer", range 0...2147483647: -1 is "4 Invalid value"."""
    lk = link("TMCM-6212")
    assert (lk.ask(SGP, 132, 0, -1).status, lk.ask(SGP, 132, 0, 2147483647).status) == (4, 100)


# --- item 8: the default interface of a served module ------------------------------------------
@pytest.mark.parametrize(("name", "interface"), [("PD28-1021", "rs485"), ("TMCM-6212", "usb"), ("PD86-1180", "usb")])
def test_serve_takes_the_interface_the_manual_lists(serve, name, interface):
    """PD28-1021 manual, title page: "RS485 interface" (no USB): `opentmcl serve --pty` stands for
    an RS-485 line, where "the module will ... reply ... only" to its address (3: "strict master/
    slave relationship"), so a frame to address 2 gets no reply. The TMCM-6212 ("USB full speed
    (12Mbit/s) device interface", 1) and the PD86-1180 ("USB, RS232, RS485 and CAN") are served as
    USB, where the address byte is ignored (docs/endpoints.md)."""
    p = serve("--module", name, "--pty")
    [line] = [x for x in p.lines if x.startswith("pty ")]
    path, shown = re.match(r"pty (\S+) .*\((\w+)\)$", line).groups()
    assert shown == interface
    lk = Link(path)
    try:
        lk.send(GGP, 66, 0, 0, address=2)               # another address
        r = lk.ask(GGP, 66, 0)                          # the next reply on the line
        assert (r.status, r.value) == (100, 1)
        if interface == "usb":
            assert Reply.decode(lk.read()).command == GGP   # the frame to address 2 came first
        else:
            assert lk.port.read(9) == b""
    finally:
        lk.close()


# --- item 9: what asm counts -------------------------------------------------------------------
def test_asm_counts_what_disasm_lists(tmp_path):
    """Issue 29 item 9: `asm` said "14 instructions" where `disasm` shows 13. It counts the source's
    instructions apart from the STOP it appends (docs/tmcl-assembler.md), in the singular for one,
    and without the appended STOP it says why `disasm` lists one fewer for a final STOP."""
    src, out = tmp_path / "p.tmc", tmp_path / "p.bin"
    src.write_text("    MVP ABS, 0, 500\n    STOP\n")
    r = cli("asm", str(src), "-o", str(out))
    assert r.stdout.strip() == f"{out}: 2 instructions + appended STOP = 3 records, 0 labels"
    assert len(cli("disasm", str(out)).stdout.splitlines()) == 2
    r = cli("asm", str(src), "-o", str(out), "--no-stop")
    assert r.stdout.strip() == f"{out}: 2 instructions (disasm lists 1: it leaves a final STOP out), 0 labels"
    assert len(cli("disasm", str(out)).stdout.splitlines()) == 1
    src.write_text("Here:\n    MVP ABS, 0, 500\n")
    r = cli("asm", str(src), "-o", str(out))
    assert r.stdout.strip() == f"{out}: 1 instruction + appended STOP = 2 records, 1 label"


# --- item 10: download, then run from the first instruction ------------------------------------
def test_load_run_starts_a_fresh_program_at_its_first_instruction(serve, tmp_path):
    """TMCM-6212 manual 3.6.36: 129 "0 – from current address, 1 – from specific address"; 132/133
    say nothing of the program counter, so after a download it stays where the last program
    stopped (docs/assumptions.md). `opentmcl load --run` starts at the program's first
    instruction (129 type 1, the load address): the second program's first SGP runs."""
    p = serve("--module", "TMCM-6212", "--tcp", "127.0.0.1:0")
    url = p.endpoint("tcp")
    first = tmp_path / "first.tmc"
    first.write_text("    SGP 8, 2, 1\n    SGP 8, 2, 2\n    SGP 8, 2, 3\n    SGP 8, 2, 4\n")
    second = tmp_path / "second.tmc"
    second.write_text("    SGP 9, 2, 42\n    SGP 8, 2, 5\n    SGP 8, 2, 6\n    SGP 8, 2, 7\n    SGP 8, 2, 8\n")
    r = cli("load", str(first), "--to", url, "--run")
    assert r.returncode == 0, r.stderr
    _wait_user_variable(url, 8, 4)
    assert _status(url) & 0xFFFF == 4                   # stopped on the appended STOP
    r = cli("load", str(second), "--to", url)            # no --run: the counter stays
    assert r.returncode == 0, r.stderr
    assert _status(url) & 0xFFFF == 4
    r = cli("load", str(second), "--to", url, "--run")
    assert r.returncode == 0 and "running from 0" in r.stdout, r.stderr
    _wait_user_variable(url, 8, 8)
    assert _user_variable(url, 9) == 42                 # its first instruction ran


def _frames(url: str, *requests: tuple[int, int, int, int]) -> list[Reply]:
    import socket

    host, port = re.match(r"tcp://([\d.]+):(\d+)", url).groups()
    with socket.create_connection((host, int(port)), timeout=WAIT) as s:
        out = []
        for req in requests:
            s.sendall(Request(1, *req).encode())
            buf = b""
            while len(buf) < 9:
                buf += s.recv(9 - len(buf))
            out.append(Reply.decode(buf))
        return out


def _user_variable(url: str, n: int) -> int:
    return _frames(url, (GGP, n, 2, 0))[0].value


def _status(url: str) -> int:
    """135 type 1: mode, wait flag and program counter (TMCM-6212 3.6.36)."""
    return _frames(url, (STATUS, 1, 0, 0))[0].value


def _wait_user_variable(url: str, n: int, want: int) -> None:
    deadline = time.monotonic() + WAIT
    while _user_variable(url, n) != want:
        assert time.monotonic() < deadline, f"user variable {n} never became {want}"
        time.sleep(0.02)
