"""OpenTMCL: an open implementation of the Trinamic TMCL motion-control system (docs/host.md).

    import opentmcl
    m = opentmcl.connect("sim://TMCM-6212")     # or tcp://, serial://, can://
    m.axes[0].move_to(51200, wait=True)

The host library (`connect`, `Module`, `Axis`, the error types) is imported with the package; the
virtual module (`VirtualModule`) and `replay` are imported on first use, so that ``import opentmcl``
(and the pytest plugin, which imports it) stays cheap and loads no firmware. Type checkers and IDEs
see every name of ``__all__`` through the imports below.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from . import registry as _registry
from .host import (
    Axis,
    Module,
    TmclConnectionError,
    TmclError,
    TmclStatusError,
    TmclTimeout,
    UnknownParameterError,
    connect,
)

if TYPE_CHECKING:
    from .capture.replay import replay  # the function (the package also has a submodule of that name)
    from .firmware.vm import VirtualModule

__version__: str
"""The installed distribution's version (importlib.metadata; pyproject.toml is its one source)."""

__all__ = ["Axis", "Module", "TmclConnectionError", "TmclError", "TmclStatusError", "TmclTimeout",
           "UnknownParameterError", "VirtualModule", "__version__", "connect", "replay"]

# The top of the tree names what the layers above the host library own, lazily
# (docs/architecture.md "Extension points"): sim:// is the in-process virtual module,
# opentmcl:// the pyserial URL handler. Nothing is imported until a URL uses them.
_registry.of(_registry.TRANSPORTS).register("sim", "opentmcl.sim:open_sim")
_registry.of(_registry.SERIAL_URL_HANDLERS).register("opentmcl", "opentmcl.urlhandler:register")
# The ramp engines of motion/, named by the profiles' `[module] engine` (modules/ cannot import motion/).
for _name, _target in (("sixpoint", "opentmcl.motion.sixpoint:SixPointRampEngine"),
                       ("linear", "opentmcl.motion.linear:LinearRampEngine"),
                       ("tmc429", "opentmcl.motion.tmc429_engine:Tmc429Engine")):
    _registry.of(_registry.ENGINES).register(_name, _target)


def _version() -> str:
    from importlib import metadata

    try:
        return metadata.version(__name__)
    except metadata.PackageNotFoundError:  # sources on sys.path without an installed distribution
        return "0+unknown"


def __getattr__(name: str) -> object:
    if name == "VirtualModule":
        from .firmware.vm import VirtualModule
        return VirtualModule
    if name == "replay":
        from .capture import replay
        return replay
    if name == "__version__":
        globals()["__version__"] = version = _version()
        return version
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
