"""The lean request path (issue 16 item 2; docs/architecture.md "Request path").

GAP, GGP and GIO requests that succeed once are answered afterwards by a pre-bound handler keyed by
the whole frame (firmware/dispatch.py). These tests pin that every such answer is byte for byte the
answer of the general path (`commands.execute`) in the same state, that the manual's status codes
stay (TMCM-6212 manual 3.2.1: 1 wrong checksum, 3 wrong type, 4 invalid value, 101 loaded into
program memory) and that everything which changes a reply header or the module's state drops the
bound handlers: SGP 66/76/87, command 137, download mode (3.6.36), a reset.
"""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.firmware import requests as dispatch
from opentmcl.modules import load_profile
from opentmcl.protocol.frame import Reply, Request

from .conftest import Host

MODULES = ["TMCM-6212", "PD86-1180", "PD28-1021"]


def frame(command, type_=0, motor=0, value=0, address=1):
    return Request(address, command, type_, motor, value).encode()


_frame = frame  # the name the tests of `dispatch.handler` use


def general(vm, raw, interface="serial"):
    """The answer of the general path: nothing bound at the time of the request."""
    vm.forget_requests()
    return vm.handle(raw, interface=interface)


def twice(vm, raw, interface="serial"):
    """(general answer, answer after it) to the same frame at the same instant."""
    return general(vm, raw, interface), vm.handle(raw, interface=interface)


def busy(name):
    """A module whose axes move, with parameters away from their defaults."""
    vm = VirtualModule(name, address=1)
    n = len(vm.axes)
    for m in range(n):
        assert vm.request(5, 4, m, 1000 + 700 * m).status == 100    # AP4 maximum speed
        assert vm.request(5, 5, m, 2000 + 300 * m).status == 100    # AP5 maximum acceleration
        assert vm.request(4, 0, m, (-1) ** m * 90_000).status == 100  # MVP ABS
    vm.advance(0.37)
    return vm


# --- manual vectors ---------------------------------------------------------------
def test_manual_gap_1_0_frame_then_prebound():
    """TMCM-6212 3.6.6 example "GAP 1, 0" = 01 06 01 00 00 00 00 00 08; the reply (3.2: reply
    address 2, module address 1, status 100, command 6, value 0, checksum 6D) is the same when the
    pre-bound handler answers the second request."""
    vm = VirtualModule("TMCM-6212", address=1)
    raw = bytes.fromhex("010601000000000008")
    expected = bytes.fromhex("0201640600000000" "6D")
    assert vm.handle(raw) == expected
    assert vm.is_prebound(raw)
    assert vm.handle(raw) == expected


def test_manual_gio_0_1_reply_vector():
    """TMCM-6212 3.6.13 example: "GIO 0, 1" = 01 0F 00 01 00 00 00 00 11, reply for value 302:
    02 01 64 0F 00 00 01 2E A5 - from the general path and from the pre-bound handler; the handler
    reads the port live (a new level is answered at once)."""
    vm = VirtualModule("TMCM-6212", address=1)
    vm.io.drive_input(1, 0, 302)
    raw = bytes.fromhex("010F000100000000" "11")
    assert twice(vm, raw) == (bytes.fromhex("0201640F0000012EA5"),) * 2
    vm.io.drive_input(1, 0, 303)
    assert vm.is_prebound(raw) and vm.handle(raw) == bytes.fromhex("0201640F0000012FA6")


def test_manual_ggp_66_vector_and_sgp_66_rebinds():
    """TMCM-6212 3.6.8 "GGP 66, 0" = 01 0A 42 00 00 00 00 00 4D answers 02 01 64 0A 00 00 00 01 72;
    after the manual's "SGP 66, 0, 3" (3.6.7, 01 09 42 00 00 00 00 03 4F) the old frame is for another
    address (no reply), and GGP 66 at address 3 replies from module address 3."""
    vm = VirtualModule("TMCM-6212", address=1)
    raw = bytes.fromhex("010A420000000000" "4D")
    assert twice(vm, raw) == (bytes.fromhex("0201640A0000000172"),) * 2
    assert vm.handle(bytes.fromhex("01094200000000034F"))[2] == 100
    assert vm.handle(raw) == b""
    at3 = frame(10, 66, 0, address=3)
    assert twice(vm, at3) == (bytes.fromhex("0203640A0000000376"),) * 2


