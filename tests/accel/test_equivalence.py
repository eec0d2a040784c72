"""The compiled request path answers every request byte for byte as the pure-Python one.

Two modules of the same profile, one built inside `accel.pure()` (the reference: `VirtualModule.handle`,
`dispatch._packed`, the engines' properties) and one on the compiled path (`_accel.Handle`,
`_accel.packed`, the C six-point reads), get the same hypothesis-drawn sequence of requests and
time advances; every reply must be the same bytes (TMCM-6212 manual 3.2 reply format: reply
address, module address, status, command, value MSB first, checksum), on the serial, USB and CAN
links. The reads are GAP (3.6.6), GGP (3.6.10) and GIO (3.6.13) of valid and invalid types,
motors and banks, read again and again so that the pre-bound handlers answer them; SAP, MVP,
ROR/ROL/MST move the axes (positions near the 32-bit wrap included), SGP 68 arms the serial
heartbeat. The PD86-1180 runs the TMC429 engine and the PD28-1021 the linear one: the C six-point
read must not apply there (their reads stay the engines' properties), which this pins as well.
"""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from opentmcl import accel
from opentmcl.protocol.frame import Request

from .conftest import answer, needs_compiled, pair

MODULES = ["TMCM-6212", "PD28-1021", "PD86-1180"]
INTERFACES = ["serial", "usb", "can"]
AXIS_TYPES = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 135, 138, 140, 193, 206, 207, 209, 254, 255]
GLOBAL_TYPES = [0, 1, 2, 3, 64, 65, 66, 68, 73, 75, 76, 77, 79, 80, 84, 128, 129, 130, 132, 255]
BIG = [0, 1, -1, 5000, -70_000, 2_000_000, 0x7FFF_FFF0, -0x7FFF_FFF0, 0x7FFF_FFFF, -0x8000_0000]

reads = st.one_of(
    st.tuples(st.just(6), st.sampled_from([1, 8]), st.integers(0, 6), st.just(0)),         # GAP 1, 8
    st.tuples(st.just(6), st.sampled_from(AXIS_TYPES), st.integers(0, 7), st.just(0)),   # GAP
    st.tuples(st.just(10), st.sampled_from(GLOBAL_TYPES), st.sampled_from([0, 1, 2, 3, 7]),
              st.just(0)),                                                                # GGP
    st.tuples(st.just(15), st.integers(0, 9), st.sampled_from([0, 1, 2, 3, 255]), st.just(0)),  # GIO
)
moves = st.one_of(
    st.tuples(st.just(5), st.sampled_from([4, 5, 17, 1, 0, 140]), st.integers(0, 6),
              st.one_of(st.integers(0, 400_000), st.sampled_from(BIG))),                  # SAP
    st.tuples(st.just(4), st.integers(0, 2), st.integers(0, 6), st.sampled_from(BIG)),    # MVP
    st.tuples(st.sampled_from([1, 2]), st.just(0), st.integers(0, 6), st.integers(0, 300_000)),  # ROR/ROL
    st.tuples(st.just(3), st.just(0), st.integers(0, 6), st.just(0)),                     # MST
    st.tuples(st.just(9), st.just(68), st.just(0), st.sampled_from([0, 0, 30, 500])),     # SGP 68
)
request = st.tuples(st.just("request"), st.one_of(reads, reads, moves), st.sampled_from(INTERFACES),
                    st.integers(1, 3))
# an advance of time, then a poll: GAP 8 and GAP 1 of every axis (the polling host of bench_polling.py)
advance = st.tuples(st.just("advance"), st.sampled_from([0.0, 0.000_01, 0.001, 0.01, 0.07, 0.5, 2.5]),
                    st.sampled_from(INTERFACES))
