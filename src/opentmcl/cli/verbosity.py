"""`-v/--verbose` and `-q/--quiet` (top level and every subcommand), the stderr log handler of the
`opentmcl` logger hierarchy, and progress bars on a terminal (docs/cli.md).

Levels: default WARNING, -v INFO, -vv DEBUG (every frame as TMCL text and hex), -q ERROR. A
progress bar (tqdm) is drawn only when stderr is a terminal and not with -q; without a terminal
nothing is drawn, so logs and pipes stay clean.
"""
from __future__ import annotations

import argparse
import logging
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

LEVELS = (logging.WARNING, logging.INFO, logging.DEBUG)


def add_options(parser: argparse.ArgumentParser, *, top: bool = False) -> None:
    """-v (repeatable) and -q; a subcommand whose own option has the short name (tmc4210 -v is
    --velocity) gets the long name only. `send -v` is both its whole-reply switch and INFO."""
    taken = parser._option_string_actions  # argparse keeps no public view of its option names
    dest = "top_verbose" if top else "verbose"
    if "--verbose" not in taken:
        names = [n for n in ("-v", "--verbose") if n not in taken]
        parser.add_argument(*names, dest=dest, action="count", default=0,
                            help="more log output on stderr: -v INFO, -vv DEBUG (every frame)")
    if "--quiet" not in taken:
        names = [n for n in ("-q", "--quiet") if n not in taken]
        parser.add_argument(*names, dest="top_quiet" if top else "quiet", action="store_true",
                            help="errors only: no warnings, no progress bar")


def add_everywhere(parser: argparse.ArgumentParser) -> None:
    """`add_options` on every subcommand parser, nested ones too (`profile probe -v`)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                add_options(child)
                add_everywhere(child)


def level_of(args: argparse.Namespace) -> int:
    """The log level the options ask for."""
    if getattr(args, "quiet", False) or getattr(args, "top_quiet", False):
        return logging.ERROR
    count = int(getattr(args, "verbose", 0) or 0) + int(getattr(args, "top_verbose", 0) or 0)
    return LEVELS[min(count, len(LEVELS) - 1)]


class _Format(logging.Formatter):
    """``opentmcl CMD: ...`` for warnings and errors (as `serve` always wrote them), ``LEVEL
    logger: ...`` below; an exception's traceback follows its record, as logging does."""

    def __init__(self, command: str) -> None:
        super().__init__()
        self.loud = logging.Formatter(f"opentmcl {command}: %(message)s")
        self.quiet = logging.Formatter("%(levelname)s %(name)s: %(message)s")

    def format(self, record: logging.LogRecord) -> str:
        return (self.loud if record.levelno >= logging.WARNING else self.quiet).format(record)


@contextmanager
def logging_to_stderr(command: str, level: int) -> Iterator[logging.Logger]:
    """The `opentmcl` logger writes to stderr at `level` while the command runs (removed afterwards,
    so that main() can run many times in one process)."""
    logger = logging.getLogger("opentmcl")
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(_Format(command))
    old_level, old_propagate = logger.level, logger.propagate
    logger.addHandler(handler)
    logger.setLevel(level)
    logger.propagate = False
    try:
        yield logger
    finally:
        logger.removeHandler(handler)
        logger.setLevel(old_level)
        logger.propagate = old_propagate


_state = {"bars": True}


def enable_bars(on: bool) -> None:
    """Progress bars and progress lines allowed (not with -q)."""
    _state["bars"] = on


def bars_wanted() -> bool:
    """A bar is drawn only on a terminal (stderr) and not with -q."""
    try:
        return _state["bars"] and sys.stderr.isatty()
    except (AttributeError, ValueError):  # a closed or replaced stream
        return False


def _size() -> tuple[int, int]:
    """(columns, lines) of the terminal on stderr; 80 x 24 where it reports none (a pty nobody
    sized says 0 x 0, and tqdm then draws nothing)."""
    try:
        size = os.get_terminal_size(sys.stderr.fileno())
        columns, lines = size.columns, size.lines
    except (OSError, ValueError, AttributeError):
        columns = lines = 0
    return (columns if columns > 0 else 80), (lines if lines > 0 else 24)


class Bar:
    """A tqdm bar on stderr, or nothing (`update` and `close` do nothing) off a terminal."""

    def __init__(self, total: float, description: str, unit: str = "it") -> None:
        self._bar: Any = None
        if bars_wanted():
            from tqdm import tqdm  # type: ignore[import-untyped]  # no stubs shipped

            columns, lines = _size()

            self._bar = tqdm(total=total, desc=description, unit=unit, file=sys.stderr, leave=False,
                             ncols=columns, nrows=lines, mininterval=0.2)

    def to(self, done: float, total: float | None = None) -> None:
        """Show `done` of `total` (the callback shape of `Loader.download`'s `progress`)."""
        if self._bar is None:
            return
        if total is not None and total != self._bar.total:
            self._bar.total = total
        self._bar.update(done - self._bar.n)

    def print(self, line: str) -> None:
        """A line on stdout (flushed), with the bar cleared and redrawn around it when drawn."""
        if self._bar is None:
            print(line, flush=True)
        else:
            self._bar.write(line, file=sys.stdout)
            sys.stdout.flush()

    def write(self, line: str) -> None:
        """A progress line on stderr (not with -q), above the bar when one is drawn."""
        if not _state["bars"]:
            return
        if self._bar is None:
            print(line, file=sys.stderr, flush=True)
        else:
            self._bar.write(line, file=sys.stderr)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> Bar:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
