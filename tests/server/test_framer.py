"""The serial framer: 9-byte frames out of a byte stream, resynchronised by silence."""
import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.server.framer import SerialFramer

# TMCM-6212 manual 3.6.8 example: GGP 66, 0 = 01 0A 42 00 00 00 00 00 4D
GGP_66 = bytes.fromhex("010A4200000000004D")
# TMCM-6212 manual 3.6.7 example: SGP 66, 0, 3 = 01 09 42 00 00 00 00 03 4F
SGP_66_3 = bytes.fromhex("01094200000000034F")


def test_frame_split_over_chunks_is_assembled():
    """Manual 3.1: a command is nine bytes; they may arrive in pieces."""
    f = SerialFramer(gap=0.1)
    assert f.feed(GGP_66[:4], 0.0) == []
    assert f.pending == 4
    assert f.feed(GGP_66[4:], 0.01) == [GGP_66]
    assert f.pending == 0


def test_two_frames_in_one_chunk():
    """Manual 3.1: back-to-back nine-byte commands are split at nine bytes."""
    f = SerialFramer(gap=0.1)
    assert f.feed(GGP_66 + SGP_66_3, 0.0) == [GGP_66, SGP_66_3]


def test_truncated_frame_is_dropped_after_a_gap():
    """A truncated command followed by silence longer than the gap is discarded;
    the next command (manual 3.6.8 example) is framed correctly."""
    f = SerialFramer(gap=0.1)
    assert f.feed(SGP_66_3[:5], 0.0) == []
    assert f.feed(GGP_66, 0.2) == [GGP_66]
    assert f.dropped == 5


def test_partial_frame_within_the_gap_is_kept():
    """Silence up to the gap does not break a frame (bytes of one command)."""
    f = SerialFramer(gap=0.1)
    f.feed(GGP_66[:3], 0.0)
    assert f.feed(GGP_66[3:], 0.1) == [GGP_66]


def test_garbage_without_gap_shifts_until_silence_then_resynchronises():
    """Without a start marker (manual 3.1) stray bytes shift the framing until the
    line falls silent; the host's retry after its timeout is then framed correctly."""
    f = SerialFramer(gap=0.05)
    out = f.feed(b"\xff\xfe" + GGP_66, 0.0)
    assert out == [b"\xff\xfe" + GGP_66[:7]]
    assert f.pending == 2
    assert f.feed(GGP_66, 1.0) == [GGP_66]


def test_expire_and_deadline():
    f = SerialFramer(gap=0.1)
    assert f.deadline() is None
    f.feed(b"\x01\x02", 1.0)
    assert f.deadline() == pytest.approx(1.1)
    f.expire(1.05)
    assert f.pending == 2
    f.expire(1.2)
    assert f.pending == 0 and f.deadline() is None


def test_bad_arguments_raise():
    with pytest.raises(ValueError):
        SerialFramer(gap=0)
    for gap in (float("nan"), float("inf")):  # a partial frame would never expire: the port could wedge
        with pytest.raises(ValueError):
            SerialFramer(gap=gap)
    with pytest.raises(ValueError):
        SerialFramer(frame_len=0)


@given(chunks=st.lists(st.binary(max_size=40), max_size=20),
       times=st.lists(st.floats(min_value=0, max_value=0.04), max_size=20))
def test_any_stream_then_silence_then_frame_yields_that_frame(chunks, times):
    """Whatever came before, a well-formed command sent after a silent gap is
    framed exactly (manual 3.6.8 example GGP 66, 0)."""
    f = SerialFramer(gap=0.05)
    now = 0.0
    for i, chunk in enumerate(chunks):
        now += times[i] if i < len(times) else 0.01
        for frame in f.feed(chunk, now):
            assert len(frame) == 9
    assert f.feed(GGP_66, now + 0.06) == [GGP_66]
