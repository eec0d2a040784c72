"""Open a module by URL, the way pyserial's `serial_for_url` and python-can's `Bus(interface=...)` do.

    connect("sim://TMCM-6212")                 # a virtual module in this process
    connect("tcp://127.0.0.1:2323")            # a module (or server) behind a TCP socket
    connect("serial:///dev/ttyUSB0?baud=9600") # RS-232 / RS-485 / USB
    connect("can://socketcan/can0?id=1")       # CAN (python-can interface and channel)

All return the same `Module` API. Several modules on one bus share one `Client`:
``bus = open_bus(url); m1, m2 = bus.module(1), bus.module(2)``.

The transport of a URL is found by its scheme in a registry (docs/architecture.md "Extension
points"): this module registers the host's own tcp/serial/can, the root package registers
``sim`` for `opentmcl.sim`, `register_transport` adds more, and the entry-point group
``opentmcl.transports`` is asked for a scheme nobody registered.
"""
from __future__ import annotations

import urllib.parse
from collections.abc import Callable, Mapping

from .. import registry
from ..modules.profile import ModuleProfile
from .client import Client, check_address
from .errors import TmclConnectionError, TmclError, TmclUrlError, check_timeout
from .module import Module
from .transport import Transport, register_checked

TransportFactory = Callable[[urllib.parse.SplitResult], Transport]
"""What a URL scheme stands for: the split URL (scheme in lower case) -> an open `Transport`."""

ENTRY_POINT_GROUP = registry.TRANSPORTS
"""Installed distributions add schemes here: ``[project.entry-points."opentmcl.transports"]``."""

_TRANSPORTS = registry.of(ENTRY_POINT_GROUP)


def register_transport(scheme: str, factory: TransportFactory | str) -> None:
    """Make `connect` open ``scheme://`` URLs with `factory`, or with the object a lazy
    ``"package.module:attribute"`` reference names (imported on first use). A later registration
    of the same scheme replaces the earlier one (docs/architecture.md "Extension points")."""
    register_checked(_TRANSPORTS, scheme, factory, "transport factory")


def transport_schemes() -> list[str]:
    """The schemes `connect` knows: registered ones, then those of installed entry points."""
    return _TRANSPORTS.available()


# The host library's own links; sim:// is registered by the package that owns the virtual module.
register_transport("tcp", "opentmcl.host.transports.tcp:open_tcp")
register_transport("serial", "opentmcl.host.transports.serial:open_serial")
register_transport("can", "opentmcl.host.transports.can:open_can")

SCHEMES: Mapping[str, object] = _TRANSPORTS.targets()
"""Read-only view: registered scheme -> factory (or its lazy reference until first use)."""


def split_url(url: str, address: int | None = None) -> urllib.parse.SplitResult:
    """`url` split as `open_transport` reads it: the scheme in lower case and, for a sim:// URL of
    one module that sets no address, `address` added as ``?address=N``. TmclUrlError if `url` is
    no module URL."""
    if not isinstance(url, str) or "://" not in url:
        raise TmclUrlError(f"not a module URL: {url!r} (expected e.g. sim://TMCM-6212, "
                                  f"tcp://HOST:PORT, serial:///dev/ttyUSB0, can://socketcan/can0?id=1)")
    try:
        parts = urllib.parse.urlsplit(url.strip())
    except ValueError as exc:  # e.g. an unclosed [IPv6 bracket
        raise TmclUrlError(f"bad module URL {url!r}: {exc}") from None
    scheme = parts.scheme.lower()
    parts = parts._replace(scheme=scheme)
    if scheme == "sim" and address is not None:
        # A single virtual module takes the address the caller will talk to,
        # unless the URL sets one ("?address=N" or "NAME@N").
        query = dict(urllib.parse.parse_qsl(parts.query, keep_blank_values=True))  # a blank value is refused later
        if "address" not in query and "@" not in parts.netloc and "," not in parts.netloc:
            query["address"] = str(address)
            parts = parts._replace(query=urllib.parse.urlencode(query))
    return parts


def open_transport(url: str, *, address: int | None = None) -> Transport:
    """The transport for `url` (see `register_transport`); `TmclConnectionError` if it cannot be opened."""
    parts = split_url(url, address)
    factory = _factory(parts.scheme, url)
    try:
        transport = factory(parts)
    except TmclError:
        raise
    except (OSError, ValueError, KeyError) as exc:
        raise TmclConnectionError(f"cannot open {url}: {exc}") from exc
    if not isinstance(transport, Transport):
        raise TmclConnectionError(f"{parts.scheme}:// factory returned {type(transport).__name__}, not a Transport")
    return transport


def _factory(scheme: str, url: str) -> Callable[[urllib.parse.SplitResult], object]:
    """The registered factory of `scheme` (an entry point only if nobody registered it)."""
    try:
        factory = _TRANSPORTS.find(scheme) if registry.NAME.fullmatch(scheme) else None
    except (ImportError, AttributeError) as exc:
        raise TmclConnectionError(f"{scheme}:// transport is not available: {exc}") from None
    if factory is None:
        raise TmclUrlError(f"unknown URL scheme {scheme!r} in {url!r}; "
                                  f"use one of {', '.join(s + '://' for s in transport_schemes())}")
    if not callable(factory):
        raise TmclConnectionError(f"{scheme}:// transport is not callable: {factory!r}")
    return factory


def _default_address(url: str) -> int:
    """1, or the address a sim:// URL gives its first module (``?address=N`` or ``NAME@N``)."""
    try:
        parts = urllib.parse.urlsplit(url.strip()) if isinstance(url, str) else None
    except ValueError:
        return 1  # open_transport reports the bad URL
    if parts is None or parts.scheme.lower() != "sim":
        return 1
    first = parts.netloc.split(",")[0]
    text = first.partition("@")[2] or dict(urllib.parse.parse_qsl(parts.query)).get("address", "1")
    try:
        return int(text, 0)
    except ValueError:
        return 1  # open_sim reports the bad address


def open_bus(url: str, *, address: int | None = None, timeout: float = 5.0, host_address: int = 2) -> Client:
    """A `Client` on the bus at `url`; `address` is its default module address (default 1, or the
    address a sim:// URL sets)."""
    check_timeout(timeout)
    if address is None:
        address = _default_address(url)
    else:
        check_address(address)
    return Client(open_transport(url, address=address), address=address, timeout=timeout,
                  host_address=host_address)


def connect(url: str, *, address: int | None = None, timeout: float = 5.0, host_address: int = 2,
            profile: ModuleProfile | str | None = None) -> Module:
    """The module at `address` (default 1, or the address a sim:// URL sets) behind `url`. Its
    profile is read from the firmware version string (command 136) on first use unless `profile`
    is given."""
    client = open_bus(url, address=address, timeout=timeout, host_address=host_address)
    try:
        return Module(client, client.address, profile)
    except BaseException:
        client.close()
        raise
