"""The ASCII interface of the PD28-1021 / PD86-1180 (PD28-1021 manual 3.4, PD86-1180 manual 4.5).

Bytes in, bytes out. A line starts with the module's address character (A = address 1, ...);
characters are echoed per GP67 bits 4/5 once the line is addressed to this module
(00: every character, 01: the whole line after <CR>, 10: no echo); backspace erases the last
character; <CR> executes the line and sends `BA 100 -5000`-style replies. BIN returns to binary
mode; RUN and STOP start and stop the TMCL program. Lines for other modules are ignored silently.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..protocol import ascii as codec
from ..protocol.status import Status

if TYPE_CHECKING:
    from .vm import VirtualModule

CR, LF = 0x0D, 0x0A
BACKSPACES = (0x08, 0x7F)
MAX_LINE = 128


class AsciiInterface:
    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm
        self.line = bytearray()
        self.addressed: bool | None = None  # None until the address character arrived
        self.leftover = b""

    @property
    def echo(self) -> codec.EchoMode:
        return codec.echo_mode(self.vm.globals.get_raw(0, 67))

    def feed(self, data: bytes) -> bytes:
        """Process received bytes; return what the module sends back. Bytes after a BIN line are
        binary frames again: they are left in `leftover` for the binary framer."""
        out = bytearray()
        self.leftover = b""
        for i, byte in enumerate(data):
            if not self.vm.ascii_mode:  # BIN switched back: the rest is binary, not ours
                self.leftover = bytes(data[i:])
                break
            out += self._byte(byte)
        return bytes(out)

    def _byte(self, byte: int) -> bytes:
        if byte == LF:
            return b""
        if byte == CR:
            return self._end_of_line()
        if byte in BACKSPACES:
            if not self.line:
                return b""
            self.line.pop()
            if not self.line:
                self.addressed = None
            return bytes([byte]) if self._echo_chars() else b""
        if self.addressed is None:
            if byte == 0x20:
                return b""
            address = self.vm.address  # A = 1 ... Z = 26 (3.4.1); other addresses have no character
            self.addressed = 0x40 < byte < 0x7F and 1 <= address <= 26 and \
                chr(byte).upper() == codec.address_letter(address)
        if len(self.line) < MAX_LINE:
            self.line.append(byte)
        return bytes([byte]) if self._echo_chars() else b""

    def _echo_chars(self) -> bool:
        return bool(self.addressed) and self.echo is codec.EchoMode.CHARACTER

    def _end_of_line(self) -> bytes:
        line, addressed = bytes(self.line), self.addressed
        self.line.clear()
        self.addressed = None
        if not addressed:
            return b""
        echo = self.echo
        out = b"\r" if echo is codec.EchoMode.CHARACTER else b""
        if echo is codec.EchoMode.LINE:
            out = line + b"\r"
        return out + self.execute(line.decode("ascii", "replace"))

    def execute(self, line: str) -> bytes:
        """One command line -> the reply line (with <CR>)."""
        from .table import execute

        vm = self.vm
        try:
            cmd = codec.parse_command(line)
        except codec.AsciiError as exc:
            return self._reply(int(exc.status), 0)
        if cmd.command is None:  # BIN, the one command without a binary form
            vm.ascii_mode = False
            return self._reply(int(Status.OK), 0)
        vm.touch()
        out = execute(vm, cmd.command, cmd.type, cmd.motor, cmd.value, program=False)
        if out is None or isinstance(out, bytes):
            return self._reply(int(Status.OK), 0)
        return self._reply(*out)

    def _reply(self, status: int, value: int) -> bytes:
        host = self.vm.host_address
        if not 1 <= host <= 26:  # no address character for the reply (3.4.3): executed, no reply
            return b""
        return codec.encode_reply(host, self.vm.address, status, value)
