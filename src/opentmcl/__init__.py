"""OpenTMCL: an open implementation of the Trinamic TMCL motion-control system."""
from __future__ import annotations

from . import registry as _registry

__version__ = "0.1.0"

__all__ = ["VirtualModule", "__version__", "replay"]

# The top of the tree names what the layers above the host library own, lazily
# (docs/architecture.md "Extension points"): sim:// is the in-process virtual module,
# opentmcl:// the pyserial URL handler. Nothing is imported until a URL uses them.
_registry.of(_registry.TRANSPORTS).register("sim", "opentmcl.sim:open_sim")
_registry.of(_registry.SERIAL_URL_HANDLERS).register("opentmcl", "opentmcl.urlhandler:register")


def __getattr__(name: str) -> object:
    if name == "VirtualModule":
        from .firmware.vm import VirtualModule
        return VirtualModule
    if name == "connect":
        from .host import connect
        return connect
    if name == "replay":
        from .capture import replay
        return replay
    raise AttributeError(name)
