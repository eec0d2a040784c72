"""`opentmcl serve`: host virtual modules in real time on TCP, a pty and/or CAN.

    opentmcl serve --module TMCM-6212 [--address 1] [--tcp 127.0.0.1:2323] [--idle-timeout 300]
                   [--pty [--link PATH] [--interface usb|rs485|rs232]]
                   [--can virtual:CH | udp_multicast:GROUP | socketcan:vcan0] [--eeprom FILE] [--scenario FILE]
                   [--faults FILE [--fault-seed N] [--fault-control PATH]]

Several --module options put several modules on one bus; the n-th --address,
--eeprom and --scenario belong to the n-th --module (a module without
--address gets the next free address). Without any endpoint option the
server listens on tcp 127.0.0.1:2323. Ctrl-C or SIGTERM stops it and flushes
the EEPROM files. See docs/endpoints.md.
"""
from __future__ import annotations

import argparse
import signal
import sys
import threading
from types import FrameType
from typing import TYPE_CHECKING, TextIO

from . import CliError, about_file, int_arg, start_error

if TYPE_CHECKING:
    from ..faults import FaultPlan
    from ..firmware.vm import VirtualModule
    from ..motion.scenario import Scenario
    from ..server import Server
    from ..server.control import FaultControl
    from ..server.endpoints import EndpointOptions
    from ..web.server import DashboardHandle

DEFAULT_TCP = "127.0.0.1:2323"


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("serve", help="host virtual modules on TCP, a pty or CAN in real time",
                              description=__doc__.split("\n\n")[0])
    p.add_argument("--module", "-m", action="append", required=True, metavar="NAME|FILE",
                   help="module type, e.g. TMCM-6212, or a profile file (docs/profiles.md); "
                        "repeat for several modules on one bus")
    p.add_argument("--address", "-a", action="append", type=_address, default=[], metavar="N",
                   help="RS485 module address (global parameter 66) of the n-th module")
    p.add_argument("--tcp", nargs="?", const=DEFAULT_TCP, metavar="[HOST:]PORT",
                   help=f"serve raw 9-byte frames on TCP (default {DEFAULT_TCP}); loopback only unless --host")
    p.add_argument("--host", metavar="ADDR",
                   help="bind TCP to this address instead of loopback (reachable from the network!)")
    p.add_argument("--max-clients", type=int, default=4, metavar="N", help="TCP clients at once (default 4)")
    p.add_argument("--idle-timeout", type=float, default=300.0, metavar="SECONDS",
                   help="drop a TCP client that sends nothing for SECONDS (default 300; 0: never)")
    p.add_argument("--pty", action="store_true", help="create a pseudo-terminal and print its path")
    p.add_argument("--link", metavar="PATH", help="with --pty: also create a symbolic link PATH to it")
    p.add_argument("--interface", choices=("usb", "rs485", "rs232"),
                   help="with --pty: the link the port stands for; usb answers any address byte "
                        "(default usb for one module that has a USB port, rs485 for several, with --pace "
                        "or for a module without USB such as the PD28-1021)")
    p.add_argument("--can", metavar="INTERFACE:CHANNEL",
                   help="serve on a python-can bus, e.g. virtual:opentmcl (this process), udp_multicast:239.74.163.2 "
                        "(other processes) or socketcan:vcan0")
    p.add_argument("--endpoint", action="append", default=[], metavar="NAME[:SPEC]",
                   help="serve on a registered endpoint, e.g. one an installed package adds "
                        "(--tcp, --pty and --can name the built-in ones; docs/endpoints.md)")
    p.add_argument("--eeprom", action="append", default=[], metavar="FILE",
                   help="EEPROM file of the n-th module (created if missing)")
    p.add_argument("--scenario", action="append", default=[], metavar="FILE",
                   help="scenario file of the n-th module")
    p.add_argument("--faults", metavar="FILE",
                   help="serve with the faults of this fault plan (docs/faults.md): dropped, garbled, delayed or "
                        "cut frames, a link down, power loss, a hung firmware, overtemperature, switches, lost steps")
    p.add_argument("--fault-seed", type=int_arg, metavar="N",
                   help="with --faults: the seed of the plan's random decisions (default: the file's, else a new one, printed)")
    p.add_argument("--fault-control", metavar="PATH",
                   help="with --faults: a socket (owner only) through which `opentmcl fault NAME --control PATH` "
                        "triggers a named fault")
    p.add_argument("--gap", type=float, default=0.1, metavar="SECONDS",
                   help="silence after which a partial serial frame is discarded (default 0.1)")
    p.add_argument("--pace", action="store_true",
                   help="pace request and reply bytes at the RS485 baud rate (global parameter 65)")
    p.add_argument("--web", metavar="HOST:PORT",
                   help="also serve the browser dashboard of every module, e.g. 127.0.0.1:8080 "
                        "(each module at /m/ADDRESS/, a selector on the page)")
    from .dashboard import add_allow_host

    add_allow_host(p)
    p.set_defaults(func=run)


