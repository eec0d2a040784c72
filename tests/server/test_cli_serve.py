"""`opentmcl serve` as a user runs it: a real process, real sockets, real signals."""
import json
import os
import re
import select
import signal
import socket
import sys
import time

import pytest

from opentmcl import VirtualModule
from opentmcl.cli import CliError, main
from opentmcl.cli.serve import assign_addresses, parse_hostport
from opentmcl.protocol.frame import Reply
from opentmcl.server.tcp import EVICT_SILENT

from .helpers import GGP_66, Link, is_ok, recv_exactly, reply, request, unique_channel

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals and ptys")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_serve_tcp_and_pty_then_clean_shutdown(serve, sig):
    """The issue's command line: two modules on one bus, TCP and pty endpoints, printed
    connection info; manual 3.6.8 GGP 66 example answered; SIGTERM/Ctrl-C exit cleanly."""
    import serial

    p = serve("--module", "TMCM-6212", "--address", "1", "--module", "TMCM-6212", "--address", "4",
              "--tcp", "127.0.0.1:0", "--pty")
    with socket.create_connection(p.tcp_address(), timeout=5) as s:
        s.sendall(GGP_66)
        assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)
        s.sendall(request(4, 10, 66, 0))
        assert recv_exactly(s, 9) == reply(2, 4, 100, 10, 4)
    with serial.Serial(p.endpoint("pty"), timeout=5) as port:
        port.write(GGP_66)
        assert port.read(9) == reply(2, 1, 100, 10, 1)
    code, out, err = p.stop(sig)
    assert code == 0, err
    assert "stopped" in out and "Traceback" not in err


def test_eeprom_is_flushed_on_sigterm(serve, tmp_path):
    """Manual 5.1: SGP on bank-0 parameters 64..127 stores them; after SIGTERM the EEPROM
    file holds the value and a new server starts with it."""
    ee = tmp_path / "ee.json"
    p = serve("--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--eeprom", str(ee))
    with socket.create_connection(p.tcp_address(), timeout=5) as s:
        s.sendall(request(1, 9, 75, 0, 12))  # SGP 75, 0, 12
        assert is_ok(recv_exactly(s, 9), 2, 1, 9)  # SGP reply value: "don't care" (3.6.7)
    assert p.stop()[0] == 0
    json.loads(ee.read_text())
    p2 = serve("--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--eeprom", str(ee))
    with socket.create_connection(p2.tcp_address(), timeout=5) as s:
        s.sendall(request(1, 10, 75, 0))
        assert recv_exactly(s, 9, timeout=5) == reply(2, 1, 100, 10, 12)
    assert p2.stop()[0] == 0


def test_sigkill_during_eeprom_writes_leaves_a_readable_file(serve, tmp_path):
    """docs/architecture.md "Errors": the EEPROM is written atomically, so SIGKILL in the
    middle of a stream of auto-stored SGP writes (manual 5.1) never leaves a torn file."""
    from opentmcl import VirtualModule

    ee = tmp_path / "ee.json"
    for round_ in range(3):
        p = serve("--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--eeprom", str(ee))
        with socket.create_connection(p.tcp_address(), timeout=5) as s:
            for i in range(40 + 17 * round_):
                s.sendall(request(1, 9, 75, 0, i % 200))
                if i < 30:
                    assert len(recv_exactly(s, 9)) == 9
            p.proc.send_signal(signal.SIGKILL)
        p.proc.communicate(timeout=20)
        vm = VirtualModule("TMCM-6212", eeprom=ee)  # must load without error
        assert 0 <= vm.request(10, 75, 0).value < 200


def test_non_loopback_needs_host_flag(capsys):
    """Safety: TCP binds to loopback unless --host is given."""
    code = main(["serve", "--module", "TMCM-6212", "--tcp", "0.0.0.0:0"])
    assert code == 2
    assert "--host" in capsys.readouterr().err


def test_host_flag_warns(serve):
    p = serve("--module", "TMCM-6212", "--tcp", "0", "--host", "0.0.0.0")
    code, _, err = p.stop()
    assert code == 0 and "warning" in err


def test_unknown_module_is_a_one_line_error(capsys):
    code = main(["serve", "--module", "TMCM-9999", "--tcp", "127.0.0.1:0"])
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "TMCM-9999" in err


SCENARIO = """module = "TMCM-6212"

[[input]]
bank = 0
port = 2
steps = [[0.0, 1]]
"""


