"""Edges of the compiled request path, each against the pure-Python reference.

The reply (TMCM-6212 manual 3.2 "reply format": reply address, module address, status, command,
the value as a signed 32-bit number MSB first, the checksum: the sum of the eight bytes) of a
pre-bound GAP (3.6.6 "get axis parameter"), GGP or GIO: the value wrapped to 32 bits at 0x7FFFFFFF
and beyond, values that are big Python ints or no ints; frames that are no `bytes`, have a wrong
checksum, length or address (3.2.1 status 1; no reply for another address); the interface
keyword; a subclass that overrides `handle`; the signature check of server/bus.py.
"""
from __future__ import annotations

import functools
import gc
import inspect
import weakref
from fractions import Fraction

import pytest

from opentmcl import VirtualModule, accel
from opentmcl.firmware import dispatch
from opentmcl.firmware import vm as vm_module
from opentmcl.motion import segments
from opentmcl.motion.segments import PSCALE, Segment, SegmentQueue
from opentmcl.motion.sixpoint import SixPointRampEngine
from opentmcl.protocol.frame import Request
from opentmcl.server import bus

from .conftest import answer, needs_compiled, pair

pytestmark = needs_compiled

HEAD = bytes((2, 1, 100, 6))


def both(value):
    """(pure reply, compiled reply) of a pre-bound read answering `value`, or the exception types."""
    out = []
    for make in (dispatch._packed, dispatch._compiled_packed):
        try:
            out.append(make(HEAD, lambda: value)())
        except Exception as exc:  # noqa: BLE001 - compared
            out.append(type(exc))
    return out


class Int(int):
    pass


@pytest.mark.parametrize("value", [0, 1, -1, 255, 256, -256, 0x7FFF_FFFF, 0x8000_0000, -0x8000_0000,
                                   -0x8000_0001, 0xFFFF_FFFF, 0x1_0000_0000, 2**63 - 1, 2**63, -(2**63),
                                   -(2**63) - 1, 2**64 + 3, 2**100 + 0x1234_5678, -(2**100) - 7,
                                   True, False, Int(-5), Int(2**40 + 9)])
def test_the_reply_value_wraps_to_32_bits_as_the_python_reply(value):
    """Manual 3.2: the value is a signed 32-bit number. 0x7FFFFFFF is the last value sent as it
    is, 0x80000000 the first that wraps (to -2^31); a big Python int keeps its low 32 bits."""
    pure, fast = both(value)
    assert fast == pure
    assert len(fast) == 9 and fast[:4] == HEAD and fast[8] == sum(fast[:8]) & 0xFF


def test_the_last_valid_value_and_the_first_beyond():
    assert both(0x7FFF_FFFF)[1] == HEAD + bytes.fromhex("7fffffff") + bytes([(sum(HEAD) + 0x7F + 3 * 0xFF) & 0xFF])
    assert both(0x8000_0000)[1] == both(-0x8000_0000)[1]
    assert both(0x8000_0000)[1][4:8] == bytes.fromhex("80000000")


@pytest.mark.parametrize("value", [Fraction(1, 2), Fraction(10**12, 3), 1.5, 1e12, None, "7"])
def test_a_value_that_is_no_int_behaves_as_in_python(value):
    """Not a value a read answers; the compiled reply hands it to the Python code, which raises
    (or answers) as `dispatch._packed` does."""
    pure, fast = both(value)
    assert fast == pure


def test_a_read_that_raises_raises_through_the_compiled_reply():
    def read():
        raise ZeroDivisionError("x")
    with pytest.raises(ZeroDivisionError):
        dispatch._compiled_packed(HEAD, read)()


def test_the_tables_are_those_of_the_python_code():
    compiled = accel.compiled
    assert compiled is not None
    assert compiled.HEARTBEAT_OF == vm_module._HEARTBEAT_OF
    if compiled.HAVE_INT128:
        assert compiled.PSCALE == segments.PSCALE


# --- frames and the interface keyword ---------------------------------------------------------
def frames():
    gap = Request(1, 6, 1, 0, 0).encode()
    return [gap, bytearray(gap), memoryview(gap), memoryview(bytearray(gap)), gap[:8], gap + b"\0",
            gap[:8] + bytes([(gap[8] + 1) & 0xFF]), Request(2, 6, 1, 0, 0).encode(),
            Request(1, 6, 1, 9, 0).encode(), Request(1, 6, 250, 0, 0).encode(), b"", "abcdefghi"]


