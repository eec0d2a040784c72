"""Split a serial byte stream into 9-byte TMCL frames (TMCM-6212 manual 3.1).

On RS-232/RS-485/USB a request is nine bytes with no start marker, so a
receiver can only find frame boundaries by counting. A stray byte or a
truncated frame would shift every following frame; the framer therefore drops
a partial frame when the line has been silent for longer than `gap` seconds
(an inter-byte gap). A host that waits for a reply, times out and retries
sends its next request after such a gap, so the stream resynchronises by
itself and the port never wedges (docs/assumptions.md).

The class is pure: the caller passes the arrival time of every chunk, so it
is tested without clocks or sockets.
"""
from __future__ import annotations

from ..protocol.frame import FRAME_GAP, FRAME_LEN

DEFAULT_GAP = FRAME_GAP
"""Seconds of silence after which a partial frame is discarded."""


class SerialFramer:
    """Collects bytes into `frame_len`-byte frames, resetting after a silent gap."""

    def __init__(self, gap: float = DEFAULT_GAP, frame_len: int = FRAME_LEN) -> None:
        if not 0 < gap < float("inf"):  # also NaN: a partial frame must expire some time
            raise ValueError(f"gap must be a positive number of seconds, got {gap!r}")
        if frame_len <= 0:
            raise ValueError("frame_len must be positive")
        self.gap = gap
        self.frame_len = frame_len
        self._partial = bytearray()
        self._last: float | None = None
        self.dropped = 0
        """Number of bytes discarded as truncated frames (for diagnostics)."""

    @property
    def pending(self) -> int:
        """Bytes of the frame currently being collected."""
        return len(self._partial)

    @property
    def partial(self) -> bytes:
        """The bytes of the frame currently being collected."""
        return bytes(self._partial)

    def expire(self, now: float) -> None:
        """Drop a partial frame whose last byte arrived more than `gap` ago."""
        if self._partial and self._last is not None and now - self._last > self.gap:
            self.dropped += len(self._partial)
            self._partial.clear()

    def deadline(self) -> float | None:
        """Time at which the current partial frame expires, or None."""
        if self._partial and self._last is not None:
            return self._last + self.gap
        return None

    def feed(self, data: bytes, now: float) -> list[bytes]:
        """Add a chunk received at time `now`; return the frames it completes."""
        self.expire(now)
        if not data:
            return []
        self._last = now
        self._partial += data
        frames = []
        n = self.frame_len
        while len(self._partial) >= n:
            frames.append(bytes(self._partial[:n]))
            del self._partial[:n]
        return frames

    def reset(self) -> None:
        """Forget any partial frame (e.g. after a reconnect)."""
        self._partial.clear()
        self._last = None