def _address(text: str) -> int:
    try:
        value = int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text[:40]!r}") from None
    from ..modules.addresses import ADDRESSES

    if value not in ADDRESSES:
        raise argparse.ArgumentTypeError("module address must be 1..255 (manual 5.1, parameter 66)")
    return value


def parse_hostport(text: str) -> tuple[str | None, int]:
    """``PORT``, ``HOST:PORT`` or ``[IPv6]:PORT`` -> (host or None, port)."""
    host: str | None = None
    port_text = text
    if text.startswith("["):
        host, sep, rest = text[1:].partition("]")
        if not sep or not rest.startswith(":"):
            raise CliError(f"bad TCP address {text!r}; use [HOST]:PORT")
        port_text = rest[1:]
    elif ":" in text:
        host, _, port_text = text.rpartition(":")
    try:
        port = int(port_text)
    except ValueError:
        raise CliError(f"bad TCP port in {text!r}") from None
    if not 0 <= port <= 65535:
        raise CliError(f"TCP port {port} out of range 0..65535")
    return (host or None), port


def assign_addresses(count: int, given: list[int]) -> list[int]:
    """Addresses for `count` modules: the given ones, then the next free ones."""
    if len(given) > count:
        raise CliError("more --address options than --module options")
    out = list(given)
    candidate = 1
    while len(out) < count:
        while candidate in out:
            candidate += 1
        out.append(candidate)
    from ..modules.addresses import address_error

    if max(out) > 255 and len(set(out)) == len(out):
        raise CliError("too many modules for the address range 1..255")
    problem = address_error(out)
    if problem:
        raise CliError(problem)
    return out


def load_scenario(path: str | None) -> Scenario | None:
    """A scenario file loaded by opentmcl.motion.scenario (the same hook as `opentmcl run`)."""
    if path is None:
        return None
    try:
        from ..motion.scenario import load_scenario as load
    except ImportError:
        raise CliError("scenario files are not supported by this version") from None
    try:
        return load(path)
    except (OSError, ValueError, KeyError) as exc:
        raise CliError(about_file(path, exc, "scenario")) from None


