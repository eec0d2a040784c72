"""`opentmcl conform`: how well does the twin match a real module? A conformance run and its report.

    opentmcl conform URL --module NAME|FILE [--address N] [--allow-writes]
                     [--allow-motion --max-travel STEPS --axes LIST [--max-speed PPS] [--max-accel PPS2]
                      [--reference] [--no-program]]
                     [--capture FILE] [--report FILE.json] [--junit FILE.xml] [--html DIR] [--tolerance ...]

Read-only by default (identity, every parameter, I/O). It captures its own traffic through the
proxy, replays the capture against the twin and prints the agreement per area. Exit status 0 when
all agrees, 1 on a divergence, 2 on bad input, 3 when the module does not answer (docs/capture.md).
"""
from __future__ import annotations

import argparse
import signal
import sys
import time

from . import CliError, int_arg
from .replay import add_comparison_options, comparison_kwargs, write_reports


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("conform", help="check a real module against its twin and report the agreement",
                              description=__doc__.split("\n\n")[0])
    p.add_argument("url", metavar="URL", help="the module: serial:///dev/ttyUSB0?baud=9600, tcp://HOST:PORT, ...")
    p.add_argument("--module", "-m", required=True, metavar="NAME|FILE",
                   help="the twin to check against: a built-in module or a profile file")
    p.add_argument("--address", "-a", type=int, default=1, metavar="N", help="module address (default 1)")
    p.add_argument("--allow-writes", action="store_true",
                   help="also write the range edges of every setting that moves nothing (each restored at once)")
    p.add_argument("--allow-motion", action="store_true",
                   help="also move the axes of --axes within --max-travel (implies --allow-writes)")
    p.add_argument("--max-travel", type=int_arg, metavar="STEPS",
                   help="with --allow-motion: the farthest any axis may go from where it stands (µsteps)")
    p.add_argument("--axes", metavar="LIST", help="axes to check, e.g. 0 or 0,2 (needed with --allow-motion; "
                                                  "default for a read-only run: all)")
    p.add_argument("--max-speed", type=int_arg, metavar="PPS",
                   help="the fastest the moves may go (default: the axis's AP4 as found)")
    p.add_argument("--max-accel", type=int_arg, metavar="PPS2",
                   help="the largest acceleration the moves may use (default: the axis's AP5 as found)")
    p.add_argument("--reference", action="store_true", help="with --allow-motion: also run a reference search")
    p.add_argument("--no-program", action="store_true",
                   help="with --allow-motion: leave out the short program (it writes program memory and puts it back)")
    p.add_argument("--capture", metavar="FILE", help="where to write the capture (default conform-MODULE-TIME.jsonl)")
    p.add_argument("--baud", type=int_arg, metavar="N", help="baud rate of the line behind a tcp:// converter")
    p.add_argument("--timeout", type=float, default=1.0, metavar="SECONDS", help="reply time-out (default 1)")
    add_comparison_options(p)
    p.set_defaults(func=run)


def _axes(args: argparse.Namespace, axes: int) -> list[int]:
    if args.axes is None:
        if args.allow_motion:
            raise CliError("--allow-motion needs --axes (the axes that may move, e.g. --axes 0)")
        return list(range(axes))
    try:
        out = sorted({int(x) for x in args.axes.split(",") if x.strip()})
    except ValueError:
        raise CliError(f"--axes must list axis numbers, e.g. 0,2; got {args.axes!r}") from None
    if not out or any(not 0 <= a < axes for a in out):
        raise CliError(f"--axes must name axes 0..{axes - 1} of the module, got {args.axes!r}")
    return out


def _check(args: argparse.Namespace) -> None:
    if not 0 <= args.address <= 255:
        raise CliError(f"--address must be 0..255, got {args.address}")
    if not 0 < args.timeout <= 60:
        raise CliError("--timeout must be 0..60 s")
    if args.allow_motion and (args.max_travel is None or args.max_travel <= 0):
        raise CliError("--allow-motion needs --max-travel STEPS (a positive number of µsteps)")
    for name in ("max_speed", "max_accel"):
        value = getattr(args, name)
        if value is not None and value <= 0:
            raise CliError(f"--{name.replace('_', '-')} must be positive, got {value}")
    if args.baud is not None and not 0 < args.baud <= 10_000_000:
        raise CliError(f"--baud must be a positive baud rate, got {args.baud}")


