"""Decode the two byte streams of a serial TMCL link into capture records (docs/capture.md).

The proxy relays bytes untouched and hands a copy of every chunk, with its arrival time and
direction, to a `Decoder`. The decoder finds 9-byte frames by counting (TMCM-6212 manual 3.1),
drops a partial frame after a silent `gap` as garbage, pairs each reply with the oldest pending
request of the same command, recognises the special replies of command 136 type 0 (no checksum,
PD86-1180 manual 4.6.39) and the event replies of command 138 (status 128, manual 3.6.35), and
follows ASCII mode from a successful command 139 to a ``BIN`` line (PD28-1021 manual 3.4).
"""
from __future__ import annotations

from ..protocol.frame import FRAME_LEN, Reply, Request, checksum_ok
from ..protocol.opcodes import (
    AXIS_PARAMETER,
    COMMANDS,
    ENTER_ASCII_MODE,
    GET_FIRMWARE_VERSION,
    GLOBAL_PARAMETER,
    PORT,
    READ_PROGRAM_MEMORY,
    REQUEST_TARGET_REACHED_EVENT,
)
from ..protocol.status import Status, message

HOST, MODULE = "host", "module"
MAX_TEXT = 256
"""Most bytes of ASCII text in one record (a record line stays far below the reader's 4096-byte cap;
the module itself keeps 128 characters of a line)."""
MAX_PENDING = 1024
"""Most requests waiting for their replies (docs/capture.md): a host may pipeline this many; beyond,
the oldest are forgotten. Over twice the 455 frames a full 4 KiB pty or serial driver buffer holds."""


def mnemonic(command: int) -> str:
    cmd = COMMANDS.get(command)
    return cmd.mnemonic if cmd is not None and cmd.mnemonic else str(command)


def parameter_name(profile, command: int, type_: int, motor: int) -> str | None:
    """The name of the parameter or port a request addresses, from `profile`, or None: the type
    field of an axis parameter command, a global parameter command (bank in the motor field) or
    an I/O command (`Command.meanings`, TMCM-6212 3.6.5-3.6.13)."""
    cmd = COMMANDS.get(command)
    if profile is None or cmd is None:
        return None
    if cmd.naming(AXIS_PARAMETER, type_):
        p = profile.axis_parameters.get(type_)
    elif cmd.naming(GLOBAL_PARAMETER, type_):
        p = profile.global_parameters.get((motor, type_))
    elif cmd.naming(PORT, type_):
        p = profile.io.get((motor, type_))
    else:
        return None
    return p.name if p is not None else None


class _Stream:
    """Bytes of one direction: a partial frame and when its last byte came."""

    def __init__(self) -> None:
        self.buf = bytearray()
        self.last = 0.0
        self.suspect = 0
        """Module bytes buffered before a pause: a reply only if the frame they start is whole."""


