"""TMCL wire protocol: frames, checksums, status codes, opcodes, CAN and ASCII codecs."""
from .frame import FRAME_LEN, FrameError, Reply, Request, checksum, to_int32
from .opcodes import COMMANDS, Command, UnknownCommand, by_mnemonic, by_number
from .status import Status

__all__ = [
    "COMMANDS", "FRAME_LEN", "Command", "FrameError", "Reply", "Request", "Status", "UnknownCommand",
    "by_mnemonic", "by_number", "checksum", "to_int32",
]
