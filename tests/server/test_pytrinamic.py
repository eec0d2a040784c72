"""Interop: unmodified PyTrinamic against the endpoints (docs/architecture.md "Request path": third-party clients
must behave the same against a virtual module); the test extra installs pytrinamic."""
import importlib
import sys
import time

import pytest
import serial

import opentmcl.urlhandler  # noqa: F401
from opentmcl import VirtualModule
from opentmcl.server import PtyServer, Server, TcpServer

pytrinamic = importlib.import_module("pytrinamic")
from pytrinamic.connections import ConnectionManager  # noqa: E402
from pytrinamic.connections.serial_tmcl_interface import SerialTmclInterface  # noqa: E402
from pytrinamic.modules import TMCM1021, TMCM6212  # noqa: E402

MODULE_CLASSES = {"TMCM-6212": TMCM6212, "PD28-1021": TMCM1021}


@pytest.fixture(params=["TMCM-6212", "TMCM-1021"])
def server(request):
    srv = Server([VirtualModule(request.param, address=1)])
    tcp = srv.add(TcpServer(srv.bus, "127.0.0.1", 0))
    pty = srv.add(PtyServer(srv.bus)) if sys.platform != "win32" else None
    srv.start()
    try:
        yield srv, tcp, pty
    finally:
        srv.stop()


def exercise(interface, vm):
    """Manual 3.6.36 command 136 (version string), 3.6.8 GGP 66, 3.6.1 ROR / 3.6.3 MST, 3.6.4 MVP and axis
    parameter 8 "position reached" through PyTrinamic's own module classes (TMCM6212, TMCM1021)."""
    assert interface.get_version_string() == vm.profile.firmware_version
    assert interface.get_global_parameter(66, 0) == 1
    module = MODULE_CLASSES[vm.profile.name](interface)
    motor = module.motors[0]
    motor.set_axis_parameter(motor.AP.MaxVelocity, 20000)
    assert motor.get_axis_parameter(motor.AP.MaxVelocity) == 20000
    motor.set_axis_parameter(motor.AP.MaxAcceleration, 200000)
    module.rotate(0, 5000)
    deadline = time.monotonic() + 10
    while motor.get_axis_parameter(motor.AP.ActualVelocity, signed=True) != 5000 and time.monotonic() < deadline:
        time.sleep(0.02)
    assert motor.get_axis_parameter(motor.AP.ActualVelocity, signed=True) == 5000
    module.stop(0)
    module.move_to(0, 2000)
    deadline = time.monotonic() + 10
    while not motor.get_position_reached() and time.monotonic() < deadline:
        time.sleep(0.02)
    assert motor.get_axis_parameter(motor.AP.ActualPosition, signed=True) == 2000


def test_pytrinamic_serial_tmcl_over_pty(server):
    srv, _, pty = server
    if pty is None:
        pytest.skip("pseudo-terminals need POSIX")
    cm = ConnectionManager(f"--interface serial_tmcl --port {pty.path} --data-rate 9600")
    with cm.connect() as interface:
        exercise(interface, srv.modules[0])


def test_pytrinamic_socket_over_tcp(server):
    srv, tcp, _ = server
    host, port = tcp.address
    cm = ConnectionManager(f"--interface socket_serial_tmcl --port {host}:{port}")
    with cm.connect() as interface:
        exercise(interface, srv.modules[0])


def test_pytrinamic_with_serial_for_url_port():
    """PyTrinamic's SerialTmclInterface accepts an open pyserial port object."""
    port = serial.serial_for_url("opentmcl://TMCM-1021", timeout=5)
    interface = SerialTmclInterface(port)
    try:
        exercise(interface, port.modules[0])
    finally:
        interface.close()


def test_pytrinamic_target_velocity_setter_during_a_move(server):
    """AP2 "Target speed": "The desired speed in velocity mode. Not valid in position mode"
    (TMCM-6212 4.1). PyTrinamic's `target_velocity` setter writes SAP 2; during a positioning
    move the motor still arrives at the MVP target and stops there (no rotation starts)."""
    srv, tcp, _ = server
    host, port = tcp.address
    cm = ConnectionManager(f"--interface socket_serial_tmcl --port {host}:{port}")
    with cm.connect() as interface:
        module = MODULE_CLASSES[srv.modules[0].profile.name](interface)
        motor = module.motors[0]
        motor.set_axis_parameter(motor.AP.MaxVelocity, 20000)
        motor.set_axis_parameter(motor.AP.MaxAcceleration, 200000)
        module.move_to(0, 6000)
        motor.target_velocity = 50000
        deadline = time.monotonic() + 10
        while not motor.get_position_reached() and time.monotonic() < deadline:
            time.sleep(0.02)
        assert motor.get_axis_parameter(motor.AP.ActualPosition, signed=True) == 6000
        time.sleep(0.1)
        assert motor.get_axis_parameter(motor.AP.ActualVelocity, signed=True) == 0
        assert motor.get_axis_parameter(motor.AP.ActualPosition, signed=True) == 6000