def _start_proxy(args: argparse.Namespace, capture: str):
    from ..capture.proxy import Proxy, ProxySession
    from ..host.errors import TmclConnectionError, TmclError
    from ..server import TcpServer

    try:
        proxy = Proxy(args.url, log=capture, baud=args.baud, snapshot="state", address=args.address,
                      snapshot_module=args.module)
    except TmclConnectionError:
        raise
    except OSError as exc:
        raise CliError(f"cannot write {capture}: {exc.strerror or exc}") from None
    proxy.listen(TcpServer(proxy, "127.0.0.1", 0, max_clients=1, idle_timeout=0, session=ProxySession))
    try:
        proxy.start()
    except TmclError as exc:
        raise CliError(f"the module at address {args.address} does not answer the snapshot: {exc}") from exc
    return proxy


def run(args: argparse.Namespace) -> int:
    from ..capture import CaptureError, ReplayError, replay
    from ..capture.conform import Battery, ConformError, Options
    from ..host.connect import open_bus
    from ..modules.profile import load_profile
    from ..modules.profile_file import ProfileError

    _check(args)
    kwargs = comparison_kwargs(args, settings="profile")
    try:
        profile = load_profile(args.module)
    except ProfileError as exc:
        raise CliError(str(exc)) from None
    except KeyError as exc:
        raise CliError(exc.args[0] if exc.args else str(exc)) from None
    axes = _axes(args, profile.axes)
    capture = args.capture or f"conform-{profile.name}-{time.strftime('%Y%m%d-%H%M%S')}.jsonl"
    options = Options(axes, allow_writes=args.allow_writes or args.allow_motion, allow_motion=args.allow_motion,
                      max_travel=args.max_travel or 0, max_speed=args.max_speed, max_accel=args.max_accel,
                      reference=args.reference, program=not args.no_program)
    mode = "motion" if args.allow_motion else "writes" if args.allow_writes else "read-only"
    print(f"conformance run ({mode}) of {args.url} address {args.address} against {profile.name}", flush=True)
    proxy = _start_proxy(args, capture)
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        endpoint = proxy.endpoints[0].url
        client = open_bus(endpoint, address=args.address, timeout=args.timeout)

        def mark(phase: str, axis: int | None, label: str) -> None:
            if proxy.writer is not None:
                proxy.writer.write({"record": "mark", "t": round(time.monotonic() - proxy.t0, 6), "phase": phase,
                                    "axis": axis, "label": label})
            print(f"  {phase}{'' if axis is None else f' axis {axis}'}: {label}", file=sys.stderr, flush=True)

        battery = Battery(client, profile, options, mark)
        try:
            battery.run()
        except ConformError as exc:   # every axis got MST and the settings are back (Battery.emergency)
            raise CliError(f"{exc}; every axis was stopped, the capture is {capture}") from None
        finally:
            client.close()
    finally:
        signal.signal(signal.SIGTERM, previous)
        proxy.stop()
    for note in battery.skipped:
        print(f"  skipped: {note}", file=sys.stderr, flush=True)
    try:
        report = replay(capture, args.module, address=args.address, **kwargs)
    except (CaptureError, ReplayError) as exc:
        raise CliError(str(exc)) from None
    print(report.text(), flush=True)
    for area, (ok, total) in report.areas.items():
        score = "not checked" if not total else f"{ok}/{total} ({ok / total * 100:.1f} %)"
        print(f"  {area:<15} {score}", flush=True)
    print(f"capture: {capture} (to send it with the report, see docs/capture.md \"Sending a capture\")", flush=True)
    write_reports(report, args)
    return 0 if report.ok else 1


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt
