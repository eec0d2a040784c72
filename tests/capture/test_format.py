"""Capture files: bounded, checked reads with one-line errors (capture/format.py, docs/capture.md)."""
from __future__ import annotations

import json

import pytest

from opentmcl.capture import MAX_LINE_BYTES, CaptureError, read_capture
from opentmcl.capture import format as fmt

from .helpers import cli

HEADER = {"record": "header", "format": "opentmcl-capture", "version": 1, "tool": "t", "target": "sim://x"}
FRAME = {"record": "frame", "n": 1, "t": 0.5, "dir": "host", "kind": "request", "raw": "01 0a 42 00 00 00 00 00 4d",
         "address": 1, "command": 10, "type": 66, "motor": 0, "value": 0}


def write(path, *records, extra=b""):
    path.write_bytes(b"".join(json.dumps(r).encode() + b"\n" for r in records) + extra)
    return path


def test_reads_header_frames_and_identity(tmp_path):
    cap = read_capture(write(tmp_path / "c.jsonl", HEADER, FRAME,
                             {"record": "identity", "address": 1, "module": "TMCM-6212"}))
    assert cap.frames[0]["bytes"] == bytes.fromhex("010A4200000000004D") and cap.module_name() == "TMCM-6212"


@pytest.mark.parametrize("content, message", [
    (b"", "empty"),
    (b"not json\n", "not a JSON record"),
    (b"[1, 2]\n", "not a JSON object"),
    (json.dumps(FRAME).encode() + b"\n", "first record must be its header"),
    (json.dumps({**HEADER, "version": 2}).encode() + b"\n", "format version 2"),
    (json.dumps(HEADER).encode() + b"\n" + json.dumps({**FRAME, "raw": "zz"}).encode() + b"\n", "'raw' is not hex"),
    (json.dumps(HEADER).encode() + b"\n" + json.dumps({**FRAME, "t": "x"}).encode() + b"\n", "valid 't'"),
    (json.dumps(HEADER).encode() + b"\n" + json.dumps({**FRAME, "command": None}).encode() + b"\n",
     "request record without an integer 'command'"),
    (json.dumps(HEADER).encode() + b"\n" + json.dumps({**FRAME, "dir": "up"}).encode() + b"\n", "'dir' must be"),
])
def test_bad_files_are_one_line_errors(tmp_path, content, message):
    path = tmp_path / "bad.jsonl"
    path.write_bytes(content)
    with pytest.raises(CaptureError, match=message):
        read_capture(path)
    done = cli("replay", str(path), "--module", "TMCM-6212")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1 and message in done.stderr


def test_line_at_the_cap_is_read_and_one_byte_more_is_refused(tmp_path):
    """docs/capture.md: lines are at most MAX_LINE_BYTES (newline included)."""
    base = json.dumps({**FRAME, "pad": ""}).encode()
    fits = json.dumps({**FRAME, "pad": "x" * (MAX_LINE_BYTES - len(base) - 1)}).encode() + b"\n"
    assert len(fits) == MAX_LINE_BYTES
    path = tmp_path / "c.jsonl"
    path.write_bytes(json.dumps(HEADER).encode() + b"\n" + fits)
    assert len(read_capture(path).frames) == 1
    longer = json.dumps({**FRAME, "pad": "x" * (MAX_LINE_BYTES - len(base))}).encode() + b"\n"
    path.write_bytes(json.dumps(HEADER).encode() + b"\n" + longer)
    with pytest.raises(CaptureError, match=r"c.jsonl:2: line longer than"):
        read_capture(path)


def test_file_larger_than_the_cap_is_refused_before_reading(tmp_path, monkeypatch):
    path = write(tmp_path / "c.jsonl", HEADER, FRAME)
    monkeypatch.setattr(fmt, "MAX_CAPTURE_BYTES", path.stat().st_size)
    assert read_capture(path).frames
    monkeypatch.setattr(fmt, "MAX_CAPTURE_BYTES", path.stat().st_size - 1)
    with pytest.raises(CaptureError, match="larger than"):
        read_capture(path)


