"""`opentmcl run PROGRAM`: download a TMCL program, run it and print what changes.

Without --to, a virtual module (--module, default TMCM-6212) runs in this process in virtual
time: the run is deterministic and takes as long as the computation, not as long as the
program. With --to URL the program runs on that module in real time.

The program is downloaded as TMCL-IDE does (132, the instructions, 133, verify with 134),
started with 129 (from --from, default 0), and the watched values are read every --sample
seconds; a line is printed whenever one of them changed:

    time [s]  changes
       0.000  state=run out0=0 out3=0 pos0=0
       0.500  out3=1

The run ends when the program stops (STOP) or after --seconds. Watch expressions: see
`opentmcl debug` (a, x, pc, flags, state, varN, outN, inN, adcN, posN, targetN, speedN, apP.M,
gpN[.B]); default: state, the module's outputs and the position of motor 0.
"""
from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import TYPE_CHECKING

from . import CliError, about_file
from .load import add_connection_options, check_connection_options, download, read_program, target_name

if TYPE_CHECKING:
    from ..firmware.vm import VirtualModule
    from ..host import Client
    from ..host.debugger import Watch
    from ..host.loader import Loader
    from ..modules.profile import ModuleProfile
    from ..motion.scenario import Scenario
    from .verbosity import Bar

DEFAULT_MODULE = "TMCM-6212"
MAX_SAMPLES = 1_000_000  # more looks than this is a typo in --seconds / --sample


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="download a TMCL program, run it and print the watched values",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("program", help="TMCL source (.tmc) or binary (.bin)")
    add_connection_options(p, required=False)
    p.add_argument("-t", "--seconds", type=float, default=10.0, help="run at most this long (default 10)")
    p.add_argument("--sample", type=float, default=0.01, help="seconds between two looks (default 0.01)")
    p.add_argument("-w", "--watch", action="append", default=[], metavar="EXPR[,EXPR...]",
                   help="values to print when they change (repeatable)")
    p.add_argument("--from", dest="start", type=int, default=0, help="start address for 129 (default 0)")
    p.add_argument("--eeprom", help="file-backed EEPROM of the in-process virtual module")
    p.add_argument("--scenario", metavar="FILE", help="physical-world scenario for the in-process "
                   "virtual module (switches, loads, inputs over time)")
    p.add_argument("--csv", metavar="FILE", help="save the world trace (position, velocity, switches, load "
                   "value, current of every axis, each --sample) of the in-process module as CSV (- for stdout)")
    p.set_defaults(func=run)


def scenario_option(path: str | None) -> Scenario | None:
    """The --scenario file, read here so that a bad file is a one-line error (docs/scenarios.md)."""
    if path is None:
        return None
    from ..motion.scenario import load_scenario

    try:
        return load_scenario(path)
    except (OSError, ValueError, KeyError) as exc:
        raise CliError(about_file(path, exc, "scenario")) from None


def open_target(args: argparse.Namespace) -> tuple[Client, str | None]:
    """(client, module name) for --to URL, or for a new in-process virtual module."""
    from ..host import Client, TmclError, open_bus
    from ..host.transports.inprocess import InProcessTransport

    if args.url:
        if args.scenario or args.eeprom:
            raise CliError("--scenario and --eeprom apply to the in-process virtual module only (no --to)")
        check_connection_options(args)
        try:
            client = open_bus(args.url, address=args.address, timeout=args.timeout)
        except (TmclError, ValueError) as exc:
            raise CliError(str(exc)) from None
        return client, None
    from ..firmware.eeprom import EepromError
    from ..firmware.vm import VirtualModule

    check_connection_options(args)
    scenario = scenario_option(args.scenario)
    name = args.module or getattr(scenario, "module", None) or DEFAULT_MODULE
    try:
        vm = VirtualModule(name, address=args.address, eeprom=args.eeprom, scenario=scenario)
    except KeyError as exc:
        raise CliError(str(exc.args[0] if exc.args else exc)) from None
    except (EepromError, ValueError) as exc:   # a scenario that does not fit the module
        raise CliError(str(exc)) from None
    return Client(InProcessTransport(vm, clock="virtual"), address=args.address, timeout=args.timeout), name


def default_watches(profile: ModuleProfile) -> list[str]:
    outs = sorted(port for (bank, port), p in profile.io.items() if bank == 2 and p.kind == "output")
    return ["state", *(f"out{port}" for port in outs), "pos0"]


