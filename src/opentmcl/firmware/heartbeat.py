"""The serial and CAN heartbeats (TMCM-6212 manual 5.1, GP68 "Serial heartbeat" and GP82 "CAN
heartbeat": "If no command is received in this time, the motor will be stopped"; 0 = off).

A request restarts the heartbeat of its link: CAN requests GP82's, every other link (serial,
RS-232, RS-485, USB) GP68's (docs/endpoints.md). Once expired, a heartbeat stays quiet until the
next request.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..motion import CLOCK_HZ

if TYPE_CHECKING:
    from .vm import VirtualModule

TICKS_PER_MS = CLOCK_HZ // 1000
SERIAL_HB, CAN_HB = (0, 68), (0, 82)
HEARTBEATS = (("serial", SERIAL_HB), ("can", CAN_HB))
OF_INTERFACE = {"serial": "serial", "rs485": "serial", "rs232": "serial", "usb": "serial", "can": "can"}
"""The heartbeat a link's requests restart."""


class Heartbeats:
    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm
        now = vm.scheduler.now
        self.last = {"serial": now, "can": now}
        """The tick of the last request per heartbeat."""
        self.fired = False

    def touch(self, heartbeat: str) -> None:
        """A request came over a link of `heartbeat` ("serial" or "can")."""
        self.last[heartbeat] = self.vm.scheduler.now
        self.fired = False

    def on(self) -> bool:
        ram = self.vm.globals.ram
        return bool(ram.get(SERIAL_HB) or ram.get(CAN_HB))

    def deadline(self) -> int | None:
        """Earliest expiry of the heartbeats that are on, in ticks; None when none is pending."""
        if self.fired:
            return None
        ram = self.vm.globals.ram
        if not (ram.get(SERIAL_HB) or ram.get(CAN_HB)):  # both off: the usual case
            return None
        best = None
        for name, key in HEARTBEATS:
            ms = ram.get(key, 0)
            if ms:
                t = self.last[name] + ms * TICKS_PER_MS
                if best is None or t < best:
                    best = t
        return best

    def expire(self, now: int) -> bool:
        """True once, at the first event at or after a heartbeat's deadline: the motors stop."""
        hb = self.deadline()
        if hb is None or now < hb:
            return False
        self.fired = True
        return True
