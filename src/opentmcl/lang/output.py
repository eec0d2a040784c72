"""The assembler's output: the program, its binary image, symbol file and listing
(docs/tmcl-assembler.md "From Python", "Binary file format")."""
from __future__ import annotations

from dataclasses import dataclass, field

from ..protocol.opcodes import Op
from .binfile import Instruction, encode
from .diagnostics import Diagnostic

STOP = Instruction(int(Op.STOP), 0, 0, 0)
"""Appended after the last instruction unless the source says #nostop (docs/tmcl-assembler.md)."""


@dataclass(frozen=True)
class SourceLine:
    file: str
    line: int
    text: str


@dataclass
class Program:
    """Result of assembly."""

    instructions: list[Instruction]
    labels: dict[str, int]
    constants: dict[str, int]
    source: list[SourceLine | None]  # per instruction; None for the appended STOP
    module: str | None = None
    filename: str = "<source>"
    origin: int = 0  # program memory address of the first instruction (labels are absolute)
    warnings: list[Diagnostic] = field(default_factory=list)
    """What the module cannot execute (only with a module), in source order."""
    warnings_more: int = 0
    """Warnings beyond diagnostics.MAX_REPORTED, counted but not listed."""

    @property
    def appended_stop(self) -> bool:
        """The last record is the STOP the assembler appended (not a source instruction)."""
        return bool(self.source) and self.source[-1] is None

    def image(self) -> bytes:
        """The binary file contents (TMCL-IDE format: 8-byte records, no header)."""
        return encode(self.instructions)

    def symbol_file(self) -> str:
        """Labels and their addresses, one per line: ``Name<TAB>address``, by address."""
        rows = sorted(self.labels.items(), key=lambda kv: (kv[1], kv[0]))
        return "".join(f"{name}\t{addr}\n" for name, addr in rows)

    def listing(self) -> str:
        """Address, record bytes and source of every instruction, with labels on their own lines."""
        by_addr: dict[int, list[str]] = {}
        for name, addr in self.labels.items():
            by_addr.setdefault(addr, []).append(name)
        out = []
        for index, ins in enumerate(self.instructions):
            addr = self.origin + index
            for name in sorted(by_addr.get(addr, ())):
                out.append(f"{'':4}  {'':23}  {'':>6}  {name}:")
            raw = " ".join(f"{b:02X}" for b in ins.encode())
            src = self.source[index]
            if src is None:
                out.append(f"{addr:04d}  {raw}  {'':>6}  STOP  // appended")
                continue
            where = str(src.line) if src.file == self.filename else f"{src.file}:{src.line}"
            out.append(f"{addr:04d}  {raw}  {where:>6}  {src.text.strip()}")
        for name in sorted(by_addr.get(self.origin + len(self.instructions), ())):
            out.append(f"{'':4}  {'':23}  {'':>6}  {name}:")
        return "\n".join(out) + "\n"