def test_missing_file_and_log_show_of_a_bad_file(tmp_path):
    done = cli("log", "show", str(tmp_path / "none.jsonl"))
    assert done.returncode == 2 and "cannot read" in done.stderr and "Traceback" not in done.stderr
    done = cli("log", "show", str(write(tmp_path / "c.jsonl", HEADER, FRAME)), "--command", "NOPE")
    assert done.returncode == 2 and "unknown TMCL mnemonic" in done.stderr


def test_writer_stops_capturing_at_the_cap_and_the_file_stays_readable(tmp_path):
    """docs/capture.md: a capture never grows past what `read_capture` reads."""
    path = tmp_path / "w.jsonl"
    writer = fmt.CaptureWriter(path, target="sim://x", gap=0.1, tool="t")
    writer.limit = writer.size + 3 * (len(json.dumps({"record": "frame", **FRAME}, separators=(",", ":"))) + 1)
    for i in range(10):
        writer.write({"record": "frame", **FRAME, "n": i})
    writer.close(1.0)
    lines = [json.loads(x) for x in path.read_text().splitlines()]
    assert [r["record"] for r in lines] == ["header", "frame", "frame", "frame", "truncated", "end"]
    assert len(read_capture(path).frames) == 3 and lines[-1]["frames"] == 3


def test_a_torn_last_line_is_skipped_with_a_warning(tmp_path):
    """Issue 30 item 4: a capture cut mid-line (a pulled cable, a full disk) keeps every complete
    record: the torn last line is skipped with a one-line warning naming it, `replay` and `log show`
    go on (exit 0 here, not 2)."""
    reply = {"record": "frame", "n": 2, "t": 0.6, "dir": "module", "kind": "reply", "address": 1, "status": 100,
             "command": 10, "value": 1, "request": 1, "raw": "02 01 64 0a 00 00 00 01 72"}
    whole = json.dumps(reply).encode()
    for cut in (1, len(whole) // 2, len(whole) - 1):   # the first byte, the middle, all but the "}"
        path = write(tmp_path / "torn.jsonl", HEADER, FRAME, reply, extra=whole[:cut])
        cap = read_capture(path)
        assert len(cap.frames) == 2 and cap.warnings == [
            f"{path}:4: torn last line skipped ({cut} bytes without an end: the capture was cut off)"]
    for args in (("replay", str(path), "--module", "TMCM-6212"), ("log", "show", str(path))):
        done = cli(*args)
        assert done.returncode == 0, done.stderr
        assert done.stderr.count("torn last line skipped") == 1 and f"{path}:4:" in done.stderr


def test_a_torn_line_before_the_end_is_an_error_with_its_line_number(tmp_path):
    """Issue 30 item 4: only the last line may be torn; anywhere else it is an error (exit 2) naming
    the line; a complete last record without its newline is no torn line."""
    torn = json.dumps(FRAME).encode()[:20]
    path = tmp_path / "bad.jsonl"
    path.write_bytes(json.dumps(HEADER).encode() + b"\n" + torn + b"\n" + json.dumps(FRAME).encode() + b"\n")
    with pytest.raises(CaptureError, match=r"bad.jsonl:2: not a JSON record"):
        read_capture(path)
    done = cli("log", "show", str(path))
    assert done.returncode == 2 and "bad.jsonl:2: not a JSON record" in done.stderr
    path.write_bytes(json.dumps(HEADER).encode() + b"\n" + json.dumps(FRAME).encode())
    cap = read_capture(path)
    assert len(cap.frames) == 1 and cap.warnings == []
    path.write_bytes(json.dumps(HEADER).encode()[:10])
    with pytest.raises(CaptureError, match=r"bad.jsonl:1: not a capture file \(its only line is cut off\)"):
        read_capture(path)