# --- every readable parameter: pre-bound == general ---------------------------------------
@pytest.mark.parametrize("name", MODULES)
def test_gap_of_every_readable_parameter_equals_the_general_path(name):
    """Manual 4 (TMCM-6212 4.1, PD86-1180 5): each readable axis parameter of each motor, read while
    the axes move; the world's readings stay on the general path (they follow the stage: no pure
    reads, firmware/table.py). AP207 is bound too: the bound read clears it as the general one."""
    vm = busy(name)
    vm.advance(0.01)
    bound = 0
    for m in range(len(vm.axes)):
        for n in sorted(vm.axes[m].readable):
            raw = frame(6, n, m)
            first, second = twice(vm, raw)
            assert first == second and Reply.decode(first).status == 100, (n, m)
            expect_bound = n not in vm.world.axis_numbers
            assert vm.is_prebound(raw) == expect_bound, (n, m)
            bound += expect_bound
    assert bound >= 40 * len(vm.axes)


@pytest.mark.parametrize("name", MODULES)
def test_ggp_of_every_readable_global_equals_the_general_path(name):
    """Manual 5 (PD86-1180 6): banks 0 and 3 and the user variables of bank 2, all bound; the values
    that are not RAM (73 lock, 128-130 status, download mode, PC, 132 tick) are read live by the
    bound read as by the general one. The random number GP133 is in test_random_numbers_..."""
    vm = busy(name)
    assert vm.request(9, 7, 2, -123456).status == 100  # a user variable
    keys = sorted(k for k, p in vm.profile.global_parameters.items() if p.readable)
    keys += [(2, 0), (2, 7), (2, len(vm.user_vars) - 1)]
    for bank, n in keys:
        raw = frame(10, n, bank)
        first, second = twice(vm, raw)
        assert vm.is_prebound(raw), (bank, n)
        if (bank, n) == (0, 133):  # the next random number each time
            continue
        assert first == second and Reply.decode(first).status == 100, (bank, n)
    assert Reply.decode(vm.handle(frame(10, 7, 2))).value == -123456


@pytest.mark.parametrize("name", MODULES)
def test_gio_of_every_port_equals_the_general_path(name):
    """TMCM-6212 3.6.13 / PD86-1180 4.6.15: every port of every bank, and GIO 255 (all ports)."""
    vm = VirtualModule(name, address=1)
    for i, (bank, port) in enumerate(sorted(vm.io.ports)):
        if bank != 2:
            vm.io.drive_input(bank, port, i % 2 if bank == 0 else 1000 + i)
        raw = frame(15, port, bank)
        first, second = twice(vm, raw)
        assert first == second and Reply.decode(first).status == 100 and vm.is_prebound(raw)
    raw = frame(15, 255, 0)
    first, second = twice(vm, raw)
    assert first == second and vm.is_prebound(raw)


@pytest.mark.parametrize("name", MODULES)
def test_random_numbers_are_the_same_sequence_bound_or_not(name):
    """GP133 "Random number" (TMCM-6212 5.1): each GGP 133 draws the next one; the bound read and the
    general path draw the same sequence from the same seed (SGP 133)."""
    bound, general = VirtualModule(name, address=1), VirtualModule(name, address=1)
    raw = frame(10, 133, 0)
    out = []
    for vm in (bound, general):
        assert vm.request(9, 133, 0, 4711).status == 100
        seq = []
        for _ in range(5):
            if vm is general:
                vm.forget_requests()
            seq.append(vm.handle(raw))
        out.append(seq)
    assert out[0] == out[1] and len(set(out[0])) == 5 and bound.is_prebound(raw)


# --- status codes at the edges ------------------------------------------------------------
@pytest.mark.parametrize("name", MODULES)
def test_last_valid_motor_is_bound_first_invalid_is_status_4(name):
    """TMCM-6212 3.6.6 "Motor/Bank 0...5" (PD86-1180 and PD28-1021: motor 0): the last valid motor
    answers 100 and is bound; the first invalid one answers status 4 "Invalid value" every time."""
    vm = VirtualModule(name, address=1)
    last = len(vm.axes) - 1
    assert Reply.decode(vm.handle(frame(6, 1, last))).status == 100 and vm.is_prebound(frame(6, 1, last))
    for _ in range(2):
        assert Reply.decode(vm.handle(frame(6, 1, last + 1))).status == 4
    assert not vm.is_prebound(frame(6, 1, last + 1))


