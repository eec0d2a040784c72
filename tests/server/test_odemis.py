"""odemis' TMCM driver starts on a served module (issue 29 item 2).

The driver (delmic/odemis, src/odemis/driver/tmcm.py) reads the supply voltage with `GIO 8, 1`
during its start-up, with its own comment "It's undocumented, but the IDE uses this feature too:
supply voltage is reported on analog channel 8" and "1 <-> 0.1 V". The three manuals do not list
the port; OpenTMCL answers it as a documented extension (docs/assumptions.md "Supply voltage and
temperature"), from the world's `supply_voltage` (docs/scenarios.md, default 24.0 V).

odemis is not on PyPI, so CI cannot run the driver itself: tests/server/odemis_init.py re-enacts
the requests its `TMCLController.__init__` sends and the checks it makes of every reply, over a real
pseudo-terminal that the server serves as USB. The unmodified driver was run once by hand against
`opentmcl serve --module TMCM-6212 --pty` and sent the same requests (docs/sources.md "odemis' TMCM
driver").
"""
from __future__ import annotations

import sys

import pytest

from opentmcl import VirtualModule
from opentmcl.server import PtyServer, Server

from . import odemis_init

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")


def served(name: str, **vm_args):
    server = Server([VirtualModule(name, address=1, **vm_args)])
    pty = server.add(PtyServer(server.bus))
    server.start()
    return server, pty


def test_odemis_initialises_on_the_tmcm6212_served_as_usb():
    """With six axes named, every request of the start-up succeeds: the sync on address 0 is
    answered (USB ignores the address byte), 136 type 1 reads model 6212 V1.05, GIO 8, 1 reads
    24.0 V ("1 <-> 0.1 V", above odemis' 10.8 V minimum), GAP 207, 1, 4 and 5 of each axis."""
    server, pty = served("TMCM-6212")
    try:
        assert pty.interface == "usb"
        with odemis_init.open_port(pty.path) as port:
            start = odemis_init.initialise(port, axes=6)
    finally:
        server.stop()
    assert (start.address, start.model, start.version) == (1, 6212, (1, 5))
    assert start.supply_volts == pytest.approx(24.0)
    assert start.positions == [0] * 6
    assert (15, 8, 1, 0) in start.sent and len(start.sent) == 3 + 4 * 6


def test_the_supply_voltage_follows_the_scenario():
    """The world's supply voltage in volts (scenario key `supply_voltage`), read in 0.1 V: a 9 V
    supply is below odemis' minimum of 10.8 V, so the driver stops with "has no power"."""
    server, pty = served("TMCM-6212", scenario={"supply_voltage": 9.0})
    try:
        with odemis_init.open_port(pty.path) as port, pytest.raises(AssertionError, match="has no power"):
            odemis_init.initialise(port, axes=1)
    finally:
        server.stop()


def test_on_the_pd86_1180_odemis_stops_at_ap207():
    """The PD86-1180 answers the sync, 136 and GIO 8, 1, but its manual (chapter 5) has no axis
    parameter 207, which odemis reads next: "3 Wrong type" (Table 4), left refused (issue 29)."""
    server, pty = served("PD86-1180")
    try:
        with odemis_init.open_port(pty.path) as port, pytest.raises(odemis_init.TmclStatusRefused) as err:
            odemis_init.initialise(port, axes=1)
    finally:
        server.stop()
    assert (err.value.request, err.value.status) == ((6, 207, 0, 0), 3)
