"""Bad and bulky input to the capture tools (issue 28 item 5):

- "a capture identity record whose `module` is a list gives "internal error: TypeError"";
- "a capture line of 4000 `[` gives an untyped RecursionError";
- "the capture size cap is bypassed by one identity record per 136 reply: capped at 300,000 B, the
  file reached 557,720 B and `replay` then refused the whole capture";
- "the capture decoder keeps only 16 pending requests, so a host that pipelines more has its
  replies paired with the wrong requests".

docs/capture.md: a reply is paired with the oldest waiting request of the same command; a capture
is never written larger than `read_capture` reads; every error is one line naming file and line
(exit 2). TMCM-6212 manual 3.1/3.2 (request and reply frames), 3.6.6 (GAP), PD86-1180 manual
4.6.39 (136 type 0: the eight-character version string).
"""
from __future__ import annotations

import json
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from opentmcl.capture import CaptureError, read_capture, replay
from opentmcl.capture import format as fmt
from opentmcl.capture.decode import HOST, MAX_PENDING, MODULE, Decoder
from opentmcl.capture.proxy import Proxy, ProxySession
from opentmcl.modules.profile import load_profile
from opentmcl.protocol.frame import Reply
from opentmcl.server import TcpServer

from .helpers import frame

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "captures" / "tmcm6212_program_reference_events.jsonl"
GAP_TYPES = sorted(load_profile("TMCM-6212").axis_parameters)   # 72 axis parameters (manual 4.1)


def cli(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "opentmcl", *map(str, args)], capture_output=True, text=True,
                          timeout=120, stdin=subprocess.DEVNULL)


def one_line(done: subprocess.CompletedProcess, *words: str) -> None:
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2, done.stderr[-500:]
    assert len(lines) == 1 and "Traceback" not in done.stderr and "internal error" not in done.stderr, done.stderr
    for word in words:
        assert word in lines[0], lines[0]


# --- bad records ----------------------------------------------------------------------------------
@pytest.mark.parametrize(("old", "new", "message"), [
    ('"module":"TMCM-6212"', '"module":["TMCM-6212"]', "'module' is not a module name"),
    ('"module":"TMCM-6212"', '"module":{"name":1}', "'module' is not a module name"),
    ('"address":1,"firmware_version"', '"address":"1","firmware_version"', "'address' is not an address"),
    ('"firmware_version":"6212V105"', '"firmware_version":6212', "'firmware_version' is not a firmware string"),
])
def test_an_identity_record_of_the_wrong_types_is_one_line(tmp_path, old, new, message):
    """The example capture's identity record (line 4) with a list, a table or a number where
    docs/capture.md has a string or an integer: CaptureError naming the line, exit 2 from
    `replay` and `log show` (before: internal error TypeError)."""
    text = EXAMPLE.read_text()
    assert text.count(old) == 1
    path = tmp_path / "id.jsonl"
    path.write_text(text.replace(old, new))
    with pytest.raises(CaptureError, match=f"id.jsonl:4: identity record: {message}"):
        read_capture(path)
    one_line(cli("replay", path), "id.jsonl:4", message)
    one_line(cli("log", "show", path), "id.jsonl:4", message)


def test_a_line_nested_4000_deep_is_one_line(tmp_path):
    """4000 "[" fit in a 4096-byte line; json.loads runs out of stack on them (RecursionError).
    Now a CaptureError naming the line, exit 2."""
    path = tmp_path / "deep.jsonl"
    path.write_text(EXAMPLE.read_text().splitlines()[0] + "\n" + "[" * 4000 + "\n")
    with pytest.raises(CaptureError, match="deep.jsonl:2: not a capture record"):
        read_capture(path)
    one_line(cli("replay", path), "deep.jsonl:2", "nested too deeply")
    one_line(cli("log", "show", path), "deep.jsonl:2", "nested too deeply")


# --- pipelined requests ---------------------------------------------------------------------------
def pipelined(count: int) -> tuple[list[dict], list[dict]]:
    """`count` GAP requests of distinct axis parameters in one chunk, then their replies in order
    (a module answers in order, manual 3.2); value = the parameter number."""
    prof = load_profile("TMCM-6212")
    d = Decoder(lambda address: prof, gap=0.1)
    types = [GAP_TYPES[i % len(GAP_TYPES)] for i in range(count)]
    requests = d.feed(1.0, HOST, b"".join(frame(6, t) for t in types))
    replies = d.feed(1.5, MODULE, b"".join(Reply(2, 1, 100, 6, t).encode() for t in types))
    return requests, replies


