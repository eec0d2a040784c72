"""Helpers for the standalone-mode tests: download and run a program exactly as TMCL-IDE does,
through the wire protocol of VirtualModule.handle (132, the instructions, 133, then 129)."""
from __future__ import annotations

from opentmcl import VirtualModule
from opentmcl.firmware.interpreter import INSTRUCTION_TICKS
from opentmcl.lang.assembler import assemble
from opentmcl.motion import CLOCK_HZ
from opentmcl.protocol.frame import Reply, Request

T = INSTRUCTION_TICKS / CLOCK_HZ  # seconds per instruction
STOP = (28, 0, 0, 0)  # STOP (TMCM-6212 3.6.21) as a downloaded instruction


class Wire:
    """A host on the wire of one virtual module."""

    def __init__(self, vm: VirtualModule, address: int = 1):
        self.vm = vm
        self.address = address

    def __call__(self, command, type=0, motor=0, value=0) -> Reply:
        raw = self.vm.handle(Request(self.address, command, type, motor, value).encode())
        assert len(raw) == 9, f"no reply to {command} {type} {motor} {value}"
        return Reply.decode(raw)

    def ok(self, command, type=0, motor=0, value=0) -> int:
        r = self(command, type, motor, value)
        assert r.status == 100, f"status {r.status} for {command} {type} {motor} {value}"
        return r.value

    def download(self, instructions, start: int = 0) -> None:
        assert self(132, 0, 0, start).status == 100
        for ins in instructions:
            r = self(*ins)
            assert r.status == 101, f"{ins} answered {r.status}"
        assert self(133).status == 100

    def load(self, source: str, module: str | None = None):
        prog = assemble(source, module=module or self.vm.profile.name)
        self.download(prog.instructions)
        return prog

    def run(self, address: int | None = None) -> None:
        if address is None:
            self.ok(129, 0)
        else:
            self.ok(129, 1, 0, address)

    @property
    def a(self) -> int:
        return self.ok(135, 2)

    @property
    def x(self) -> int:
        return self.ok(135, 3)

    @property
    def pc(self) -> int:
        return self.ok(10, 130, 0)

    @property
    def state(self) -> int:
        return self.ok(10, 128, 0)

    def var(self, n: int) -> int:
        return self.ok(10, n, 2)

    def out(self, port: int) -> int:
        return self.ok(15, port, 2)


def module(name: str = "TMCM-6212", **kw) -> Wire:
    return Wire(VirtualModule(name, address=1, **kw))


def run_program(source: str, seconds: float, name: str = "TMCM-6212", **kw) -> Wire:
    w = module(name, **kw)
    w.load(source)
    w.run()
    w.vm.advance(seconds)
    return w


def run_raw(name: str, *instructions: tuple[int, int, int, int], seconds: float = 20 * T) -> Wire:
    """Download `instructions` as they are (no assembler checks), run them, advance `seconds`."""
    w = module(name)
    w.download(instructions)
    w.run()
    w.vm.advance(seconds)
    return w