def test_unknown_parameter_is_status_3_every_time():
    """Manual 3.2.1 status 3 "Wrong type": a number that is not an axis parameter (TMCM-6212 4.1
    lists none as 250), a global parameter bank 0 lacks (5.1: none as 250), the port after the last
    of bank 0 (3.6.13: IN0...IN3, so 4). The last user variable (bank 2: 0...255) answers 100."""
    vm = VirtualModule("TMCM-6212", address=1)
    cases = [(6, 250, 0), (10, 250, 0), (15, 4, 0)]
    assert vm.request(10, 255, 2).status == 100 and vm.request(15, 3, 0).status == 100
    for command, t, m in cases:
        for _ in range(2):
            assert Reply.decode(vm.handle(frame(command, t, m))).status == 3, (command, t, m)
        assert not vm.is_prebound(frame(command, t, m))


def test_bank_that_does_not_exist_is_status_4():
    """TMCM-6212 3.6.8 "Motor/Bank 0/2/3": bank 1 answers status 4; GIO bank 3 (banks 0/1/2 in
    3.6.13) too."""
    vm = VirtualModule("TMCM-6212", address=1)
    for raw in (frame(10, 66, 1), frame(15, 0, 3)):
        assert [Reply.decode(vm.handle(raw)).status for _ in range(2)] == [4, 4]
        assert not vm.is_prebound(raw)


def test_checksum_error_on_a_bound_frame_is_status_1():
    """Manual 3.2.1 status 1 "Wrong checksum": a bound GAP frame with its checksum byte changed."""
    vm = busy("TMCM-6212")
    raw = frame(6, 1, 2)
    vm.handle(raw)
    assert vm.is_prebound(raw)
    bad = raw[:8] + bytes(((raw[8] + 1) & 0xFF,))
    assert Reply.decode(vm.handle(bad), verify=True).status == 1
    assert vm.handle(raw[:8]) == b"" and vm.handle(raw + b"\x00") == b""


def test_value_field_is_dont_care_each_value_its_own_frame():
    """3.6.6 GAP "Value: <value>" is not used: frames with other values answer the same value."""
    vm = busy("TMCM-6212")
    replies = {Reply.decode(vm.handle(frame(6, 4, 1, v))).value for v in (0, 1, -1, 2**31 - 1)}
    assert replies == {1700}


# --- state changes that drop or bypass bound handlers -------------------------------------
def test_unit_mode_change_is_seen_by_bound_velocity_reads():
    """TMCM-6212 4.1 AP255 unit mode: 0 internal TMC5130 units, 1 pps. Bound GAP 2, 3, 4 and 5
    answer the general path's value after SAP 255 in both directions; in internal units every one
    of them differs from its pps value."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert vm.request(1, 0, 0, 20_000).status == 100  # ROR 20000 pps
    vm.advance(0.2)
    frames = [frame(6, n, 0) for n in (2, 3, 4, 5)]
    before = [vm.handle(f) for f in frames]
    assert all(vm.is_prebound(f) for f in frames)
    for mode in (0, 1):
        assert vm.request(5, 255, 0, mode).status == 100
        after = [vm.handle(f) for f in frames]
        assert after == [general(vm, f) for f in frames]
        if mode == 0:
            assert all(a != b for a, b in zip(after, before, strict=True))
    assert Reply.decode(before[0]).value == 20_000


def test_gp255_suppresses_writes_not_bound_reads():
    """TMCM-6212 5.1 GP255 "suppress reply": with 1 the module answers no command except GAP, GGP,
    GIO (docs/assumptions.md); a bound GAP still replies, a SAP does not."""
    vm = VirtualModule("TMCM-6212", address=1)
    raw = frame(6, 4, 0)
    vm.handle(raw)
    assert vm.request(9, 255, 0, 1) is None
    assert vm.handle(frame(5, 4, 0, 777)) == b""
    assert Reply.decode(vm.handle(raw)).value == 777 and vm.is_prebound(raw)


def test_download_mode_stores_a_bound_frame():
    """3.6.36 command 132: "All following commands (except control commands) are ... stored"
    (status 101); after 133 the same GAP frame is answered with its value again."""
    vm = VirtualModule("TMCM-6212", address=1)
    raw = frame(6, 4, 0)
    value = Reply.decode(vm.handle(raw)).value
    assert vm.is_prebound(raw)
    assert vm.request(132).status == 100
    assert not vm.is_prebound(raw)
    for _ in range(2):
        assert Reply.decode(vm.handle(raw)).status == 101
        assert not vm.is_prebound(raw)
    assert vm.request(133).status == 100
    assert [Reply.decode(vm.handle(raw)).value for _ in range(2)] == [value, value]


def test_factory_reset_137_rebinds_to_the_new_state():
    """3.6.36 command 137 "restore factory settings" (value 1234): a bound GGP of a user variable and
    a bound GAP answer the restarted module's values (user variable 0, default AP4)."""
    vm = VirtualModule("TMCM-6212", address=1)
    gp, ap = frame(10, 3, 2), frame(6, 4, 0)
    default = Reply.decode(vm.handle(ap)).value
    assert vm.request(9, 3, 2, 55).status == 100 and vm.request(5, 4, 0, default + 1).status == 100
    assert [Reply.decode(vm.handle(f)).value for f in (gp, ap)] == [55, default + 1]
    assert vm.request(137, 0, 0, 1234) is None
    assert [Reply.decode(vm.handle(f)).value for f in (gp, ap)] == [0, default]


