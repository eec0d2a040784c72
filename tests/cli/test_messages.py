"""Issue 15 item 5: errors that help - one line, the cause once, the likely fix (docs/cli.md).

Real parts: a device path that does not exist, files that do not exist, a TCP peer that closes.
"""
from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time

import pytest

from opentmcl.host.errors import TmclConnectionError
from opentmcl.host.transports.tcp import TcpTransport

SIM = "sim://TMCM-6212"


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], capture_output=True, text=True, timeout=120)


def one_line(done: subprocess.CompletedProcess[str]) -> str:
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    return lines[0]


@pytest.mark.skipif(sys.platform == "win32", reason="a POSIX device path")
def test_a_missing_serial_port_lists_the_ports_that_exist_and_says_the_cause_once(tmp_path):
    """pyserial words it "[Errno 2] could not open port X: [Errno 2] No such file or directory: 'X'";
    we say the cause once and list the ports pyserial's list_ports finds (or that there are none)."""
    from serial.tools import list_ports

    missing = tmp_path / "ttyUSB-none"
    done = cli("send", "GAP 1, 0", "--to", f"serial://{missing}")
    line = one_line(done)
    assert done.returncode == 3
    assert line == f"opentmcl send: error: cannot open serial port {missing}: No such file or directory; " + (
        "serial ports here: " + ", ".join(sorted(p.device for p in list_ports.comports()))
        if list_ports.comports() else "no serial port found here: is the adapter plugged in?")
    assert "Errno" not in line


@pytest.mark.parametrize("command", [["load", "--to", SIM], ["run"], ["plot", "-o", "out.png"]])
def test_a_missing_program_file_is_a_file_error_without_a_fake_position(tmp_path, command):
    """Old code: `missing.tmc:0:0: cannot read file: ...` (an assembler position for a file that was
    never read)."""
    missing = tmp_path / "missing.tmc"
    done = cli(command[0], str(missing), *command[1:])
    line = one_line(done)
    assert done.returncode == 2
    assert line == f"opentmcl {command[0]}: error: cannot read {missing}: No such file or directory"


def test_a_directory_given_as_program_is_named_so(tmp_path):
    done = cli("load", str(tmp_path), "--to", SIM)
    assert done.returncode == 2 and ":0:0" not in one_line(done) and f"cannot read {tmp_path}" in one_line(done)


def test_a_connection_the_peer_closed_is_a_sentence_not_an_errno():
    """The dashboard console showed `send failed: [Errno 32] Broken pipe`: the text of the
    transport's TmclConnectionError, which the console passes on (web/service.py)."""
    server = socket.create_server(("127.0.0.1", 0))

    def accept_and_close():
        conn, _ = server.accept()
        conn.close()

    closer = threading.Thread(target=accept_and_close, daemon=True)
    closer.start()
    t = TcpTransport("127.0.0.1", server.getsockname()[1])
    closer.join(5)
    try:
        with pytest.raises(TmclConnectionError) as err:
            for _ in range(200):   # the first write may still reach the kernel; a later one fails
                t.send(b"\x01\x06\x01\x00\x00\x00\x00\x00\x08")
                time.sleep(0.01)
    finally:
        t.close()
        server.close()
    text = str(err.value)
    assert "Errno" not in text and "failed" not in text
    assert text.startswith(f"{t.name}: the other end closed the connection while sending; check that")


def test_a_refused_tcp_connection_names_the_likely_fix():
    """Issue 15 item 5: "the cause once, and the likely fix": a port where nothing listens is refused
    by the peer; the line says so once and points at the server that would answer (exit 3, docs/cli.md)."""
    with socket.socket() as s:   # a loopback port that was free a moment ago: nothing listens there
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    done = cli("send", "GAP 1, 0", "--to", f"tcp://127.0.0.1:{port}")
    line = one_line(done)
    assert done.returncode == 3
    assert line == (f"opentmcl send: error: tcp://127.0.0.1:{port}: connection refused; is a TMCL server "
                    f"listening on port {port} (e.g. `opentmcl serve --tcp 127.0.0.1:{port}`)?")


def _silent_server() -> tuple[socket.socket, list]:
    """A real TCP peer that accepts and never answers (a module at another address)."""
    server = socket.create_server(("127.0.0.1", 0))
    held: list = []
    threading.Thread(target=lambda: held.append(server.accept()), daemon=True).start()
    return server, held


