"""`opentmcl demo`: a virtual TMCM-6212 runs a few moves in virtual time and prints a table."""
from __future__ import annotations

import argparse
import math

from . import CliError

MAX_ROWS = 100_000  # a table longer than this is a typo in --duration / --interval


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("demo", help="run a virtual module through a few moves and print a table")
    p.add_argument("--module", default=None, help="module type (default: the scenario's, else TMCM-6212)")
    p.add_argument("--duration", type=float, default=2.0, help="virtual seconds to run (default 2)")
    p.add_argument("--interval", type=float, default=0.1, help="table row interval in seconds (default 0.1)")
    p.add_argument("--scenario", metavar="FILE", help="run in a physical world (docs/scenarios.md) and print its trace")
    p.add_argument("--csv", metavar="FILE", help="with --scenario: save the trace as CSV instead of printing it (- for stdout)")
    p.set_defaults(func=run)


def _plan(vm) -> list[tuple[int, int, int, int]]:
    """Requests (command, type, motor, value): each axis gets its own ramp and target."""
    reqs = []
    fast = vm.profile.capabilities.velocity_unit == "pps"
    for axis in range(vm.profile.axes):
        speed = (20000 + 10000 * axis) if fast else 400 + 200 * axis
        accel = (40000 + 20000 * axis) if fast else 100 + 50 * axis
        reqs += [(5, 4, axis, speed), (5, 5, axis, accel)]
        if axis % 3 == 2:
            reqs.append((1, 0, axis, speed // 2))       # ROR: velocity mode
        else:
            sign = 1 if axis % 2 == 0 else -1
            reqs.append((4, 0, axis, sign * (12000 + 8000 * axis)))  # MVP ABS
    return reqs


def run(args: argparse.Namespace) -> int:
    from ..firmware.vm import VirtualModule

    if not (math.isfinite(args.interval) and math.isfinite(args.duration)):
        raise CliError("--duration and --interval must be finite numbers")
    if args.interval <= 0 or args.duration <= 0:
        raise CliError("--duration and --interval must be positive")
    if args.duration / args.interval > MAX_ROWS:
        raise CliError(f"--duration / --interval gives more than {MAX_ROWS} rows; use a longer --interval")
    if args.scenario or args.csv:
        from . import same_file

        if args.csv and args.scenario and same_file(args.csv, args.scenario):
            raise CliError(f"--csv {args.csv} would overwrite the scenario {args.scenario}")
        from ..trace import world_demo  # the world trace (position, switches, load value, current)
        return world_demo(args, _plan, CliError)
    try:
        vm = VirtualModule(args.module or "TMCM-6212")
    except KeyError as exc:
        raise CliError(exc.args[0]) from None
    for cmd, type_, motor, value in _plan(vm):
        reply = vm.request(cmd, type_, motor, value)
        if reply is None or reply.status != 100:
            raise CliError(f"module refused command {cmd} {type_} {motor} {value}")
    unit = "pps" if vm.profile.capabilities.velocity_unit == "pps" else "internal"
    print(f"Virtual {vm.profile.name} (firmware {vm.profile.firmware_version}), virtual time; "
          f"position in microsteps, velocity in {unit}")
    head = "  time/s" + "".join(f"  {f'axis{a} pos':>11} {'vel':>7}" for a in range(vm.profile.axes))
    print(head)
    print("-" * len(head))
    steps = round(args.duration / args.interval)
    for i in range(steps + 1):
        if i:
            vm.advance(args.interval)
        cells = "".join(f"  {vm.request(6, 1, a).value:>11} {vm.request(6, 3, a).value:>7}"
                        for a in range(vm.profile.axes))
        print(f"{vm.time:8.3f}{cells}")
    reached = [a for a in range(vm.profile.axes) if vm.request(6, 8, a).value]
    print(f"position reached (AP8) on axes: {reached or 'none'}")
    return 0