def test_host_address_gp76_changes_the_reply_address():
    """Manual 3.2 byte 1 "Reply address" is the host address GP76: a bound frame replies to the new
    host address after SGP 76."""
    vm = VirtualModule("TMCM-6212", address=1)
    raw = frame(6, 4, 0)
    assert vm.handle(raw)[0] == 2
    assert vm.request(9, 76, 0, 9).status == 100
    assert vm.handle(raw)[0] == 9 and vm.is_prebound(raw)
    assert vm.handle(raw) == general(vm, raw)


def test_secondary_address_gp87():
    """5.1 GP87 secondary address: a frame at the secondary address is answered from the module
    address GP66; when GP87 goes back to 0 (off) the bound frame gets no reply."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert vm.request(9, 87, 0, 7).status == 100
    raw = frame(6, 4, 0, address=7)
    first, second = twice(vm, raw)
    assert first == second and Reply.decode(first).module_address == 1 and vm.is_prebound(raw)
    assert vm.request(9, 87, 0, 0).status == 100
    assert vm.handle(raw) == b""


def test_assign_address_drops_bound_frames():
    """`assign_address` (a server's --address): the frame for the old address gets no reply."""
    vm = VirtualModule("TMCM-6212", address=1)
    raw = frame(6, 4, 0)
    vm.handle(raw)
    vm.assign_address(5)
    assert vm.handle(raw) == b""
    assert Reply.decode(vm.handle(frame(6, 4, 0, address=5))).module_address == 5


def test_another_address_gets_no_reply():
    """GP66 "RS485 serial address": a frame for address 2 is not answered, bound or not."""
    vm = VirtualModule("TMCM-6212", address=1)
    vm.handle(frame(6, 1, 0))
    assert [vm.handle(frame(6, 1, 0, address=2)) for _ in range(2)] == [b"", b""]


@pytest.mark.parametrize("interface", ["usb", "rs485", "rs232"])
def test_other_interfaces_answer_like_the_general_path(interface):
    """USB ignores the address byte and answers from the module address (docs/endpoints.md); RS485
    and RS232 filter like serial. A frame bound on the serial link answers the same on them, and
    a foreign address byte on USB is answered without being bound."""
    vm = busy("TMCM-6212")
    raw = frame(6, 1, 3)
    vm.handle(raw)
    assert vm.handle(raw, interface=interface) == general(vm, raw, interface)
    foreign = frame(6, 1, 3, address=9)
    reply = vm.handle(foreign, interface=interface)
    assert (reply != b"") == (interface == "usb") and not vm.is_prebound(foreign)


@pytest.mark.parametrize("interface, gp", [("serial", 68), ("can", 82)])
def test_bound_reads_restart_their_heartbeat(interface, gp):
    """TMCM-6212 5.1 GP68 serial / PD86-1180 GP82 CAN heartbeat: "If the module does not receive a
    command within this time the motor will be stopped". A bound GAP every 80 ms with a 100 ms
    heartbeat keeps the motor running; after 110 ms without one it stops."""
    vm = VirtualModule("PD86-1180", address=1)
    raw = frame(6, 1, 0)
    assert vm.request(9, gp, 0, 100).status == 100
    assert vm.request(1, 0, 0, 500).status == 100
    vm.handle(raw, interface=interface)
    assert vm.is_prebound(raw)
    for _ in range(3):
        vm.advance(0.08)
        vm.handle(raw, interface=interface)
    assert vm.axes[0].engine.velocity != 0
    vm.advance(0.11)
    assert vm.axes[0].engine.velocity == 0


def test_reads_keep_the_engines_clean_writes_mark_them():
    """A pure read does not make the module look up the engines' next events again; a write does
    (issue 16: the scheduler's `_dirty` means a command may have changed an engine's next event)."""
    vm = busy("TMCM-6212")
    vm.advance(0.01)
    assert vm.next_event_in() is not None  # looks the next events up: the engines are clean
    assert not vm.scheduler._dirty
    for raw in (frame(6, 1, 0), frame(6, 1, 0), frame(10, 66, 0), frame(15, 0, 1), frame(6, 207, 0)):
        vm.handle(raw)
        assert not vm.scheduler._dirty
    assert all(ax.engine.now == vm.now for ax in vm.axes)
    vm.handle(frame(5, 4, 0, 500))
    assert vm.scheduler._dirty


@pytest.mark.parametrize("interface", ["usb", "rs485", "rs232"])
def test_every_link_binds_frames_for_the_module_address(interface):
    """A served single module is a USB link by default (docs/endpoints.md) and a bus an RS485
    line: their reads of the module's own address (GP66) are bound like serial ones and answer
    the same bytes as the general path (TMCM-6212 manual 3.2 reply format)."""
    vm = busy("TMCM-6212")
    raw = frame(6, 1, 3)
    first = vm.handle(raw, interface=interface)
    assert vm.is_prebound(raw)
    vm.advance(0.01)
    assert vm.handle(raw, interface=interface) == general(vm, raw, interface) != first


@pytest.mark.parametrize("interface", ["usb", "rs485"])
def test_bound_requests_on_usb_and_rs485_restart_the_serial_heartbeat(interface):
    """TMCM-6212 5.1 GP68: "If the module does not receive a command within this time the motor
    will be stopped". USB and RS485 requests are serial requests for the heartbeat: a bound GAP
    and a bound SAP every 80 ms keep a 100 ms heartbeat from stopping the motor."""
    vm = VirtualModule("TMCM-6212", address=1)
    vm.handle(frame(9, 68, 0, 100))
    vm.handle(frame(1, 0, 0, 20000))  # ROR
    for i in range(6):
        vm.advance(0.08)
        vm.handle(frame(6, 3, 0) if i % 2 else frame(5, 4, 0, 51200 + i), interface=interface)
    assert vm.is_prebound(frame(6, 3, 0)) and vm.is_prebound(frame(5, 4, 0, 1))
    assert vm.request(6, 3, 0).value != 0
    vm.advance(0.11)
    assert vm.request(6, 3, 0).value == 0


# --- dispatch.handler: None for what it does not cover; a bound GGP of 32 bits ----------------
def test_entry_of_a_motor_the_module_lacks_is_none():
    """dispatch.py module docstring: "`entry()` answers None for every request it does not cover
    (a wrong type, a motor the module lacks, ...)". The TMCM-6212 has motors 0...5 (manual 3.6.6
    GAP "0...5"): GAP of motor 5 has a handler answering what the general path answers, motor 6
    none."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert len(vm.axes) == 6
    fast = dispatch.handler(vm, 6, 4, 5)
    assert fast is not None
    assert fast() == vm.handle(_frame(6, 4, 5))
    assert dispatch.handler(vm, 6, 4, 6) is None
    assert Reply.decode(vm.handle(_frame(6, 4, 6))).status == 4


def test_entry_of_a_command_without_a_handler_is_none(tmp_path):
    """dispatch.py: handlers exist for "GAP, GGP and GIO of a valid (type, motor/bank)", and
    "`entry()` answers None for every request it does not cover": MVP and SAP have none, and a
    module whose command set lacks GIO (docs/profiles.md `opcodes` replaces the list; status 2,
    TMCM-6212 3.2.1) has no GIO handler, while GAP keeps one."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert dispatch.handler(vm, 4, 0, 0) is None
    assert dispatch.handler(vm, 5, 4, 0) is None
    assert dispatch.handler(vm, 15, 0, 0) is not None
    opcodes = sorted(set(load_profile("TMCM-6212").opcodes) - {15})
    path = tmp_path / "nogio.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "NOGIO-6212"\n'
                    f"opcodes = {opcodes}\n")
    nogio = VirtualModule(str(path), address=1)
    assert Reply.decode(nogio.handle(_frame(15, 0, 0))).status == 2
    assert dispatch.handler(nogio, 15, 0, 0) is None
    assert dispatch.handler(nogio, 6, 4, 0) is not None


