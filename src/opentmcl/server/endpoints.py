"""Endpoints by name (docs/architecture.md "Extension points"; docs/endpoints.md).

`opentmcl serve` builds every endpoint through the endpoint registry (registry.ENDPOINTS): its
`--tcp`, `--pty` and `--can` options name the built-in ones below, and `--endpoint NAME[:SPEC]`
any other, such as one an installed distribution adds with an entry point in the group
"opentmcl.endpoints":

    [project.entry-points."opentmcl.endpoints"]
    myfieldbus = "myrig.endpoint:open_endpoint"

A factory is called as `factory(bus, spec, options)`: the `ModuleBus` to serve, the text after
`NAME:` (empty when none was given) and the serve command's link options (`EndpointOptions`); it
answers an object with `start()` and `stop()` (server/app.py `Server.add`), which may also be a
`bus.Channel` to carry unsolicited replies.
"""
from __future__ import annotations

from dataclasses import dataclass

from .. import registry
from .bus import ModuleBus

DEFAULT_GAP = 0.1


@dataclass(frozen=True)
class EndpointOptions:
    """The link options of `opentmcl serve` that endpoints may use."""

    gap: float = DEFAULT_GAP
    """Seconds of silence after which a partial serial frame is dropped."""
    pace_bytes: bool = False
    """Pace bytes at the RS485 baud rate (GP65)."""
    max_clients: int = 4
    idle_timeout: float = 300.0
    interface: str | None = None
    """The serial link a pty stands for (usb, rs485, rs232; None: its default)."""
    link: str | None = None
    """A symbolic link to create to the pty."""


def _split_hostport(spec: str) -> tuple[str, int]:
    host, sep, port = spec.rpartition(":")
    if not sep:
        host, port = "", spec
    return host.strip("[]") or "127.0.0.1", int(port)


def tcp(bus: ModuleBus, spec: str, options: EndpointOptions) -> object:
    """Raw 9-byte frames on TCP at HOST:PORT (server/tcp.py)."""
    from .tcp import TcpServer

    host, port = _split_hostport(spec)
    return TcpServer(bus, host, port, max_clients=options.max_clients, gap=options.gap,
                     pace_bytes=options.pace_bytes, idle_timeout=options.idle_timeout)


def pty(bus: ModuleBus, spec: str, options: EndpointOptions) -> object:
    """A pseudo-terminal (server/pty.py); `spec` or `options.link`: a symbolic link to it."""
    from .pty import PtyServer

    return PtyServer(bus, link=spec or options.link, gap=options.gap, pace_bytes=options.pace_bytes,
                     interface=options.interface)


def can(bus: ModuleBus, spec: str, options: EndpointOptions) -> object:
    """A python-can bus INTERFACE:CHANNEL (server/can.py)."""
    from .can import CanServer

    interface, sep, channel = spec.partition(":")
    if not sep or not interface or not channel:
        raise ValueError(f"a CAN endpoint needs INTERFACE:CHANNEL, e.g. virtual:opentmcl, got {spec!r}")
    return CanServer(bus, interface, channel)


ENDPOINTS = registry.of(registry.ENDPOINTS)
for _name, _factory in (("tcp", tcp), ("pty", pty), ("can", can)):
    ENDPOINTS.register(_name, _factory)


def make(name: str, bus: ModuleBus, spec: str = "", options: EndpointOptions | None = None) -> object:
    """The endpoint `name` builds; ValueError for a name no endpoint has (the message lists them)."""
    try:
        factory = ENDPOINTS.find(name)
    except ValueError:
        factory = None
    if factory is None or not callable(factory):
        raise ValueError(f"unknown endpoint {name!r}; known: {', '.join(ENDPOINTS.available())}")
    return factory(bus, spec, options or EndpointOptions())
