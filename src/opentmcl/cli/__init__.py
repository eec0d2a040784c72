"""The `opentmcl` command line.

Each subcommand lives in its own module `opentmcl.cli.<name>` with
`register(subparsers)` that adds a parser whose default `func(args) -> int`
runs it. Errors the user can cause raise `CliError`; main() turns every exception into a
one-line message and the exit status of the table in `cli/exits.py` (docs/cli.md): 2 for bad
input, 3 when the module does not answer, 4 when it answers with an error status, 1 for a bug
(with its traceback only under -v). `-v`/`-q` set the log level (`cli/verbosity.py`).
"""
from __future__ import annotations

import argparse
import importlib
import logging
import os
import pathlib
import sys
from typing import NoReturn

from . import exits, verbosity

COMMANDS = ["demo", "serve", "fault", "tmc4210", "send", "asm", "disasm", "load", "run", "debug", "plot", "dashboard",
            "proxy", "log", "replay", "profile", "conform"]


class CliError(Exception):
    """A user-facing error: printed as one line. Exit status `code` if given, else the status 3 or 4
    of the library error it was raised from, else 2 (`exits.code_of`)."""

    def __init__(self, message: str, code: int | None = None) -> None:
        super().__init__(message)
        self.code = code


def about_file(path: object, exc: BaseException, what: str) -> str:
    """`exc`'s message about the file `path`, naming the file once: as it is when it names the
    file already (a read or syntax error), else after ``cannot load WHAT PATH:``."""
    text = str(exc.args[0] if isinstance(exc, KeyError) and exc.args else exc)
    return text if str(path) in text else f"cannot load {what} {path}: {text}"


def start_error(what: str, exc: OSError, tcp: str | None) -> CliError:
    """`cannot start WHAT: cause` without the errno, and for an address in use the likely fix."""
    import errno

    text = f"cannot start {what}: {exc.strerror or exc}"
    if exc.errno == errno.EADDRINUSE:
        text += (f" (--tcp {tcp})" if tcp else "") + ("; another program (an earlier `opentmcl serve` or "
                                                      "`proxy`?) listens there: stop it or choose another port")
    return CliError(text)


def same_file(a: str, b: str) -> bool:
    """Do two paths name one file (so writing one would destroy the other)?"""
    if a == "-" or b == "-":
        return False
    try:
        return pathlib.Path(a).resolve() == pathlib.Path(b).resolve()
    except OSError:
        return False


def int_arg(text: str) -> int:
    """argparse type: an int of at most LITERAL_DIGITS_MAX digits (decimal, or 0x/0b with base 0
    rules), so a 5000-digit argument is a short usage error, not int()'s digit-limit message."""
    from ..limits import LiteralTooLong, check_literal

    t = text.strip().lstrip("+-")
    try:
        check_literal(t[2:] if t[:2].lower() in ("0x", "0b", "0o") else t)
        return int(text, 0) if t[:2].lower() in ("0x", "0b", "0o") else int(text, 10)
    except LiteralTooLong as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text[:40]!r}") from None


def float_arg(text: str) -> float:
    """argparse type: a finite float written in at most 64 characters."""
    value = None
    if len(text) <= 64:
        try:
            value = float(text)
        except ValueError:
            pass
    if value is None or value != value or value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"not a finite number of at most 64 characters: {text[:40]!r}")
    return value


class _Parser(argparse.ArgumentParser):
    """argparse with the house rule for usage errors: one line, exit status 2 (not the usage block)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="opentmcl", description="Open TMCL tools: virtual modules, client, assembler.",
                     epilog=exits.epilog(), formatter_class=argparse.RawDescriptionHelpFormatter)
    from .. import __version__
    parser.add_argument("--version", action="version", version=f"opentmcl {__version__}")
    verbosity.add_options(parser, top=True)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"{__name__}.{name}").register(sub)
    verbosity.add_everywhere(parser)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version or a usage error: its status, also when called in-process
        return exc.code if isinstance(exc.code, int) else 2
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    level = verbosity.level_of(args)
    verbosity.enable_bars(level <= logging.WARNING)
    with verbosity.logging_to_stderr(args.command, level):
        return _run(args, level)


def _run(args: argparse.Namespace, level: int) -> int:
    """Run the command; any exception becomes one line and its exit status (cli/exits.py)."""
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0
    except Exception as exc:
        code = exits.code_of(exc)
        if code != exits.INTERNAL:
            print(f"opentmcl {args.command}: error: {exc}{exits.hint_for(exc, args)}", file=sys.stderr)
            return code
        if os.environ.get("OPENTMCL_DEBUG"):
            raise
        if level <= logging.INFO:
            import traceback

            traceback.print_exc(file=sys.stderr)
        print(f"opentmcl {args.command}: internal error: {type(exc).__name__}: {exc} "
              "(a bug: please report it, with the output of -v)", file=sys.stderr)
        return exits.INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
