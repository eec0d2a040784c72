"""Which reply each request returns, at run time and for the type checker (TMCM-6212 manual 3.2,
3.6.36 Table 13).

Table 13: 134 "Return contents of the specified program memory location (special reply format)";
136 "Return firmware version in string format (special reply) or binary format"; 137 "This
command does not send a reply". Every other command is answered in the reply format of 3.2.
"""
from __future__ import annotations

import tempfile
import textwrap
from pathlib import Path

import pytest
from mypy import api as mypy_api

import opentmcl
from opentmcl.host import Client, TmclValueError, VersionReply
from opentmcl.host.loader import Loader
from opentmcl.host.transports.inprocess import InProcessTransport
from opentmcl.protocol.frame import Reply, Request
from opentmcl.protocol.replies import MemoryReply

SRC = Path(__file__).resolve().parents[2] / "src"


class Recording(InProcessTransport):
    """The in-process transport, remembering the bytes sent."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)
        self.sent: list[bytes] = []

    def send(self, data: bytes) -> None:
        self.sent.append(bytes(data))
        super().send(data)


@pytest.fixture
def wire():
    vm = opentmcl.VirtualModule("TMCM-6212", address=1)
    t = Recording(vm, clock="virtual")
    client = Client(t)
    yield vm, t, client
    client.close()


@pytest.mark.parametrize(("command", "type_"), [(134, 0), (136, 0), (137, 0)])
def test_loader_request_refuses_the_special_replies_before_sending(wire, command, type_):
    """`Loader.request` returns a `Reply`: 134 (special reply format), 136 type 0 (string) and
    137 ("does not send a reply") do not give one, so they are refused and nothing is sent -
    137 would reset the EEPROM to its factory defaults."""
    vm, t, client = wire
    with pytest.raises(TmclValueError, match=f"command {command} type {type_} has no reply"):
        Loader(client).request(command, type_, 0, 1234)
    assert t.sent == []


def test_client_reply_and_read_memory(wire):
    """`Client.reply` is `request` for the 3.2 format only; `read_memory` sends 134. 136 type 1,
    "binary format", is the edge next to the refused string format."""
    vm, t, client = wire
    assert client.reply(6, 4, 0).value == vm.request(6, 4, 0).value
    with pytest.raises(TmclValueError):
        client.reply(134)
    assert t.sent == [Request(1, 6, 4, 0, 0).encode()]
    assert isinstance(Loader(client).request(136, 1), Reply)
    Loader(client).download([(5, 4, 0, 51200)], verify=False)
    stored = client.read_memory(0)
    assert isinstance(stored, MemoryReply)
    assert (stored.command, stored.type, stored.motor, stored.value) == (5, 4, 0, 51200)
    assert t.sent[-1] == Request(1, 134, 0, 0, 0).encode()
    assert isinstance(client.request(136, 0), VersionReply)
    assert client.request(137, 0, 0, 1234) is None


SNIPPET = """
    from typing import assert_type

    from opentmcl.host.client import Client, VersionReply
    from opentmcl.host.loader import Loader
    from opentmcl.host.module import Module
    from opentmcl.protocol.frame import Reply
    from opentmcl.protocol.replies import MemoryReply

    Any_reply = Reply | VersionReply | MemoryReply | None

    def check(c: Client, m: Module, ld: Loader, frame: bytes) -> None:
        assert_type(c.send_raw(frame), Any_reply)
        assert_type(c.request(134), Any_reply)
        assert_type(m.request(134), Any_reply)
        assert_type(c.reply(6), Reply)
        assert_type(c.read_memory(0), MemoryReply)
        assert_type(ld.request(6), Reply)
"""


def test_annotations_admit_every_reply_a_request_can_return(tmp_path, monkeypatch):
    """`Client.send_raw` forwards any frame, so a 134 frame returns a MemoryReply: its annotation
    (and `Client.request`'s, `Module.request`'s) includes it; the narrow methods are typed narrow.
    Checked by mypy on a snippet that uses them."""
    snippet = tmp_path / "snippet.py"
    snippet.write_text(textwrap.dedent(SNIPPET))
    monkeypatch.setenv("MYPYPATH", str(SRC))  # these sources, not the installed package
    with tempfile.TemporaryDirectory() as cache:
        out, err, status = mypy_api.run(["--cache-dir", cache, "--no-error-summary", "--config-file", "",
                                         "--follow-imports", "silent", "--python-version", "3.11",
                                         str(snippet)])
    assert status == 0, out + err