class Decoder:
    """Chunks in (`feed`), capture records out. `profile_for(address)` names parameters."""

    def __init__(self, profile_for=lambda address: None, gap: float = 0.1) -> None:
        self.profile_for = profile_for
        self.gap = gap
        self._streams = {HOST: _Stream(), MODULE: _Stream()}
        self._pending: list[dict] = []
        self.ascii = {HOST: False, MODULE: False}
        self.identity: dict | None = None
        self._seq = 0

    def _whole_reply(self, frame: bytes) -> bool:
        """Is `frame` a reply as the module sends it: a valid checksum, or the version string that
        a pending 136 type 0 asked for?"""
        oldest = self._pending[0] if self._pending else None
        version = oldest is not None and oldest["command"] == GET_FIRMWARE_VERSION and oldest["type"] == 0
        return checksum_ok(frame) or (version and all(0x20 <= b < 0x7F for b in frame[1:]))

    def feed(self, t: float, direction: str, data: bytes) -> list[dict]:
        out: list[dict] = []
        stream = self._streams[direction]
        if stream.buf and t - stream.last > self.gap:
            if direction == MODULE and not self.ascii[direction]:
                stream.suspect = len(stream.buf)   # decided once the frame is whole
            else:
                out.append(self._record(stream.last, direction, "garbage", bytes(stream.buf)))
                stream.buf.clear()
        pos = 0
        while pos < len(data):
            if self.ascii[direction]:
                pos = self._ascii(t, direction, data, pos, out)
                continue
            need = FRAME_LEN - len(stream.buf)
            stream.buf += data[pos:pos + need]
            pos += need
            if len(stream.buf) == FRAME_LEN:
                frame = bytes(stream.buf)
                stream.buf.clear()
                if stream.suspect:
                    cut, stream.suspect = stream.suspect, 0
                    if not self._whole_reply(frame):   # the bytes before the pause were garbage
                        out.append(self._record(stream.last, direction, "garbage", frame[:cut]))
                        stream.buf += frame[cut:]
                        continue
                out.append(self._request(t, frame) if direction == HOST else self._reply(t, frame))
        stream.last = t
        return out

    def flush(self, t: float) -> list[dict]:
        """Records for bytes still buffered at the end of the capture."""
        out = []
        for direction, stream in self._streams.items():
            stream.suspect = 0
            if stream.buf:
                kind = "ascii" if self.ascii[direction] else "garbage"
                rec = self._record(stream.last, direction, kind, bytes(stream.buf))
                if kind == "ascii":
                    rec["text"] = bytes(stream.buf).decode("latin-1")
                out.append(rec)
                stream.buf.clear()
        return out

    # -- records -----------------------------------------------------------------------
    def _record(self, t: float, direction: str, kind: str, raw: bytes) -> dict:
        self._seq += 1
        return {"n": self._seq, "t": round(t, 6), "dir": direction, "kind": kind, "raw": raw.hex(" ")}

    def _request(self, t: float, frame: bytes) -> dict:
        if self.ascii[MODULE]:  # the host is binary again (after BIN): so are the replies
            self.ascii[MODULE] = False
        req = Request.decode(frame, verify=False)
        rec = self._record(t, HOST, "request", frame)
        rec.update(address=req.address, command=req.command, mnemonic=mnemonic(req.command), type=req.type,
                   motor=req.motor, value=req.value, checksum_ok=checksum_ok(frame))
        name = parameter_name(self.profile_for(req.address), req.command, req.type, req.motor)
        if name:
            rec["parameter"] = name
        self._pending.append(rec)
        if len(self._pending) > MAX_PENDING:  # requests that never got a reply are forgotten
            del self._pending[0]
        return rec

    def _reply(self, t: float, frame: bytes) -> dict:
        oldest = self._pending[0] if self._pending else None
        if oldest is not None and oldest["command"] == GET_FIRMWARE_VERSION and oldest["type"] == 0 \
                and all(0x20 <= b < 0x7F for b in frame[1:]):
            self._pending.pop(0)
            rec = self._record(t, MODULE, "version", frame)
            rec.update(reply_address=frame[0], version=frame[1:].decode("ascii"), request=oldest["n"],
                       latency=round(t - oldest["t"], 6), address=oldest["address"])
            if self.identity is None:
                self.identity = {"address": oldest["address"], "firmware_version": rec["version"]}
            return rec
        if oldest is not None and oldest["command"] == READ_PROGRAM_MEMORY:
            self._pending.pop(0)  # special reply format: the stored instruction (docs/assumptions.md)
            rec = self._record(t, MODULE, "memory", frame)
            rec.update(reply_address=frame[0], address=oldest["address"], request=oldest["n"],
                       latency=round(t - oldest["t"], 6), checksum_ok=checksum_ok(frame))
            return rec
        reply = Reply.decode(frame, verify=False)
        status, command = reply.status, reply.command
        event = status == Status.POSITION_REACHED_EVENT and command == REQUEST_TARGET_REACHED_EVENT
        rec = self._record(t, MODULE, "event" if event else "reply", frame)
        rec.update(reply_address=reply.reply_address, address=reply.module_address, status=status,
                   status_text=message(status), command=command, mnemonic=mnemonic(command), value=reply.value,
                   checksum_ok=checksum_ok(frame))
        if event:
            return rec
        for i, req in enumerate(self._pending):
            if req["command"] == command:
                del self._pending[:i + 1]
                rec["request"] = req["n"]
                rec["latency"] = round(t - req["t"], 6)
                if "parameter" in req:
                    rec["parameter"] = req["parameter"]
                if command == ENTER_ASCII_MODE and status == Status.OK:
                    self.ascii[HOST] = self.ascii[MODULE] = True
                break
        return rec

    def _ascii(self, t: float, direction: str, data: bytes, pos: int, out: list) -> int:
        """ASCII text: host bytes as lines up to <CR>; module bytes as they come."""
        stream = self._streams[direction]
        if direction == MODULE:
            for start in range(pos, len(data), MAX_TEXT):
                chunk = data[start:start + MAX_TEXT]
                rec = self._record(t, direction, "ascii", chunk)
                rec["text"] = chunk.decode("latin-1")
                out.append(rec)
            return len(data)
        end = data.find(b"\r", pos)
        if end < 0:
            stream.buf += data[pos:]
            while len(stream.buf) >= MAX_TEXT:  # no <CR> for this long: record it, keep memory bounded
                piece = bytes(stream.buf[:MAX_TEXT])
                del stream.buf[:MAX_TEXT]
                rec = self._record(t, direction, "ascii", piece)
                rec["text"] = piece.decode("latin-1")
                out.append(rec)
            return len(data)
        line = bytes(stream.buf) + data[pos:end + 1]
        stream.buf.clear()
        for start in range(0, len(line), MAX_TEXT):
            rec = self._record(t, direction, "ascii", line[start:start + MAX_TEXT])
            rec["text"] = line[start:start + MAX_TEXT].decode("latin-1")
            out.append(rec)
        words = line.decode("latin-1").strip().upper().replace(" ", "")
        if words[1:] == "BIN":  # address character + BIN: back to binary frames
            self.ascii[HOST] = False
        return end + 1
