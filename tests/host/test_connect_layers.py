"""docs/architecture.md "Layers": the host library talks bytes and never imports the firmware; the
virtual module reaches it only through the sim:// transport that `opentmcl.sim` registers."""
from __future__ import annotations

import subprocess
import sys


def _child(code: str) -> list[str]:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          timeout=60).stdout.split()


def test_importing_the_host_library_does_not_import_the_firmware():
    out = _child("import sys, opentmcl.host, opentmcl.host.transports.inprocess, opentmcl.cli.send; "
                 "print(sorted(m for m in sys.modules if m.startswith('opentmcl.firmware')))")
    assert out == ["[]"]


def test_a_tcp_connection_loads_neither_firmware_nor_server(tcp_url):
    """A program that only uses connect("tcp://...") against a served module (TMCM-6212 manual
    3.6.8: GGP 66 answers the module address) never loads the firmware, the server, opentmcl.sim
    or the pyserial URL handler: the process running the host library holds no virtual module."""
    code = ("import sys, opentmcl.host\n"
            f"m = opentmcl.host.connect({tcp_url!r})\n"
            "print(m.get_global(66)); m.close()\n"
            "print(sorted(n for n in sys.modules if n.split('.')[:2] in (['opentmcl', 'firmware'], "
            "['opentmcl', 'server'], ['opentmcl', 'sim'], ['opentmcl', 'urlhandler'])))\n")
    assert _child(code) == ["1", "[]"]


def test_importing_opentmcl_registers_sim_without_importing_it():
    """The root package names sim:// and opentmcl:// as lazy references: importing it loads the host
    library (`opentmcl.connect` is a real import, issue 15 item 8) but neither the virtual module
    nor the endpoints (docs/architecture.md "Extension points")."""
    code = ("import sys, opentmcl\n"
            "from opentmcl import registry\n"
            "print(dict(registry.of(registry.TRANSPORTS).targets())['sim'])\n"
            "print(dict(registry.of(registry.SERIAL_URL_HANDLERS).targets())['opentmcl'])\n"
            "print(opentmcl.connect is opentmcl.host.connect)\n"
            "print(sorted({n.split('.')[1] for n in sys.modules if n.startswith('opentmcl.')}))\n")
    assert _child(code) == ["opentmcl.sim:open_sim", "opentmcl.urlhandler:register", "True",
                            "['host',", "'limits',", "'modules',", "'motion',", "'protocol',", "'registry']"]
