"""`opentmcl dashboard --to URL`: the browser dashboard for a module reached through the host library.

    opentmcl dashboard --to serial:///dev/ttyUSB0?baud=9600 --web 127.0.0.1:8080
    opentmcl dashboard --to tcp://127.0.0.1:2323
    opentmcl dashboard --to sim://TMCM-6212          # a virtual module in this process, on the wall clock

Open the printed URL in a browser. The page answers only under loopback names unless
--allow-host NAME adds one (for a LAN; a token printed at start-up is then required). For modules served by `opentmcl serve`, `serve --web` gives the
same page without a second process. Ctrl-C stops it. See docs/dashboard.md.
"""
from __future__ import annotations

import argparse
import os
import signal
import threading
import urllib.parse
from typing import TYPE_CHECKING

from . import CliError

if TYPE_CHECKING:
    from ..web.server import DashboardHandle

DEFAULT_WEB = "127.0.0.1:8080"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("dashboard", help="serve the browser dashboard for a module at URL",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--to", dest="url", default=os.environ.get("OPENTMCL_URL"),
                   help="module URL (sim://, tcp://, serial://, can://; default $OPENTMCL_URL)")
    p.add_argument("--address", type=int, default=None, help="module address (default 1)")
    p.add_argument("--timeout", type=float, default=2.0, help="seconds to wait for each reply (default 2)")
    p.add_argument("--web", default=DEFAULT_WEB, metavar="HOST:PORT",
                   help=f"where to serve the page (default {DEFAULT_WEB}; loopback unless you say otherwise)")
    add_allow_host(p)
    p.set_defaults(func=run)


def add_allow_host(p: argparse.ArgumentParser) -> None:
    """--allow-host, shared with `opentmcl serve --web`."""
    p.add_argument("--allow-host", action="append", default=[], metavar="NAME",
                   help="also accept the dashboard under this host name or address (repeat for several; "
                        "for a LAN: a token printed at start-up is then required, see docs/dashboard.md)")


def require_web(feature: str) -> None:
    """The packages of the 'web' extra, or a one-line CliError naming it (opentmcl/extras.py)."""
    from ..extras import MissingExtra, require

    try:
        require("web", feature)
    except MissingExtra as exc:
        raise CliError(str(exc)) from None


def allowed_hosts(names: list[str]) -> tuple[str, ...]:
    from ..web.server import check_allowed_hosts

    try:
        return check_allowed_hosts(names)
    except ValueError as exc:
        raise CliError(str(exc)) from None


def print_urls(handle: DashboardHandle, prefix: str, suffix: str = "") -> None:
    """The URL(s) to open; with a token, say that it is needed."""
    first, *others = handle.urls_to_open()
    print(f"{prefix}{first}{suffix}", flush=True)
    for url in others:
        print(f"    also at {url}", flush=True)
    if handle.token:
        print("    (the token is required: open one of these URLs once, scripts send the header "
              "X-OpenTMCL-Token)", flush=True)


def sim_url_real_time(url: str) -> str:
    """A sim:// module has no clock of its own: run it on the wall clock unless the URL says otherwise."""
    parts = urllib.parse.urlsplit(url)
    if parts.scheme.lower() != "sim":
        return url
    query = dict(urllib.parse.parse_qsl(parts.query))
    query.setdefault("clock", "real")
    # not urlunsplit: it drops the empty host of sim:///path/my.toml (a profile file, docs/profiles.md)
    return f"{parts.scheme}://{parts.netloc}{parts.path}?{urllib.parse.urlencode(query)}" \
        + (f"#{parts.fragment}" if parts.fragment else "")


def parse_web(text: str) -> tuple[str, int]:
    from .serve import parse_hostport

    host, port = parse_hostport(text)
    return host or "127.0.0.1", port


def wait_for_signal() -> None:
    stop = threading.Event()
    previous = {s: signal.signal(s, lambda *_: stop.set()) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        while not stop.wait(0.5):
            pass
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def run(args: argparse.Namespace) -> int:
    from ..host import TmclError, connect
    from ..host.transports.inprocess import InProcessTransport

    require_web("opentmcl dashboard")
    if not args.url:
        raise CliError("give the module URL with --to (or set $OPENTMCL_URL)")
    if not args.timeout > 0:
        raise CliError(f"--timeout must be a number of seconds > 0, got {args.timeout:g}")
    host, port = parse_web(args.web)
    hosts = allowed_hosts(args.allow_host)
    try:
        from ..web.server import DashboardStartError, start_dashboard
    except ImportError as exc:
        raise CliError(f"the dashboard needs the 'web' extra (pip install 'opentmcl[web]'): {exc}") from None
    url = sim_url_real_time(args.url)
    try:
        module = connect(url, address=args.address, timeout=args.timeout)
        _ = module.profile
    except TmclError as exc:
        raise CliError(str(exc)) from None
    transport = module.client.transport
    vm = transport.module if isinstance(transport, InProcessTransport) else None
    lock = transport.lock if vm is not None else None
    try:
        handle = start_dashboard(module, host, port, vm=vm, vm_lock=lock, url=args.url, on_stop=module.close,
                                 allow_hosts=hosts)
    except DashboardStartError as exc:
        module.close()
        raise CliError(str(exc)) from None
    print_urls(handle, f"OpenTMCL dashboard for {module.profile.name} at {args.url}: ")
    print("Press Ctrl-C to stop.", flush=True)
    try:
        wait_for_signal()
    finally:
        handle.stop()
    return 0