@pytest.mark.parametrize(("period", "wire"), [
    (0x7FFF_FFFF, 0x7FFF_FFFF), (0x8000_0000, -0x8000_0000), (0xFFFF_FFFF, -1)])
def test_a_prebound_ggp_of_an_unsigned_timer_period_answers_its_32_bits(period, wire):
    """TMCM-6212 5.4 bank 3 "Timer 0 period ... 0 .. 4294967295 [ms]"; 3.2 the reply value is
    four bytes, MSB first, with the checksum over the first eight bytes. The second GGP of the
    same frame is answered by its pre-bound handler (dispatch.py); both replies carry the same
    32 bits: 2^31 - 1 as it is, 2^31 and 2^32 - 1 as -2^31 and -1 in signed form."""
    vm = VirtualModule("TMCM-6212", address=1)
    h = Host(vm)
    assert h(9, 0, 3, wire).status == 100
    frame = _frame(10, 0, 3)
    first = vm.handle(frame)
    assert vm.is_prebound(frame)
    second = vm.handle(frame)
    assert second == first
    assert second[4:8] == (period & 0xFFFF_FFFF).to_bytes(4, "big")
    assert second[8] == sum(second[:8]) & 0xFF
    assert Reply.decode(second).value == wire


# --- a reply handed over as a value (as_reply, the in-process host) ---------------------------
@pytest.mark.parametrize("name", MODULES)
def test_a_reply_handed_over_as_a_value_is_the_reply_on_the_wire(name):
    """Manual 3.2: the reply is reply address, module address, status, command and a 4-byte value.
    `handle(frame, as_reply=True)` (docs/architecture.md "Request path": what `sim://` asks for)
    hands a pre-bound read's reply over as a `Reply`: for every bound GAP of moving axes, it is
    the reply the same request gets as bytes at the same instant, decoded; over time it follows
    the axis (a position read after 10 ms is another value); every other request comes as bytes."""
    vm = busy(name)
    seen = 0
    for _ in range(2):
        for m in range(len(vm.axes)):
            for n in sorted(vm.axes[m].readable):
                raw = frame(6, n, m)
                wire = vm.handle(raw)
                if not vm.is_prebound(raw):
                    continue
                value = vm.handle(raw, True)
                assert value.__class__ is Reply and value == Reply.decode(wire), (n, m)
                seen += 1
        vm.advance(0.01)
    assert seen >= 2 * 40 * len(vm.axes)
    before = vm.handle(frame(6, 1, 0), True)
    vm.advance(0.01)
    assert vm.engine_now(0).moving and vm.handle(frame(6, 1, 0), True).value != before.value
    write = vm.handle(frame(5, 4, 0, 1234), True)
    assert write.__class__ is bytes and Reply.decode(write).status == 100


@pytest.mark.parametrize(("period", "wire"), [
    (0x7FFF_FFFF, 0x7FFF_FFFF), (0x8000_0000, -0x8000_0000), (0xFFFF_FFFF, -1)])
def test_a_reply_value_of_an_unsigned_timer_period_is_its_32_bits_signed(period, wire):
    """TMCM-6212 5.4 bank 3 timer 0 period 0 .. 4294967295 ms; manual 3.2's value is 32 bits: the
    `Reply` handed over in process carries the value a host decodes from the wire (2^31 and
    2^32 - 1 as -2^31 and -1)."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert Host(vm)(9, 0, 3, wire).status == 100
    raw = frame(10, 0, 3)
    first = vm.handle(raw)
    assert vm.is_prebound(raw)
    assert vm.handle(raw, True) == Reply.decode(first) and Reply.decode(first).value == wire
