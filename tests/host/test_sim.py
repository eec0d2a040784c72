"""The client library against the real VirtualModule through the in-process transport."""
from __future__ import annotations

import threading

import pytest

import opentmcl
from opentmcl.host import (
    Client,
    TmclConnectionError,
    TmclError,
    TmclStatusError,
    TmclTimeout,
    UnknownParameterError,
    connect,
    open_bus,
    profile_for_version,
)
from opentmcl.host.transports.inprocess import InProcessTransport
from opentmcl.modules.profile import load_profile, module_names


class Recording(InProcessTransport):
    """The in-process transport, remembering the bytes sent."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.sent: list[bytes] = []

    def send(self, data: bytes) -> None:
        self.sent.append(bytes(data))
        super().send(data)


def recorded(name="TMCM-6212", clock="virtual"):
    vm = opentmcl.VirtualModule(name, address=1)
    t = Recording(vm, clock=clock)
    return vm, t, Client(t).module()


@pytest.fixture
def m6212():
    m = connect("sim://TMCM-6212")
    yield m
    m.close()


# --- identity ---------------------------------------------------------------------------

def test_profile_is_chosen_from_the_version_string(m6212):
    """TMCM-6212 manual 3.6.36: command 136 type 0 returns the firmware version in string format."""
    assert m6212.firmware_version() == "6212V105"
    assert m6212.profile.name == "TMCM-6212"
    assert len(m6212.axes) == 6


@pytest.mark.parametrize("name", module_names())
def test_every_profile_is_found_by_its_version_string(name):
    """PD86-1180 manual 4.6.39: the string names the module type, e.g. "1180V1.30"."""
    prof = load_profile(name)
    with connect(f"sim://{name}") as m:
        assert m.firmware_version() == prof.firmware_version
        assert m.profile is prof
    assert profile_for_version(prof.firmware_version) is prof


def test_unknown_version_string_needs_an_explicit_profile():
    with pytest.raises(TmclError, match="no module profile"):
        profile_for_version("9999V100")


def test_binary_version_uses_the_normal_reply():
    """PD86-1180 manual 4.6.39: "Type set to 1 - version number in binary format: Please use the
    normal reply format"."""
    with connect("sim://PD86-1180") as m:
        assert m.firmware_version_binary() == m.profile.firmware_binary


# --- parameters -----------------------------------------------------------------------------

def test_set_and_get_named_axis_parameter_sends_the_manuals_frame():
    """TMCM-6212 manual 3.6.5: "SAP 4, 0, 51200" is 01 05 04 00 00 00 C8 00 D2; 3.6.6: "GAP 1, 0"
    is 01 06 01 00 00 00 00 00 08."""
    vm, t, m = recorded()
    m.profile  # noqa: B018 - resolve the profile first (one 136 request)
    t.sent.clear()
    ax = m.axes[0]
    ax.set("max_positioning_speed", 51200)
    assert ax.get("actual_position") == 0
    assert t.sent == [bytes.fromhex("01 05 04 00 00 00 C8 00 D2"), bytes.fromhex("01 06 01 00 00 00 00 00 08")]
    ax.set("max_positioning_speed", 1000)
    assert ax.get(4) == 1000
    assert ax.get("Maximum positioning speed") == 1000  # the manual's title works too
    assert ax.params.max_positioning_speed == 1000
    ax.params.max_positioning_speed = 2000
    assert ax.get("max_positioning_speed") == 2000
    assert "max_positioning_speed" in dir(ax.params)


def test_unknown_parameter_name_suggests_close_names(m6212):
    """Names come from the module profile (TMCM-6212 manual 4.1); a typo is a clear error."""
    with pytest.raises(UnknownParameterError, match="actual_position"):
        m6212.axes[0].get("actual_postion")
    with pytest.raises(AttributeError):
        m6212.axes[0].params.no_such_parameter  # noqa: B018


def test_value_out_of_range_is_answered_with_status_4(m6212):
    """TMCM-6212 manual 4.1: maximum positioning speed is 0...7999774 pps; 3.2.1: 4 = Invalid value."""
    with pytest.raises(TmclStatusError) as ei:
        m6212.axes[0].set("max_positioning_speed", 8_000_000)
    assert ei.value.status == 4
    assert "Invalid value" in str(ei.value) and "SAP 4, 0, 8000000" in str(ei.value)


def test_unknown_command_is_answered_with_status_2(m6212):
    """TMCM-6212 manual 3.2.1: status 2 "Invalid command" (no command 99 in Table 5)."""
    with pytest.raises(TmclStatusError, match="Invalid command") as ei:
        m6212.request(99, 0, 0, 0)
    assert ei.value.status == 2


