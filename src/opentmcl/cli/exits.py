"""Exit statuses of `opentmcl` and the one table that maps an exception to its status (docs/cli.md).

    0  done
    1  internal error: an exception we did not expect (a bug; one line, "please report")
    2  usage or bad input: an option, a file, a program, a profile, an argument the library refused
    3  no reply or connection failure: the module did not answer, the link could not be opened or broke
    4  the module answered with an error status (TMCM-6212 manual 3.2.1: 1..6)

Check commands keep the statuses they document: `replay` and `conform` exit 1 when replies diverge
and `profile check` 1 when the file has errors (docs/capture.md, docs/profiles.md).
"""
from __future__ import annotations

import urllib.parse

OK, INTERNAL, USAGE, NO_REPLY, STATUS = 0, 1, 2, 3, 4

DESCRIPTIONS = {
    OK: "done",
    INTERNAL: "internal error (a bug: please report it; -v shows the traceback)",
    USAGE: "usage error or bad input (option, file, program, profile, argument)",
    NO_REPLY: "no reply or connection failure (module silent, link not opened or broken)",
    STATUS: "the module answered with an error status (wrong checksum, invalid command, type or value, ...)",
}


def _table() -> list[tuple[type[BaseException], int]]:
    """(exception type, status), the first match wins: the specific types come first."""
    from ..host.errors import (
        TmclArgumentError,
        TmclConnectionError,
        TmclError,
        TmclProtocolError,
        TmclStatusError,
        TmclTimeout,
        TmclUrlError,
    )
    from ..host.loader import LoaderError
    from ..host.probe import ProbeError
    from . import CliError

    return [
        (CliError, USAGE),               # its own `code` wins (see code_of)
        (TmclStatusError, STATUS),
        (LoaderError, STATUS),           # the module refused an instruction or stored another one
        (TmclArgumentError, USAGE),      # refused before anything was sent
        (TmclUrlError, USAGE),           # a module URL that names no link
        (ProbeError, NO_REPLY),
        (TmclTimeout, NO_REPLY),
        (TmclConnectionError, NO_REPLY),
        (TmclProtocolError, NO_REPLY),   # bytes that are not a reply: a link problem
        (TmclError, NO_REPLY),
        (ConnectionError, NO_REPLY),
        (TimeoutError, NO_REPLY),
        (ValueError, USAGE),             # the library's bad-input errors are ValueErrors
        (KeyError, USAGE),               # unknown names (modules, parameters)
        (OSError, USAGE),                # a file that cannot be read or written
    ]


def code_of(exc: BaseException) -> int:
    """The exit status for `exc`. A CliError keeps its explicit `code`; without one it keeps the
    status 3 or 4 of the library error it was raised from (``raise CliError(...)`` inside
    ``except TmclTimeout``), else 2."""
    from . import CliError

    if isinstance(exc, CliError):
        if exc.code is not None:
            return exc.code
        cause = exc.__cause__ or exc.__context__
        inner = code_of(cause) if cause is not None else USAGE
        return inner if inner in (NO_REPLY, STATUS) else USAGE
    for kind, code in _table():
        if isinstance(exc, kind):
            return code
    return INTERNAL


def _root(exc: BaseException) -> BaseException:
    """The library error behind a CliError (its cause or context), else `exc`."""
    return exc.__cause__ or exc.__context__ or exc


def _query_value(url: str, key: str, default: str) -> str:
    try:
        query = dict(urllib.parse.parse_qsl(urllib.parse.urlsplit(url).query))
    except ValueError:
        return default
    return query.get(key, default)


def no_reply_hint(url: str | None, address: int | None, host_address: int | None) -> str:
    """What to check when a module does not answer: its address (GP66), the baud rate on serial
    links (GP65, default 9600) and the host address of its replies (GP76), TMCM-6212 manual 5.1;
    on CAN the CAN IDs (GP71, GP70)."""
    scheme = (url or "").partition(":")[0].lower()
    if scheme == "can":
        return ("check the module's CAN ID (?id=, GP71), its reply ID (?reply_id=, GP70) and the "
                "bit rate (?bitrate=)")
    parts = [f"the module address ({address if address is not None else 1}: --address; GP66)"]
    if scheme == "serial":
        parts.append(f"the baud rate ({_query_value(url or '', 'baud', '9600')}: ?baud= in the URL; GP65)")
    parts.append(f"the host address ({host_address if host_address is not None else 2}: GP76)")
    if scheme == "tcp":
        parts.append("that a module is behind the TCP port")
    return "check " + ", ".join(parts[:-1]) + " and " + parts[-1]


# What to check for an error status (TMCM-6212 manual 3.2.1, table 4); the manual names no fix
# for 5 (EEPROM locked) and 6 (not available), so those get none (docs/assumptions.md).
_STATUS_CHECKS = {
    1: "the frame arrived damaged: check the cabling, the baud rate and that one host talks at a time",
    2: "the module has no such command: check the command number in its manual",
    3: "the module has no such type or parameter number: see {table}",
    4: "check the value, motor and bank against the module's ranges: see {table}",
}


def module_of(args: object) -> str | None:
    """The module type the command names: --module, or the one module of a sim:// URL (set by
    `send` from the module's version string when it answered an error status); else None."""
    given = getattr(args, "module", None)
    if isinstance(given, str) and given:
        return given
    url = getattr(args, "url", None) or ""
    if url.lower().startswith("sim://"):
        parts = urllib.parse.urlsplit(url)
        spec = parts.netloc + parts.path if ".toml" in parts.path.lower() else parts.netloc
        name = spec.partition("@")[0]
        return name if name and "," not in spec else None
    return None


def profile_table(module: str | None) -> str:
    """Where the module's parameter numbers and ranges are: its `opentmcl profile show` command,
    or, when its type is not known, that command's choices."""
    if module:
        return f"`opentmcl profile show {module}`"
    from ..modules import module_names

    return (f"`opentmcl profile show` with the module's type ({', '.join(module_names())} or a profile file; "
            "`opentmcl send 136` asks the module)")


def status_hint(exc: BaseException, args: object) -> str:
    """The likely fix for an error status a module answered, else ""."""
    from ..host.errors import TmclStatusError

    root = _root(exc)
    if not isinstance(root, TmclStatusError) or root.status not in _STATUS_CHECKS:
        return ""
    return "; " + _STATUS_CHECKS[root.status].format(table=profile_table(module_of(args)))


def hint_for(exc: BaseException, args: object) -> str:
    """A likely fix appended to the message of a no-reply error, bytes that are no reply or an
    error status, else ""."""
    from ..host.errors import TmclProtocolError, TmclTimeout

    if "check " in str(exc) or " see `" in str(exc):
        return ""
    if isinstance(_root(exc), TmclProtocolError):
        return ("; bytes that are no TMCL reply: check the baud rate (serial), that the port or socket "
                "leads to a TMCL module and that one host talks at a time")
    if not isinstance(_root(exc), TmclTimeout):
        return status_hint(exc, args)
    return "; " + no_reply_hint(getattr(args, "url", None), getattr(args, "address", None),
                                getattr(args, "host_address", None))


def epilog() -> str:
    """The status table for `opentmcl --help`."""
    rows = "\n".join(f"  {code}  {text}" for code, text in DESCRIPTIONS.items())
    return ("exit status:\n" + rows + "\n  (replay, conform: 1 when replies diverge; profile check: 1 when the file "
            "has errors)\n\nlogging: -v INFO, -vv DEBUG (every frame as TMCL text and hex), -q errors only; "
            "before or after the command")