@pytest.mark.parametrize("interface", ["serial", "rs485", "rs232", "usb", "can", "spi", "Serial", None])
def test_frames_of_every_shape_are_answered_as_by_the_python_method(interface):
    """bytes, bytearray and memoryview frames (a mutable buffer takes the general path; a
    read-only memoryview hashes as its bytes), a wrong checksum (status 1), a short or long
    frame or another address (no reply), a motor or type the module lacks (status 4, 3); each
    twice, once bound; every link name, an unknown one too."""
    ref, fast = pair("TMCM-6212", address=1)
    for _ in range(3):
        ref.advance(0.01)
        fast.advance(0.01)
        for f in frames():
            kwargs = {} if interface is None else {"interface": interface}
            assert answer(fast, f, **kwargs) == answer(ref, f, **kwargs), (f, interface)
        assert fast._last_command == ref._last_command


def test_an_unhashable_interface_raises_as_in_python():
    ref, fast = pair("TMCM-6212", address=1)
    f = Request(1, 6, 1, 0, 0).encode()
    ref.handle(f)
    fast.handle(f)
    assert answer(fast, f, interface=[]) == answer(ref, f, interface=[])
    assert answer(fast, f, interface=[])[0] is TypeError


@pytest.mark.parametrize("call", [lambda h: h(), lambda h: h(b"x", "serial"), lambda h: h(b"x", link="can"),
                                  lambda h: h(b"x", interface="can", link="can"), lambda h: h(b"x", frame=b"x"),
                                  lambda h: h(interface="can")])
def test_wrong_arguments_raise_type_error(call):
    ref, fast = pair("TMCM-6212", address=1)
    for h in (ref.handle, fast.handle):
        with pytest.raises(TypeError):
            call(h)


def test_the_frame_may_be_passed_by_keyword():
    ref, fast = pair("TMCM-6212", address=1)
    f = Request(1, 6, 1, 0, 0).encode()
    for _ in range(2):
        assert fast.handle(frame=f, interface="usb") == ref.handle(frame=f, interface="usb")
        assert fast.handle(frame=f) == ref.handle(frame=f)


def test_the_fast_path_restarts_the_heartbeat_of_its_link_and_syncs_the_engines():
    ref, fast = pair("TMCM-6212", address=1)
    f = Request(1, 6, 1, 0, 0).encode()
    for vm in (ref, fast):
        vm.request(4, 0, 0, 100_000)
        vm.handle(f, interface="can")  # binds
        vm.advance(0.2)
        vm._heartbeat_fired = True
        vm.handle(f, interface="can")
    assert fast._last_command == ref._last_command == {"serial": 0, "can": fast.now}
    assert fast._heartbeat_fired is ref._heartbeat_fired is False
    assert fast._synced_at == fast.now and fast.axes[0].engine.now == fast.now


# --- installing --------------------------------------------------------------------------------
class Logged(VirtualModule):
    def __init__(self, *args, **kwargs):
        self.seen: list[bytes] = []
        super().__init__(*args, **kwargs)

    def handle(self, frame, *, interface="serial"):
        self.seen.append(bytes(frame))
        return super().handle(frame, interface=interface)


class Plain(VirtualModule):
    pass


def test_a_subclass_that_overrides_handle_keeps_its_override():
    vm = Logged("TMCM-6212")
    assert "handle" not in vm.__dict__
    f = Request(1, 6, 1, 0, 0).encode()
    assert vm.handle(f) == vm.handle(f) and vm.seen == [f, f]
    assert accel.enabled(vm)  # its pre-bound reads are still the compiled ones
    assert type(vm._requests[f]) is accel.compiled.Packed  # type: ignore[union-attr]


def test_a_subclass_that_keeps_handle_gets_the_compiled_one():
    assert type(Plain("TMCM-6212").handle) is accel.compiled.Handle  # type: ignore[union-attr]


def test_a_wrapper_patched_onto_the_class_is_not_bypassed(monkeypatch):
    """A test that wraps `VirtualModule.handle` on the class sees every request of modules built
    afterwards: they keep the Python attribute look-up."""
    seen = []
    original = VirtualModule.handle

    @functools.wraps(original)
    def wrapper(self, frame, *, interface="serial"):
        seen.append(frame)
        return original(self, frame, interface=interface)

    monkeypatch.setattr(VirtualModule, "handle", wrapper)
    vm = VirtualModule("TMCM-6212")
    assert "handle" not in vm.__dict__
    vm.handle(Request(1, 6, 1, 0, 0).encode())
    assert len(seen) == 1


def test_pure_builds_python_modules_that_stay_python():
    with accel.pure():
        assert not accel.active()
        vm = VirtualModule("TMCM-6212")
    assert accel.active()
    f = Request(1, 6, 1, 0, 0).encode()
    vm.handle(f)
    assert inspect.ismethod(vm.handle) and not accel.enabled(vm)
    assert vm._requests[f].__module__ == dispatch.__name__  # dispatch._packed's closure


