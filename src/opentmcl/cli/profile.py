"""`opentmcl profile`: check, show and probe module profiles (docs/profiles.md).

    opentmcl profile check FILE            # every error one line with its key path; exit 1 if any
    opentmcl profile show NAME|FILE        # the resolved parameter tables
    opentmcl profile probe URL [-o FILE]   # read-only: write a profile skeleton of a real module
"""
from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping
from typing import TYPE_CHECKING

from . import CliError
from .verbosity import Bar

if TYPE_CHECKING:
    from ..modules.profile import Param


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("profile", help="check, show or probe module profiles (bring your own module)",
                              description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="profile_command", metavar="ACTION", required=True)
    check = sub.add_parser("check", help="validate a profile file (with its extends chain)")
    check.add_argument("file", metavar="FILE")
    check.set_defaults(func=run_check)
    show = sub.add_parser("show", help="print the resolved parameter tables of a module or profile file")
    show.add_argument("module", metavar="NAME|FILE")
    show.set_defaults(func=run_show)
    probe = sub.add_parser("probe", help="ask a module which parameters it has (reading commands only)")
    probe.add_argument("url", metavar="URL", help="e.g. serial:///dev/ttyUSB0?baud=9600 or tcp://HOST:PORT")
    probe.add_argument("--address", "-a", type=int, default=1, metavar="N", help="module address (default 1)")
    probe.add_argument("-o", "--output", metavar="FILE", help="write the profile skeleton here (default stdout)")
    probe.add_argument("--timeout", type=float, default=1.0, metavar="SECONDS",
                       help="reply time-out per request (default 1)")
    probe.add_argument("--max-seconds", type=float, default=300.0, metavar="SECONDS",
                       help="give up after this long (default 300)")
    probe.set_defaults(func=run_probe)


def run_check(args: argparse.Namespace) -> int:
    from ..limits import open_regular
    from ..modules.profile import builtin_raw, parse_profile
    from ..modules.profile_file import ProfileError, ProfileLimitError, resolve, validate

    try:  # a FILE that cannot be read is bad input (2, docs/cli.md), not a file with errors (1)
        with open_regular(args.file):
            pass
    except OSError as exc:
        raise CliError(f"cannot read {args.file}: {exc.strerror or exc}") from None
    try:
        data = resolve(args.file, builtin_raw)
    except ProfileLimitError as exc:   # beyond a size bound: bad input (2), one line
        raise CliError(str(exc)) from None
    except ProfileError as exc:
        for line in exc.errors:
            print(line, file=sys.stderr)
        return 1
    errors = validate(data)
    for line in errors:
        print(f"{args.file}: {line}", file=sys.stderr)
    if errors:
        return 1
    prof = parse_profile(data)
    print(f"{args.file}: ok: {prof.name}, {prof.axes} axes, {len(prof.axis_parameters)} axis parameters, "
          f"{len(prof.global_parameters)} global parameters, {len(prof.io)} I/O ports")
    return 0


def run_show(args: argparse.Namespace) -> int:
    from ..modules.profile import load_profile
    from ..modules.profile_file import ProfileError

    try:
        prof = load_profile(args.module)
    except ProfileError as exc:
        raise CliError(str(exc)) from None
    except KeyError as exc:
        raise CliError(exc.args[0] if exc.args else str(exc)) from None
    print(f"{prof.name}  firmware {prof.firmware_version!r}  {prof.axes} axes  engine {prof.engine}  "
          f"program memory {prof.program_memory}")

    def rows(title: str, params: Mapping[int, Param] | Mapping[tuple[int, int], Param]) -> None:
        print(f"\n{title}")
        print(f"  {'no':>7}  {'name':<40} {'access':<6} {'min':>12} {'max':>12} {'default':>12}  unit")
        for key, p in sorted(params.items()):
            number = f"{key[0]}:{key[1]}" if isinstance(key, tuple) else str(key)
            print(f"  {number:>7}  {p.name:<40} {p.access:<6} {p.min:>12} {p.max:>12} {p.default:>12}  {p.unit}")

    rows("Axis parameters (GAP/SAP)", prof.axis_parameters)
    rows("Global parameters (GGP/SGP, bank:number)", prof.global_parameters)
    print("\nI/O ports (GIO/SIO, bank:port)")
    for (bank, port), io in sorted(prof.io.items()):
        print(f"  {bank}:{port:<5} {io.name:<12} {io.kind:<8} {io.access:<3} {io.min}..{io.max}")
    return 0


def _probe_line(bar: Bar, text: str) -> None:
    """A probe progress line on stderr (above the bar when there is one)."""
    bar.write(f"probe: {text}")


def run_probe(args: argparse.Namespace) -> int:
    from ..atomicfile import write_atomic
    from ..host.connect import open_bus
    from ..host.probe import probe, skeleton

    if not 0 < args.timeout <= 60 or not 0 < args.max_seconds < float("inf"):
        raise CliError("--timeout must be 0..60 s and --max-seconds a positive number")
    if not 0 <= args.address <= 255:
        raise CliError(f"--address must be 0..255, got {args.address}")
    client = open_bus(args.url, address=args.address, timeout=args.timeout)   # errors: exit 2/3 (cli/exits.py)
    bar = Bar(0, "probe", unit="req")
    try:
        result = probe(client, max_seconds=args.max_seconds, counted=bar.to,
                       progress=lambda text: _probe_line(bar, text))
    finally:
        bar.close()
        client.close()
    text = skeleton(result, args.url)
    if args.output:
        try:
            write_atomic(args.output, text.encode("utf-8"))
        except OSError as exc:
            raise CliError(f"cannot write {args.output}: {exc.strerror or exc}") from None
        print(f"probe: wrote {args.output}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0
