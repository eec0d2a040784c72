"""CAN endpoint through python-can (TMCM-6212 manual 3.1, 3.2, 5.1).

A request is a standard data frame whose identifier is a module's CAN ID
(global parameter 71) or its secondary CAN ID (83, off when 0), carrying 7
bytes (command, type, motor/bank, value) or 8 (the same plus a checksum byte
that is ignored). The reply goes out with the module's CAN reply ID
(parameter 70) and 7 data bytes: module address, status, command, value; the
string reply of command 136 asked with an 8-byte frame has 8 bytes (PD86-1180
manual 4.2). The telegram pause (parameter 75) "has no effect" on CAN.

Frames with extended identifiers, remote and error frames are ignored.
"""
from __future__ import annotations

import logging
import threading
from typing import TYPE_CHECKING

from ..faults import LinkFaults
from . import canmap, vmapi
from .linkfaults import can_fate, can_reply_passes, can_request_lost, link_faults

if TYPE_CHECKING:
    from can import BusABC

log = logging.getLogger("opentmcl.server.can")  # every frame at DEBUG (docs/host.md "Logging")

POLL = 0.2


def open_can_bus(interface: str, channel: str, **kwargs) -> BusABC:
    """A python-can bus, e.g. ("virtual", "opentmcl") or ("socketcan", "vcan0")."""
    import can

    return can.Bus(interface=interface, channel=channel, **kwargs)


class CanServer:
    """Serve the bus on a python-can bus; `start()` opens it, `stop()` shuts it down."""

    interface = "can"

    def __init__(self, bus, interface: str = "virtual", channel: str = "opentmcl", **can_kwargs) -> None:
        self.bus = bus
        self.can_interface = interface
        self.channel = channel
        self.can_kwargs = can_kwargs
        self.canbus: BusABC | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._send_lock = threading.Lock()
        self.send_errors = 0
        self.faults: LinkFaults | None = None

    @property
    def url(self) -> str:
        return f"can://{self.can_interface}/{self.channel}"

    def start(self) -> None:
        self.faults = link_faults(self.bus, "can")  # `opentmcl serve --faults` (server/linkfaults.py)
        self.canbus = open_can_bus(self.can_interface, self.channel, **self.can_kwargs)
        self._thread = threading.Thread(target=self._loop, name="opentmcl-can", daemon=True)
        self._thread.start()

    def _loop(self) -> None:
        import can

        while not self._stop.is_set():
            canbus = self.canbus  # opened by start() before the thread runs
            if canbus is None:
                return
            try:
                msg = canbus.recv(POLL)
            except (can.CanError, OSError, ValueError):
                if self._stop.wait(POLL):
                    return
                continue
            if msg is None or msg.is_error_frame or msg.is_remote_frame or msg.is_extended_id:
                continue
            faults = self.faults
            fate = None if faults is None else can_fate(faults, bytes(msg.data))
            if fate is not None and can_request_lost(fate):
                continue
            try:
                replies = self.bus.can_request(msg.arbitration_id, bytes(msg.data), self)
            except Exception:  # a module bug must not stop the endpoint
                log.exception("module failed on CAN frame %03x %s", msg.arbitration_id, bytes(msg.data).hex(" "))
                continue
            if log.isEnabledFor(logging.DEBUG):
                _log_exchange(msg.arbitration_id, bytes(msg.data), replies)
            for _vm, reply_id, payload in replies:
                if fate is None or can_reply_passes(fate, self.faults, self._stop.wait):
                    self._send(reply_id, payload)

    def _send(self, reply_id: int, payload: bytes) -> None:
        import can

        message = can.Message(arbitration_id=reply_id & 0x7FF, data=payload, is_extended_id=False)
        with self._send_lock:
            canbus = self.canbus
            if canbus is None:
                return
            try:
                canbus.send(message, timeout=POLL)
            except (can.CanError, OSError, ValueError):
                self.send_errors += 1

    def deliver(self, vm, reply: bytes) -> None:
        """An unsolicited 9-byte reply (command 138 event) sent as a CAN reply."""
        if self.canbus is None or self._stop.is_set() or (self.faults is not None and
                                                          self.faults.down(self.faults.log.clock())):
            return
        with self.bus.lock:
            reply_id = vmapi.global_param(vm, vmapi.GP_CAN_REPLY_ID)
        self._send(reply_id, canmap.reply_to_payload(reply))

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        self.bus.forget(self)
        with self._send_lock:
            canbus, self.canbus = self.canbus, None
        if canbus is not None:
            canbus.shutdown()


def _log_exchange(can_id: int, data: bytes, replies: list) -> None:
    """A CAN request and the replies to it, as TMCL text plus hex."""
    from ..host.transport import frame_text

    log.debug("ID %03x <- %s", can_id, frame_text(data, "can", request=True))
    for _vm, reply_id, payload in replies:
        log.debug("ID %03x -> %s", reply_id, frame_text(payload, "can", request=False))
