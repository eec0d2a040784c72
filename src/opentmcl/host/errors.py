"""Typed exceptions of the host library (DESIGN.md "Errors and bad input").

Every failure a user can meet while talking to a module is a `TmclError`:
a reply with a non-success status (`TmclStatusError`, worded as in the
manual's status table, TMCM-6212 manual 3.2.1), a reply that did not come in
time (`TmclTimeout`), a transport that cannot be opened or broke
(`TmclConnectionError`), bytes that are not a valid reply
(`TmclProtocolError`) and a parameter name the module profile does not know
(`UnknownParameterError`).
"""
from __future__ import annotations

from ..protocol.frame import Reply, Request
from ..protocol.opcodes import format_instruction
from ..protocol.status import message


def describe_request(request: Request) -> str:
    """The request as the manual writes it, e.g. ``MVP ABS, 0, 1000`` or ``GAP 1, 0``; control
    commands, which have no mnemonic, as their numbers."""
    text = format_instruction(request.command, request.type, request.motor, request.value)
    if text is None:
        text = (f"command {request.command} (type {request.type}, motor/bank {request.motor}, "
                f"value {request.value})")
    return text


class TmclError(Exception):
    """Base class of every error raised by opentmcl.host."""


class TmclStatusError(TmclError):
    """The module answered with a status other than 100/101 (manual 3.2.1)."""

    def __init__(self, status: int, request: Request, reply: Reply | None = None):
        self.status = status
        self.request = request
        self.reply = reply
        super().__init__(f"status {status} ({message(status)}) for {describe_request(request)}"
                         f" at module {request.address}")

    @property
    def message(self) -> str:
        """The manual's wording of the status code."""
        return message(self.status)


class TmclTimeout(TmclError, TimeoutError):
    """No (complete) reply within the timeout."""


class TmclConnectionError(TmclError, ConnectionError):
    """The transport could not be opened, or it was closed or broke."""


class TmclAddressError(TmclError, ValueError):
    """A request for a module address this connection cannot reach (on CAN the connection's
    CAN ID, not an address byte, selects the module)."""


class TmclProtocolError(TmclError):
    """Bytes were received that are not a valid reply (e.g. wrong checksum)."""


class UnknownParameterError(TmclError, KeyError):
    """A parameter, port or module name that the module profile does not define."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""
