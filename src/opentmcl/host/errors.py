"""Typed exceptions of the host library (docs/architecture.md "Errors").

Every failure a user can meet while talking to a module is a `TmclError`:
a reply with a non-success status (`TmclStatusError`, worded as in the
manual's status table, TMCM-6212 manual 3.2.1), a reply that did not come in
time (`TmclTimeout`), a transport that cannot be opened or broke
(`TmclConnectionError`), bytes that are not a valid reply
(`TmclProtocolError`) and a parameter name the module profile does not know
(`UnknownParameterError`).

An argument the library refuses before anything is sent is a `TmclArgumentError`,
which also keeps the built-in class that plain Python code would raise:
`TmclValueError` (ValueError: out of range, not finite), `TmclTypeError`
(TypeError: not an int, not a number) and `AxisNumberError` (IndexError and
KeyError: ``module.axes[6]`` on a six-axis module). The message is one line.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

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
    """The module answered with a status other than 100/101 (manual 3.2.1).

    Raised by `Client.request_many` after every reply of the batch was read: `index` is the
    position of the (first) failed request in the batch, `answers` the answers of the batch
    (None at each failed request); both None for a single request."""

    index: int | None = None
    answers: Sequence[object] | None = None

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


class TmclUrlError(TmclConnectionError, ValueError):
    """A module URL that names no link that could be opened: unknown scheme or key, missing host,
    port or device, a bad number, an unknown sim:// module. Bad input, not a link failure (the CLI
    exits 2, not 3); still a TmclConnectionError, as before it had its own class."""


class TmclAddressError(TmclError, ValueError):
    """A request for a module address this connection cannot reach (on CAN the connection's
    CAN ID, not an address byte, selects the module)."""


class TmclProtocolError(TmclError):
    """Bytes were received that are not a valid reply (e.g. wrong checksum)."""


class TmclChecksumError(TmclProtocolError):
    """The reply to `request` came with a wrong checksum (manual 3.1.1): a garbled reply. The
    link is brought back in step before the next request (docs/host.md "Lost, late and garbled
    replies")."""

    def __init__(self, request: Request, raw: bytes):
        self.request = request
        self.raw = bytes(raw)
        super().__init__(f"reply to {describe_request(request)} from module {request.address} with a wrong "
                         f"checksum: {self.raw.hex(' ')}")


class TmclArgumentError(TmclError):
    """An argument refused by the library before anything was sent."""


class TmclValueError(TmclArgumentError, ValueError):
    """An argument of the right type but out of range (e.g. a value beyond 32 bits, timeout=-1)."""


class TmclBatchError(TmclValueError):
    """A `request_many` batch longer than `opentmcl.host.client.MAX_BATCH`; nothing was sent."""


class TmclTypeError(TmclArgumentError, TypeError):
    """An argument of the wrong type (e.g. a float where the frame carries an integer)."""


class UnknownParameterError(TmclArgumentError, KeyError):
    """A parameter, port or module name that the module profile does not define."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class UnknownAttributeError(UnknownParameterError, AttributeError):
    """``axis.params.NAME`` for a name the profile does not define (an AttributeError too, so that
    hasattr() and getattr() with a default work)."""


class AxisNumberError(UnknownParameterError, IndexError):
    """An axis number the module does not have (``module.axes[6]`` on a six-axis module)."""


def check_timeout(value: object, name: str = "timeout") -> float:
    """`value` as float seconds: a finite number > 0; TmclTypeError / TmclValueError otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TmclTypeError(f"{name} must be a number of seconds, got {value!r}")
    if not 0 < value < math.inf:  # also NaN
        raise TmclValueError(f"{name} must be a positive, finite number of seconds, got {value!r}")
    return float(value)


def check_seconds(value: object, name: str = "seconds") -> float:
    """`value` as float seconds: a finite number >= 0 (a sleep of 0 is allowed)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TmclTypeError(f"{name} must be a number of seconds, got {value!r}")
    if not 0 <= value < math.inf:
        raise TmclValueError(f"{name} must be a finite number of seconds >= 0, got {value!r}")
    return float(value)


def check_int(value: object, name: str) -> int:
    """`value` if it is an int (not a bool); TmclTypeError otherwise."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise TmclTypeError(f"{name} must be an int, got {type(value).__name__} {value!r}")
    return value