def build_modules(args: argparse.Namespace) -> list:
    """The modules of the bus. The n-th --address wins; a module without one keeps the address its
    EEPROM file stores (GP66), else gets the next free address (docs/endpoints.md)."""
    from ..firmware.eeprom import EepromError
    from ..firmware.vm import VirtualModule

    names = args.module
    for option in ("address", "eeprom", "scenario"):
        if len(getattr(args, option)) > len(names):
            raise CliError(f"more --{option} options than --module options")
    modules, free = [], []
    for i, name in enumerate(names):
        address = args.address[i] if i < len(args.address) else None
        eeprom = args.eeprom[i] if i < len(args.eeprom) else None
        scenario = load_scenario(args.scenario[i] if i < len(args.scenario) else None)
        try:
            vm = VirtualModule(name, address=address, eeprom=eeprom, scenario=scenario)
        except KeyError as exc:
            raise CliError(str(exc.args[0]) if exc.args else f"unknown module {name!r}") from None
        except (EepromError, ValueError) as exc:  # also a scenario for another module
            raise CliError(str(exc)) from None
        if address is None and vm.stored_global(0, 66) is None:
            free.append(vm)
        modules.append(vm)
    taken = [vm.address for vm in modules if vm not in free]
    for vm, address in zip(free, assign_addresses(len(free) + len(taken), taken)[len(taken):], strict=True):
        vm.assign_address(address)
    addresses = [vm.address for vm in modules]
    if len(set(addresses)) != len(addresses):
        raise CliError(f"module addresses must be distinct on one bus, got {addresses} "
                       "(give --address to override an address stored in an EEPROM file)")
    return modules


def check_listen_options(args: argparse.Namespace) -> None:
    """--gap, --max-clients and --idle-timeout, shared by `serve` and `proxy`."""
    from ..server.tcp import check_idle_timeout

    if not 0 < args.gap < float("inf"):  # also NaN
        raise CliError(f"--gap must be a positive number of seconds, got {args.gap}")
    if args.max_clients < 1:
        raise CliError("--max-clients must be at least 1")
    try:
        check_idle_timeout(args.idle_timeout, "--idle-timeout")
    except ValueError as exc:
        raise CliError(str(exc)) from None


def build_server(args: argparse.Namespace, out: TextIO = sys.stdout, err: TextIO = sys.stderr) -> Server:
    """The Server with its endpoints, not started."""
    from ..server import Server

    check_listen_options(args)
    if args.link and not args.pty:
        args.pty = True
    if args.interface and not args.pty:
        raise CliError("--interface applies to --pty (TCP stands for a serial line: rs485/rs232)")
    tcp_spec = args.tcp
    extra = getattr(args, "endpoint", [])
    if tcp_spec is None and not args.pty and not args.can and not extra:
        tcp_spec = DEFAULT_TCP
    plan = load_faults(args)
    modules = build_modules(args)
    if len(modules) > 1:
        _give_can_ids(modules)
    server = Server(modules)
    if plan is not None or any(vm.world.scenario.faults for vm in modules):
        _arm(server, plan)
    if tcp_spec is not None or args.host:
        _add_tcp(server, args, tcp_spec or DEFAULT_TCP)
    if args.pty:
        _add_pty(server, args, modules)
    if args.can:
        _add(server, args, "can", args.can)
    for item in extra:
        name, _, spec = item.partition(":")
        if name in ("tcp", "pty"):
            raise CliError(f"--endpoint {item}: use --{name}, which checks its options")
        _add(server, args, name, spec)
    return server


def load_faults(args: argparse.Namespace) -> FaultPlan | None:
    """The plan of --faults (with --fault-seed); a bad file or fault is one line (exit 2)."""
    from ..faults import FaultError, load_plan, seed_of

    if getattr(args, "faults", None) is None:
        if getattr(args, "fault_seed", None) is not None or getattr(args, "fault_control", None) is not None:
            raise CliError("--fault-seed and --fault-control belong to --faults FILE")
        return None
    try:
        plan = load_plan(args.faults)
        return plan if args.fault_seed is None else plan.with_seed(seed_of(args.fault_seed, "--fault-seed"))
    except FaultError as exc:
        raise CliError(about_file(args.faults, exc, "fault plan")) from None


def _arm(server: Server, plan: FaultPlan | None) -> None:
    from ..faults import FaultError, FaultPlan

    try:
        server.arm(plan if plan is not None else FaultPlan())
    except FaultError as exc:
        raise CliError(str(exc)) from None


def _options(args: argparse.Namespace) -> EndpointOptions:
    from ..server.endpoints import EndpointOptions

    return EndpointOptions(gap=args.gap, pace_bytes=args.pace, max_clients=args.max_clients,
                           idle_timeout=args.idle_timeout, interface=args.interface, link=args.link)