def test_store_axis_parameter_on_the_1180():
    """PD86-1180 manual 4.4.1: STAP stores an axis parameter permanently; RSAP restores it."""
    with connect("sim://PD86-1180") as m:
        ax = m.axes[0]
        ax.set("max_positioning_speed", 700)
        ax.store("max_positioning_speed")
        ax.set("max_positioning_speed", 100)
        ax.restore("max_positioning_speed")
        assert ax.get("max_positioning_speed") == 700


def test_global_parameters_by_name_imply_their_bank(m6212):
    """TMCM-6212 manual 5: global parameter 66 (bank 0) is the serial address, 1 here."""
    assert m6212.get_global("serial_address") == 1
    assert m6212.get_global(66) == 1
    assert m6212.globals.serial_address == 1


def test_user_variables_are_bank_2(m6212):
    """TMCM-6212 manual 3.6.9 example STGP 42, 2: user variables are global parameters of bank 2."""
    m6212.set_variable(42, -123456)
    assert m6212.get_variable(42) == -123456
    assert m6212.get_global(42, bank=2) == -123456
    m6212.store_variable(42)
    m6212.set_variable(42, 0)
    m6212.restore_variable(42)
    assert m6212.get_variable(42) == -123456
    with pytest.raises(UnknownParameterError):
        m6212.get_variable(256)


def test_outputs_and_inputs():
    """TMCM-6212 manual 3.6.12: "SIO 3, 2, 1" (01 0E 03 02 00 00 00 01 15) sets OUT3;
    3.6.13: GIO reads it back in bank 2; digital inputs are bank 0, analog inputs bank 1."""
    vm, t, m = recorded()
    m.set_output(3, 1)
    assert bytes.fromhex("01 0E 03 02 00 00 00 01 15") in t.sent
    assert m.output("OUT3") == 1
    assert m.digital_input("IN0") in (0, 1)
    assert 0 <= m.analog_input(0) <= 65535
    with pytest.raises(UnknownParameterError, match="OUT0"):
        m.set_output(7, 1)


# --- motion and events ---------------------------------------------------------------------------

def test_move_to_with_wait_uses_the_position_reached_event():
    """TMCM-6212 manual 3.6.35: command 138 type 0 asks for one additional reply (status 128) when
    the next MVP reaches its target; 3.6.4 MVP ABS."""
    vm, t, m = recorded()
    ax = m.axes[0]
    ax.move_to(51200, wait=True, timeout=30)
    assert bytes.fromhex("01 8A 00 00 00 00 00 01 8C") in t.sent
    assert ax.position == 51200 and ax.position_reached
    assert t.elapsed > 0  # virtual time was spent waiting
    assert vm.time == pytest.approx(t.elapsed)


def test_event_mask_of_the_manuals_example_reports_each_motor():
    """TMCM-6212 manual 3.6.35 example: 01 8A 01 00 00 00 00 05 91 asks for reached messages for the
    motors of bit mask 5 (motors 0 and 2) after every MVP."""
    vm, t, m = recorded()
    m.request_position_reached_event(0b101, every=True)
    assert t.sent[-1] == bytes.fromhex("01 8A 01 00 00 00 00 05 91")
    m.axes[0].move_to(1000)
    m.axes[2].move_to(-3000)
    assert m.wait_position_reached(0b101, timeout=30) == 0b101
    assert (m.axes[0].position, m.axes[2].position) == (1000, -3000)
    m.axes[0].move_by(500)  # type 1: again for every MVP
    assert m.wait_position_reached(0b001, timeout=30) == 1
    assert m.axes[0].position == 1500


def test_waiting_for_an_event_that_never_comes_times_out_in_virtual_time():
    """Manual 3.6.35: the additional reply only comes after an MVP; without one the wait times out."""
    vm, t, m = recorded()
    m.request_position_reached_event(1)
    with pytest.raises(TmclTimeout):
        m.wait_position_reached(1, timeout=0.5)
    assert vm.time == pytest.approx(0.5, abs=0.06)


def test_rotate_and_stop():
    """TMCM-6212 manual 3.6.1/3.6.2: ROR turns towards increasing, ROL towards decreasing positions;
    3.6.3 MST stops."""
    vm, t, m = recorded()
    ax = m.axes[1]
    ax.rotate(-20000)
    assert t.sent[-1][1] == 2  # ROL
    m.sleep(1.0)
    assert ax.actual_speed < 0 and ax.position < 0
    ax.stop()
    m.sleep(2.0)
    assert ax.actual_speed == 0


def test_coordinates(m6212):
    """TMCM-6212 manual 3.6.22 SCO 1, 0, 1000; 3.6.23 GCO; 3.6.4 MVP COORD."""
    ax = m6212.axes[0]
    ax.set_coordinate(1, 1000)
    assert ax.get_coordinate(1) == 1000
    ax.move_to_coordinate(1, wait=True, timeout=30)
    assert ax.position == 1000


