"""OpenTMCL: an open implementation of the Trinamic TMCL motion-control system."""
__version__ = "0.1.0"

__all__ = ["VirtualModule", "__version__", "replay"]


def __getattr__(name):
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