def test_the_signature_is_that_of_the_python_method():
    """server/bus.py asks `inspect.signature(vm.handle)` whether it takes `interface` and what
    its default is: the compiled handle answers through `__wrapped__`."""
    vm = VirtualModule("TMCM-6212")
    assert type(vm.handle) is accel.compiled.Handle  # type: ignore[union-attr]
    assert inspect.signature(vm.handle) == inspect.signature(VirtualModule.handle.__get__(vm))
    assert vm.handle.__wrapped__ == VirtualModule.handle.__get__(vm)
    assert vm.handle.__self__ is vm
    assert bus._takes_interface(vm)
    assert bus._bound_handle(vm, True, "serial") is vm.handle
    can = bus._bound_handle(vm, True, "can")
    assert isinstance(can, functools.partial) and can.keywords == {"interface": "can"}
    f = Request(1, 6, 1, 0, 0).encode()
    assert can(f) == can(f) == vm.handle(f)


def test_a_module_with_the_compiled_handle_is_collected():
    vm = VirtualModule("TMCM-6212")
    vm.handle(Request(1, 6, 1, 0, 0).encode())
    vm.handle(Request(1, 6, 1, 0, 0).encode())
    ref = weakref.ref(vm)
    del vm
    gc.collect()
    assert ref() is None


# --- the six-point reads ------------------------------------------------------------------------
class Counting:
    def __init__(self, engine, attribute):
        self.engine, self.attribute, self.calls = engine, attribute, 0

    def __call__(self):
        self.calls += 1
        return getattr(self.engine, self.attribute)


def reads(engine):
    out = {}
    for attribute in ("position", "position_reached"):
        fallback = Counting(engine, attribute)
        out[attribute] = (accel.sixpoint_read(engine, attribute, fallback), fallback)
    return out


def check(engine, r, expect_fallback=()):
    """The C reads before the property has cached the tick, then after it; `expect_fallback`
    names the reads that must go to the property."""
    for attribute, (read, fallback) in r.items():
        before = fallback.calls
        first = read()
        truth = getattr(engine, attribute)
        again = read()
        assert first == truth == again and type(first) is type(truth), (attribute, engine.now)
        assert (fallback.calls > before) is (attribute in expect_fallback), attribute


def test_the_c_reads_follow_moves_both_ways_and_the_32_bit_wrap():
    """AP1 (actual position, wrapped to 32 bits) and AP8 (position reached) at many ticks of
    moves forwards, backwards, on both sides of 0 and through the wrap at 2^31 - 1."""
    if not accel.compiled.HAVE_INT128:  # type: ignore[union-attr]
        pytest.skip("no 128-bit integers: the reads are the properties")
    e = SixPointRampEngine(max_positioning_speed=400_000, max_acceleration=300_000, velocity_v1=20_000,
                           acceleration_a1=90_000, deceleration_d1=70_000, velocity_vstop=5)
    r = reads(e)
    plan = [(None, 40_000), (0x7FFF_FF00, 0x7FFF_FF00 + 9000), (None, -0x7FFF_FF00), (3000, -2500),
            (-100, 100), (None, -100)]
    for position, target in plan:
        if position is not None:
            e.set_position(position)
        e.move_to(target)
        for _ in range(0, 16_000_000 * 3, 49_999):
            e.advance(e.now + 49_999)
            check(e, r)
    e.rotate(-30_000)
    for _ in range(30):
        e.advance(e.now + 123_457)
        check(e, r)
    e.hard_stop()
    e.advance(e.now + 10)
    check(e, r)


def test_states_beyond_the_c_case_are_answered_by_the_property():
    """An operand beyond 128 bits, a product that overflows, a piece that ended before now."""
    e = SixPointRampEngine()
    r = reads(e)
    e._queue = SegmentQueue([Segment(0, None, (2**130 + 7) * PSCALE + 12345, 0, 0, None)])
    e._target_abs = 2**130 + 7
    e._target = 7
    check(e, r, expect_fallback={"position", "position_reached"})
    e._queue = SegmentQueue([Segment(0, None, 5 * PSCALE, 2**110, 0, None)])
    e.advance(16_000_000 * 60)
    check(e, r, expect_fallback={"position"})  # AP8: a moving piece answers from its velocity
    e = SixPointRampEngine()
    r = reads(e)
    e.move_to(10_000)
    first = e._queue.pieces[0]
    e.now = first.k1 + 3  # as if time moved without `advance` dropping the piece
    check(e, r, expect_fallback={"position", "position_reached"})


def test_a_standing_motor_reached_through_the_wrap():
    """AP8 of a standing motor: the unwrapped target, or the wrapped counter equal to AP0."""
    e = SixPointRampEngine()
    r = reads(e)
    e.set_position(0x7FFF_FFF0)
    e.move_to(-0x7FFF_FFF0)  # the shorter way: 32 steps forwards through the wrap
    e.advance(16_000_000 * 5)
    check(e, r)
    assert e.position == -0x7FFF_FFF0 and e.position_reached
    e._target_abs += 2**32  # the same wrapped target one turn of the counter further
    check(e, r)
