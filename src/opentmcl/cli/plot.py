"""`opentmcl plot FILE -o out.png`: plot position, velocity, acceleration, load, current and switches.

FILE is a TMCL program (.tmc source or .bin), run on an in-process virtual module in virtual
time (or, with --to URL, on that module in real time); a trace recorded earlier (.csv: a trace
file of `plot --csv`, or the table of `run --csv` / `demo --csv`); or a scenario file for the
virtual module (any other name). The output format follows the name
(.png or .svg); --csv also saves the trace. Examples:

    opentmcl plot examples/tmcm6212_2.4_first_program.tmc -o first.png --seconds 15
    opentmcl plot move.tmc --axes 0,1 --rpm -o move.svg --csv move.csv
    opentmcl plot move.csv -o move.png --channels position,velocity
    opentmcl plot - --to tcp://127.0.0.1:2323 --seconds 5 -o live.png --csv live.csv   # record only
"""
from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from . import CliError

if TYPE_CHECKING:
    from ..plot import Trace

PROGRAM_SUFFIXES = (".tmc", ".bin")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("plot", help="plot axis motion over time from a virtual run or a CSV trace",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", metavar="PROGRAM_OR_SCENARIO", help=".tmc/.bin program, .csv trace, scenario file, or - (with --to: record only)")
    p.add_argument("-o", "--output", required=True, help="image file to write (.png or .svg)")
    p.add_argument("--axes", default=None, help="comma-separated axis numbers (default 0; for a .csv trace all of its axes)")
    p.add_argument("--channels", help="comma-separated panels: position, velocity, acceleration, load, "
                   "current, encoder, stage, switches (default all the module has but encoder and stage, "
                   "which traces of `run --csv` hold)")
    p.add_argument("-t", "--seconds", type=float, default=None,
                   help="record at most this long (default: a program runs until it stops or has looped twice, "
                   "at most 300 s; otherwise 10 s)")
    p.add_argument("--interval", type=float, default=0.01, help="seconds between samples (default 0.01)")
    p.add_argument("-m", "--module", default=None, help="virtual module type (default TMCM-6212)")
    p.add_argument("--scenario", help="scenario file for the virtual module (with a program)")
    p.add_argument("--to", dest="url", help="record on this module instead of a virtual one (real time)")
    p.add_argument("--address", type=int, default=1, help="module address (default 1)")
    p.add_argument("--rpm", action="store_true", help="velocity in rpm instead of pps")
    p.add_argument("--csv", help="also save the recorded trace to this CSV file")
    p.add_argument("--title", help="figure title")
    p.add_argument("--phases", action="store_true", help="shade the ramp phases (accelerating, constant, "
                   "decelerating) in the velocity panel")
    p.add_argument("--no-marks", dest="marks", action="store_false",
                   help="leave out the program's instruction marks")
    p.add_argument("--no-target", dest="target", action="store_false",
                   help="leave out the target position (AP 0) over the position")
    p.add_argument("--keep-going", action="store_true",
                   help="record the full --seconds even after the program stopped and the axes are idle")
    p.set_defaults(func=run)


def _axes(text: str) -> list[int]:
    try:
        axes = [int(a) for a in text.split(",") if a.strip()]
    except ValueError:
        raise CliError(f"--axes must be numbers separated by commas, got {text!r}") from None
    if not axes or any(a < 0 for a in axes):
        raise CliError("--axes needs at least one axis number >= 0")
    return sorted(set(axes))


def _record(args: argparse.Namespace, axes: list[int]) -> Trace:
    from ..host import TmclError, UnknownParameterError
    from ..plot import run_virtual
    from .load import read_program
    from .run import scenario_option

    path = Path(args.file)
    is_program = path.suffix.lower() in PROGRAM_SUFFIXES
    if args.url:
        if not is_program and args.file != "-":
            raise CliError("with --to, FILE must be a .tmc or .bin program, or - to record only")
        return _record_remote(args, axes, is_program)
    if args.file == "-":
        raise CliError("FILE - (record only) needs --to URL")
    scenario_path = args.scenario if is_program else args.file
    scenario = scenario_option(scenario_path)
    module = args.module or getattr(scenario, "module", None) or "TMCM-6212"
    program = read_program(args.file, module).instructions if is_program else None
    # A scenario alone runs for the full --seconds: its world may move things at any time.
    idle_stop = is_program and not args.keep_going
    try:
        return run_virtual(program, module=module, axes=axes, seconds=args.seconds, interval=args.interval,
                           scenario=scenario, address=args.address, stop_when_idle=idle_stop)
    except KeyError as exc:
        raise CliError(str(exc.args[0] if exc.args else exc)) from None
    except (UnknownParameterError, TmclError) as exc:
        raise CliError(str(exc)) from None


def _record_remote(args: argparse.Namespace, axes: list[int], is_program: bool) -> Trace:
    from ..host import TmclError, connect
    from ..plot import record_program
    from .load import module_name, read_program
    from .verbosity import Bar

    try:
        m = connect(args.url, address=args.address)
    except TmclError as exc:
        raise CliError(str(exc)) from None
    try:
        if not is_program:  # FILE "-": record what the module does for --seconds
            with Bar(args.seconds or 0, "recording", unit="s") as bar:
                return record_program(m, None, axes, args.seconds, args.interval, stop_when_idle=False,
                                      sample_progress=bar.to)
        program = read_program(args.file, module_name(m, args.module))
        n = len(program.instructions)
        with Bar(n, "load", unit="instr") as load_bar, Bar(args.seconds or 0, "recording", unit="s") as bar:
            return record_program(m, program.instructions, axes, args.seconds, args.interval,
                                  stop_when_idle=not args.keep_going, sample_progress=bar.to,
                                  download_progress=load_bar.to)
    except TmclError as exc:
        raise CliError(str(exc)) from None
    finally:
        m.close()


def _check_duration(args: argparse.Namespace) -> None:
    """Without --seconds a program's length is derived and capped to fit: only the interval counts."""
    from ..extras import MissingExtra, require
    from ..plot.recording import check_duration

    derived = args.seconds is None and Path(args.file).suffix.lower() in PROGRAM_SUFFIXES
    try:
        require("plot", "opentmcl plot")   # before a recording that could not be drawn
    except MissingExtra as exc:
        raise CliError(str(exc)) from None
    try:
        check_duration(0.0 if derived else 10.0 if args.seconds is None else args.seconds, args.interval)
    except ValueError as exc:
        raise CliError(f"--seconds/--interval: {exc}") from None


def run(args: argparse.Namespace) -> int:
    from ..plot import DEFAULT_CHANNELS, Trace, TraceError, channel_names, render

    _check_duration(args)
    if Path(args.output).suffix.lower() not in (".png", ".svg"):
        raise CliError(f"cannot write {args.output}: use a .png or .svg file name")
    axes = _axes(args.axes or "0")
    channels: Sequence[str] = DEFAULT_CHANNELS
    if args.channels is not None:
        channels = [c.strip() for c in args.channels.split(",") if c.strip()]
        if not channels:
            raise CliError(f"--channels needs at least one of: {', '.join(channel_names())}")
    try:
        if Path(args.file).suffix.lower() == ".csv":
            trace = Trace.from_csv(args.file)
            if args.axes is not None:
                if not set(axes) <= set(trace.axes):
                    raise CliError(f"axes {axes} not all in the trace (it has {trace.axes})")
                trace.axes = axes
        else:
            trace = _record(args, axes)
        if args.csv:
            trace.to_csv(args.csv)
        render(trace, args.output, channels=channels, rpm=args.rpm, title=args.title, phases=args.phases,
               marks=args.marks, target=args.target)
    except TraceError as exc:
        raise CliError(str(exc)) from None
    except ImportError as exc:
        raise CliError(f"plotting needs the 'plot' extra (pip install 'opentmcl[plot]'): {exc}") from None
    except OSError as exc:
        raise CliError(f"cannot write {exc.filename or args.output}: {exc.strerror or exc}") from None
    print(f"wrote {args.output} ({len(trace)} samples, {trace.time[-1] if len(trace) else 0:.2f} s, "
          f"axes {', '.join(map(str, trace.axes))})")
    return 0
