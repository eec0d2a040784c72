"""Map CAN payloads to and from 9-byte serial frames (TMCM-6212 manual 3.1, 3.2).

"When using the CAN interface, leave out the address byte and the checksum
byte" (manual 3.1); for replies "the first byte (reply address) and the last
byte (checksum) are left out" (PD86-1180 manual 4.2). A request may also carry
an eighth byte (a checksum public clients send and modules ignore). Command
136 type 0 answers with a special reply of host address and eight characters
without checksum; sent "in an eight byte frame instead of a seven byte frame.
Then, eight bytes will be sent back" (PD86-1180 manual 4.2, command 136).

The payload layouts themselves are the protocol layer's (`protocol.can`); this
module only moves between them and the modules' serial frames.
"""
from __future__ import annotations

from ..protocol import can as codec
from ..protocol import replies
from ..protocol.frame import FRAME_LEN, Reply, Request


def is_version_request(data: bytes) -> bool:
    """A CAN request for command 136 type 0 (string version): its reply has the special format."""
    return len(data) >= 2 and replies.is_version_request(data[0], data[1])


def request_to_frame(data: bytes, address: int) -> bytes:
    """A 7- or 8-byte CAN request as a 9-byte serial frame to `address`."""
    req = codec.decode_request(data)  # CanFrameError (a ValueError) for other lengths
    return Request(address, req.command, req.type, req.motor, req.value).encode()


def reply_to_payload(reply: bytes, request: bytes = b"") -> bytes:
    """A module's 9-byte reply as CAN payload for `request` (the CAN request data).

    Normal replies: module address, status, command, value (7 bytes). The string
    reply of command 136 type 0: its eight characters when the request had 8
    bytes, else the first seven.
    """
    if len(reply) != FRAME_LEN:
        raise ValueError(f"reply must be {FRAME_LEN} bytes, got {len(reply)}")
    if is_version_request(request):
        text = bytes(reply[1:9])
        return text if len(request) == codec.LONG_REQUEST_LEN else text[:codec.REQUEST_LEN]
    r = Reply.decode(reply, verify=False)
    return codec.encode_reply(r.module_address, r.status, r.command, r.value)
