"""`opentmcl replay`: send a capture's host requests to a virtual module in virtual time, compare replies.

    opentmcl replay FILE [--module NAME|PROFILE.toml] [--address N] [--eeprom F] [--scenario F]
                    [--tolerance KEY=VALUE[,KEY=VALUE...]]...

Prints every divergence (time, request as TMCL text, parameter name, captured vs virtual) and a
summary. Exit status 0 when all replies agree, 1 when any diverge, 2 on bad input (docs/capture.md).
"""
from __future__ import annotations

import argparse

from . import CliError


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("replay", help="replay a capture against a virtual module and list divergences",
                              description=__doc__.split("\n\n")[0])
    p.add_argument("file", metavar="FILE", help="capture file written by opentmcl proxy --log")
    p.add_argument("--module", "-m", metavar="NAME|FILE",
                   help="module name or profile file (default: the module the capture identified)")
    p.add_argument("--address", "-a", type=int, metavar="N",
                   help="module address to replay (default: the first one the host talked to)")
    p.add_argument("--eeprom", metavar="FILE", help="EEPROM file of the virtual module (its state at power-up)")
    p.add_argument("--scenario", metavar="FILE", help="scenario file of the virtual module")
    p.add_argument("--tolerance", "-t", action="append", default=[], metavar="KEY=VALUE",
                   help="time=SECONDS (window, default 0.1), position=, velocity=, load=, timer= (absolute; "
                        "timers are not compared unless given); repeat or separate with commas")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..capture import CaptureError, ReplayError, replay
    from .serve import load_scenario

    if args.address is not None and not 0 <= args.address <= 255:
        raise CliError(f"--address must be 0..255, got {args.address}")
    scenario = load_scenario(args.scenario)
    try:
        report = replay(args.file, args.module, address=args.address, eeprom=args.eeprom, scenario=scenario,
                        tolerance=args.tolerance)
    except (CaptureError, ReplayError) as exc:
        raise CliError(str(exc)) from None
    print(report.text(), flush=True)
    return 0 if report.ok else 1