def test_wait_until_reached_polls_the_position_reached_flag(m6212):
    """TMCM-6212 manual 4.1, axis parameter 8: set when target and actual position are equal."""
    ax = m6212.axes[3]
    ax.move_by(-2000)
    ax.wait_until_reached(timeout=30)
    assert ax.position == -2000


def test_axis_unit_helpers_read_parameters_140_and_202(m6212):
    """TMCM-6212 manual 6.5: with 256 microsteps (140 = 8) and 200 full steps, 51200 pps = 1 rps."""
    ax = m6212.axes[0]
    assert ax.pps_to_rps(51200) == 1.0
    assert ax.rpm_to_pps(60) == 51200
    ax.set("microstep_resolution", 4)
    assert ax.pps_to_rps(3200) == 1.0


def test_tmc429_unit_helpers_read_the_divisors():
    """PD86-1180 manual 5: speed unit 16 MHz / (65536 * 2^pulse_div) µsteps/s (axis parameter 154)."""
    with connect("sim://PD86-1180") as m:
        ax = m.axes[0]
        pulse_div = ax.get("pulse_divisor")
        assert ax.velocity_to_pps(2047) == pytest.approx(16e6 * 2047 / (65536 * 2**pulse_div))
        assert ax.pps_to_velocity(ax.velocity_to_pps(1000)) == 1000
    with connect("sim://TMCM-6212") as m, pytest.raises(TmclError, match="divisor"):
        m.axes[0].velocity_to_pps(100)


# --- transports, buses, clocks ---------------------------------------------------------------------

def test_several_modules_on_one_bus():
    """Modules on one RS-485 bus share the line; each answers only its own address (manual 3.1)."""
    with open_bus("sim://TMCM-6212@1,PD86-1180@2") as bus:
        a, b = bus.module(1), bus.module(2)
        assert (a.name, b.name) == ("TMCM-6212", "PD86-1180")
        a.axes[0].set("max_positioning_speed", 1234)
        assert b.axes[0].get("max_positioning_speed") != 1234
        with pytest.raises(TmclTimeout, match="module 3"):
            bus.request(6, 1, 0, address=3, timeout=0.2)


def test_connect_address_goes_to_the_virtual_module():
    """The module answers with its own address (manual 3.2 Table 3)."""
    with connect("sim://TMCM-6212", address=5) as m:
        assert m.request(6, 1, 0).module_address == 5
        assert m.get_global("serial_address") == 5


def test_clock_none_never_lets_time_pass():
    vm = opentmcl.VirtualModule("TMCM-6212", address=1)
    m = Client(InProcessTransport(vm, clock="none")).module()
    m.axes[0].move_to(5000)
    with pytest.raises(TmclTimeout):
        m.axes[0].wait_until_reached(timeout=10)
    assert vm.time == 0


def test_clock_real_follows_the_wall_clock():
    vm = opentmcl.VirtualModule("TMCM-6212", address=1)
    m = Client(InProcessTransport(vm, clock="real")).module()
    m.axes[0].rotate(10000)
    m.sleep(0.02)
    m.axes[0].position  # noqa: B018 - a request syncs the module to the wall clock
    assert vm.time >= 0.02


def test_bad_clock_policy():
    with pytest.raises(TmclConnectionError, match="clock"):
        connect("sim://TMCM-6212?clock=sometimes")


def test_threads_share_one_client():
    """One request in flight at a time (manual 3.2: "Do not send the next command before having
    received the reply!"): a lock lets threads share the client without mixing replies."""
    with connect("sim://TMCM-6212") as m:
        m.profile  # noqa: B018
        errors = []

        def worker(axis: int):
            try:
                ax = m.axes[axis]
                for i in range(100):
                    ax.set("max_positioning_speed", 1000 * axis + i)
                    assert ax.get("max_positioning_speed") == 1000 * axis + i
            except Exception as exc:  # pragma: no cover - reported below
                errors.append(exc)

        threads = [threading.Thread(target=worker, args=(i,)) for i in range(6)]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        assert errors == []
        assert m.client.stray_replies == 0


def test_closed_transport_raises_connection_error():
    m = connect("sim://TMCM-6212")
    m.close()
    with pytest.raises(TmclConnectionError):
        m.request(6, 1, 0)


@pytest.mark.parametrize("url", ["TMCM-6212", "ftp://x", "sim://", "sim://TMCM-9999", "sim://TMCM-6212@x",
                                 "tcp://127.0.0.1", "serial://", "can://socketcan"])
def test_bad_urls_raise_connection_error(url):
    with pytest.raises(TmclConnectionError):
        connect(url)


def test_top_level_connect_is_the_host_connect():
    with opentmcl.connect("sim://PD28-1021") as m:
        assert m.name == "PD28-1021"


