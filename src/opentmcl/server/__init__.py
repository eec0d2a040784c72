"""Endpoints that host virtual modules in real time: pty, TCP, CAN (docs/endpoints.md).

    from opentmcl import VirtualModule
    from opentmcl.server import Server, TcpServer
    server = Server([VirtualModule("TMCM-6212", address=1)])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0))
    server.start(); print(tcp.url); ...; server.stop()
"""
from . import endpoints  # noqa: F401  (registers the built-in endpoints)
from .app import Server
from .bus import ModuleBus, RealTimeRunner
from .can import CanServer
from .framer import SerialFramer
from .pty import PtyServer
from .session import SerialSession
from .stream import SerialStream
from .tcp import TcpServer

__all__ = ["CanServer", "ModuleBus", "PtyServer", "RealTimeRunner", "SerialFramer", "SerialSession",
           "SerialStream", "Server", "TcpServer"]
