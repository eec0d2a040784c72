"""A long random stream of frames through the lean request path and through the general path alone.

Two modules get the same frames and the same time steps; one answers with its pre-bound handlers
(firmware/dispatch.py), the other forgets them before every frame, so the general path
(`commands.execute`) answers all of it. Every reply byte must agree (TMCM-6212 manual 3.2 reply
format, 3.2.1 status codes). The stream mixes the reads with what changes the tables: SAP 255
(4.1 unit mode), SGP 66/76/87/255 (5.1), command 132/133 download mode and 137 reset (3.6.36),
wrong checksums, other addresses and the USB, RS485 and CAN interfaces.
"""
from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from opentmcl import VirtualModule
from opentmcl.protocol.frame import Request

READ_TYPES = [0, 1, 2, 3, 4, 5, 8, 9, 135, 138, 140, 207, 209, 250, 255]
STEPS = st.one_of(
    st.tuples(st.just("read"), st.sampled_from([6, 10, 15]), st.sampled_from(READ_TYPES),
              st.integers(0, 7), st.sampled_from([0, 1, -1])),
    st.tuples(st.just("write"), st.sampled_from([(5, 4), (5, 255), (5, 1), (4, 0), (1, 0), (3, 0),
                                                 (9, 66), (9, 76), (9, 87), (9, 255), (9, 0), (14, 0)]),
              st.integers(0, 6), st.integers(-3, 60_000)),
    st.tuples(st.just("control"), st.sampled_from([132, 133, 137, 138])),
    st.tuples(st.just("advance"), st.integers(0, 40)),
)
FRAME_SHAPE = st.tuples(st.sampled_from([1, 1, 1, 2, 3, 7]), st.sampled_from(["serial", "serial", "usb", "can", "rs485"]),
                        st.booleans())


def _frame(step, address):
    kind = step[0]
    if kind == "read":
        _, command, type_, motor, value = step
        return Request(address, command, type_, motor, value).encode()
    if kind == "write":
        _, (command, type_), motor, value = step
        if command == 9:  # globals: bank 0 (motor field), small values for the addresses
            motor, value = (2 if type_ == 0 else 0), value % 8
        if command == 5 and type_ == 255:
            value %= 2
        return Request(address, command, type_, motor, value).encode()
    _, command = step
    return Request(address, command, 1 if command == 138 else 0, 0, 1234 if command == 137 else 1).encode()


@pytest.mark.parametrize("name", ["TMCM-6212", "PD86-1180"])
@settings(max_examples=40, deadline=None)
@given(stream=st.lists(st.tuples(STEPS, FRAME_SHAPE), min_size=20, max_size=120))
def test_every_reply_byte_agrees_with_the_general_path(name, stream):
    lean, reference = VirtualModule(name, address=1), VirtualModule(name, address=1)
    for i, (step, (address, interface, corrupt)) in enumerate(stream):
        if step[0] == "advance":
            for vm in (lean, reference):
                vm.advance(step[1] / 1000)
            continue
        raw = _frame(step, address)
        if corrupt and step[0] == "read":
            raw = raw[:8] + bytes(((raw[8] ^ 0x10),))
        for repeat in range(2 if step[0] == "read" else 1):  # a read twice: its second answer is pre-bound
            got = lean.handle(raw, interface=interface)
            reference.forget_requests()
            want = reference.handle(raw, interface=interface)
            assert got == want, (i, step, address, interface, repeat)
        assert lean.drain_events() == reference.drain_events()
