"""``sim://``: virtual modules in this process behind the host library (docs/architecture.md "Layers").

This package sits above both the host library and the firmware: it builds `VirtualModule` objects
from a ``sim://`` URL and puts them behind the host's `InProcessTransport`, so the host itself
never imports the firmware. The root package registers ``sim`` as the lazy reference
``opentmcl.sim:open_sim``; importing this package registers the function itself.

    sim://NAME[@ADDR][,NAME@ADDR...][?address=N&clock=virtual|real|none&step=S&faults=FILE&seed=N]

With ``faults=FILE`` (a fault plan, docs/faults.md) the link and the modules fail as the plan says,
reproducibly from its seed (``seed=N`` overrides it); the transport's `faults` triggers a named
fault and lists what fired.
"""
from __future__ import annotations

import urllib.parse

from ..faults import FaultBoard, FaultError, FaultPlan, load_plan, seed_of
from ..firmware.vm import VirtualModule
from ..host.client import Client
from ..host.connect import register_transport
from ..host.errors import TmclUrlError
from ..host.module import Module
from ..host.transport import url_query
from ..host.transports.faulty import FaultyTransport
from ..host.transports.inprocess import Clock, InProcessTransport, VirtualClock, make_clock, parse_modules

__all__ = ["connect", "open_sim", "with_faults"]


def open_sim(url: urllib.parse.SplitResult) -> InProcessTransport:
    """Factory for ``sim://NAME[@ADDR][,NAME@ADDR...][?address=N&clock=virtual|real|none&step=S&faults=FILE&seed=N]``."""
    query = url_query(url, ("address", "clock", "step", "faults", "seed"))
    try:
        default_address = int(query.get("address", "1"), 0)
    except ValueError:
        raise TmclUrlError(f"bad address {query['address']!r} in sim:// URL") from None
    # A profile file is a path: sim:///abs/module.toml or sim://relative/module.toml (docs/profiles.md).
    spec = url.netloc + url.path if ".toml" in url.path.lower() else (url.netloc or url.path.lstrip("/"))
    modules = []
    for name, address in parse_modules(spec, default_address):
        try:
            modules.append(VirtualModule(name, address=address))
        except (KeyError, ValueError) as exc:  # ValueError: a bad profile file
            raise TmclUrlError(f"sim://: {exc.args[0] if exc.args else exc}") from None
    try:
        return with_faults(modules, _plan(query), _clock(query))
    except FaultError as exc:
        raise TmclUrlError(f"sim://: {exc}") from None


def with_faults(modules: list[VirtualModule], plan: FaultPlan, clock: str | Clock = "virtual") -> InProcessTransport:
    """The in-process link to `modules`; with a plan, its faults armed on the link and on the
    modules, all drawing on the plan's seed and recording in one log (`transport.faults`).
    FaultError for a fault a module cannot take (an axis it lacks)."""
    if not plan:
        return InProcessTransport(modules, clock=clock)
    plan.check_addresses(vm.address for vm in modules)
    first = modules[0]
    board = FaultBoard(plan, clock=lambda: first.time)
    for vm in modules:
        vm.faults.load(None, board=board)
    link = board.link("sim")
    transport: InProcessTransport = InProcessTransport(modules, clock=clock) if link is None else \
        FaultyTransport(modules, link, clock=clock)
    transport.faults = board
    return transport


def _plan(query: dict[str, str]) -> FaultPlan:
    """The fault plan of ``?faults=FILE`` and ``?seed=N``."""
    if "faults" in query and not query["faults"]:
        raise TmclUrlError("sim://: faults= needs a fault file (docs/faults.md)")
    if "seed" in query and "faults" not in query:
        raise TmclUrlError("sim://: seed= belongs to faults=FILE (the seed of its random decisions)")
    try:
        plan = load_plan(query["faults"]) if "faults" in query else FaultPlan()
        if "seed" in query:
            try:
                seed = int(query["seed"], 0)
            except ValueError:
                raise FaultError(f"seed: expected an integer, got {query['seed']!r}") from None
            plan = plan.with_seed(seed_of(seed))
    except FaultError as exc:
        raise TmclUrlError(f"sim://: {exc}") from None
    return plan


def _clock(query: dict[str, str]) -> Clock:
    """The clock policy of ``?clock=`` (default virtual), with ``?step=`` for the virtual one."""
    clock_name = query.get("clock", "virtual")
    try:
        if clock_name == "virtual" and "step" in query:
            return VirtualClock(float(query["step"]))
        return make_clock(clock_name)
    except ValueError as exc:
        raise TmclUrlError(f"sim://: {exc}") from None


register_transport("sim", open_sim)


def connect(spec: str = "TMCM-6212", *, faults: object = None, timeout: float = 5.0, clock: str | Clock = "virtual",
            address: int | None = None) -> Module:
    """`opentmcl.connect("sim://SPEC")` with `faults` armed on the link and the modules: a fault plan,
    a fault file, one fault table or a list of them (docs/faults.md), e.g.

        m = opentmcl.sim.connect("TMCM-6212", faults=[{"kind": "drop_reply", "probability": 0.05}])

    The plan's seed, when it has one, makes every run the same; `m.client.transport.faults` triggers
    named faults and lists what fired. TmclUrlError for a bad spec, FaultError for a bad fault."""
    plain = open_sim(urllib.parse.urlsplit(f"sim://{spec}"))
    transport = with_faults(plain.modules, load_plan(faults), clock)
    target = plain.modules[0].address if address is None else address
    module = next((vm for vm in plain.modules if vm.accepts_address(target)), plain.modules[0])
    return Module(Client(transport, address=target, timeout=timeout), target, module.profile)

