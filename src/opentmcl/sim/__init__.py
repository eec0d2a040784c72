"""``sim://``: virtual modules in this process behind the host library (docs/architecture.md "Layers").

This package sits above both the host library and the firmware: it builds `VirtualModule` objects
from a ``sim://`` URL and puts them behind the host's `InProcessTransport`, so the host itself
never imports the firmware. The root package registers ``sim`` as the lazy reference
``opentmcl.sim:open_sim``; importing this package registers the function itself.

    sim://NAME[@ADDR][,NAME@ADDR...][?address=N&clock=virtual|real|none&step=S]
"""
from __future__ import annotations

import urllib.parse

from ..firmware.vm import VirtualModule
from ..host.connect import register_transport
from ..host.errors import TmclUrlError
from ..host.transport import url_query
from ..host.transports.inprocess import Clock, InProcessTransport, VirtualClock, make_clock, parse_modules

__all__ = ["open_sim"]


def open_sim(url: urllib.parse.SplitResult) -> InProcessTransport:
    """Factory for ``sim://NAME[@ADDR][,NAME@ADDR...][?address=N&clock=virtual|real|none&step=S]``."""
    query = url_query(url, ("address", "clock", "step"))
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
    return InProcessTransport(modules, clock=_clock(query))


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
