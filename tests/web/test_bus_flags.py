"""The program flags on the dashboard of `opentmcl serve --web`: no TMCL request reads them
(TMCM-6212 3.6.36 Table 13 / PD86-1180 4.6.39: command 135 has no type for them), so the dashboard,
which runs in the server's process, reads them from the served module itself."""
from opentmcl import VirtualModule
from opentmcl.host import Client
from opentmcl.host.debugger import describe_flags
from opentmcl.host.loader import Loader
from opentmcl.lang.assembler import assemble
from opentmcl.server.bus import ModuleBus
from opentmcl.web.bus_transport import BusTransport

PROGRAM = "CALC LOAD, 5\nCOMP 7\nSTOP\n"


def test_flags_of_the_addressed_module_on_a_served_bus():
    """PD86-1180 4.6.17 COMP: "The specified value is compared to the internal accumulator ... The
    internal arithmetic status flags are set according to the comparison result": 5 against
    7 sets LT on the module at address 2; the module at address 1, which ran nothing, has no flag."""
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1), VirtualModule("PD86-1180", address=2)])
    client = Client(BusTransport(bus), address=2, timeout=2.0)
    try:
        loader = Loader(client, address=2)
        loader.download(assemble(PROGRAM, module="PD86-1180"))
        loader.run(0)
        st = loader.wait_stopped(2.0)
        assert describe_flags(st.flags).split() == ["LT"]
        assert describe_flags(Loader(client, address=1).status().flags) == "-"
        assert Loader(client, address=9).flags() is None      # nobody answers address 9
    finally:
        client.close()