@pytest.mark.parametrize("command", ["load", "run", "debug"])
def test_no_reply_while_finding_the_module_type_does_not_send_the_user_to_module(tmp_path, command):
    """Issue 15 item 5: "for no reply name the address, baud rate and host address to check". When
    the version request (136) goes unanswered, giving --module would only move the same silence to
    the next request: the line is the no-reply error with its checks, once, and no "give --module"."""
    source = tmp_path / "p.tmc"
    source.write_text("STOP\n")
    server, held = _silent_server()
    try:
        done = cli(command, str(source), "--to", f"tcp://127.0.0.1:{server.getsockname()[1]}",
                   "--address", "5", "--timeout", "0.3")
    finally:
        server.close()
        for conn, _ in held:
            conn.close()
    line = one_line(done)
    assert done.returncode == 3
    assert "give --module" not in line and "cannot tell the module type" not in line
    assert "no reply from module 5" in line and line.count("check ") == 1 and "GP66" in line


def test_a_server_that_closes_at_once_names_the_likely_fix():
    """Issue 15 item 5: "one line, the cause once, and the likely fix". `opentmcl serve` closes a
    client beyond --max-clients at once (docs/endpoints.md); the client's line says what to check."""
    server = socket.create_server(("127.0.0.1", 0))

    def accept_and_close():
        conn, _ = server.accept()
        conn.shutdown(socket.SHUT_WR)   # an orderly close: the client reads end of stream
        time.sleep(2)
        conn.close()

    threading.Thread(target=accept_and_close, daemon=True).start()
    try:
        done = cli("send", "GAP 1, 0", "--to", f"tcp://127.0.0.1:{server.getsockname()[1]}", "--timeout", "1")
    finally:
        server.close()
    line = one_line(done)
    assert done.returncode == 3
    assert line.endswith(": connection closed by the server; check that it is still running, has room for "
                         "another client and keeps idle ones (opentmcl serve --max-clients, --idle-timeout 0), "
                         "then connect again")


@pytest.mark.parametrize("command", [("demo", "--scenario"), ("run", "PROG", "--scenario"),
                                     ("serve", "-m", "TMCM-6212", "--tcp", "127.0.0.1:0", "--scenario")])
@pytest.mark.parametrize("kind", ["missing", "syntax"])
def test_a_scenario_file_error_names_the_file_once(tmp_path, command, kind):
    """Issue 15 item 5: "one line, the cause once". `demo --scenario missing.toml` said `cannot use
    scenario missing.toml: cannot read scenario missing.toml: ...`: the file is named once."""
    program = tmp_path / "p.tmc"
    program.write_text("STOP\n")
    scenario = tmp_path / "world.toml"
    if kind == "syntax":
        scenario.write_text("this is = = not toml\n")
    args = [str(program) if a == "PROG" else a for a in command]
    done = cli(*args, str(scenario))
    line = one_line(done)
    assert done.returncode == 2 and line.count(str(scenario)) == 1, line
    if kind == "missing":
        assert line.endswith(f"cannot read scenario {scenario}: No such file or directory")



def test_bytes_that_are_no_reply_name_the_likely_fix():
    """Issue 15 item 5: "the cause once, and the likely fix". A peer that answers nine bytes whose
    checksum is wrong (TMCM-6212 manual 3.1.1: "adding up all bytes (including the module address
    byte) using 8-bit addition") is no TMCL module at that baud rate: exit 3, and what to check."""
    server = socket.create_server(("127.0.0.1", 0))

    def answer_garbage():
        conn, _ = server.accept()
        conn.recv(9)
        conn.sendall(b"\xff" * 9)
        time.sleep(2)
        conn.close()

    threading.Thread(target=answer_garbage, daemon=True).start()
    try:
        done = cli("send", "GAP 1, 0", "--to", f"tcp://127.0.0.1:{server.getsockname()[1]}", "--timeout", "1")
    finally:
        server.close()
    line = one_line(done)
    assert done.returncode == 3 and "reply to GAP 1, 0 from module 1 with a wrong checksum: ff ff ff ff ff ff ff ff ff" in line
    assert line.endswith("check the baud rate (serial), that the port or socket leads to a TMCL module "
                         "and that one host talks at a time")


@pytest.mark.parametrize("command", [("serve", "-m", "TMCM-6212"), ("proxy", "--to", SIM)])
def test_a_tcp_port_in_use_names_the_likely_fix_without_the_errno(command):
    """Issue 15 item 5: "one line, the cause once, and the likely fix". A port another program
    listens on said `cannot start server: [Errno 98] Address already in use`."""
    held = socket.create_server(("127.0.0.1", 0))
    spec = f"127.0.0.1:{held.getsockname()[1]}"
    try:
        done = cli(*command, "--tcp", spec)
    finally:
        held.close()
    line = one_line(done)
    assert done.returncode == 2 and "Errno" not in line
    assert f"Address already in use (--tcp {spec}); another program" in line
    assert line.endswith("listens there: stop it or choose another port")
