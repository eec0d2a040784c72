"""What one assembly run has read so far: the statements, labels and constants, the files
included, and the errors and warnings collected (lang/diagnostics.py)."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..protocol.opcodes import Command
from .diagnostics import Collector
from .errors import AsmError, Cascade, Where
from .expressions import Expr


@dataclass
class Operand:
    text: str
    column: int
    expr: Expr


@dataclass
class Stmt:
    """An instruction as written: its command (None for RAW) and operands."""

    where: Where
    command: Command | None  # None for RAW
    mnemonic: str
    column: int
    operands: list[Operand]


@dataclass
class Const:
    """One definition ``Name = expression`` (a constant may be defined again with the same value)."""

    where: Where
    column: int
    expr: Expr


@dataclass
class State:
    module: str | None
    include_path: list[Path]
    append_stop: bool = True
    filename: str = "<source>"
    origin: int = 0
    statements: list[Stmt] = field(default_factory=list)
    labels: dict[str, tuple[int, Where]] = field(default_factory=dict)
    constants: dict[str, list[Const]] = field(default_factory=dict)
    included: set[str] = field(default_factory=set)
    values: dict[str, int] = field(default_factory=dict)
    resolving: list[str] = field(default_factory=list)
    poisoned: set[str] = field(default_factory=set)  # constants whose definition failed
    errors: Collector = field(default_factory=Collector)
    warnings: Collector = field(default_factory=Collector)
    lines_read: int = 0
    strict: bool = False

    def report(self, exc: AsmError) -> None:
        if not isinstance(exc, Cascade):
            self.errors.add(exc.diagnostic)
