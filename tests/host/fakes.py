"""Stand-ins for transport-level error tests only: they produce what a real module cannot
(garbage, wrong checksums, silence, late or stray replies). Everything else is tested against
the real VirtualModule."""
from __future__ import annotations

from opentmcl.host.errors import TmclTimeout
from opentmcl.host.transport import Transport


class ScriptedTransport(Transport):
    """Answers each request with the next scripted byte string (may be b"" or several frames).

    Time is virtual: `recv` with too few bytes "waits" its whole timeout and raises.
    """

    def __init__(self, *answers: bytes, frame_format: str = "serial"):
        self.answers = list(answers)
        self.frame_format = frame_format
        self.sent: list[bytes] = []
        self.rx = bytearray()
        self.now = 0.0
        self.closed = False

    def feed(self, data: bytes) -> None:
        self.rx += data

    def send(self, data: bytes) -> None:
        self.sent.append(bytes(data))
        if self.answers:
            self.rx += self.answers.pop(0)

    def recv(self, n: int, timeout: float) -> bytes:
        if len(self.rx) < n:
            self.now += timeout
            raise TmclTimeout(f"fake: {len(self.rx)} of {n} bytes")
        out = bytes(self.rx[:n])
        del self.rx[:n]
        return out

    def reset_input(self) -> None:
        self.rx.clear()

    def sleep(self, seconds: float) -> None:
        self.now += seconds

    def monotonic(self) -> float:
        return self.now

    def close(self) -> None:
        self.closed = True


class FencedScript(ScriptedTransport):
    """`ScriptedTransport` that answers the client's fence itself (GGP 66, sent to bring the link
    back in step after a lost reply, opentmcl.host.client.FENCES): the scripted answers are left to
    the requests of the test. `fences` counts them."""

    def __init__(self, *answers: bytes, frame_format: str = "serial"):
        super().__init__(*answers, frame_format=frame_format)
        self.fences = 0

    def send(self, data: bytes) -> None:
        body = data if self.frame_format == "can" else data[1:]
        if body[0] == 10 and body[1] == 66:  # GGP 66, bank 0
            self.sent.append(bytes(data))
            self.fences += 1
            self.rx += bytes([1, 100, 10, 0, 0, 0, 1]) if self.frame_format == "can" else \
                bytes([2, 1, 100, 10, 0, 0, 0, 1]) + bytes([(2 + 1 + 100 + 10 + 1) % 256])
            return
        super().send(data)
