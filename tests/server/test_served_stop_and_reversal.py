"""What a host on the served port reads after a stop and at a direction inversion (issue 29 items 1
and 6): "target position reached" (AP8) after MST, at the target and short of it, and the ramp wait
time (AP21) before ROL reverses a ROR. Each module is served alone by an in-process `Server` on a
real pseudo-terminal; the test's host speaks 9-byte frames through pyserial."""
from __future__ import annotations

import sys

import pytest

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")

MST, MVP, SAP, GAP, GGP, RUN = 3, 4, 5, 6, 10, 129


@pytest.mark.parametrize(("name", "ramp_mode"), [("PD86-1180", 0), ("PD86-1180", 1), ("TMCM-6212", None)])
def test_position_reached_after_mst_on_the_target(pty_link, name, ramp_mode):
    """PD86-1180 manual ch. 5 AP8 "Target pos. reached": "Indicates that the actual position
    equals the target position" (TMCM-6212 4.1: "always set when target position and actual
    position are equal"). MVP ABS 0, 2000 in position mode (AP138 = 0) or soft mode (1), arrival,
    MST, which selects velocity mode (AP138 = 2, "Automatically set when using ROR, ROL, MST and
    MVP"): AP0 = AP1 = 2000 at rest, so GAP 8 reads 1 in every ramp mode (the PD86-1180 read 0 in
    velocity mode), and a program's MST; WAIT POS ends."""
    lk = pty_link(name)
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
def test_no_position_reached_after_mst_elsewhere(pty_link, name):
    """The other side of AP8 (PD86-1180 ch. 5: "the actual position equals the target position"):
    an MST during a move stops the motor short of AP0, which the stop leaves alone, so GAP 8 reads
    0 at rest."""
    lk = pty_link(name)
    assert lk.ask(MVP, 0, 0, 10**8).status == 100
    lk.until(GAP, 1, 0, lambda v: v >= 100)
    assert lk.ask(MST).status == 100
    assert lk.until(GAP, 3, 0, lambda v: v == 0) == 0
    target, actual = lk.value(GAP, 0), lk.value(GAP, 1)
    assert target == 10**8 and 0 < actual < target
    assert lk.value(GAP, 8) == 0


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


def test_ramp_wait_time_before_a_direction_inversion(pty_link):
    """TMCM-6212 manual 4.1 AP21 "Ramp wait time": "waiting time after ramping down to zero
    velocity before next movement or direction inversion can start", 0.000032 s per unit. ROR then
    ROL with AP21 = 65535: the motor ramps down, stands 2097.12 ms, then turns left. A program on
    the module times it with its own clock (GP132 tick timer, "incremented by one every
    millisecond"), so the host's speed does not enter: whole ms 2097, plus at most one for the poll."""
    lk = pty_link("TMCM-6212")
    lk.download(AP21_PROGRAM, "TMCM-6212")
    assert lk.ask(RUN, 1, 0, 0).status == 100
    assert lk.until(GGP, 2, 2, lambda v: v == 1) == 1
    rest, moving = lk.value(GGP, 0, 2), lk.value(GGP, 1, 2)
    assert 2097 <= moving - rest <= 2099
