"""Interop: unmodified python-tmcl (`pip install tmcl`) over pyserial ports
(docs/sources.md "Public host clients"; the test extra installs it). python-tmcl packs the
checksum unmasked, so only requests whose byte sum stays below 256 can be sent with it - the values
below respect that."""
import importlib
import sys

import pytest
import serial

import opentmcl.urlhandler  # noqa: F401
from opentmcl import VirtualModule
from opentmcl.server import PtyServer, Server

TMCL = importlib.import_module("TMCL")


def exercise(port):
    """SAP/GAP 4 (manual 3.6.5/3.6.6), SGP/GGP on user variables in bank 2 (3.6.7/3.6.8), MST."""
    bus = TMCL.connect(port)
    motor = bus.get_motor(1)
    motor.axis.max_positioning_speed = 100
    assert motor.axis.max_positioning_speed == 100
    assert motor.set_user_var(3, 42) == 100
    assert motor.get_user_var(3) == 42
    motor.stop()


def test_python_tmcl_through_serial_for_url():
    with serial.serial_for_url("opentmcl://TMCM-6212", timeout=5) as port:
        exercise(port)


@pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")
def test_python_tmcl_through_the_pty():
    server = Server([VirtualModule("TMCM-6212", address=1)])
    pty = server.add(PtyServer(server.bus))
    server.start()
    try:
        with serial.Serial(pty.path, 9600, timeout=5) as port:
            exercise(port)
    finally:
        server.stop()
