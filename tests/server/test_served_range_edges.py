"""The last valid and the first invalid type or value of a command, as a host on the served port
sees them (issue 29 items 5 and 7): CALCX and CALCVV end at SWAP and CALCV at LOAD ("3 Wrong
type"), the PD86-1180's ROR/ROL velocity ends at 2047 ("4 Invalid value"), and the tick timer GP132
takes the range its manual gives. Each module is served alone by an in-process `Server` on a real
pseudo-terminal; the test's host speaks 9-byte frames through pyserial."""
from __future__ import annotations

import sys

import pytest

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")

SGP, GGP, RUN = 9, 10, 129


@pytest.mark.parametrize(("name", "command"), [("TMCM-6212", 33), ("PD86-1180", 33), ("PD28-1021", 40)])
def test_calcx_beyond_swap_is_wrong_type(pty_link, name, command):
    """TMCM-6212 manual 3.6.26 CALCX: types "0 ADD ... 10 SWAP"; Table 4 "3 Wrong type". In direct
    mode CALCX has no effect (status 100 up to SWAP) and type 11 is status 3, as CALC's type 10
    is (3.6.14 lists 0...9). The PD28-1021's CALCVV (Table 5) takes the same operations."""
    lk = pty_link(name)
    got = {t: lk.ask(command, t, 0, 0).status for t in (0, 10, 11, 255)}
    assert got == {0: 100, 10: 100, 11: 3, 255: 3}
    assert (lk.ask(19, 9, 0, 1).status, lk.ask(19, 10, 0, 1).status) == (100, 3)


def test_calcv_ends_at_load(pty_link):
    """PD28-1021 Table 5 CALCV (45): "Arithmetical operation between user variable and direct
    value": a constant cannot be swapped, so its last operation is 9 LOAD and 10 SWAP is "3 Wrong
    type" (Table 4), in direct mode as in a program (docs/assumptions.md "PD28-1021 extended set")."""
    lk = pty_link("PD28-1021")
    assert [lk.ask(45, t, 0, 1).status for t in (0, 9, 10, 11)] == [100, 100, 3, 3]
    lk.download("    CALCV SWAP, 3, 1\n    SGP 4, 2, 1\n", "PD28-1021")
    assert lk.ask(RUN, 1, 0, 0).status == 100
    assert lk.until(GGP, 4, 2, lambda v: v == 1) == 1  # the program went on past it
    assert lk.value(GGP, 3, 2) == 0                    # the refused CALCV changed nothing


def test_pd86_1180_ror_rol_range_and_tick_timer(pty_link):
    """PD86-1180 manual 4.6.1/4.6.2 ROR/ROL: "<velocity> 0… 2047", "This makes possible choosing a
    velocity between 0 and 2047": 0 and 2047 are accepted, -1 and 2048 "4 Invalid value". Chapter
    6 GP132 tick timer: "A 32 bit counter that gets incremented by one every millisecond", range
    "0… 2^32": -1 on the wire is 2^32 - 1, inside the range, and the counter goes on from there."""
    lk = pty_link("PD86-1180")
    got = {(c, v): lk.ask(c, 0, 0, v).status for c in (1, 2) for v in (0, 2047, -1, 2048)}
    assert got == {(1, 0): 100, (1, 2047): 100, (1, -1): 4, (1, 2048): 4,
                   (2, 0): 100, (2, 2047): 100, (2, -1): 4, (2, 2048): 4}
    assert lk.ask(SGP, 132, 0, -1).status == 100
    since = (lk.value(GGP, 132, 0) - 0xFFFFFFFF) % 2**32        # ms counted since the SGP, wrapped
    assert since < 10000


def test_tmcm6212_tick_timer_range(pty_link):
    """TMCM-6212 manual 5.1 GP132 "TMCL tick timer", range 0...2147483647: -1 is "4 Invalid value"."""
    lk = pty_link("TMCM-6212")
    assert (lk.ask(SGP, 132, 0, -1).status, lk.ask(SGP, 132, 0, 2147483647).status) == (4, 100)
