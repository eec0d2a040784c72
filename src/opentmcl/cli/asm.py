"""`opentmcl asm SOURCE.tmc -o OUT.bin`: assemble TMCL-IDE source to a binary program file.

Every error and warning is printed on stderr as `file:line:column: [warning: ]message`, in source
order (docs/tmcl-assembler.md "Errors and warnings").
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..lang.assembler import AsmError, Program

from ..atomicfile import write_atomic
from . import CliError, same_file


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("asm", help="assemble TMCL source (.tmc) to a binary program (.bin)",
                       description="Assemble TMCL-IDE source to the 8-byte-record binary file format.")
    p.add_argument("source", help="TMCL source file")
    p.add_argument("-o", "--output", help="binary output file (default: SOURCE with .bin; '-' for stdout)")
    p.add_argument("-I", "--include", action="append", default=[], metavar="DIR",
                   help="add a directory to the #include search path (repeatable)")
    p.add_argument("-m", "--module", metavar="NAME|FILE", help="target module (TMCM-6212, PD86-1180, PD28-1021 "
                   "or a profile file NAME.toml): selects the bundled include files, checks the program size "
                   "and warns about instructions the module cannot execute")
    add_strict_option(p)
    p.add_argument("-D", "--define", action="append", default=[], metavar="NAME=VALUE",
                   help="define a constant (repeatable)")
    p.add_argument("-l", "--listing", metavar="FILE", help="write a listing ('-' for stdout)")
    p.add_argument("-s", "--symbols", metavar="FILE", help="write the label table ('-' for stdout)")
    p.add_argument("--no-stop", action="store_true", help="do not append the trailing STOP")
    p.set_defaults(func=run)


MAX_LISTED = 50  # findings printed for a binary program (diagnostics.MAX_REPORTED)


def add_strict_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--strict", action="store_true", help="refuse instructions the module cannot execute "
                   "(motor, bank, parameter or port number, opcode) instead of warning")


def print_warnings(program: Program) -> None:
    """The warnings of a successful assembly, one line each on stderr."""
    from ..lang.diagnostics import more_line

    for diag in program.warnings:
        print(diag, file=sys.stderr)
    if program.warnings_more:
        print(more_line(program.warnings_more, "warning"), file=sys.stderr)


def error_lines(exc: AsmError) -> CliError:
    """Print every error and warning of a failed assembly (source order) and return the CliError
    that ends the command: the error itself when it is the only diagnostic, else the counts."""
    from ..lang.diagnostics import more_line, summary

    found = exc.diagnostics()
    if len(found) == 1 and not exc.more:
        return CliError(str(found[0]))
    for diag in found:
        print(diag, file=sys.stderr)
    for count, what in ((exc.more, "error"), (exc.warnings_more, "warning")):
        if count:
            print(more_line(count, what), file=sys.stderr)
    return CliError(summary(len(exc.errors) + exc.more, len(exc.warnings) + exc.warnings_more))


def check_binary(path: str, code: list, module: str | None, strict: bool) -> None:
    """Warn about (or, strict, refuse) the records of a binary program `module` cannot execute."""
    from ..lang.capabilities_check import check
    from ..lang.diagnostics import ERROR, WARNING, Diagnostic, more_line, summary
    from ..modules.profile import load_profile

    if module is None:
        return
    try:
        profile = load_profile(module)
    except (KeyError, OSError, ValueError) as exc:
        raise CliError(f"cannot use the module profile {module}: {exc.args[0] if exc.args else exc}") from None
    found = [Diagnostic(path, 0, 0, f"record {addr}: {f.message}", ERROR if strict else WARNING)
             for addr, ins in enumerate(code) for f in check(ins, profile)]
    for diag in found[:MAX_LISTED]:
        print(diag, file=sys.stderr)
    if len(found) > MAX_LISTED:
        print(more_line(len(found) - MAX_LISTED, "error" if strict else "warning"), file=sys.stderr)
    if strict and found:
        raise CliError(summary(len(found), 0))


def _defines(items: list[str]) -> dict[str, int]:
    from ..limits import LiteralTooLong
    from ..protocol.opcodes import parse_number
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            num = parse_number(value) if sep else None
        except LiteralTooLong as exc:
            raise CliError(f"bad --define {name.strip()[:40]}: {exc}") from None
        if not name.strip().isidentifier() or num is None:
            raise CliError(f"bad --define {item!r}; expected NAME=NUMBER")
        out[name.strip()] = num
    return out


def _emit(target: str, text: str) -> None:
    if target == "-":
        sys.stdout.write(text)
        return
    _check_folder(target)
    try:
        write_atomic(target, text.encode("utf-8"))
    except OSError as exc:
        raise CliError(f"cannot write {target}: {exc.strerror or exc}") from None


def _check_outputs(source: str, outputs: list[str]) -> None:
    """House rule "loses nothing": no output may overwrite the source or another output."""
    named = [t for t in outputs if t and t != "-"]
    for i, target in enumerate(named):
        if same_file(target, source):
            raise CliError(f"output {target} would overwrite the source {source}")
        if any(same_file(target, other) for other in named[i + 1:]):
            raise CliError(f"two outputs are the same file {target}")
        _check_folder(target)   # before anything is written


def _check_folder(target: str) -> None:
    """A typo in an output path is a one-line error, found before any output is written."""
    folder = Path(target).parent
    if not folder.is_dir():
        raise CliError(f"cannot write {target}: folder {folder} does not exist")


def run(args: argparse.Namespace) -> int:
    from ..lang import binfile
    from ..lang.assembler import AsmError, assemble_file

    if args.strict and not args.module:
        raise CliError("--strict needs --module (the module whose capabilities are checked)")
    try:
        program = assemble_file(args.source, include_path=args.include, module=args.module,
                                append_stop=not args.no_stop, defines=_defines(args.define),
                                strict=args.strict)
    except AsmError as exc:
        raise error_lines(exc) from None
    print_warnings(program)
    out = args.output or str(Path(args.source).with_suffix(".bin"))
    if "-" in (args.listing, args.symbols) and out == "-":
        raise CliError("only one of -o, -l and -s can write to stdout ('-')")
    _check_outputs(args.source, [out, args.listing, args.symbols])
    if out == "-":
        sys.stdout.buffer.write(binfile.encode(program.instructions))
        sys.stdout.flush()
    else:
        try:
            binfile.write(out, program.instructions)
        except OSError as exc:
            raise CliError(f"cannot write {out}: {exc.strerror or exc}") from None
    if args.listing:
        _emit(args.listing, program.listing())
    if args.symbols:
        _emit(args.symbols, program.symbol_file())
    if "-" not in (out, args.listing, args.symbols):
        print(f"{out}: {summary(program)}")
    return 0


def summary(program) -> str:
    """What `asm` reports: the source's instructions, as `disasm` lists them again, and the STOP
    appended after them (docs/tmcl-assembler.md): "12 instructions + appended STOP = 13 records".
    Without an appended STOP (`--no-stop`, `#nostop`) a final STOP of the source is the one record
    `disasm` leaves out, and the summary says so."""
    from ..lang.output import STOP

    count, labels = len(program.instructions), _count(len(program.labels), "label")
    if program.appended_stop:
        return f"{_count(count - 1, 'instruction')} + appended STOP = {count} records, {labels}"
    if count and program.instructions[-1] == STOP:
        return f"{_count(count, 'instruction')} (disasm lists {count - 1}: it leaves a final STOP out), {labels}"
    return f"{_count(count, 'instruction')}, {labels}"


def _count(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"
