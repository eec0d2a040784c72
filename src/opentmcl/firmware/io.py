"""SIO/GIO on the I/O banks of the module profile (TMCM-6212 manual 3.6.12-3.6.13,
PD86-1180 manual 4.6.14-4.6.15).

Bank 0 digital inputs, bank 1 analog inputs, bank 2 digital outputs. Port
255 addresses all ports of a digital bank at once as a bit mask
(PD86-1180: `SIO 255, 2, x` with x in 0...255, value -1 copies the
accumulator's low bits; `GIO 255, 0`); on a module whose manual prints no
range for it the mask must fit the outputs (TMCM-6212: 0...15). `SIO <n>, 0, <mask>` switches input pull-ups on modules whose
profile has pull-up ports in bank 0.

"The ADIN lines can be read as digital or analogue inputs at the same time"
(TMCM-6212 3.6.13, PD86-1180 4.6.15): a line that has both a digital port and
an analog port (same name) carries one level. Driving the analog side sets the
digital reading (1 from half of the ADC range on); driving the digital side
sets the analog reading to 0 or full scale (docs/assumptions.md).
"""
from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING

from .status import TmclStatus

if TYPE_CHECKING:
    from ..modules.profile import IOPort
    from .vm import VirtualModule

ALL_PORTS = 255


class IOBanks:
    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm
        self.ports = vm.profile.io
        self.values: dict[tuple[int, int], int] = {key: 0 for key in self.ports}
        self.forced: dict[tuple[int, int], int] = {}
        self.pullups = 0
        self.twins = _adin_twins(self.ports)
        self.sources: dict[tuple[int, int], Callable[[], int]] = {}  # driven by the world, read lazily

    def _bank_ports(self, bank: int, kind: str | None = None) -> list[tuple[int, int]]:
        return sorted(k for k, p in self.ports.items() if k[0] == bank and (kind is None or p.kind == kind))

    def port(self, port: int, bank: int) -> IOPort:
        p = self.ports.get((bank, port))
        if p is None:
            if not any(b == bank for b, _ in self.ports):
                raise TmclStatus(4)
            raise TmclStatus(3)
        return p

    def set(self, port: int, bank: int, value: int) -> None:
        if port == ALL_PORTS:
            outputs = self._bank_ports(bank, "output")
            if not outputs:
                raise TmclStatus(3)
            top = self.all_ports_max(outputs)
            if value == -1:  # PD86-1180 4.6.14: "the lower 8 bits of the accumulator are copied"
                value = self.vm.accumulator & top
            if not 0 <= value <= top:
                raise TmclStatus(4)
            for key in outputs:
                self.values[key] = (value >> key[1]) & 1
            return
        pullups = self.vm.profile.extra.get("pullups")
        if pullups and (bank, port) == (pullups["bank"], pullups["port"]):
            if not 0 <= value <= pullups["max"]:
                raise TmclStatus(4)
            self.pullups = value
            return
        p = self.port(port, bank)
        if "W" not in p.access:
            raise TmclStatus(3)
        if not p.min <= value <= p.max:
            raise TmclStatus(4)
        self.values[(bank, port)] = value

    def all_ports_max(self, outputs: list[tuple[int, int]]) -> int:
        """Largest value of `SIO 255, <bank>`: the profile's `sio_all_max` where the manual prints
        a range (PD86-1180 4.6.14: 0...255), else one bit per output port (TMCM-6212: 0...15)."""
        top = self.vm.profile.extra.get("sio_all_max")
        return top if top is not None else (1 << (max(p for _, p in outputs) + 1)) - 1

    def get(self, port: int, bank: int) -> int:
        """GIO (TMCM-6212 3.6.13): the value now; TmclStatus(3/4) if it cannot be read."""
        return self.reader(port, bank)()

    def reader(self, port: int, bank: int) -> Callable[[], int]:
        """The read of `port` of `bank`: the one rule of GIO, which the request path and programs
        bind ahead. Port 255 reads every digital port of the bank at once as a bit mask."""
        if port == ALL_PORTS:
            ports = [k for k in self._bank_ports(bank) if k[1] < 8]  # one byte of port bits
            if not ports or any(self.ports[k].kind == "analog" for k in ports):
                raise TmclStatus(3)
            return partial(self._mask, ports)
        self.port(port, bank)
        return partial(self.read, (bank, port))

    def _mask(self, ports: list[tuple[int, int]]) -> int:
        return sum((self.read(k) & 1) << k[1] for k in ports)

    def read(self, key: tuple[int, int]) -> int:
        if key in self.forced:
            return self.forced[key]
        source = self.sources.get(key)
        return source() if source is not None else self.values.get(key, 0)

    def drive_source(self, bank: int, port: int, source: Callable[[], int]) -> None:
        """The outside world drives an input with a level that `source()` gives at any moment
        (a scenario signal over time); the line's other reading follows it."""
        key = (bank, port)
        if key not in self.ports:
            raise KeyError(f"no I/O port {port} in bank {bank}")
        self.sources[key] = source
        twin = self.twins.get(key)
        if twin is not None:
            driven, other = self.ports[key], self.ports[twin]
            self.sources[twin] = lambda: _twin_level(driven, other, source())

    def drive_input(self, bank: int, port: int, value: int) -> None:
        """The outside world sets an input (scenario, tests, dashboard)."""
        key = (bank, port)
        if key not in self.ports:
            raise KeyError(f"no I/O port {port} in bank {bank}")
        self.values[key] = value
        self.sources.pop(key, None)
        twin = self.twins.get(key)
        if twin is not None:
            self.sources.pop(twin, None)
            self.values[twin] = _twin_level(self.ports[key], self.ports[twin], value)


def threshold(port: IOPort) -> int:
    """Smallest level of a digital input or of an ADIN line's analog side that reads as 1."""
    return 1 if port.kind == "digital" else (port.max + 2) // 2


def _adin_twins(ports: dict[tuple[int, int], IOPort]) -> dict[tuple[int, int], tuple[int, int]]:
    """Digital input port <-> analog input port of the same line (same name), both ways."""
    analog = {p.name: key for key, p in ports.items() if p.kind == "analog"}
    twins = {}
    for key, p in ports.items():
        if p.kind == "digital" and p.name in analog and "W" not in p.access:
            twins[key] = analog[p.name]
            twins[analog[p.name]] = key
    return twins


def _twin_level(driven: IOPort, twin: IOPort, value: int) -> int:
    """The other reading of one line: analog -> digital at mid-scale, digital -> 0 or full scale."""
    if driven.kind == "analog":
        return 1 if value >= threshold(driven) else 0
    return twin.max if value else twin.min
