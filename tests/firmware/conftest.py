import pytest

from opentmcl import VirtualModule
from opentmcl.protocol.frame import Reply, Request


class Host:
    """Sends requests through VirtualModule.handle exactly as bytes on a wire."""

    def __init__(self, vm, address=1):
        self.vm = vm
        self.address = address

    def raw(self, command, type=0, motor=0, value=0, address=None):
        return self.vm.handle(Request(self.address if address is None else address, command, type, motor,
                                      value).encode())

    def __call__(self, command, type=0, motor=0, value=0):
        raw = self.raw(command, type, motor, value)
        assert len(raw) == 9, f"no reply to {command} {type} {motor} {value}"
        return Reply.decode(raw)

    def ok(self, command, type=0, motor=0, value=0):
        reply = self(command, type, motor, value)
        assert reply.status == 100, f"status {reply.status} for {command} {type} {motor} {value}"
        return reply.value


@pytest.fixture
def m6212():
    return Host(VirtualModule("TMCM-6212", address=1))


@pytest.fixture
def m1180():
    return Host(VirtualModule("PD86-1180", address=1))


@pytest.fixture
def m1021():
    return Host(VirtualModule("PD28-1021", address=1))


@pytest.fixture(params=["TMCM-6212", "PD86-1180", "PD28-1021"])
def anymod(request):
    return Host(VirtualModule(request.param, address=1))
