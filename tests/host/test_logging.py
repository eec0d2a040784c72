"""Issue 15 item 3: the ``opentmcl`` logger hierarchy logs every frame at DEBUG as TMCL text plus hex
(docs/host.md "Logging"); nothing is formatted when DEBUG is off; no print() in library code.

The vectors are the manual's instruction forms: "MVP ABS, 0, 51200" is MVP (command 4) type ABS (0)
on motor 0 to 51200 (TMCM-6212 manual 3.6.3), and the reply carries "reply address, module address,
status, command number, value" with status 100 "Successfully executed, no error" (manual 3.2, 3.2.1).
"""
from __future__ import annotations

import ast
import logging
import pathlib

import pytest

import opentmcl
from opentmcl.host import connect
from opentmcl.host import transport as transport_module
from opentmcl.host.transport import frame_text
from opentmcl.protocol.frame import Reply, Request

MVP = Request(1, 4, 0, 0, 51200).encode()          # built by the protocol layer, not by the code under test
MVP_HEX = "[" + MVP.hex(" ") + "]"
PACKAGE = pathlib.Path(opentmcl.__file__).parent


def frames(caplog, name="opentmcl.host.transport"):
    return [r.getMessage() for r in caplog.records if r.name == name and r.levelno == logging.DEBUG]


def test_every_frame_of_a_host_transport_is_logged_as_tmcl_text_and_hex(caplog):
    """In-process link: the request as the manual writes it, the reply with its status text."""
    caplog.set_level(logging.DEBUG, logger="opentmcl")
    with connect("sim://TMCM-6212") as m:
        m.client.request(4, 0, 0, 51200)
    sent, got = frames(caplog)
    assert sent == f"-> MVP ABS, 0, 51200  {MVP_HEX}"
    assert MVP_HEX == "[01 04 00 00 00 00 c8 00 cd]"
    assert got.startswith("<- MVP reply from 1 to 2: status 100 (Successfully executed, no error)")
    assert got.endswith("[" + Reply(2, 1, 100, 4, 0).encode().hex(" ") + "]")


def test_tcp_transport_and_server_log_both_sides(caplog, tcp_url):
    """A real socket: the client's transport logs the frames it sends and receives, the server's
    stream logs what its module read and answered (logger opentmcl.server.stream)."""
    caplog.set_level(logging.DEBUG, logger="opentmcl")
    with connect(tcp_url) as m:
        m.client.request(6, 1, 0, 0)   # GAP 1, 0: actual position
    assert frames(caplog)[0] == "-> GAP 1, 0  [" + Request(1, 6, 1, 0, 0).encode().hex(" ") + "]"
    server = frames(caplog, "opentmcl.server.stream")
    assert server[0].startswith("bus <- GAP 1, 0  [")
    assert server[1].startswith("TMCM-6212 -> GAP reply from 1 to 2: status 100")


def test_can_frames_have_no_address_byte_and_no_checksum():
    """CAN requests are eight bytes, replies seven (PD86-1180 manual 4.2: "the first byte (reply
    address) and the last byte (checksum) are left out")."""
    assert frame_text(MVP[1:], "can") == f"MVP ABS, 0, 51200  [{MVP[1:].hex(' ')}]"
    reply = Reply(2, 1, 100, 4, 0).encode()[1:8]
    assert frame_text(reply, "can", request=False).startswith("MVP reply from 1: status 100")


def test_what_is_not_one_frame_is_shown_as_bytes_only():
    """A wrong checksum and a part of a frame are not decoded as a reply."""
    bad = MVP[:8] + bytes([(MVP[8] + 1) & 0xFF])
    assert frame_text(bad) == f"[{bad.hex(' ')}]"
    assert frame_text(MVP[:5]) == f"[{MVP[:5].hex(' ')}]"


def test_the_version_string_reply_is_text_plus_hex():
    """Issue 15 item 3: "every frame at DEBUG as TMCL text plus hex". TMCM-6212 manual table 13:
    136 type 0 "Return firmware version in string format (special reply)": the host address and
    eight characters, which the log shows as text too; the same bytes sent as a request are not."""
    version = b"\x02" + b"6212V105"
    assert frame_text(version, request=False) == f'version "6212V105" to 2  [{version.hex(" ")}]'
    assert frame_text(version, request=True) == f"[{version.hex(' ')}]"
    assert frame_text(b"\x02" + b"6212V10\x1f", request=False).startswith("[")   # not printable


def test_nothing_is_formatted_while_debug_is_off(monkeypatch, caplog):
    """The hot path pays one isEnabledFor check: with DEBUG off the formatter is never called."""
    caplog.set_level(logging.WARNING, logger="opentmcl")

    def boom(*args, **kwargs):
        raise AssertionError("frame formatted with logging off")

    monkeypatch.setattr(transport_module, "frame_text", boom)
    with connect("sim://TMCM-6212") as m:
        assert m.client.request(6, 1, 0, 0).value == 0
    caplog.set_level(logging.DEBUG, logger="opentmcl")
    with connect("sim://TMCM-6212") as m, pytest.raises(AssertionError, match="logging off"):
        m.client.request(6, 1, 0, 0)


def test_the_loggers_form_one_hierarchy():
    """Every logger of the package is a child of ``opentmcl`` (logging.getLogger("opentmcl") sets
    the level of all of them)."""
    names = set()
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if (isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "getLogger" and node.args
                    and isinstance(node.args[0], ast.Constant)):
                names.add(node.args[0].value)
    ours = {n for n in names if n.startswith("opentmcl")}
    assert {"opentmcl.host.transport", "opentmcl.server.stream", "opentmcl.server.can"} <= ours
    assert all(n == "opentmcl" or n.startswith("opentmcl.") for n in ours), ours


SCRIPTS = {"lang/gen_includes.py"}  # `python -m` developer scripts, not library code


def test_no_print_in_library_code():
    """Issue 15: "no print() in library code": outside opentmcl/cli only log records and warnings
    (the CLI prints). AST scan of the installed package; docstring examples do not count."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        if rel.startswith("cli/") or rel in SCRIPTS:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "print":
                found.append(f"{rel}:{node.lineno}")
    assert found == []
