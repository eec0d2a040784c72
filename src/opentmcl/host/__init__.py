"""Client library: talk to TMCL modules, real or virtual, through byte transports
(docs/architecture.md "Layers", "Request path").

    import opentmcl
    m = opentmcl.connect("sim://TMCM-6212")
    m.axes[0].move_to(51200, wait=True)
    print(m.axes[0].get("actual_position"))

This layer never imports the firmware, the servers, the web dashboard or the CLI. Transports are
found by URL scheme in a registry (`register_transport`); ``sim://`` is registered by
`opentmcl.sim`, the package above both host and firmware.
"""
from __future__ import annotations

from .client import Client, VersionReply
from .connect import SCHEMES, connect, open_bus, open_transport, register_transport, transport_schemes
from .errors import (
    AxisNumberError,
    TmclAddressError,
    TmclArgumentError,
    TmclBatchError,
    TmclChecksumError,
    TmclConnectionError,
    TmclError,
    TmclProtocolError,
    TmclStatusError,
    TmclTimeout,
    TmclTypeError,
    TmclValueError,
    UnknownAttributeError,
    UnknownParameterError,
)
from .module import Axis, Module, profile_for_version
from .transport import Transport

__all__ = [
    "SCHEMES", "Axis", "AxisNumberError", "Client", "Module", "TmclArgumentError", "TmclBatchError",
    "TmclChecksumError", "TmclConnectionError",
    "TmclError", "TmclAddressError", "TmclProtocolError", "TmclStatusError", "TmclTimeout", "TmclTypeError",
    "TmclValueError", "Transport", "UnknownAttributeError", "UnknownParameterError", "VersionReply", "connect",
    "open_bus", "open_transport", "profile_for_version", "register_transport", "transport_schemes",
]
