"""`opentmcl replay`: send a capture's host requests to a virtual module in virtual time, compare replies.

    opentmcl replay FILE [--module NAME|PROFILE.toml] [--address N] [--eeprom F] [--scenario F]
                    [--initial-state FILE] [--settings snapshot|profile]
                    [--tolerance KEY=VALUE[,KEY=VALUE...]]... [--clock-lag S]
                    [--report FILE.json] [--junit FILE.xml] [--html DIR]

Prints the root causes first, each with the divergences it explains (time, request as TMCL text,
parameter name, captured vs twin), the agreement per area and a summary. Exit status 0 when all
replies agree, 1 when any diverge, 2 on bad input (docs/capture.md).
"""
from __future__ import annotations

import argparse
import logging

from . import CliError, float_arg


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("replay", help="replay a capture against a virtual module and list divergences",
                              description=__doc__.split("\n\n")[0])
    p.add_argument("file", metavar="FILE", help="capture file written by opentmcl proxy --log")
    p.add_argument("--module", "-m", metavar="NAME|FILE",
                   help="module name or profile file (default: the module the capture identified, else the "
                        "built-in one of the same module number)")
    p.add_argument("--address", "-a", type=int, metavar="N",
                   help="module address to replay (default: the first one the host talked to)")
    p.add_argument("--eeprom", metavar="FILE", help="EEPROM file of the virtual module (its state at power-up)")
    p.add_argument("--scenario", metavar="FILE", help="scenario file of the virtual module")
    add_comparison_options(p)
    p.set_defaults(func=run)


def add_comparison_options(p: argparse.ArgumentParser) -> None:
    """--initial-state, --tolerance, --clock-lag and the report files (also `opentmcl conform`)."""
    p.add_argument("--initial-state", metavar="FILE",
                   help="start the twin from this snapshot: a capture with one, or a profile written by "
                        "opentmcl profile probe (default: the capture's own snapshot, else inferred values)")
    p.add_argument("--settings", choices=("snapshot", "profile"), default=None,
                   help="where the twin's settings come from: the snapshot (default for replay: the module as it "
                        "was), or the profile's defaults with only the positions from the snapshot (default for "
                        "conform: checks the profile)")
    p.add_argument("--tolerance", "-t", action="append", default=[], metavar="KEY=VALUE",
                   help="time=SECONDS (added at both ends of each sampling interval, default 0), position=, "
                        "velocity=, load=, timer= (absolute; timers are not compared unless given), "
                        "latency=SECONDS (of command-138 events, default 0.05); repeat or separate with commas")
    p.add_argument("--clock-lag", type=float_arg, default=None, metavar="SECONDS",
                   help="how long the module's clock may trail the host's (default 0.002: the step of a "
                        "served module's clock)")
    p.add_argument("--report", metavar="FILE.json", help="also write the report as JSON")
    p.add_argument("--junit", metavar="FILE.xml", help="also write JUnit XML (a test case per area)")
    p.add_argument("--html", metavar="DIR", help="also write an HTML report with plots to DIR/index.html")


def write_reports(report, args: argparse.Namespace) -> None:
    """The files asked for with --report, --junit and --html."""
    from ..capture.html import write_html
    from ..capture.report import write_json, write_junit

    for path, writer in ((args.report, write_json), (args.junit, write_junit), (args.html, write_html)):
        if path:
            try:
                writer(report, path)
            except OSError as exc:
                raise CliError(f"cannot write {path}: {exc.strerror or exc}") from None


def comparison_kwargs(args: argparse.Namespace, settings: str = "snapshot") -> dict:
    """replay()'s keyword arguments from the comparison options; `settings`: the command's default."""
    from ..capture.timing import CLOCK_LAG

    lag = CLOCK_LAG if args.clock_lag is None else args.clock_lag
    if not 0 <= lag < 1:
        raise CliError(f"--clock-lag must be 0 <= SECONDS < 1, got {args.clock_lag}")
    scope = "all" if (args.settings or settings) == "snapshot" else "state"
    return {"tolerance": args.tolerance, "initial_state": args.initial_state, "clock_lag": lag, "state_scope": scope}


def run(args: argparse.Namespace) -> int:
    from ..capture import CaptureError, ReplayError, read_capture, replay
    from .serve import load_scenario

    if args.address is not None and not 0 <= args.address <= 255:
        raise CliError(f"--address must be 0..255, got {args.address}")
    scenario = load_scenario(args.scenario)
    kwargs = comparison_kwargs(args)
    try:
        cap = read_capture(args.file)
        for warning in cap.warnings:
            logging.getLogger("opentmcl.cli").warning("warning: %s", warning)
        report = replay(cap, args.module, address=args.address, eeprom=args.eeprom, scenario=scenario, **kwargs)
    except (CaptureError, ReplayError) as exc:
        raise CliError(str(exc)) from None
    print(report.text(), flush=True)
    write_reports(report, args)
    return 0 if report.ok else 1
