"""pyserial URL handler: ``serial.serial_for_url("opentmcl://TMCM-6212")``.

Importing this package registers it in pyserial's
``serial.protocol_handler_packages``; from then on any pyserial-based code
(PyTrinamic, python-tmcl, your own) that opens the URL gets an in-process
virtual module instead of a real port:

    import opentmcl.urlhandler  # registers the opentmcl:// scheme
    import serial
    port = serial.serial_for_url("opentmcl://TMCM-6212", timeout=1)

URL grammar (see protocol_opentmcl):
``opentmcl://NAME[@ADDR][,NAME@ADDR...][?eeprom=FILE[,FILE...]&gap=S&pace=1]``
"""
from __future__ import annotations

PACKAGE = __name__


def register() -> None:
    """Make pyserial look for ``protocol_<scheme>`` modules in this package (idempotent)."""
    import serial

    if PACKAGE not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append(PACKAGE)


register()
