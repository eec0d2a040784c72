"""Helpers for the axis-world tests: a virtual module in a scenario, driven by TMCL requests."""
import pytest

from opentmcl import VirtualModule


class Rig:
    def __init__(self, module: str, scenario: dict) -> None:
        self.vm = VirtualModule(module, scenario=scenario)

    def sap(self, n: int, value: int, motor: int = 0) -> None:
        reply = self.vm.request(5, n, motor, value)
        assert reply.status == 100, (n, value, reply.status)

    def gap(self, n: int, motor: int = 0) -> int:
        reply = self.vm.request(6, n, motor)
        assert reply.status == 100, (n, reply.status)
        return reply.value

    def cmd(self, command: int, type_: int = 0, motor: int = 0, value: int = 0) -> int:
        reply = self.vm.request(command, type_, motor, value)
        assert reply.status == 100, (command, type_, reply.status)
        return reply.value

    def phys(self, motor: int = 0) -> int:
        return self.vm.world.axis(motor).physical_position

    def search(self, motor: int = 0, limit: float = 200.0) -> None:
        """RFS START, then advance until RFS STATUS reports the end (at most `limit` virtual s)."""
        self.cmd(13, 0, motor)
        t = 0.0
        while self.cmd(13, 2, motor):
            assert t < limit, "reference search did not end"
            self.vm.advance(0.25)
            t += 0.25


@pytest.fixture
def rig():
    return Rig
