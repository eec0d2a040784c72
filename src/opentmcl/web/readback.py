"""Program read-back (docs/dashboard-program.md "Read back"): the module's program memory read with
command 134 ("read program memory", TMCM-6212 manual 3.6.36), disassembled with labels, and
compared with the editor's program.

The memory is read from address 0 until `EMPTY_RUN` locations in a row hold nothing (all four
fields 0: TMCL has no command 0, and an erased virtual module reads so; docs/assumptions.md) or the
profile's program memory ends. Each 134 takes its own turn on the link, so a stop goes between two.
"""
from __future__ import annotations

import difflib

from ..host import TmclError
from ..lang.assembler import Program
from ..lang.binfile import Instruction
from ..lang.disassembler import disassemble
from ..protocol.opcodes import format_instruction
from .service import Dashboard, DashboardError

EMPTY = (0, 0, 0, 0)
EMPTY_RUN = 16      # empty locations in a row that end the read
MAX_DIFFERENCES = 200


def read_memory(d: Dashboard) -> list[Instruction]:
    """The stored program: locations 0.. up to the last one before `EMPTY_RUN` empty ones."""
    loader = d.loader()
    out: list[Instruction] = []
    empty = 0
    for address in range(d.profile.program_memory):
        try:
            ins = loader.read_one(address)
        except TmclError as exc:
            if address == 0:
                raise DashboardError(f"command 134 refused: {exc} (is the program protected, GP81?)") from None
            raise DashboardError(f"reading program memory at {address}: {exc}") from None
        out.append(ins)
        empty = empty + 1 if tuple(ins) == EMPTY else 0
        if empty >= EMPTY_RUN:
            break
    while out and tuple(out[-1]) == EMPTY:
        out.pop()
    return out


def _one(ins: Instruction | None) -> str | None:
    """One instruction in the manual's numbers ("SAP 4, 0, 51200"), or None past the end."""
    if ins is None:
        return None
    return format_instruction(*ins) or ", ".join(map(str, ins))


def _text(d: Dashboard, code: list[Instruction], labels: dict[str, int] | None, comments: bool) -> str:
    """TMCL source with the module's bundled names when it has them (#include <tmcm6212.inc>)."""
    try:
        return disassemble(code, labels=labels, comments=comments, module=d.profile.name)
    except ValueError:  # a user profile without bundled include files
        return disassemble(code, labels=labels, comments=comments)


def read_back(d: Dashboard, editor_source: str) -> dict[str, object]:
    """{"source": the module's program as TMCL source, "count": instructions, "same": whether the
    editor's program assembles to exactly them, "editor_ok", "differences": [{address, line,
    editor, module}], "diff": unified diff lines of the two disassemblies}."""
    stored = read_memory(d)
    prog: Program | None = d.assemble(editor_source).get("_program") if editor_source.strip() else None
    mine: list[Instruction] = list(prog.instructions) if prog is not None else []
    same = prog is not None and [tuple(i) for i in mine] == [tuple(i) for i in stored]
    labels = dict(prog.labels) if same and prog is not None else None
    differences = []
    for address in range(max(len(mine), len(stored))):
        a = mine[address] if address < len(mine) else None
        b = stored[address] if address < len(stored) else None
        if a is None or b is None or tuple(a) != tuple(b):
            src = prog.source[address] if prog is not None and address < len(prog.source) else None
            differences.append({"address": address, "line": src.line if src is not None and src.file == "<editor>" else None,
                                "editor": _one(a), "module": _one(b)})
            if len(differences) >= MAX_DIFFERENCES:
                break
    diff = list(difflib.unified_diff(_text(d, mine, None, False).splitlines() if mine else [],
                                     _text(d, stored, None, False).splitlines(),
                                     "editor", "module", lineterm="", n=2))
    return {"source": _text(d, stored, labels, True), "count": len(stored), "same": same,
            "editor_ok": prog is not None, "differences": differences, "diff": diff[:2000]}
