"""SIO/GIO on the I/O banks of the module profile (TMCM-6212 manual 3.6.12-3.6.13,
PD86-1180 manual 4.6.14-4.6.15).

Bank 0 digital inputs, bank 1 analog inputs, bank 2 digital outputs. Port
255 addresses all ports of a digital bank at once as a bit mask
(PD86-1180: `SIO 255, 2, x`, value -1 copies the accumulator's low bits;
`GIO 255, 0`). `SIO <n>, 0, <mask>` switches input pull-ups on modules whose
profile has pull-up ports in bank 0.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from .status import TmclStatus

if TYPE_CHECKING:
    from .vm import VirtualModule

ALL_PORTS = 255


class IOBanks:
    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm
        self.ports = vm.profile.io
        self.values: dict[tuple[int, int], int] = {key: 0 for key in self.ports}
        self.forced: dict[tuple[int, int], int] = {}
        self.pullups = 0

    def _bank_ports(self, bank: int, kind: str | None = None) -> list[tuple[int, int]]:
        return sorted(k for k, p in self.ports.items() if k[0] == bank and (kind is None or p.kind == kind))

    def port(self, port: int, bank: int):
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
            if value == -1:
                value = self.vm.accumulator
            if not 0 <= value <= 255:
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

    def get(self, port: int, bank: int) -> int:
        if port == ALL_PORTS:
            ports = [k for k in self._bank_ports(bank) if k[1] < 8]  # one byte of port bits
            if not ports or any(self.ports[k].kind == "analog" for k in ports):
                raise TmclStatus(3)
            return sum((self.read(k) & 1) << k[1] for k in ports)
        self.port(port, bank)
        return self.read((bank, port))

    def read(self, key: tuple[int, int]) -> int:
        return self.forced.get(key, self.values.get(key, 0))

    def drive_input(self, bank: int, port: int, value: int) -> None:
        """The outside world sets an input (scenario, tests, dashboard)."""
        if (bank, port) not in self.ports:
            raise KeyError(f"no I/O port {port} in bank {bank}")
        self.values[(bank, port)] = value
