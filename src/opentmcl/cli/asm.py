"""`opentmcl asm SOURCE.tmc -o OUT.bin`: assemble TMCL-IDE source to a binary program file."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..atomicfile import write_atomic
from . import CliError, same_file


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("asm", help="assemble TMCL source (.tmc) to a binary program (.bin)",
                       description="Assemble TMCL-IDE source to the 8-byte-record binary file format.")
    p.add_argument("source", help="TMCL source file")
    p.add_argument("-o", "--output", help="binary output file (default: SOURCE with .bin; '-' for stdout)")
    p.add_argument("-I", "--include", action="append", default=[], metavar="DIR",
                   help="add a directory to the #include search path (repeatable)")
    p.add_argument("-m", "--module", help="target module (TMCM-6212, PD86-1180, PD28-1021): selects the "
                   "bundled include files and checks commands and program size")
    p.add_argument("-D", "--define", action="append", default=[], metavar="NAME=VALUE",
                   help="define a constant (repeatable)")
    p.add_argument("-l", "--listing", metavar="FILE", help="write a listing ('-' for stdout)")
    p.add_argument("-s", "--symbols", metavar="FILE", help="write the label table ('-' for stdout)")
    p.add_argument("--no-stop", action="store_true", help="do not append the trailing STOP")
    p.set_defaults(func=run)


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

    try:
        program = assemble_file(args.source, include_path=args.include, module=args.module,
                                append_stop=not args.no_stop, defines=_defines(args.define))
    except AsmError as exc:
        raise CliError(str(exc)) from None
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
        print(f"{out}: {len(program.instructions)} instructions, {len(program.labels)} labels")
    return 0
