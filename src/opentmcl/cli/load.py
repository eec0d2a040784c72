"""`opentmcl load PROGRAM --to URL`: download a TMCL program into a module and verify it.

PROGRAM is TMCL source (.tmc, assembled for the module) or a TMCL-IDE binary file (.bin).
The download is what TMCL-IDE does: command 132 <start>, every instruction (each answered
with status 101), 133, then every address read back with 134 and compared (TMCM-6212
manual 3.6.36). `--run` starts the program afterwards (129).
"""
from __future__ import annotations

import argparse
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from . import CliError

if TYPE_CHECKING:
    from ..host import Module
    from ..host.loader import Loader

ENV_URL = "OPENTMCL_URL"


@dataclass
class LoadedProgram:
    """Instructions plus what the debugger and `run` show about them (labels, source lines)."""

    instructions: list
    labels: dict[str, int] = field(default_factory=dict)
    source: list = field(default_factory=list)   # per address: lang SourceLine or None
    filename: str = ""


def read_program(path: str, module: str | None, include: list[str] | None = None,
                 origin: int = 0, strict: bool = False) -> LoadedProgram:
    """Assemble a .tmc file (for `module`, to be loaded at address `origin`) or read a .bin file
    (loaded as it is: its jump addresses are those it was assembled with); CliError on any problem.
    What `module` cannot execute is printed as warnings on stderr, refused with `strict`."""
    from ..lang.assembler import AsmError, assemble_file
    from ..lang.binfile import BinFileError, read
    from .asm import check_binary, error_lines, print_warnings

    p = Path(path)
    if p.suffix.lower() == ".bin":
        try:
            code = read(p)
        except OSError as exc:
            raise CliError(f"cannot read {path}: {exc.strerror or exc}") from None
        except BinFileError as exc:
            raise CliError(f"{path}: {exc}") from None
        if not code:
            raise CliError(f"{path}: empty program file (no 8-byte records)")
        check_binary(str(p), code, module, strict)
        return LoadedProgram(code, {}, [None] * len(code), str(p))
    _check_readable(path)
    try:
        prog = assemble_file(p, module=module, include_path=include or [], origin=origin, strict=strict)
    except AsmError as exc:
        raise error_lines(exc) from None
    print_warnings(prog)
    return LoadedProgram(prog.instructions, dict(prog.labels), list(prog.source), str(p))


def _check_readable(path: str) -> None:
    """A source file that cannot be read is a plain file error (not an assembler position)."""
    from ..limits import open_regular

    try:
        with open_regular(path):
            pass
    except OSError as exc:
        raise CliError(f"cannot read {path}: {exc.strerror or exc}") from None


def add_connection_options(p: argparse.ArgumentParser, *, required: bool) -> None:
    p.add_argument("--to", dest="url", default=os.environ.get(ENV_URL),
                   help="module URL: sim://TMCM-6212, tcp://HOST:PORT, serial:///dev/ttyUSB0?baud=9600, "
                        f"can://socketcan/can0?id=1 (default ${ENV_URL})"
                        + ("" if required else "; without it a virtual module runs in this process"))
    p.add_argument("--address", type=int, default=1, help="module address (default 1)")
    p.add_argument("--timeout", type=float, default=5.0, help="seconds to wait for each reply (default 5)")
    p.add_argument("-m", "--module", help="module type for assembling .tmc source (default: asked from the "
                   "module with command 136, or TMCM-6212 for a new virtual module)")
    p.add_argument("-I", "--include", action="append", default=[], metavar="DIR",
                   help="#include search directory (repeatable)")
    from .asm import add_strict_option
    add_strict_option(p)


def check_connection_options(args: argparse.Namespace) -> None:
    """--timeout is a finite number of seconds > 0 (NaN would wait forever or never)."""
    if not 0 < args.timeout < float("inf"):
        raise CliError(f"--timeout must be a positive number of seconds, got {args.timeout}")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("load", help="download a TMCL program into a module and verify it",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("program", help="TMCL source (.tmc) or binary (.bin)")
    add_connection_options(p, required=True)
    p.add_argument("--start", type=int, default=0, help="program memory address to load at (default 0); .tmc source is assembled for it, a .bin "
                   "image is loaded unchanged")
    p.add_argument("--no-verify", action="store_true", help="do not read the program back (134)")
    p.add_argument("--run", action="store_true", help="start the program after loading (129)")
    p.set_defaults(func=run)


def module_name(module: Module, given: str | None) -> str:
    """The module type: --module, else the profile found from the version string (136). A module
    that does not answer is that error (its own hint, exit 3): --module would not help."""
    from ..host import TmclConnectionError, TmclError, TmclTimeout

    if given:
        return given
    try:
        return module.profile.name
    except (TmclTimeout, TmclConnectionError):
        raise
    except (TmclError, KeyError) as exc:
        raise CliError(f"cannot tell the module type ({exc}); give --module") from None


def target_name(module: Module, given: str | None, program: str, strict: bool) -> str | None:
    """The module type a program is checked against (docs/tmcl-assembler.md, "Checking against a
    module"): a .tmc file needs it (its include files); a .bin file is checked when it can be
    told, and --strict refuses to load one unchecked."""
    if given or program.lower().endswith(".tmc") or strict:
        return module_name(module, given)
    try:
        return module_name(module, None)
    except CliError:
        return None


def download(loader: Loader, instructions: list, *, start: int = 0, verify: bool = True) -> None:
    """`Loader.download` with a progress bar (on a terminal only): the instructions written, then
    the ones read back (134)."""
    from .verbosity import Bar

    n = len(instructions)
    total = 2 * n if verify else n
    with Bar(total, "load", unit="instr") as bar:
        loader.download(instructions, start=start, verify=verify, progress=lambda i, _: bar.to(i),
                        verify_progress=lambda i, _: bar.to(n + i))


def run(args: argparse.Namespace) -> int:
    from ..host import TmclError, open_bus
    from ..host.loader import Loader, LoaderError

    if not args.url:
        raise CliError(f"no module URL: give --to URL (or set ${ENV_URL})")
    if not 0 <= args.start < 2 ** 31:   # a 32-bit value of command 132 (manual 3.6.36)
        raise CliError(f"--start must be 0..{2 ** 31 - 1}, got {args.start}")
    check_connection_options(args)
    try:
        client = open_bus(args.url, address=args.address, timeout=args.timeout)
    except (TmclError, ValueError) as exc:
        raise CliError(str(exc)) from None
    try:
        module = client.module(args.address)
        name = target_name(module, args.module, args.program, args.strict)
        program = read_program(args.program, name, args.include, origin=args.start, strict=args.strict)
        loader = Loader(module)
        try:
            download(loader, program.instructions, start=args.start, verify=not args.no_verify)
            end = args.start + len(program.instructions) - 1
            check = "" if args.no_verify else ", verified"
            print(f"loaded {len(program.instructions)} instructions at {args.start}..{end}{check}")
            if args.run:
                loader.run(args.start)
                print(f"running from {args.start}")
        except (TmclError, LoaderError, ValueError) as exc:   # ValueError: --start beyond 32 bits
            raise CliError(str(exc)) from None
    finally:
        client.close()
    return 0
