"""The assembler's exception and the position it names (docs/tmcl-assembler.md "Errors and warnings").

`AsmError` carries every error of a run (lang/diagnostics.py keeps them in source order); `fail`
raises one at a column of a source line (`Where`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import NoReturn

from .diagnostics import ERROR, Collector, Diagnostic, merged, more_line


class AsmError(Exception):
    """Errors in TMCL source. `file`, `line`, `column` (1-based; line 0: no position) and `message`
    are those of the first error; `errors` lists every error in source order (at most
    diagnostics.MAX_REPORTED, `more` counts the rest), `warnings` and `warnings_more` likewise.
    str() is one line per error."""

    def __init__(self, file: str, line: int, column: int, message: str, *,
                 order: tuple[int, int] = (0, 0)):
        self.file, self.line, self.column, self.message = file, line, column, message
        self.errors = [Diagnostic(file, line, column, message, ERROR, order)]
        self.warnings: list[Diagnostic] = []
        self.more = self.warnings_more = 0
        super().__init__(str(self.errors[0]))

    @classmethod
    def from_collected(cls, errors: Collector, warnings: Collector) -> AsmError:
        first, *_ = kept = errors.items
        exc = cls(first.file, first.line, first.column, first.message, order=first.order)
        exc.errors, exc.more = kept, errors.more
        exc.warnings, exc.warnings_more = warnings.items, warnings.more
        exc.args = ("\n".join(str(d) for d in kept) + (f"\n{more_line(exc.more, 'error')}" if exc.more else ""),)
        return exc

    @property
    def diagnostic(self) -> Diagnostic:
        return self.errors[0]

    def diagnostics(self) -> list[Diagnostic]:
        """Errors and warnings together, in source order."""
        return merged(self.errors, self.warnings)


class Cascade(AsmError):
    """A consequence of an error already reported (a constant whose definition failed)."""


@dataclass
class Where:
    """A source line: its file (as displayed), number and text."""

    file: str
    line: int
    text: str
    seq: int = 0  # position in reading order (an include's lines come where it is included)


def fail(where: Where, column: int, message: str) -> NoReturn:
    """Raise AsmError at `column` of the line `where`."""
    raise AsmError(where.file, where.line, column, message, order=(where.seq, column))