steps = st.lists(st.one_of(request, request, request, advance), min_size=1, max_size=40)
# first, every axis moves: from a position (SAP 1) at a speed (SAP 4) to a target (MVP ABS), near
# or far, either way, on either side of 0 (the step counter rounds towards where the motor comes from)
near = st.integers(-9000, 9000)
starts = st.lists(st.tuples(st.sampled_from(BIG) | near, st.integers(0, 250_000), st.sampled_from(BIG[:6]) | near),
                  min_size=6, max_size=6)


def started(start, sequence):
    head = []
    for a, (position, speed, target) in enumerate(start):
        head += [("request", (5, 1, a, position), "serial", 1), ("request", (5, 4, a, speed), "serial", 1),
                 ("request", (4, 0, a, target), "serial", 1)]
    return head + sequence


def run(name: str, sequence) -> None:
    ref, fast = pair(name, address=1)
    for i, step in enumerate(sequence):
        if step[0] == "advance":
            ref.advance(step[1])
            fast.advance(step[1])
            assert ref.drain_events() == fast.drain_events()
            for a in range(len(ref.axes)):
                for t in (8, 1):
                    raw = Request(1, 6, t, a, 0).encode()
                    want = answer(ref, raw, interface=step[2])
                    assert answer(fast, raw, interface=step[2]) == want, (i, step, a, t)
            continue
        _, (command, type_, motor, value), interface, times = step
        raw = Request(1, command, type_, motor, value).encode()
        for _ in range(times):  # again: a read that succeeded is answered by its pre-bound handler
            want = answer(ref, raw, interface=interface)
            got = answer(fast, raw, interface=interface)
            assert got == want, (i, step, want, got)
    assert ref.now == fast.now


@needs_compiled
@pytest.mark.parametrize("name", MODULES)
@settings(suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(start=starts, sequence=steps)
def test_the_compiled_path_answers_as_the_pure_one(name, start, sequence):
    run(name, started(start, sequence))


@needs_compiled
@pytest.mark.parametrize("name", MODULES)
def test_moving_axes_polled_over_many_instants(name):
    """The polling host of bench/bench_polling.py on both paths: GAP 8 and GAP 1 (manual 3.6.6)
    of every axis moving at another speed, every 10 ms, then reversals, a stop and a far move
    through the 32-bit wrap of the position counter (SAP 1 near 2^31 - 1)."""
    sequence = []
    ref, _ = pair(name, address=1)
    axes = len(ref.axes)
    for a in range(axes):
        sequence += [("request", (5, 4, a, 3000 + 1100 * a), "serial", 1),
                     ("request", (5, 1, a, 0x7FFF_FF00 - 5000 * a), "serial", 1),
                     ("request", (4, 0, a, -0x7FFF_FF00 + 90_000 * a), "serial", 1)]
    polls = [("request", (6, t, a, 0), iface, 1) for a in range(axes) for t in (8, 1, 3)
             for iface in ("serial", "can")]
    for k in range(120):
        sequence.append(("advance", 0.01, "serial"))
        sequence += polls
        if k == 40:
            sequence += [("request", (2, 0, a, 20_000), "usb", 1) for a in range(axes)]  # ROL
        if k == 80:
            sequence += [("request", (3, 0, a, 0), "serial", 1) for a in range(axes)]    # MST
    run(name, sequence)


@needs_compiled
def test_the_six_point_read_applies_to_the_six_point_engine_only():
    """The GAP 1 / GAP 8 handlers of the TMCM-6212 (TMC5130 six-point ramps) read through the C
    evaluation; those of the PD28-1021 (linear) and PD86-1180 (TMC429) through the properties."""
    compiled = accel.compiled
    assert compiled is not None
    for name, c_read in (("TMCM-6212", True), ("PD28-1021", False), ("PD86-1180", False)):
        _, fast = pair(name, address=1)
        for t in (1, 8):
            raw = Request(1, 6, t, 0, 0).encode()
            fast.handle(raw)
            handler = fast._requests[raw]
            assert type(handler) is compiled.Packed
            assert (type(handler.read) is compiled.SixPointRead) is c_read, (name, t)