def test_scenario_drives_the_served_module(serve, tmp_path):
    """`--scenario FILE` (docs/scenarios.md) sets up the served module's world: the digital input
    the scenario switches on reads 1 through GIO 2, 0 (manual 3.6.13); it reads 0 without it."""
    scenario = tmp_path / "in2.toml"
    scenario.write_text(SCENARIO)
    for args, expected in (((), 0), (("--scenario", str(scenario)), 1)):
        p = serve("--module", "TMCM-6212", "--tcp", "127.0.0.1:0", *args)
        with socket.create_connection(p.tcp_address(), timeout=5) as s:
            s.sendall(request(1, 15, 2, 0))
            assert recv_exactly(s, 9) == reply(2, 1, 100, 15, expected)
        assert p.stop()[0] == 0


def test_scenario_for_another_module_is_a_one_line_error(capsys, tmp_path):
    scenario = tmp_path / "in2.toml"
    scenario.write_text(SCENARIO)
    assert main(["serve", "--module", "PD86-1180", "--tcp", "127.0.0.1:0", "--scenario", str(scenario)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "TMCM-6212" in err


@pytest.mark.parametrize("gap", ["0", "-1", "nan", "inf"])
def test_bad_gap_is_a_one_line_error(capsys, gap):
    """The inter-byte gap must let a truncated frame expire (manual 3.1: frames are found by
    counting nine bytes), so only a positive, finite number of seconds is accepted."""
    assert main(["serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--gap", gap]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--gap" in err


def test_bad_can_spec_and_busy_port(capsys):
    assert main(["serve", "--module", "TMCM-6212", "--can", "virtual"]) == 2
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        assert main(["serve", "--module", "TMCM-6212", "--tcp", f"127.0.0.1:{port}"]) == 2
    assert "cannot start" in capsys.readouterr().err


def test_parse_hostport():
    assert parse_hostport("2323") == (None, 2323)
    assert parse_hostport("127.0.0.1:0") == ("127.0.0.1", 0)
    assert parse_hostport("[::1]:5") == ("::1", 5)
    for bad in ("x", "1:99999", "[::1]5"):
        with pytest.raises(CliError):
            parse_hostport(bad)


def test_assign_addresses():
    """Several modules on one bus need distinct addresses (manual 5.1 GP66 range 1..255)."""
    assert assign_addresses(3, [1]) == [1, 2, 3]
    assert assign_addresses(2, [2]) == [2, 1]
    with pytest.raises(CliError):
        assign_addresses(2, [3, 3])
    with pytest.raises(CliError):
        assign_addresses(1, [1, 2])


def test_several_modules_get_distinct_can_ids(serve):
    """Manual 5.1 GP71 "The module (target) address for CAN" (default 1): with two modules
    on one CAN bus, the printed connection lines give each its own ID."""
    p = serve("--module", "TMCM-6212", "--address", "1", "--module", "TMCM-6212", "--address", "5",
              "--can", f"virtual:{unique_channel()}")
    assert [line.rsplit("?", 1)[1] for line in p.lines if line.startswith("can ")] == [
        "id=1&reply_id=2", "id=5&reply_id=2"]
    assert p.stop()[0] == 0


def test_can_between_processes_on_python_can_udp_multicast(serve):
    """Manual 3.1 (CAN: the CAN ID selects the module, 7 data bytes) and 5.1 GP71/GP70: a module
    served by one process on python-can's `udp_multicast` virtual bus (a CAN bus between processes
    without SocketCAN) answers this process; manual 3.6.4 MVP ABS and 3.6.6 GAP 0 read back the
    target. A group address of our own keeps parallel runs apart."""
    from opentmcl.host import TmclConnectionError, connect

    group = f"239.{os.getpid() % 250 + 1}.{time.monotonic_ns() % 250 + 1}.{os.getppid() % 250 + 1}"
    p = serve("--module", "TMCM-6212", "--can", f"udp_multicast:{group}")
    url = p.endpoint("can")
    assert url == f"can://udp_multicast/{group}?id=1&reply_id=2"
    try:
        module = connect(url, timeout=5)
    except TmclConnectionError as exc:  # the server could open it, so this is rare: no loopback route
        pytest.skip(f"udp_multicast not usable here: {exc}")
    try:
        assert module.request(10, 66, 0).value == 1          # GGP 66: the module's address
        module.request(4, 0, 0, 1000)                         # MVP ABS, 0, 1000
        assert module.request(6, 0, 0).value == 1000          # GAP 0: target position
    finally:
        module.client.close()
    assert p.stop()[0] == 0


def test_build_server_assigns_can_ids_in_ram(tmp_path):
    """The same rule in-process, exercised on python-can's virtual bus: ID 3 reaches the
    module at address 3, ID 1 the other; the IDs are not stored in the EEPROM file: a module
    powered up from it again has the default CAN ID 1 (manual 5.1, GP71)."""
    import can

    from opentmcl.cli import build_parser
    from opentmcl.cli.serve import build_server

    channel = unique_channel()
    args = build_parser().parse_args(["serve", "--module", "TMCM-6212", "--module", "TMCM-6212",
                                      "--address", "3", "--eeprom", str(tmp_path / "a.json"),
                                      "--can", f"virtual:{channel}"])
    server = build_server(args)
    server.start()
    host = can.Bus(interface="virtual", channel=channel)
    try:
        for can_id, address in ((3, 3), (1, 1)):
            host.send(can.Message(arbitration_id=can_id, data=GGP_66[1:8], is_extended_id=False))
            msg = host.recv(5)
            assert msg is not None and bytes(msg.data) == bytes([address, 100, 10, 0, 0, 0, address])
    finally:
        host.shutdown()
        server.stop()
    again = VirtualModule("TMCM-6212", eeprom=tmp_path / "a.json")
    try:
        assert again.globals.get_raw(0, 71) == 1
    finally:
        again.close()


def _stored(path, module="TMCM-6212", **globals_):
    """An EEPROM file in which SGP (manual 5.1: bank-0 parameters 64..127 are stored at once)
    left the given global parameters; GP66 last, as it changes the address."""
    vm = VirtualModule(module, eeprom=path)
    for number, value in sorted(globals_.items(), key=lambda kv: kv[0] == "gp66"):
        assert vm.request(9, int(number[2:]), 0, value).status == 100
    vm.close()
    return path


def test_eeprom_without_address_serves_at_the_stored_address(serve, tmp_path):
    """TMCM-6212 manual 5.1 GP66 "serial address" and GP76 "serial host address" are stored by
    SGP; `serve --eeprom FILE` without --address powers the module up with them, as the real
    module does: GGP 66 to address 7 is answered from 7 to host 3; address 1 stays silent."""
    ee = _stored(tmp_path / "ee.json", gp76=3, gp66=7)
    p = serve("--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--eeprom", str(ee))
    assert any("at address 7" in line for line in p.lines), p.lines
    with socket.create_connection(p.tcp_address(), timeout=5) as s:
        s.sendall(GGP_66)
        assert recv_exactly(s, 9, timeout=0.5) == b""
        s.sendall(request(7, 10, 66, 0))
        assert recv_exactly(s, 9) == reply(3, 7, 100, 10, 7)
    assert p.stop()[0] == 0


def test_explicit_address_wins_over_the_stored_one(serve, tmp_path):
    """--address overrides the stored GP66 (in RAM; docs/endpoints.md); the other stored bus
    parameters (host address GP76) still apply."""
    ee = _stored(tmp_path / "ee.json", gp76=3, gp66=7)
    p = serve("--module", "TMCM-6212", "--address", "4", "--tcp", "127.0.0.1:0", "--eeprom", str(ee))
    with socket.create_connection(p.tcp_address(), timeout=5) as s:
        s.sendall(request(4, 10, 66, 0))
        assert recv_exactly(s, 9) == reply(3, 4, 100, 10, 4)
    assert p.stop()[0] == 0
    assert VirtualModule("TMCM-6212", eeprom=ee).address == 7      # the file is not rewritten


def test_stored_addresses_and_can_ids_of_a_bus(tmp_path):
    """Two modules whose EEPROM files store GP66 (5, 9) and the second one a CAN ID GP71 = 20:
    a third module without a file gets the next free address (1), the stored CAN ID is kept
    and only the others get their serial address as CAN ID (docs/assumptions.md)."""
    from opentmcl.cli import build_parser
    from opentmcl.cli.serve import build_server

    a = _stored(tmp_path / "a.json", gp66=5)
    b = _stored(tmp_path / "b.json", gp71=20, gp66=9)
    args = build_parser().parse_args(["serve", "--module", "TMCM-6212", "--module", "TMCM-6212",
                                      "--module", "TMCM-6212", "--eeprom", str(a), "--eeprom", str(b),
                                      "--tcp", "127.0.0.1:0"])
    server = build_server(args)
    try:
        assert [vm.address for vm in server.modules] == [5, 9, 1]
        assert [vm.globals.get_raw(0, 71) for vm in server.modules] == [5, 20, 1]
    finally:
        server.stop()


def test_two_stored_addresses_that_collide_are_a_one_line_error(capsys, tmp_path):
    """Addresses on one bus must be distinct (manual 3: one bus, several nodes)."""
    a = _stored(tmp_path / "a.json", gp66=5)
    b = _stored(tmp_path / "b.json", gp66=5)
    assert main(["serve", "--module", "TMCM-6212", "--module", "TMCM-6212", "--eeprom", str(a),
                 "--eeprom", str(b), "--tcp", "127.0.0.1:0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "distinct" in err


def test_pty_of_one_module_is_usb_and_answers_any_address(serve):
    """`serve --pty` with one module stands for its USB port (docs/endpoints.md): Trinamic's
    TMCL firmware ignores the address byte on USB, so GGP 66 (manual 3.6.8) sent to address 0
    or 9 is answered, from the module's own address 1."""
    import serial

    p = serve("--module", "TMCM-6212", "--pty")
    assert any(line.startswith("pty ") and line.endswith("(usb)") for line in p.lines), p.lines
    with serial.Serial(p.endpoint("pty"), timeout=5) as port:
        for target in (0, 9, 1):
            port.write(request(target, 10, 66, 0))
            assert port.read(9) == reply(2, 1, 100, 10, 1)
    assert p.stop()[0] == 0


@pytest.mark.parametrize("interface", ["rs485", "rs232"])
def test_pty_as_rs485_or_rs232_filters_by_address(serve, interface):
    """`--interface rs485|rs232`: only frames for the module's address (GP66) are answered."""
    import serial

    p = serve("--module", "PD86-1180", "--pty", "--interface", interface)
    with serial.Serial(p.endpoint("pty"), timeout=0.5) as port:
        port.write(request(0, 10, 66, 0))
        assert port.read(9) == b""
        port.timeout = 5
        port.write(GGP_66)
        assert port.read(9) == reply(2, 1, 100, 10, 1)
    assert p.stop()[0] == 0


def test_pty_of_a_bus_is_rs485(serve):
    """Several modules on one pty are an RS-485 bus (manual 3: several nodes on one bus): each
    answers its own address, a frame for nobody stays unanswered."""
    import serial

    p = serve("--module", "TMCM-6212", "--module", "PD28-1021", "--pty")
    assert any(line.startswith("pty ") and line.endswith("(rs485)") for line in p.lines), p.lines
    with serial.Serial(p.endpoint("pty"), timeout=5) as port:
        port.write(request(2, 10, 66, 0))
        assert port.read(9) == reply(2, 2, 100, 10, 2)
        port.timeout = 0.5
        port.write(request(0, 10, 66, 0))
        assert port.read(9) == b""
    assert p.stop()[0] == 0


@pytest.mark.parametrize(("name", "interface"), [("PD28-1021", "rs485"), ("TMCM-6212", "usb"), ("PD86-1180", "usb")])
def test_serve_takes_the_interface_the_manual_lists(serve, name, interface):
    """Issue 29 item 8. PD28-1021 manual, title page: "RS485 interface" (no USB): `opentmcl serve
    --pty` stands for an RS-485 line, where "the module will ... reply ... only" to its address (3:
    "strict master/slave relationship"), so a frame to address 2 gets no reply. The TMCM-6212 ("USB
    full speed (12Mbit/s) device interface", 1) and the PD86-1180 ("USB, RS232, RS485 and CAN") are
    served as USB, where the address byte is ignored (docs/endpoints.md)."""
    ggp = 10
    p = serve("--module", name, "--pty")
    [line] = [x for x in p.lines if x.startswith("pty ")]
    path, shown = re.match(r"pty (\S+) .*\((\w+)\)$", line).groups()
    assert shown == interface
    lk = Link(path)
    try:
        lk.send(ggp, 66, 0, 0, address=2)               # another address
        r = lk.ask(ggp, 66, 0)                          # the next reply on the line
        assert (r.status, r.value) == (100, 1)
        if interface == "usb":
            assert Reply.decode(lk.read()).command == ggp   # the frame to address 2 came first
        else:
            assert lk.port.read(9) == b""
    finally:
        lk.close()


@pytest.mark.parametrize(("argv", "says"), [
    (["--module", "TMCM-6212", "--module", "TMCM-6212", "--pty", "--interface", "usb"], "one module"),
    (["--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--interface", "rs232"], "applies to --pty"),
    (["--module", "TMCM-6212", "--pty", "--pace", "--interface", "usb"], "baud rate"),
    (["--module", "PD28-1021", "--pty", "--interface", "usb"], "no USB port")])
def test_bad_interface_use_is_a_one_line_error(capsys, argv, says):
    """USB carries one module; --interface describes the pty only; --pace paces at GP65, the
    "RS485 baud rate" (manual 5.1), which a USB link does not have; the PD28-1021 has no USB port
    (its manual's title page: "RS485 interface"), so the pty cannot stand for one."""
    assert main(["serve", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err


def test_serve_pace_paces_requests_and_replies(serve):
    """`serve --pty --pace` (docs/endpoints.md): TMCM-6212 manual 5.1 GP65 0 = 9600 baud, so a
    GGP 66 round trip (9 + 9 bytes, 10 bit times each) takes at least 18.75 ms (lower bound)."""
    import serial

    p = serve("--module", "TMCM-6212", "--pty", "--pace")
    with serial.Serial(p.endpoint("pty"), timeout=5) as port:
        for _ in range(5):
            start = time.monotonic()
            port.write(GGP_66)
            assert port.read(9) == reply(2, 1, 100, 10, 1)
            assert time.monotonic() - start >= 18 * 10 / 9600


def wait_eof(sock, timeout):
    """True once the server closed `sock` (recv gives b"") within `timeout` seconds."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        sock.settimeout(max(0.01, deadline - time.monotonic()))
        try:
            if sock.recv(64) == b"":
                return True
        except TimeoutError:
            return False
        except ConnectionResetError:
            return True
    return False


def test_silent_clients_give_a_fifth_client_their_slot_within_a_second(serve):
    """Issue 28 item 3: with the defaults (4 slots, 300 s idle timeout), four sockets that were
    served once and then fell silent kept every other client out for 300 s. Now a fifth client is
    served within 1 s: it takes the slot of the client silent longest (docs/endpoints.md "Slots"),
    which is closed and logged; the other three keep theirs. Vector: manual 3.6.8, GGP 66, 0 ->
    02 01 64 0A 00 00 00 01 72."""
    p = serve("--module", "TMCM-6212", "--tcp", "127.0.0.1:0")
    address = p.tcp_address()
    idle = [socket.create_connection(address, timeout=5) for _ in range(4)]
    try:
        for s in idle:  # served once, then silent; idle[0] is the one silent longest
            s.sendall(GGP_66)
            assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)
        time.sleep(EVICT_SILENT)  # all four are now silent clients, not fresh ones
        start = time.monotonic()
        with socket.create_connection(address, timeout=5) as fifth:
            fifth.sendall(GGP_66)
            assert recv_exactly(fifth, 9) == reply(2, 1, 100, 10, 1)
            assert time.monotonic() - start < 1.0
            assert wait_eof(idle[0], 30)
            for s in idle[1:]:
                s.sendall(GGP_66)
                assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)
    finally:
        for s in idle:
            s.close()
    code, _, err = p.stop()
    assert code == 0
    assert sum("gave its slot to a new client" in line for line in err.splitlines()) == 1


def test_without_idle_timeout_a_lone_client_keeps_its_slot(serve):
    """`--idle-timeout 0` switches the drop for silence off (docs/endpoints.md): a silent client that
    is alone keeps the only slot however long it is silent; only a new client takes it over."""
    p = serve("--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--idle-timeout", "0", "--max-clients", "1")
    with socket.create_connection(p.tcp_address(), timeout=5) as held:
        held.sendall(GGP_66)
        assert recv_exactly(held, 9) == reply(2, 1, 100, 10, 1)
        assert not wait_eof(held, 3.0)
        with socket.create_connection(p.tcp_address(), timeout=5) as other:
            other.sendall(GGP_66)
            assert recv_exactly(other, 9) == reply(2, 1, 100, 10, 1)
            assert wait_eof(held, 30)
    assert p.stop()[0] == 0


@pytest.mark.parametrize("seconds", ["-1", "nan", "inf", "-inf"])
def test_bad_idle_timeout_is_a_one_line_error(capsys, seconds):
    """The idle timeout is 0 (none) or a positive, finite number of seconds (docs/endpoints.md)."""
    assert main(["serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0", f"--idle-timeout={seconds}"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--idle-timeout must be 0 (none) or a positive, finite number" in err


def test_default_idle_timeout_is_finite():
    """Issue 11 deliverable: an idle timeout with a sensible default (300 s, docs/endpoints.md), so
    that a plain `opentmcl serve` cannot be locked out for ever."""
    import argparse

    from opentmcl.cli.serve import build_server, register

    parser = argparse.ArgumentParser()
    register(parser.add_subparsers())
    args = parser.parse_args(["serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0"])
    server = build_server(args)
    (tcp,) = server.endpoints
    assert tcp.idle_timeout == 300.0


def peak_rss_kb(pid):
    """VmHWM (peak resident set) of a process, in kB, from /proc (Linux)."""
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    raise AssertionError("no VmHWM")


def flood(sock, chunk, total):
    """Send `total` bytes of `chunk` repeated while reading (and discarding) what comes back;
    return the number of bytes received."""
    sent = received = 0
    sock.setblocking(False)
    try:
        while sent < total:
            readable, writable, _ = select.select([sock], [sock], [], 30)
            if not readable and not writable:
                raise AssertionError("server neither reads nor writes")
            if readable:
                data = sock.recv(65536)
                if not data:
                    raise AssertionError("server closed the connection during the flood")
                received += len(data)
            if writable:
                sent += sock.send(chunk)
    finally:
        sock.setblocking(True)
    return received


FLOOD = 4 * 1024 * 1024


def read_until_tail(sock, tail, timeout):
    """Read (and discard) until the bytes received so far end with `tail`; False on time-out."""
    deadline = time.monotonic() + timeout
    last = b""
    while time.monotonic() < deadline:
        sock.settimeout(max(0.01, deadline - time.monotonic()))
        try:
            data = sock.recv(65536)
        except TimeoutError:
            return False
        if not data:
            return False
        last = (last + data)[-len(tail):]
        if last == tail:
            return True
    return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/PID/status")
@pytest.mark.parametrize("ascii_mode", [False, True], ids=["binary", "ascii"])
def test_garbage_forever_keeps_the_server_bounded(serve, ascii_mode):
    """Issue 11 "Per-connection buffers stay bounded": 4 MB of garbage (binary mode: frames for
    no module, manual 3.1 frames found by counting nine bytes; ASCII mode, PD28-1021 manual 3.4:
    one line addressed to module 1 that never ends with <CR>) grow the server's peak memory by less
    than half of that (measured: under 100 kB), and the client is still served afterwards."""
    p = serve("--module", "PD28-1021", "--tcp", "127.0.0.1:0")
    with socket.create_connection(p.tcp_address(), timeout=5) as s:
        s.sendall(GGP_66)
        assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)
        if ascii_mode:
            s.sendall(request(1, 139))  # "The ASCII command line interface is entered by ... 139"
            assert recv_exactly(s, 9) == reply(2, 1, 100, 139, 0)
            s.sendall(b"A")
        before = peak_rss_kb(p.proc.pid)
        flood(s, (b"X" if ascii_mode else b"\xee") * 65536, FLOOD)
        growth_kb = peak_rss_kb(p.proc.pid) - before
        assert growth_kb < FLOOD // 2048, f"peak memory grew by {growth_kb} kB"  # < half the flood
        if ascii_mode:
            s.sendall(b"\rABIN\r")  # <CR> ends the over-long line (an error status), BIN leaves ASCII
            assert read_until_tail(s, b"BA 100 0\r", 60)  # BIN answered with status 100 (3.4.1)
        # The garbage still queued in the socket buffers is read first; a host that gets no reply
        # retries after a pause, which ends any partial frame (docs/assumptions.md, framer).
        deadline = time.monotonic() + 60
        answer = b""
        while answer != reply(2, 1, 100, 10, 1) and time.monotonic() < deadline:
            s.sendall(GGP_66)
            answer = recv_exactly(s, 9, timeout=0.5)
        assert answer == reply(2, 1, 100, 10, 1)
    assert p.stop()[0] == 0
