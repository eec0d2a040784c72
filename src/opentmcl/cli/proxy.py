"""`opentmcl proxy`: sit between a host program and a module, relay every byte, capture the traffic.

    opentmcl proxy --to URL (--pty [--link PATH] | --tcp [HOST:]PORT) [--log FILE] [--idle-timeout 300]
                   [--snapshot full|state|none] [--snapshot-program] [--address N] [--baud N]

URL is the module: serial:///dev/ttyUSB0?baud=9600, tcp://HOST:PORT, sim://NAME or
can://INTERFACE/CHANNEL?id=N (a gateway: frames are converted, docs/capture.md). The host
program opens the pty (or connects to the TCP port) exactly as it would a served module
(`opentmcl serve`). Bytes pass unchanged; --log writes the decoded traffic as JSON Lines
(docs/capture.md). Before relaying it reads the module's state with reading commands only (the
snapshot that `replay` starts the twin from). Ctrl-C or SIGTERM stops it and closes the capture file.
"""
from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
from typing import TYPE_CHECKING

from . import CliError, start_error
from .exits import NO_REPLY

if TYPE_CHECKING:
    from ..capture.proxy import Proxy


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("proxy", help="relay a host program's traffic to a module and capture it",
                              description=__doc__.split("\n\n")[0])
    p.add_argument("--to", required=True, metavar="URL",
                   help="the module: serial:///dev/ttyUSB0?baud=9600, tcp://HOST:PORT, sim://NAME or "
                        "can://INTERFACE/CHANNEL?id=N")
    p.add_argument("--pty", action="store_true", help="listen on a new pseudo-terminal and print its path")
    p.add_argument("--link", metavar="PATH", help="with --pty: also create a symbolic link PATH to it")
    p.add_argument("--tcp", metavar="[HOST:]PORT", help="listen on TCP (loopback unless --host)")
    p.add_argument("--host", metavar="ADDR", help="bind TCP to this address instead of loopback")
    p.add_argument("--max-clients", type=int, default=4, metavar="N", help="TCP clients at once (default 4)")
    p.add_argument("--idle-timeout", type=float, default=300.0, metavar="SECONDS",
                   help="drop a TCP client that sends nothing for SECONDS (default 300; 0: never)")
    p.add_argument("--log", metavar="FILE", help="write the capture (JSON Lines) to FILE")
    p.add_argument("--gap", type=float, default=0.1, metavar="SECONDS",
                   help="silence after which the decoder drops a partial frame as garbage (default 0.1)")
    p.add_argument("--snapshot", choices=("full", "state", "none"), default="full",
                   help="read the module before relaying, with reading commands only: every readable "
                        "parameter and port (full, default), only where it is (state: positions, "
                        "encoder, timers), or nothing (none)")
    p.add_argument("--snapshot-program", action="store_true",
                   help="also read the TMCL program memory into the snapshot (command 134)")
    p.add_argument("--snapshot-module", metavar="NAME|FILE",
                   help="the module profile that says what to read (default: from its firmware string)")
    p.add_argument("--address", "-a", type=int, default=1, metavar="N",
                   help="address of the module the snapshot reads (default 1)")
    p.add_argument("--baud", type=int, metavar="N",
                   help="baud rate of the line behind a tcp:// converter (recorded as the capture's link; "
                        "serial:// URLs give their own)")
    p.set_defaults(func=run)


