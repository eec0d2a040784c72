"""CAN transport through python-can (TMCM-6212 manual 3.1, 3.2, 5.1).

    can://socketcan/can0?id=1              (real adapter or vcan)
    can://virtual/CHANNEL?id=1             (python-can's in-process virtual bus)
    can://INTERFACE/CHANNEL?id=1&reply_id=2&bitrate=1000000

`id` is the module's CAN ID (global parameter 71, default 1), `reply_id` the
ID the module answers with (parameter 70, default 2). One CAN frame per
`send`/`recv` call: the client sends the request payload, `recv` returns the
data bytes of the next frame carrying `reply_id`.
"""
from __future__ import annotations

import time
import urllib.parse
from typing import Any

from ..errors import TmclConnectionError, TmclProtocolError, TmclTimeout, TmclUrlError, check_int
from ..transport import DEBUG, Transport, log, log_frame, url_query

DEFAULT_ID = 1
DEFAULT_REPLY_ID = 2


class CanTransport(Transport):
    """A python-can bus talking to one module CAN ID."""

    frame_format = "can"

    def __init__(self, interface: str, channel: str, can_id: int = DEFAULT_ID,
                 reply_id: int = DEFAULT_REPLY_ID, **kwargs: Any) -> None:
        # kwargs go to can.Bus unchanged (its own signature: **kwargs: Any), e.g. bitrate
        import can

        for name, value in (("id", can_id), ("reply_id", reply_id)):
            if not 0 <= check_int(value, f"CAN {name}") <= 0x7FF:
                raise TmclUrlError(f"CAN {name} must be 0..2047 (manual 5.1), got {value}")
        self.interface, self.channel = interface, channel
        self.can_id, self.reply_id = can_id, reply_id
        try:
            self._bus = can.Bus(interface=interface, channel=channel, **kwargs)
        except (can.CanError, OSError, ValueError, ImportError, NotImplementedError) as exc:
            raise TmclConnectionError(f"cannot open CAN bus {interface}/{channel}: {exc}") from None
        self._closed = False
        log.info("opened %s (CAN ID %d, reply ID %d)", self.name, can_id, reply_id)

    @property
    def name(self) -> str:
        return f"can://{self.interface}/{self.channel}"

    @property
    def bus(self) -> Any:
        """The python-can bus (`can.BusABC`) under the transport, for a gateway that reads every
        frame itself (the capture proxy's CAN upstream); `send`/`recv` stay the client's way in."""
        return self._bus

    def _check_open(self) -> None:
        if self._closed:
            raise TmclConnectionError(f"{self.name} is closed")

    def send(self, data: bytes) -> None:
        import can

        self._check_open()
        if not 1 <= len(data) <= 8:
            raise TmclProtocolError(f"a CAN frame carries 1..8 data bytes, got {len(data)}")
        message = can.Message(arbitration_id=self.can_id, data=bytes(data), is_extended_id=False)
        if log.isEnabledFor(DEBUG):
            log_frame("->", data, self.frame_format)
        try:
            self._bus.send(message, timeout=1.0)
        except (can.CanError, OSError) as exc:
            raise TmclConnectionError(f"{self.name}: send failed: {exc}") from None

    def recv(self, n: int, timeout: float) -> bytes:
        import can

        self._check_open()
        deadline = time.monotonic() + max(0.0, timeout)
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TmclTimeout(f"{self.name}: no reply with ID {self.reply_id} within {timeout:g} s")
            try:
                msg = self._bus.recv(left)
            except (can.CanError, OSError) as exc:
                raise TmclConnectionError(f"{self.name}: receive failed: {exc}") from None
            if msg is None or msg.is_error_frame or msg.is_remote_frame or msg.is_extended_id:
                continue
            if msg.arbitration_id != self.reply_id:
                continue
            data = bytes(msg.data)
            if len(data) < n:
                raise TmclProtocolError(f"{self.name}: reply of {len(data)} bytes, expected {n}: {data.hex(' ')}")
            if log.isEnabledFor(DEBUG):
                log_frame("<-", data[:n], self.frame_format)
            return data[:n]

    def reset_input(self) -> None:
        if self._closed:
            return
        try:
            while self._bus.recv(0) is not None:
                pass
        except Exception:  # draining is best effort
            pass

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        try:
            self._bus.shutdown()
        except Exception:  # shutting down a vanished adapter must not raise
            pass


def open_can(url: urllib.parse.SplitResult) -> CanTransport:
    """Factory for ``can://INTERFACE/CHANNEL?id=N&reply_id=M[&bitrate=B]``."""
    query = url_query(url, ("id", "reply_id", "bitrate"))
    interface = url.netloc
    channel = urllib.parse.unquote(url.path.lstrip("/"))
    if not interface or not channel:
        raise TmclUrlError(f"CAN URL needs an interface and a channel, e.g. can://socketcan/can0?id=1, "
                                  f"got {url.geturl()!r}")
    kwargs: dict[str, int] = {}
    try:
        can_id = int(query.get("id", str(DEFAULT_ID)), 0)
        reply_id = int(query.get("reply_id", str(DEFAULT_REPLY_ID)), 0)
        if "bitrate" in query:
            kwargs["bitrate"] = int(query["bitrate"])
    except ValueError:
        raise TmclUrlError(f"bad number in {url.geturl()!r}") from None
    return CanTransport(interface, channel, can_id, reply_id, **kwargs)
