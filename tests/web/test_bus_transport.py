"""The dashboard of `opentmcl serve --web` reaches the served modules through the bus (BusTransport)."""
from __future__ import annotations

from opentmcl import VirtualModule
from opentmcl.host import Client
from opentmcl.protocol.frame import Reply, Request
from opentmcl.server.bus import ModuleBus
from opentmcl.web.bus_transport import BusTransport


class FakeClock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


class Channel:
    interface = "serial"

    def __init__(self):
        self.events = []

    def deliver(self, vm, reply):
        self.events.append(reply)


def test_module_api_through_the_bus():
    """TMCM-6212 manual 3.6.36: command 136 type 0 answers "6212V105"."""
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)], clock=FakeClock())
    module = Client(BusTransport(bus), address=1).module(1)
    assert module.firmware_version() == "6212V105"
    module.axes[0].set(4, 1234)
    assert module.axes[0].get(4) == 1234


def test_dashboard_requests_do_not_steal_another_hosts_events():
    """Manual 3.6.35: the "target position reached" reply goes to the host that asked for it,
    even while the dashboard polls the same module."""
    clock = FakeClock()
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)], clock=clock)
    tcp = Channel()
    bus.request(Request(1, 138, 0, 0, 1).encode(), tcp)
    bus.request(Request(1, 4, 0, 0, 1000).encode(), tcp)   # MVP ABS, 0, 1000
    dashboard = Client(BusTransport(bus), address=1).module(1)
    dashboard.axes[0].get(1)
    clock.t = 5.0
    dashboard.axes[0].get(1)
    delivered = [(ch, reply) for ch, _vm, reply in bus.poll()]
    assert [ch for ch, _ in delivered] == [tcp]
    assert Reply.decode(delivered[0][1]).status == 128
