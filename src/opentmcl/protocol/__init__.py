"""TMCL wire protocol: frames, checksums, status codes, opcodes, CAN and ASCII codecs."""
from .frame import FRAME_LEN, FrameError, Reply, Request, checksum, to_int32
from .status import Status

__all__ = ["FRAME_LEN", "FrameError", "Reply", "Request", "Status", "checksum", "to_int32"]
