"""`opentmcl fault`: trigger a named fault of a running `opentmcl serve --faults FILE
--fault-control PATH`, or list the named faults and what fired (docs/faults.md).

    opentmcl fault power-cut --control /tmp/tmcl-faults
    opentmcl fault --list --control /tmp/tmcl-faults
"""
from __future__ import annotations

import argparse

from . import CliError
from .exits import NO_REPLY


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("fault", help="trigger a named fault of a running `opentmcl serve --faults`",
                              description=__doc__.split("\n\n")[0])
    p.add_argument("names", nargs="*", metavar="NAME", help="the named faults to trigger, in order")
    p.add_argument("--control", required=True, metavar="PATH",
                   help="the --fault-control socket of `opentmcl serve`")
    p.add_argument("--list", action="store_true", help="list the named faults and the faults that fired")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..server.control import ask

    if not args.names and not args.list:
        raise CliError("give the NAME of a fault to trigger, or --list")
    lines = ([f"trigger {name}" for name in args.names]) + (["list"] if args.list else [])
    for line in lines:
        try:
            out = ask(args.control, line)
        except OSError as exc:
            raise CliError(f"cannot reach the fault control {args.control}: {exc.strerror or exc} "
                           "(is `opentmcl serve --faults FILE --fault-control PATH` running?)", NO_REPLY) from None
        if not out.get("ok"):
            raise CliError(str(out.get("error", "refused")))
        if line == "list":
            print(f"seed {out.get('seed')}; named faults: {', '.join(out.get('names', [])) or 'none'}")
            for fired in out.get("fired", []):
                print(f"  {fired}")
        else:
            print(f"{line.split(' ', 1)[1]}: fired")
    return 0