def test_more_than_16_pipelined_requests_are_paired_in_order():
    """40 GAPs in one chunk (old code kept 16 and paired reply 1 with request 25): reply k pairs
    with request k, its parameter name and latency with it."""
    requests, replies = pipelined(40)
    assert len(requests) == len(replies) == 40
    assert [r["request"] for r in replies] == [q["n"] for q in requests]
    assert [r["parameter"] for r in replies] == [q["parameter"] for q in requests]
    assert all(r["latency"] == 0.5 for r in replies)


def test_pending_requests_stay_bounded_at_max_pending():
    """docs/capture.md: up to MAX_PENDING requests wait for their replies; one more and the oldest
    is forgotten (a host that never reads its replies cannot grow the decoder without bound)."""
    requests, replies = pipelined(MAX_PENDING)
    assert [r["request"] for r in replies] == [q["n"] for q in requests]
    requests, replies = pipelined(MAX_PENDING + 1)
    assert requests[0]["n"] not in {r.get("request") for r in replies}


def talk(address, data: bytes, expect: int) -> bytes:
    with socket.create_connection(address, timeout=10) as sock:
        sock.sendall(data)
        got = b""
        deadline = time.monotonic() + 30
        while len(got) < expect and time.monotonic() < deadline:
            got += sock.recv(65536)
    return got


@pytest.fixture
def proxy_of(tmp_path):
    """A real proxy in this process: a TCP front (as `opentmcl proxy --tcp`) and a served virtual
    TMCM-6212 behind it (sim://), capturing to c.jsonl."""
    made = []

    def make():
        proxy = Proxy("sim://TMCM-6212", log=str(tmp_path / "c.jsonl"))
        front = proxy.listen(TcpServer(proxy, "127.0.0.1", 0, session=ProxySession))
        proxy.start()
        made.append(proxy)
        return proxy, front.address

    yield make
    for proxy in made:
        proxy.stop()


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX")
def test_a_host_that_pipelines_40_requests_through_the_proxy_gets_them_paired(tmp_path, proxy_of):
    """The same through a real proxy and served module: 40 GAPs written at once."""
    proxy, address = proxy_of()
    types = GAP_TYPES[:40]
    got = talk(address, b"".join(frame(6, t) for t in types), 40 * 9)
    proxy.stop()
    assert len(got) == 40 * 9
    frames = read_capture(tmp_path / "c.jsonl").frames
    requests = [r for r in frames if r["kind"] == "request"]
    replies = [r for r in frames if r["kind"] == "reply"]
    assert [r["request"] for r in replies] == [q["n"] for q in requests]
    assert [r["parameter"] for r in replies] == [q["parameter"] for q in requests]


# --- the size cap ---------------------------------------------------------------------------------
def test_every_record_counts_against_the_cap(tmp_path):
    """Identity records (one per 136 reply) count as frames do: past the cap nothing but the one
    `truncated` note and the `end` record is written."""
    path = tmp_path / "w.jsonl"
    writer = fmt.CaptureWriter(path, target="sim://x", gap=0.1, tool="t")
    ident = {"record": "identity", "t": 1.0, "address": 1, "firmware_version": "6212V105", "module": "TMCM-6212"}
    writer.limit = writer.size + 3 * (len(json.dumps(ident, separators=(",", ":"))) + 1)
    for _ in range(5):
        writer.write(ident)
    writer.write({"record": "frame", "n": 1, "t": 1.0, "dir": "host", "kind": "garbage", "raw": "01"})
    writer.close(2.0)
    lines = [json.loads(x) for x in path.read_text().splitlines()]
    assert [r["record"] for r in lines] == ["header", "identity", "identity", "identity", "truncated", "end"]
    assert len(read_capture(path).identities) == 3


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX")
def test_a_capped_capture_of_136_polling_stays_under_the_cap_and_replays(tmp_path, proxy_of, monkeypatch):
    """The issue's run: a cap of 300,000 B and a host that asks 136 type 0 over and over (each
    reply adds a version frame and an identity record). The file stays within the cap, ends with
    its `end` record, and reads and replays (before: 557,720 B, refused as a whole)."""
    monkeypatch.setattr(fmt, "MAX_CAPTURE_BYTES", 300_000)
    proxy, address = proxy_of()
    batch = frame(136, 0) * 100
    for _ in range(16):   # 1600 round trips, about 800 kB of records uncapped
        assert len(talk(address, batch, 900)) == 900
    writer = proxy.writer
    proxy.stop()   # the writer thread has written every record it was given
    assert writer.truncated
    path = tmp_path / "c.jsonl"
    assert path.stat().st_size <= 300_000
    records = [json.loads(x)["record"] for x in path.read_text().splitlines()]
    assert records[-2:] == ["truncated", "end"] and records.count("identity") > 100
    cap = read_capture(path)
    assert cap.module_name() == "TMCM-6212" and cap.truncated is not None
    report = replay(cap)   # the last request may have lost its reply to the cap: skipped, not a divergence
    assert report.ok and report.compared > 100, report.text()
