"""The requests odemis' TMCM driver sends while `TMCLController.__init__` runs, and the checks it
makes of each reply, restated from the driver's source (delmic/odemis, src/odemis/driver/tmcm.py;
docs/sources.md "odemis' TMCM driver"; the published version with `CANController`). odemis is not on
PyPI, so this re-enacts its start-up on a real serial port opened with pyserial as the driver opens
it. The unmodified driver, run once by hand on a served TMCM-6212, sent these requests in this order.

The driver, with its defaults (address=None, refproc=None, temp=False, no param_file, no
abs_encoder, no refswitch, minpower=10.8 V):

1. opens the port at 9600 baud, 8N1, timeout 0.1 s, write_timeout 1 s, and flock()s it;
2. resynchronises: flushes the input, reads up to 1000 bytes of garbage, sends nine zero bytes
   (address 0, "there is no command 0") and wants one 9-byte reply with a good checksum (status 2
   expected, 1 tolerated); the reply's module address becomes the target of every later request;
3. 136 type 1: model = value >> 16, firmware major/minor in the low bytes (an unknown model is
   only a warning);
4. GAP 1 of the highest axis it is given ("doesn't support N axes" otherwise);
5. GIO 8, 1 "supply voltage ... on analog channel 8", 1 <-> 0.1 V; below minpower: "has no power";
6. (the user configuration in bank 2 is read only on TMCM-1110/1140/3110/6110);
7. per axis: GAP 207 (extended error flags; bit 0 stall, bit 1 deviation: only logged, but for
   bit 1 without bit 0 it first reads GAP 1 and GAP 209 for its message; a refused GAP 207 stops
   the start-up);
8. per axis GAP 1 (position), GAP 4 (speed; with GAP 154 on TMC429 models 1110/1140/3110/6110),
   GAP 5 (acceleration).

Every request is answered as `SendInstruction` reads it: 9 bytes, the checksum checked, a reply
for another command skipped, a status other than 100/101 an error (`TmclStatusRefused`).
"""
from __future__ import annotations

import fcntl
import struct
import time
from dataclasses import dataclass, field

import serial

OK_STATUS = {100, 101}          # odemis' TMCL_OK_STATUS
MIN_POWER = 10.8                # odemis' default minpower, volts
TMC429_MODELS = {1110, 1140, 3110, 6110}  # odemis' USE_INTERNAL_UNIT_429
REPLY_WAIT = 10.0
"""Seconds a reply may take here. odemis waits 0.1 s (its port timeout); a loaded test machine
may take longer, so the re-enactment waits longer for the same bytes and checks the same things."""


class TmclStatusRefused(Exception):
    """A reply whose status odemis takes for an error (its TMCLError)."""

    def __init__(self, request: tuple[int, int, int, int], status: int) -> None:
        super().__init__(f"{request}: status {status}")
        self.request, self.status = request, status


@dataclass
class OdemisStart:
    """What the driver learnt while starting, and every request it sent."""

    address: int = 0
    model: int = 0
    version: tuple[int, int] = (0, 0)
    supply_volts: float = 0.0
    positions: list[int] = field(default_factory=list)
    sent: list[tuple[int, int, int, int]] = field(default_factory=list)


def open_port(path: str) -> serial.Serial:
    """The port as odemis' `_openSerialPort` opens it, locked as it locks it."""
    port = serial.Serial(port=path, baudrate=9600, bytesize=serial.EIGHTBITS, parity=serial.PARITY_NONE,
                         stopbits=serial.STOPBITS_ONE, timeout=0.1, write_timeout=1)
    fcntl.flock(port.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    return port


def _read(port: serial.Serial, n: int) -> bytes:
    """n bytes (or what came within REPLY_WAIT)."""
    deadline = time.monotonic() + REPLY_WAIT
    buf = b""
    while len(buf) < n and time.monotonic() < deadline:
        buf += port.read(n - len(buf))
    return buf


def _checksum_ok(frame: bytes) -> bool:
    return sum(frame[:8]) & 0xFF == frame[8]


def resynchronise(port: serial.Serial) -> int:
    """odemis' `_resynchonise`: the address of the module that answers nine zero bytes."""
    port.reset_input_buffer()
    garbage = port.read(1000)
    assert garbage == b"", f"unexpected bytes before the sync: {garbage!r}"
    port.write(b"\x00" * 9)
    port.flush()
    res = _read(port, 9)
    assert len(res) == 9, f"odemis wants a 9-byte answer to the sync message, got {res!r}"
    assert port.read(1) == b"", "the device talks too much"   # odemis reads 10 and wants 9
    _ra, rt, status, _rn, _value, _chk = struct.unpack(">BBBBiB", res)
    assert status in (1, 2), f"odemis expects 'wrong checksum' or 'invalid command', got {status}"
    assert _checksum_ok(res), "odemis: 'Device message has wrong checksum'"
    return rt


def send(port: serial.Serial, start: OdemisStart, n: int, typ: int = 0, mot: int = 0, val: int = 0) -> int:
    """odemis' `SendInstruction`: the reply value; TmclStatusRefused for a status it rejects."""
    msg = bytearray(struct.pack(">BBBBiB", start.address, n, typ, mot, val, 0))
    msg[8] = sum(msg[:8]) & 0xFF
    start.sent.append((n, typ, mot, val))
    port.write(bytes(msg))
    port.flush()
    while True:
        res = _read(port, 9)
        assert len(res) == 9, f"odemis: 'Received only {len(res)} bytes after' {(n, typ, mot, val)}"
        _ra, rt, status, rn, rval, _chk = struct.unpack(">BBBBiB", res)
        assert _checksum_ok(res), "odemis only warns of a bad checksum; a served module must not send one"
        assert rt == start.address, "odemis warns of a reply from another address"
        if rn != n:
            continue            # "Skipping a message about instruction"
        if status not in OK_STATUS:
            raise TmclStatusRefused((n, typ, mot, val), status)
        return rval


def initialise(port: serial.Serial, axes: int) -> OdemisStart:
    """`TMCLController.__init__` up to the end, for `axes` axes named and connected (0..axes-1)."""
    start = OdemisStart(address=resynchronise(port))
    value = send(port, start, 136, 1)                                   # GetVersion
    start.model, start.version = value >> 16, ((value & 0xFF00) >> 8, value & 0xFF)
    send(port, start, 6, 1, axes - 1)                                   # the highest axis exists
    start.supply_volts = 0.1 * send(port, start, 15, 8, 1)              # _isFullyPowered
    assert start.supply_volts >= MIN_POWER, "odemis: 'has no power, check the power supply input'"
    for axis in range(axes):
        flags = send(port, start, 6, 207, axis)                         # _checkErrorFlag
        if flags & 2 and not flags & 1:                                 # "Encoder deviation too large"
            send(port, start, 6, 1, axis)
            send(port, start, 6, 209, axis)
    start.positions = [send(port, start, 6, 1, axis) for axis in range(axes)]   # _updatePosition
    for axis in range(axes):                                            # _updateSpeed (_readSpeed)
        send(port, start, 6, 4, axis)
        if start.model in TMC429_MODELS:
            send(port, start, 6, 154, axis)
    for axis in range(axes):                                            # _readAccel
        send(port, start, 6, 5, axis)
        if start.model in TMC429_MODELS:
            send(port, start, 6, 154, axis)
            send(port, start, 6, 153, axis)
    return start
