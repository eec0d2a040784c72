"""Assembler diagnostics: errors and warnings with their position (docs/tmcl-assembler.md "Errors").

A diagnostic prints as ``file:line:column: message`` (an error) or ``file:line:column: warning:
message``; line and column are 1-based, the column is that of the token at fault. A diagnostic
without a position (an unreadable file, a bad ``--module``) prints as ``file: message``.

`Collector` keeps the first `limit` diagnostics in source order, whatever order they were found
in, and counts the rest, so a source full of errors costs bounded memory.
"""
from __future__ import annotations

from dataclasses import dataclass, field

ERROR, WARNING = "error", "warning"
MAX_REPORTED = 50
"""Errors (and, separately, warnings) reported per run; the rest are counted ("N more")."""


@dataclass(frozen=True)
class Diagnostic:
    """One error or warning. `order` sorts diagnostics into reading order (includes in place)."""

    file: str
    line: int
    column: int
    message: str
    severity: str = ERROR
    order: tuple[int, int] = field(default=(0, 0), compare=False, repr=False)

    def __str__(self) -> str:
        head = f"{self.file}:{self.line}:{self.column}" if self.line > 0 else self.file
        return f"{head}: {'warning: ' if self.severity == WARNING else ''}{self.message}"

    def as_dict(self) -> dict[str, object]:
        """The JSON form the dashboard's editor reads."""
        return {"file": self.file, "line": self.line, "column": self.column,
                "severity": self.severity, "message": self.message}


class Collector:
    """The first `limit` diagnostics by `order` (duplicates dropped) and how many more there were."""

    def __init__(self, limit: int = MAX_REPORTED) -> None:
        self.limit = limit
        self._kept: list[Diagnostic] = []
        self._seen: set[Diagnostic] = set()
        self._cutoff: tuple[tuple[int, int], int] | None = None  # key of the last kept, once full
        self.more = 0

    @staticmethod
    def _key(d: Diagnostic) -> tuple[tuple[int, int], int]:
        return d.order, d.column

    def add(self, diag: Diagnostic) -> None:
        if diag in self._seen:
            return
        if self._cutoff is not None and self._key(diag) > self._cutoff:
            self.more += 1  # after the first `limit`: counted, not kept
            return
        self._kept.append(diag)
        self._seen.add(diag)
        if len(self._kept) > 2 * self.limit:
            self._trim()

    def _trim(self) -> None:
        self._kept.sort(key=self._key)
        dropped = self._kept[self.limit:]
        self.more += len(dropped)
        del self._kept[self.limit:]
        self._seen.difference_update(dropped)
        if len(self._kept) == self.limit:
            self._cutoff = self._key(self._kept[-1])

    @property
    def items(self) -> list[Diagnostic]:
        self._trim()
        return list(self._kept)

    def __len__(self) -> int:
        return len(self._kept) + self.more


def merged(errors: list[Diagnostic], warnings: list[Diagnostic]) -> list[Diagnostic]:
    """Errors and warnings together, in source order."""
    return sorted((*errors, *warnings), key=lambda d: (d.order, d.column))


def more_line(count: int, what: str) -> str:
    return f"... and {count} more {what}{'s' if count != 1 else ''} (only the first {MAX_REPORTED} are listed)"


def summary(errors: int, warnings: int) -> str:
    """'3 errors, 1 warning' - the last line `opentmcl asm` prints."""
    parts = [f"{errors} error{'s' if errors != 1 else ''}"] if errors else []
    if warnings:
        parts.append(f"{warnings} warning{'s' if warnings != 1 else ''}")
    return ", ".join(parts) or "no errors"
