"""`opentmcl disasm OUT.bin`: turn a binary program file back into TMCL source."""
from __future__ import annotations

import argparse
import re

from ..atomicfile import write_atomic
from . import CliError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("disasm", help="disassemble a binary program (.bin) to TMCL source",
                       description="Disassemble an 8-byte-record TMCL binary file; the output "
                       "re-assembles to identical bytes.")
    p.add_argument("binary", help="binary program file ('-' for stdin)")
    p.add_argument("-o", "--output", help="source output file (default: stdout)")
    p.add_argument("-s", "--symbols", metavar="FILE",
                   help="label table (as written by 'opentmcl asm -s') to name jump targets")
    p.add_argument("-m", "--module", help="use this module's bundled names (AP..., GP..., TI_..., Motor<n>)")
    p.add_argument("--no-comments", action="store_true", help="omit the '// address' comments")
    p.set_defaults(func=run)


def _read_symbols(path: str) -> dict[str, int]:
    from ..limits import TEXT_MAX, InputTooLarge, read_text

    try:
        text = read_text(path, TEXT_MAX, "label table")
    except InputTooLarge as exc:
        raise CliError(f"{path}: {exc}") from None
    except OSError as exc:
        raise CliError(f"cannot read {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise CliError(f"{path}: not a label table (not UTF-8 text)") from None
    out = {}
    for n, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        parts = line.split()
        if len(parts) != 2 or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", parts[0]) or not parts[1].isdigit():
            raise CliError(f"{path}:{n}: expected 'NAME ADDRESS'")
        if parts[0] in out:
            raise CliError(f"{path}:{n}: label {parts[0]} defined twice")
        out[parts[0]] = int(parts[1])
    return out


def run(args: argparse.Namespace) -> int:
    from ..lang.binfile import BinFileError
    from ..lang.disassembler import disassemble
    from ..limits import IMAGE_MAX, InputTooLarge, read_bytes

    try:
        data = read_bytes(args.binary, IMAGE_MAX, "binary program image", stdin=True)
    except InputTooLarge as exc:
        raise CliError(f"{args.binary}: {exc}") from None
    except OSError as exc:
        raise CliError(f"cannot read {args.binary}: {exc.strerror or exc}") from None
    labels = _read_symbols(args.symbols) if args.symbols else None
    try:
        text = disassemble(data, labels=labels, comments=not args.no_comments, module=args.module)
    except BinFileError as exc:
        raise CliError(f"{args.binary}: {exc}") from None
    except ValueError as exc:
        raise CliError(str(exc)) from None
    if args.output:
        from . import same_file

        for given in (args.binary, args.symbols):
            if given and same_file(args.output, given):
                raise CliError(f"output {args.output} would overwrite the input {given}")
        try:
            write_atomic(args.output, text.encode("utf-8"))
        except OSError as exc:
            raise CliError(f"cannot write {args.output}: {exc.strerror or exc}") from None
    else:
        print(text, end="")
    return 0