def _add(server: Server, args: argparse.Namespace, name: str, spec: str) -> None:
    """An endpoint of the registry (server/endpoints.py); a bad name or spec is one line."""
    from ..server.endpoints import make

    try:
        server.add(make(name, server.bus, spec, _options(args)))
    except ValueError as exc:
        raise CliError(f"--{'can' if name == 'can' else 'endpoint'}: {exc}") from None


def _give_can_ids(modules: list[VirtualModule]) -> None:
    """Several modules on one CAN bus need distinct CAN IDs (GP 71, default 1 on every module):
    each gets its serial address as CAN ID, in RAM only (docs/assumptions.md)."""
    from ..server import vmapi

    for vm in modules:
        if vm.stored_global(0, vmapi.GP_CAN_ID) is None:  # a CAN ID stored in the EEPROM stays
            vmapi.set_global_ram(vm, vmapi.GP_CAN_ID, vmapi.global_param(vm, vmapi.GP_SERIAL_ADDRESS))


def _add_tcp(server: Server, args: argparse.Namespace, spec: str) -> None:
    """--tcp [HOST:]PORT and --host: loopback unless --host names another address (with a warning)."""
    from ..server.tcp import is_loopback

    host, port = parse_hostport(spec)
    if args.host:
        host = args.host
    host = host or "127.0.0.1"
    if not is_loopback(host):
        if not args.host:
            raise CliError(f"refusing to bind TCP to {host}: give --host {host} to serve beyond loopback")
        import logging  # a warning record: -q hides it (cli/verbosity.py)

        logging.getLogger("opentmcl.cli").warning("warning: TCP bound to %s is reachable from the network; "
                                                  "anyone who can connect can move the motors", host)
    _add(server, args, "tcp", f"[{host}]:{port}" if ":" in host else f"{host}:{port}")


def _add_pty(server: Server, args: argparse.Namespace, modules: list[VirtualModule]) -> None:
    """--pty [--link PATH] [--interface]: the interface must suit the modules and --pace."""
    if sys.platform == "win32":
        raise CliError("--pty needs a POSIX system")
    from ..server.bus import interface_error

    problem = args.interface and interface_error(args.interface, modules, args.pace)
    if problem:
        raise CliError(f"--interface {args.interface}: {problem}")
    _add(server, args, "pty", "")


def describe(server: Server) -> list[str]:
    """Lines telling the user how to connect."""
    from ..server import CanServer, PtyServer, TcpServer, vmapi

    lines = []
    for vm in server.modules:
        name = getattr(getattr(vm, "profile", None), "name", type(vm).__name__)
        can_id = vmapi.global_param(vm, vmapi.GP_CAN_ID)
        lines.append(f"module {name} at address {vmapi.global_param(vm, vmapi.GP_SERIAL_ADDRESS)}"
                     f" (CAN ID {can_id}, reply ID {vmapi.global_param(vm, vmapi.GP_CAN_REPLY_ID)})"
                     + (", in ASCII mode (GP67 bit 0)" if getattr(vm, "ascii_mode", False) is True else ""))
    for ep in server.endpoints:
        if isinstance(ep, TcpServer):
            lines.append(f"tcp {ep.url}")
        elif isinstance(ep, PtyServer):
            link = f" (link {ep.link})" if ep.link else ""
            lines.append(f"pty {ep.path}{link}  ->  serial://{ep.path}  ({ep.interface})")
        elif isinstance(ep, CanServer):
            for vm in server.modules:
                lines.append(f"can {ep.url}?id={vmapi.global_param(vm, vmapi.GP_CAN_ID)}"
                             f"&reply_id={vmapi.global_param(vm, vmapi.GP_CAN_REPLY_ID)}")
        else:  # an endpoint of another package: its url, else its type
            lines.append(f"endpoint {getattr(ep, 'url', type(ep).__name__)}")
    if server.faults is not None:
        names = server.faults.names()
        lines.append(f"faults: {len(server.faults.plan.faults)} armed, seed {server.faults.seed}"
                     + (f"; by name: {', '.join(names)}" if names else ""))
    return lines


