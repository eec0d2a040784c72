"""Assembler for TMCL-IDE source (TMCM-6212 manual 2.4, 3.3, 3.5.6.4, chapter 7).

Source syntax, one statement per line:

- ``// comment`` to the end of the line;
- ``Label:`` defines a label (the address of the next instruction); it may share the line with an
  instruction (``Loop: MVP ABS, 0, 1000``) and may have spaces before the colon (``Loop :``);
- ``Name = expression`` defines a constant (7.3 "Using Symbolic Constants");
- ``#include file`` reads another source file (searched in the including file's directory, the
  include path, then the bundled include files of the selected module); a file is read once;
- ``#nostop`` suppresses the STOP that is otherwise appended after the last instruction;
- ``MNEMONIC operand, operand, ...`` - mnemonics are case-insensitive; operands are expressions of
  decimal, ``0x``/``$`` hex and ``0b`` binary literals, constants and labels with ``+ - * / % & | ^
  ~ << >>`` and parentheses, or the command's symbolic names (ABS, TICKS, ADD, GE, ETO, ...);
- ``RAW command, type, motor, value`` emits any instruction verbatim (used by the disassembler for
  records that have no mnemonic form).

Output: the program (a list of instructions), its 8-byte-record image, the label table, a
listing and the warnings (`Program.warnings`). Every error is found in one run: AsmError carries
them all, in source order (lang/diagnostics.py), each naming file, line and column. With a module,
instructions it cannot execute (lang/capabilities_check.py) are warnings, or errors with `strict`.

The work is done in rooms of their own: reading lines and includes (reader.py, includes.py),
expressions (expressions.py), labels and constants (symbols.py), encoding and the program
(encoder.py, output.py), errors (errors.py, diagnostics.py). This module puts them together and
keeps the names callers import from it.
"""
from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from ..limits import TEXT_MAX, InputTooLarge, read_text
from .binfile import Instruction
from .encoder import finish
from .errors import AsmError, Where
from .expressions import MAX_EXPR_DEPTH, MAX_EXPR_TOKENS, MAX_INTERMEDIATE, Expr, ExpressionError, evaluate
from .includes import DEFAULT_MODULE, INCLUDE_DIR, bundled_include, include_key
from .output import STOP, Program, SourceLine
from .reader import MAX_INCLUDE_DEPTH, RAW, read_lines
from .state import Const, State
from .symbols import MAX_CONSTANT_DEPTH

if TYPE_CHECKING:
    from ..modules.profile import ModuleProfile

__all__ = [
    "DEFAULT_MODULE", "INCLUDE_DIR", "MAX_CONSTANT_DEPTH", "MAX_EXPR_DEPTH", "MAX_EXPR_TOKENS",
    "MAX_INCLUDE_DEPTH", "MAX_INTERMEDIATE", "RAW", "STOP", "AsmError", "ExpressionError",
    "Instruction", "Program", "SourceLine", "assemble", "assemble_file", "bundled_include",
    "evaluate", "include_key",
]


def _profile(module: str | None) -> ModuleProfile | None:
    if module is None:
        return None
    from ..modules.profile import load_profile
    try:
        return load_profile(module)
    except KeyError as exc:
        raise AsmError("<options>", 0, 0, str(exc.args[0])) from None
    except (OSError, ValueError) as exc:  # a profile file that cannot be read or used
        raise AsmError(str(module), 0, 0, f"cannot use the module profile: {exc}") from None


def _source_text(source: str | bytes | bytearray) -> str:
    if isinstance(source, (bytes, bytearray)):
        source = bytes(source).decode("utf-8", errors="replace")
    if not isinstance(source, str):
        raise TypeError(f"assemble() takes the source text (str or bytes), not {type(source).__name__}; "
                        "assemble_file() reads a file")
    return source


def assemble(source: str, *, filename: str = "<source>", include_path: Iterable[str | os.PathLike[str]] = (),
             module: str | ModuleProfile | None = None, append_stop: bool = True,
             defines: Mapping[str, int] | None = None, origin: int = 0, strict: bool = False) -> Program:
    """Assemble TMCL source text; AsmError lists every error (and the warnings so far).

    `module` ("TMCM-6212", "PD86-1180", "PD28-1021", an alias, a profile file NAME.toml or a loaded
    ModuleProfile, e.g. the profile of the module a client talks to) selects
    the bundled include files, checks that the program fits its memory (an error) and that the
    module can execute every instruction - its opcodes, motors, parameter banks and numbers, ports,
    coordinates and interrupts (`Program.warnings`; errors with `strict`). Without it the TMCM-6212
    includes are used and only the commands of direct mode only (138 and the control commands,
    which no module runs in a program) are warned of. `defines` are extra constants. `origin` is the
    program memory address the program is loaded at (labels are absolute).
    """
    if isinstance(origin, bool) or not isinstance(origin, int) or origin < 0:
        raise ValueError(f"origin must be a program memory address >= 0, not {origin!r}")
    source = _source_text(source)
    if module is None or isinstance(module, str):
        profile, key = _profile(module), module
    else:
        profile, key = module, module.name   # the name picks the bundled includes
    st = State(key, [Path(p) for p in include_path], append_stop, filename, origin, strict=bool(strict))
    where = Where("<defines>", 0, "")
    for name, value in (defines or {}).items():
        st.constants[name] = [Const(where, 0, Expr("num", 0, value=int(value)))]
    path = Path(filename) if filename and not filename.startswith("<") else None
    if path is not None:
        st.included.add(str(path.resolve()))
    read_lines(source, filename, path, st, 0)
    return finish(st, profile)


def assemble_file(path: str | os.PathLike[str], *, include_path: Iterable[str | os.PathLike[str]] = (),
                  module: str | ModuleProfile | None = None, append_stop: bool = True,
                  defines: Mapping[str, int] | None = None, origin: int = 0, strict: bool = False) -> Program:
    """Assemble a source file; AsmError (line 0: no position) if it cannot be read."""
    p = Path(path)
    try:
        text = read_text(p, TEXT_MAX, "program source", errors="replace")
    except InputTooLarge as exc:
        raise AsmError(str(p), 0, 0, str(exc)) from None
    except OSError as exc:
        raise AsmError(str(p), 0, 0, f"cannot read file: {exc.strerror or exc}") from None
    return assemble(text, filename=str(p), include_path=include_path, module=module,
                    append_stop=append_stop, defines=defines, origin=origin, strict=strict)