class EventAwareModule(opentmcl.VirtualModule):
    """The real module, also telling the seconds to its next internal event (ramp phase change)."""

    advances = 0

    def next_event_in(self):
        ticks = [t for t in (ax.engine.next_event() for ax in self.axes) if t is not None and t > self.now]
        return (min(ticks) - self.now) / 16_000_000 if ticks else None

    def advance(self, seconds):
        self.advances += 1
        super().advance(seconds)


def test_virtual_clock_jumps_from_event_to_event_when_the_module_tells_them():
    """docs/architecture.md "Time": advance jumps ahead as far as the next event, never by fixed small steps."""
    vm = EventAwareModule("TMCM-6212", address=1)
    m = Client(InProcessTransport(vm)).module()
    m.axes[0].move_to(51200 * 20, wait=True, timeout=120)
    assert m.axes[0].position == 51200 * 20
    assert vm.advances < 2100  # in 1 ms slices this 21 s move would take 21000 advances
    m.request_position_reached_event(1)
    with pytest.raises(TmclTimeout):  # nothing pending: the whole timeout passes at once
        m.wait_position_reached(1, timeout=10)
    assert vm.time == pytest.approx(31.0, abs=0.1)


def test_reference_search_start_status_stop(m6212):
    """TMCM-6212 manual 3.6.11: RFS START starts, RFS STATUS answers 0 only when no reference search
    is active, RFS STOP stops it. Without a switch the search does not end, so a wait times out."""
    ax = m6212.axes[0]
    assert not ax.reference_search_active()
    ax.reference_search()
    assert ax.reference_search_active()
    with pytest.raises(TmclTimeout, match="reference search"):
        ax.reference_search(wait=True, timeout=2)
    ax.stop_reference_search()
    assert not ax.reference_search_active()


def test_connect_takes_the_address_a_sim_url_sets():
    """A module answers only its own address (manual 3.1); connect talks to the one the URL names."""
    with connect("sim://PD86-1180?address=3") as m:
        assert m.address == 3 and m.name == "PD86-1180"
    with connect("sim://TMCM-6212@4,PD86-1180@2") as m:
        assert m.address == 4 and m.name == "TMCM-6212"
        assert m.client.module(2).name == "PD86-1180"


def test_a_thread_waiting_for_an_event_does_not_block_other_requests():
    """Manual 3.6.35: the event reply may arrive while other requests are answered; whichever
    thread reads it, the waiting thread gets it, and the others' replies are not mixed up."""
    with connect("sim://TMCM-6212") as m:
        m.profile  # noqa: B018
        m.request_position_reached_event(1)
        m.axes[0].move_to(100000)
        result = {}

        def waiter():
            try:
                result["mask"] = m.wait_position_reached(1, timeout=60)
            except Exception as exc:  # pragma: no cover - reported below
                result["error"] = exc

        th = threading.Thread(target=waiter)
        th.start()
        reads = 0
        while th.is_alive():
            m.axes[1].set("max_positioning_speed", 1000 + reads % 100)
            assert m.axes[1].get("max_positioning_speed") == 1000 + reads % 100
            reads += 1
        th.join()
        assert result == {"mask": 1}
        assert m.axes[0].position == 100000


def test_download_read_back_and_run_a_program(m6212):
    """TMCM-6212 manual 3.6.36: 132 enters download mode (following commands are stored, status 101),
    133 leaves it, 134 reads a memory location, 129 type 1 runs from an address."""
    program = [(5, 4, 0, 1234), (28, 0, 0, 0)]  # SAP 4, 0, 1234; STOP
    assert m6212.download_program(program) == 2
    assert m6212.axes[0].get(4) != 1234  # stored, not executed
    assert [m6212.read_program_memory(a) for a in (0, 1)] == program
    m6212.run_application(0)
    m6212.sleep(0.1)
    assert m6212.axes[0].get(4) == 1234


def test_reading_beyond_program_memory_is_refused(m6212):
    """TMCM-6212 manual 1: program memory for 6144 commands; 3.2.1 status 4 "Invalid value"."""
    with pytest.raises(TmclStatusError, match="Invalid value"):
        m6212.read_program_memory(6144)


@pytest.mark.parametrize("url", [
    "sim://TMCM-6212?clok=real",                 # typo of clock
    "serial:///dev/ttyUSB0?baudrate=9600",       # typo of baud
    "tcp://127.0.0.1:2323?timeout=1",            # connect_timeout is meant
    "can://virtual/x?id=1&replyid=2",            # typo of reply_id
])
def test_a_url_with_an_unknown_query_key_is_refused(url):
    """docs/architecture.md "Errors": a typo in a transport URL (docs/host.md lists each
    scheme's keys) is a TmclConnectionError naming the key, not silently ignored - the user would
    otherwise talk at the wrong baud rate or with the wrong clock without knowing it."""
    with pytest.raises(TmclConnectionError, match="unknown"):
        opentmcl.connect(url)