def run(args: argparse.Namespace) -> int:
    if getattr(args, "allow_host", None) and not getattr(args, "web", None):
        raise CliError("--allow-host belongs to the dashboard: give --web HOST:PORT too")
    if getattr(args, "web", None):
        from .dashboard import require_web

        require_web("opentmcl serve --web")
    return _run(args)   # endpoint events reach stderr through main()'s log handler (cli/verbosity.py)


SWITCH_INTERVAL = 0.001
"""Seconds a Python thread may keep the interpreter while another waits for it (CPython's default is
0.005): an endpoint's thread then waits at most this long behind the clock thread's slice."""


def _run(args: argparse.Namespace) -> int:
    sys.setswitchinterval(SWITCH_INTERVAL)
    try:
        server = build_server(args)
        server.start()
    except OSError as exc:
        raise start_error("server", exc, args.tcp) from None
    except ImportError as exc:
        raise CliError(f"cannot start server: {exc}") from None
    except Exception as exc:  # python-can reports a missing interface with its own errors
        if type(exc).__module__.split(".")[0] == "can":
            raise CliError(f"cannot open CAN bus: {exc}") from None
        raise
    stop = threading.Event()

    def on_signal(_signum: int, _frame: FrameType | None) -> None:
        stop.set()

    previous = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        previous[signum] = signal.signal(signum, on_signal)
    web = control = None
    try:
        if getattr(args, "web", None):
            web = _start_web(server, args.web, getattr(args, "allow_host", []))
        control = _start_control(server, getattr(args, "fault_control", None))
        print("OpenTMCL serving in real time:", flush=True)
        for line in describe(server):
            print(f"  {line}", flush=True)
        if web is not None:
            from .dashboard import print_urls

            many = len(web.dashboards) > 1
            print_urls(web, "  dashboard ", f" ({len(web.dashboards)} modules, choose on the page):" if many else "")
            if many:
                for d in web.dashboards:
                    print(f"    {d.profile.name} at address {d.module.address}: {web.module_url(d.module.address)}",
                          flush=True)
        print("Press Ctrl-C to stop.", flush=True)
        while not stop.wait(0.1):
            pass
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        if web is not None:
            web.stop()
        if control is not None:
            control.stop()
        server.stop()
    from ..server.pacing import REPORT_LAG

    report = server.bus.clock_report()
    if report.worst >= REPORT_LAG:
        print(f"the modules' clock lagged the wall clock by up to {report.worst:.2f} s; "
              f"{report.dropped:.1f} s were dropped (docs/endpoints.md)", flush=True)
    print("stopped; EEPROM flushed", flush=True)
    return 0


def _start_control(server: Server, path: str | None) -> FaultControl | None:
    """--fault-control PATH: the socket that triggers named faults (server/control.py)."""
    if path is None or server.faults is None:
        return None
    from ..server.control import FaultControl

    control = FaultControl(server.faults, path)
    try:
        control.start()
    except OSError as exc:
        raise CliError(f"--fault-control {path}: {exc.strerror or exc}") from None
    return control


def _start_web(server: Server, spec: str, allow_host: list[str]) -> DashboardHandle:
    """The dashboard (opentmcl.web) for every served module on HOST:PORT (--allow-host names too)."""
    from .dashboard import allowed_hosts

    host, port = parse_hostport(spec)
    hosts = allowed_hosts(allow_host)
    try:
        from ..web.server import DashboardStartError, start_dashboard_for_bus
    except ImportError as exc:
        raise CliError(f"--web needs the 'web' extra (pip install 'opentmcl[web]'): {exc}") from None
    try:
        return start_dashboard_for_bus(server.bus, host or "127.0.0.1", port, allow_hosts=hosts)
    except DashboardStartError as exc:
        raise CliError(str(exc)) from None