def run(args: argparse.Namespace) -> int:
    from ..host import TmclError
    from ..host.debugger import DebugError, parse_watches, read_watch
    from ..host.loader import Loader

    if not (0 <= args.seconds < float("inf") and 0 < args.sample < float("inf")):  # also NaN
        raise CliError(f"--seconds must be a finite number >= 0 and --sample one > 0, "
                       f"got {args.seconds} and {args.sample}")
    if not -(2 ** 31) <= args.start < 2 ** 31:   # the 32-bit value of command 129
        raise CliError(f"--from must fit in 32 bits, got {args.start}")
    if args.seconds / args.sample > MAX_SAMPLES:
        raise CliError(f"--seconds / --sample gives more than {MAX_SAMPLES} samples; use a longer --sample")
    _check_csv(args)
    client, name = open_target(args)
    try:
        module = client.module(args.address, name)
        if name is None:
            name = target_name(module, args.module, args.program, args.strict)
        program = read_program(args.program, name or args.module, args.include, strict=args.strict)
        try:
            specs = [s for item in args.watch for s in item.split(",") if s.strip()]
            watches = parse_watches(specs or default_watches(module.profile))
        except DebugError as exc:
            raise CliError(str(exc)) from None
        loader = Loader(module)
        args.recorder = _recorder(client, args)   # --csv: the world trace (trace.py)
        try:
            download(loader, program.instructions)
            loader.run(args.start)
            try:
                _trace(loader, watches, read_watch, args)
            finally:
                if args.recorder is not None:
                    args.recorder.save()
        except (TmclError, ValueError) as exc:   # ValueError: --from beyond 32 bits
            raise CliError(str(exc)) from None
    finally:
        client.close()
    return 0


def _check_csv(args: argparse.Namespace) -> None:
    """House rule "loses nothing": the --csv trace may not overwrite an input file."""
    from . import same_file

    for option, given in (("program", args.program), ("--eeprom", args.eeprom), ("--scenario", args.scenario)):
        if args.csv and given and same_file(args.csv, given):
            raise CliError(f"--csv {args.csv} would overwrite the {option} {given}")


def _trace(loader: Loader, watches: list[Watch], read_watch: Callable[[Loader, Watch], int | str],
           args: argparse.Namespace) -> None:
    from .verbosity import Bar

    with Bar(args.seconds, "run", unit="s") as bar:
        _looks(loader, watches, read_watch, args, bar)


def _looks(loader: Loader, watches: list[Watch], read_watch: Callable[[Loader, Watch], int | str],
           args: argparse.Namespace, bar: Bar) -> None:
    """Look every --sample seconds until the program stops or --seconds pass; a line per change."""
    bar.print(f"{'time [s]':>9}  changes")
    last: dict[str, object] = {}
    elapsed, steps = 0.0, 0
    total = round(args.seconds / args.sample)
    while True:
        values = [(w.name, read_watch(loader, w)) for w in watches]
        changed = [f"{n}={v}" for n, v in values if last.get(n, object()) != v]
        last.update(values)
        if getattr(args, "recorder", None) is not None:
            args.recorder.sample()
        if changed:
            bar.print(f"{elapsed:9.3f}  {' '.join(changed)}")
        st = loader.status()
        if st.mode != 1:
            bar.print(f"program stopped at address {st.pc} after {elapsed:.3f} s (A={st.accumulator}, "
                      f"X={st.x_register})")
            return
        if steps >= total:
            bar.print(f"{elapsed:.3f} s elapsed, program still running at address {st.pc}")
            return
        loader.client.sleep(args.sample)
        steps += 1
        elapsed = steps * args.sample
        bar.to(min(elapsed, args.seconds))


class _Recorder:
    """`run --csv FILE`: samples the in-process module at each look of the run (trace.py)."""

    def __init__(self, vm: VirtualModule, path: str) -> None:
        from ..trace import Trace

        self.vm, self.path = vm, path
        self.trace = Trace()

    def sample(self) -> None:
        self.trace.sample(self.vm)

    def save(self) -> None:
        if self.path == "-":
            print(self.trace.to_csv(layout="table"), end="")
            return
        try:
            self.trace.to_csv(self.path, layout="table")
        except OSError as exc:
            raise CliError(f"cannot write {self.path}: {exc.strerror or exc}") from None
        print(f"world trace: {len(self.trace)} rows written to {self.path}")


def _recorder(client: Client, args: argparse.Namespace) -> _Recorder | None:
    """The recorder for `run --csv`, or None without --csv (needs the in-process module)."""
    if not args.csv:
        return None
    modules = getattr(client.transport, "modules", None)
    if not modules:
        raise CliError("--csv records the in-process virtual module only (no --to)")
    return _Recorder(modules[0], args.csv)