def build_proxy(args: argparse.Namespace) -> Proxy:
    from ..capture.proxy import Proxy, ProxySession
    from ..host.errors import TmclConnectionError
    from ..server import PtyServer, TcpServer
    from ..server.tcp import is_loopback
    from .serve import check_listen_options, parse_hostport

    if args.link:
        args.pty = True
    if not args.pty and not args.tcp:
        raise CliError("give --pty (a pseudo-terminal) or --tcp [HOST:]PORT to listen on")
    check_listen_options(args)
    if args.pty and sys.platform == "win32":
        raise CliError("--pty needs a POSIX system")
    tcp = None
    if args.tcp:
        host, port = parse_hostport(args.tcp)
        host = args.host or host or "127.0.0.1"
        if not is_loopback(host) and not args.host:
            raise CliError(f"refusing to bind TCP to {host}: give --host {host} to listen beyond loopback")
        tcp = (host, port)
    if not 0 <= args.address <= 255:
        raise CliError(f"--address must be 0..255, got {args.address}")
    if args.baud is not None and not 0 < args.baud <= 10_000_000:
        raise CliError(f"--baud must be a positive baud rate, got {args.baud}")
    try:
        proxy = Proxy(args.to, log=args.log, gap=args.gap, baud=args.baud,
                      snapshot=None if args.snapshot == "none" else args.snapshot, address=args.address,
                      snapshot_program=args.snapshot_program, snapshot_module=args.snapshot_module)
    except TmclConnectionError as exc:
        raise CliError(str(exc)) from None
    except OSError as exc:
        raise CliError(f"cannot write {args.log}: {exc.strerror or exc}") from None
    if tcp is not None:
        proxy.listen(TcpServer(proxy, tcp[0], tcp[1], max_clients=args.max_clients,
                                     idle_timeout=args.idle_timeout, session=ProxySession))
    if args.pty:
        proxy.listen(PtyServer(proxy, link=args.link, session=ProxySession))
    return proxy


def run(args: argparse.Namespace) -> int:
    proxy = build_proxy(args)
    _start(proxy, args)
    stop = threading.Event()
    previous = {s: signal.signal(s, lambda *_: stop.set()) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        _announce(proxy, args)
        error = _relay(proxy, args, stop)
        if error:
            print(f"opentmcl proxy: error: {error}", file=sys.stderr, flush=True)
            return NO_REPLY   # the module's link broke (docs/cli.md)
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        proxy.stop()
    print("stopped; capture closed" if args.log else "stopped", flush=True)
    return 0


def _start(proxy: Proxy, args: argparse.Namespace) -> None:
    """Snapshot, then relay; what went wrong as one CliError line."""
    from ..host.errors import TmclError

    try:
        proxy.start()
    except TmclError as exc:   # the snapshot: the module did not answer (exit 3) or is unknown
        raise CliError(f"the snapshot of the module at address {args.address} failed (--snapshot none "
                       f"relays without one): {exc}") from exc
    except OSError as exc:
        raise start_error("proxy", exc, args.tcp) from None
    except (KeyError, ValueError) as exc:   # --snapshot-module names no profile
        raise CliError(str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc)) from None


def _announce(proxy: Proxy, args: argparse.Namespace) -> None:
    """Where the host program connects, the capture file and the snapshot."""
    from ..server import PtyServer, TcpServer

    print(f"OpenTMCL proxy to {args.to}:", flush=True)
    for ep in proxy.endpoints:
        if isinstance(ep, TcpServer):
            print(f"  tcp {ep.url}", flush=True)
        elif isinstance(ep, PtyServer):
            link = f" (link {ep.link})" if ep.link else ""
            print(f"  pty {ep.path}{link}  ->  serial://{ep.path}", flush=True)
    if args.log:
        print(f"  capture {args.log}", flush=True)
    snap = proxy.snapshot
    if snap is not None:
        print(f"  snapshot of {snap.module} at address {snap.address}: {snap.count()} values", flush=True)
    print("Press Ctrl-C to stop.", flush=True)


def _relay(proxy: Proxy, args: argparse.Namespace, stop: threading.Event) -> str | None:
    """Relay until `stop` is set (None) or the module's link breaks (why, with a hint)."""
    warned = False
    while not stop.wait(0.2):
        if not warned and proxy.writer is not None and proxy.writer.truncated:
            warned = True
            logging.getLogger("opentmcl.cli").warning(   # -q hides it (cli/verbosity.py)
                "warning: %s reached its size limit; relaying goes on, capturing stopped", args.log)
        error = getattr(proxy.upstream, "error", None)
        if error:
            if args.to.startswith("tcp://") and "closed" in error and "--idle-timeout" not in error:  # e.g. serve's idle timeout
                error += " (it may drop idle clients: run `opentmcl serve` with --idle-timeout 0)"
            return error
    return None
