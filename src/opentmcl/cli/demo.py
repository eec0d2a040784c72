"""`opentmcl demo`: a virtual TMCM-6212 runs a few moves in virtual time and prints a table.

The table fits the terminal (80 columns when there is none): axes that do not fit wrap into
further blocks below, each with the time column; `--axes 0,2` shows only some axes.
"""
from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING

from ..protocol.opcodes import Op
from . import CliError, about_file

if TYPE_CHECKING:
    from ..firmware.vm import VirtualModule

MAX_ROWS = 100_000  # a table longer than this is a typo in --duration / --interval


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("demo", help="run a virtual module through a few moves and print a table")
    p.add_argument("--module", default=None, help="module type (default: the scenario's, else TMCM-6212)")
    p.add_argument("--duration", type=float, default=2.0, help="virtual seconds to run (default 2)")
    p.add_argument("--interval", type=float, default=0.1, help="table row interval in seconds (default 0.1)")
    p.add_argument("--scenario", metavar="FILE", help="run in a physical world (docs/scenarios.md) and print its trace")
    p.add_argument("--csv", metavar="FILE", help="with --scenario: save the trace as CSV instead of printing it (- for stdout)")
    p.add_argument("--axes", metavar="LIST", help="comma-separated axis numbers to show (default all); every "
                   "axis moves")
    p.set_defaults(func=run)


def _plan(vm: VirtualModule) -> list[tuple[int, int, int, int]]:
    """Requests (command, type, motor, value): each axis gets its own ramp and target."""
    reqs: list[tuple[int, int, int, int]] = []
    fast = vm.profile.capabilities.velocity_unit == "pps"
    for axis in range(vm.profile.axes):
        speed = (20000 + 10000 * axis) if fast else 400 + 200 * axis
        accel = (40000 + 20000 * axis) if fast else 100 + 50 * axis
        reqs += [(Op.SAP, 4, axis, speed), (Op.SAP, 5, axis, accel)]
        if axis % 3 == 2:
            reqs.append((Op.ROR, 0, axis, speed // 2))  # velocity mode
        else:
            sign = 1 if axis % 2 == 0 else -1
            reqs.append((Op.MVP, 0, axis, sign * (12000 + 8000 * axis)))  # ABS
    return reqs


def run(args: argparse.Namespace) -> int:
    _check_table_size(args.duration, args.interval)
    if args.scenario or args.csv:
        return _run_in_world(args)
    vm = _start_moves(args.module or "TMCM-6212")
    _print_table(vm, args.duration, args.interval, _shown_axes(args.axes, vm.profile.axes))
    return 0


def _shown_axes(text: str | None, count: int) -> list[int]:
    """--axes: numbers of axes the module has (default all `count`)."""
    if text is None:
        return list(range(count))
    try:
        axes = sorted({int(a) for a in text.split(",") if a.strip()})
    except ValueError:
        raise CliError(f"--axes must be axis numbers separated by commas, got {text[:40]!r}") from None
    bad = [a for a in axes if not 0 <= a < count]
    if not axes or bad:
        raise CliError(f"--axes: the module has axes 0..{count - 1}, got {text[:40]!r}")
    return axes


def _check_table_size(duration: float, interval: float) -> None:
    """--duration and --interval: finite, positive, at most MAX_ROWS rows."""
    if not (math.isfinite(interval) and math.isfinite(duration)):
        raise CliError("--duration and --interval must be finite numbers")
    if interval <= 0 or duration <= 0:
        raise CliError("--duration and --interval must be positive")
    if duration / interval > MAX_ROWS:
        raise CliError(f"--duration / --interval gives more than {MAX_ROWS} rows; use a longer --interval")


def _run_in_world(args: argparse.Namespace) -> int:
    """--scenario [--csv]: the same moves in a physical world, printed or saved as its trace."""
    from . import same_file

    if args.csv and args.scenario and same_file(args.csv, args.scenario):
        raise CliError(f"--csv {args.csv} would overwrite the scenario {args.scenario}")
    return _world_demo(args)


def _world_demo(args: argparse.Namespace) -> int:
    """`demo --scenario FILE [--csv OUT]`: the demo moves in a world; prints the trace table (fit
    to the terminal) or writes it as CSV."""
    from ..firmware.vm import VirtualModule
    from ..motion.scenario import load_scenario
    from ..trace import Trace

    if not args.scenario:
        raise CliError("--csv needs --scenario")
    try:
        scenario = load_scenario(args.scenario)
        vm = VirtualModule(args.module or scenario.module or "TMCM-6212", scenario=scenario)
    except KeyError as exc:
        raise CliError(str(exc.args[0] if exc.args else exc)) from None
    except ValueError as exc:
        raise CliError(about_file(args.scenario, exc, "scenario")) from None
    _request_all(vm)
    trace = Trace(_shown_axes(args.axes, vm.profile.axes) if args.axes else None)
    trace.record(vm, args.duration, args.interval)
    if args.csv == "-":
        print(trace.to_csv(layout="table"), end="")
    elif args.csv:
        try:
            trace.to_csv(args.csv, layout="table")
        except OSError as exc:
            raise CliError(f"cannot write {args.csv}: {exc.strerror or exc}") from None
        print(f"{len(trace)} rows written to {args.csv}")
    else:
        from .table import fit, width

        print(f"Virtual {vm.profile.name} in a physical world, virtual time; scenario:")
        print(f"  {args.scenario}")
        header, cells = trace.cells()
        group = len(trace.channels or ()) or 1
        print("\n".join(fit(header, cells, width(), group=group)))   # an axis's columns together
    return 0


def _request_all(vm: VirtualModule) -> None:
    """Send the moves of `_plan`; a refusal is a one-line error."""
    for cmd, type_, motor, value in _plan(vm):
        reply = vm.request(cmd, type_, motor, value)
        if reply is None or reply.status != 100:
            raise CliError(f"module refused command {cmd} {type_} {motor} {value}")


def _start_moves(module: str) -> VirtualModule:
    """A virtual `module` with the moves of `_plan` started on every axis."""
    from ..firmware.vm import VirtualModule

    try:
        vm = VirtualModule(module)
    except KeyError as exc:
        raise CliError(exc.args[0]) from None
    _request_all(vm)
    return vm


def _print_table(vm: VirtualModule, duration: float, interval: float, axes: list[int]) -> None:
    """Position and velocity of `axes` each `interval` virtual seconds, then who reached AP8."""
    from .table import fit, width

    unit = "pps" if vm.profile.capabilities.velocity_unit == "pps" else "internal"
    print(f"Virtual {vm.profile.name} (firmware {vm.profile.firmware_version}), virtual time;")
    print(f"position in microsteps, velocity in {unit}")
    header = ["time/s"] + [h for a in axes for h in (f"axis{a} pos", "vel")]
    rows = []
    steps = round(duration / interval)
    for i in range(steps + 1):
        if i:
            vm.advance(interval)
        rows.append([f"{vm.time:.3f}"] + [str(_axis_parameter(vm, n, a)) for a in axes for n in (1, 3)])
    print("\n".join(fit(header, rows, width(), keep=1, group=2)))
    reached = [a for a in range(vm.profile.axes) if _axis_parameter(vm, 8, a)]
    print(f"position reached (AP8) on axes: {reached or 'none'}")


def _axis_parameter(vm: VirtualModule, number: int, axis: int) -> int:
    """GAP `number` of `axis` (command 6)."""
    reply = vm.request(Op.GAP, number, axis)
    if reply is None:
        raise CliError(f"module gave no reply to GAP {number} {axis}")
    return reply.value
