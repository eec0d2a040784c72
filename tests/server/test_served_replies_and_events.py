"""Which replies and events reach a host on the served port (issue 29 items 3 and 4): GP255
suppresses the reply of 136 too, and command 138 arms events only in direct mode (a program skips a
stored 138). Each module is served alone by an in-process `Server` on a real pseudo-terminal; the
test's host speaks 9-byte frames through pyserial."""
from __future__ import annotations

import sys
import time

import pytest

from .helpers import WAIT

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")

MVP, GAP, SGP, GGP = 4, 6, 9, 10
RUN, READ_MEMORY, VERSION = 129, 134, 136


def test_gp255_suppresses_the_reply_of_136(pty_link):
    """TMCM-6212 manual 5.1 GP255: "The reply in direct mode will be suppressed when this parameter
    is set to 1. ... The reply will not be suppressed for GAP, GGP and GIO commands." 136 type 0
    (special reply) and type 1 get no reply; a GGP sent after them is the next reply on the line."""
    lk = pty_link("TMCM-6212")
    lk.send(SGP, 255, 0, 1)                      # its own reply is suppressed already
    lk.send(VERSION, 0)
    lk.send(VERSION, 1)
    r = lk.ask(GGP, 255, 0)
    assert (r.status, r.value) == (100, 1)
    lk.send(SGP, 255, 0, 0)
    assert lk.reply().command == SGP            # replies again
    lk.send(VERSION, 0)
    assert lk.read(9) == b"\x02" + b"6212V105"   # host address + 8 characters (special format)


def test_a_stored_138_arms_no_event(pty_link):
    """TMCM-6212 manual 3.6.35: "This instruction can only be used in direct mode (in standalone
    mode, it is covered by the WAIT command)". 3.6.36: in download mode "All following commands
    (except control commands) are not executed but stored"; 138 is none of Table 13's control
    commands, so it is stored (status 101). The program skips it: its MVP brings no status-128
    "position reached" reply, while 138 sent in direct mode before an MVP does."""
    lk = pty_link("TMCM-6212")
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
