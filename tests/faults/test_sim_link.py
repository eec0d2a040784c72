"""Link faults on an in-process link, ``sim://NAME?faults=FILE`` (issue 34, "Link faults ... and
in-process (sim://)"), each checked through the wire (what the host receives, what GAP reads back
afterwards) in virtual time. Manual references: TMCM-6212 manual 3.1 (request frame), 3.2 and
3.2.1 (reply, status 1 "wrong checksum"); the frame-gap rule of a served module (server/framer.py)."""
from __future__ import annotations

import pytest

from opentmcl.host import TmclChecksumError, TmclStatusError, TmclTimeout

from .helpers import GAP, SAP, now, sim

DEFAULT_AP4 = 51200   # TMCM-6212 AP4 default (maximum positioning speed), modules/data/tmcm6212.toml


def test_a_dropped_request_never_reaches_the_module(tmp_path):
    """drop_request on the first SAP: no reply (timeout), and GAP reads the value of before."""
    m = sim(tmp_path, [{"kind": "drop_request", "command": "SAP", "count": 1}])
    with pytest.raises(TmclTimeout, match="SAP 4, 0, 777"):
        m.request(SAP, 4, 0, 777)
    assert m.request(GAP, 4, 0).value == DEFAULT_AP4
    m.request(SAP, 4, 0, 778)                   # once only (count)
    assert m.request(GAP, 4, 0).value == 778


def test_a_dropped_reply_leaves_the_request_done(tmp_path):
    """drop_reply on the first SAP: no reply, but the module did it (GAP reads the new value)."""
    m = sim(tmp_path, [{"kind": "drop_reply", "command": "SAP", "count": 1}])
    with pytest.raises(TmclTimeout):
        m.request(SAP, 4, 0, 777)
    assert m.request(GAP, 4, 0).value == 777


def test_the_reply_to_the_third_mvp_is_dropped(tmp_path):
    """The issue's example, "drop the reply to the third MVP": the first two and the fourth answer."""
    m = sim(tmp_path, [{"kind": "drop_reply", "command": "MVP", "count": 3}])
    outcomes = []
    for target in (100, 200, 300, 400):
        try:
            outcomes.append(m.request(4, 0, 0, target).status)
        except TmclTimeout:
            outcomes.append("timeout")
    assert outcomes == [100, 100, "timeout", 100]


def test_a_garbled_request_is_answered_with_status_1(tmp_path):
    """corrupt_request, the value's last byte flipped: the module answers status 1 ("wrong
    checksum", manual 3.2.1) and does nothing."""
    m = sim(tmp_path, [{"kind": "corrupt_request", "command": "SAP", "count": 1, "byte": 7}])
    with pytest.raises(TmclStatusError) as info:
        m.request(SAP, 4, 0, 777)
    assert info.value.status == 1 and info.value.request.value == 777
    assert m.request(GAP, 4, 0).value == DEFAULT_AP4


def test_a_garbled_reply_is_a_checksum_error_naming_the_request(tmp_path):
    """corrupt_reply: the host sees a bad checksum (manual 3.1.1) and raises TmclChecksumError for
    that request; the next request gets its own reply."""
    m = sim(tmp_path, [{"kind": "corrupt_reply", "command": "GAP", "count": 1}])
    m.request(SAP, 4, 0, 4321)
    with pytest.raises(TmclChecksumError, match="GAP 4, 0"):
        m.request(GAP, 4, 0)
    assert m.request(GAP, 4, 0).value == 4321


def test_a_delayed_reply_arrives_late(tmp_path):
    """delay 0.2 s with jitter 0.05 s: the reply comes, 0.15..0.25 virtual seconds later; a
    delay beyond the timeout is a timeout, and the late reply is not taken for the next request."""
    m = sim(tmp_path, [{"kind": "delay", "command": "GAP", "count": 1, "delay": 0.2, "jitter": 0.05},
                       {"kind": "delay", "command": "GGP", "count": 1, "delay": 2.0}])
    t0 = now(m)
    assert m.request(GAP, 4, 0).value == DEFAULT_AP4
    assert 0.15 <= now(m) - t0 <= 0.25
    with pytest.raises(TmclTimeout):
        m.request(10, 66, 0)
    with pytest.raises(TmclTimeout, match="was not sent"):  # replies keep their order: all wait behind it
        m.request(SAP, 4, 0, 5)
    m.client.sleep(2.0)
    m.request(SAP, 4, 0, 5)
    assert m.request(GAP, 4, 0).value == 5
    assert m.request(10, 66, 0).value == 1


@pytest.mark.parametrize(("gap", "arrives"), [(0.05, True), (0.1, True), (0.11, False)])
def test_a_request_in_pieces_meets_the_frame_gap_rule(tmp_path, gap, arrives):
    """split_request into 3 pieces: with gaps up to the frame gap (0.1 s, server/framer.py) the
    module assembles the frame; a longer gap drops the partial frame: no reply, nothing done."""
    m = sim(tmp_path, [{"kind": "split_request", "command": "SAP", "count": 1, "pieces": 3, "gap": gap}])
    if arrives:
        t0 = now(m)
        assert m.request(SAP, 4, 0, 999).status == 100
        assert now(m) - t0 >= 2 * gap
        assert m.request(GAP, 4, 0).value == 999
    else:
        with pytest.raises(TmclTimeout):
            m.request(SAP, 4, 0, 999)
        assert m.request(GAP, 4, 0).value == DEFAULT_AP4


def test_a_reply_in_pieces_is_read_whole(tmp_path):
    """split_reply into 4 pieces 0.03 s apart: the host reads the reply when its last piece came."""
    m = sim(tmp_path, [{"kind": "split_reply", "command": "GAP", "count": 1, "pieces": 4, "gap": 0.03}])
    t0 = now(m)
    assert m.request(GAP, 4, 0).value == DEFAULT_AP4
    assert now(m) - t0 >= 0.09 - 1e-9


def test_a_link_down_for_a_time(tmp_path):
    """link_down for 1 s from the first GGP: that request, and a SAP 0.5 s later, are lost; after
    the second the link carries again."""
    m = sim(tmp_path, [{"kind": "link_down", "command": "GGP", "count": 1, "duration": 1.0}])
    with pytest.raises(TmclTimeout):
        m.request(10, 66, 0)
    with pytest.raises(TmclTimeout):
        m.request(SAP, 4, 0, 3)
    m.client.sleep(0.5)
    assert m.request(GAP, 4, 0).value == DEFAULT_AP4
    assert m.client.transport.faults.log.fired[0].detail.startswith("link down for 1 s")


def test_a_fault_at_a_time(tmp_path):
    """`at`: the first request from that (virtual) time on is the one that is dropped."""
    m = sim(tmp_path, [{"kind": "drop_reply", "at": 2.0}])
    m.request(GAP, 4, 0)
    m.client.sleep(1.0)
    m.request(GAP, 4, 0)
    m.client.sleep(1.5)
    with pytest.raises(TmclTimeout):
        m.request(GAP, 4, 0)
    m.request(GAP, 4, 0)


def test_the_same_seed_gives_the_same_run(tmp_path):
    """"All are reproducible from a seed": two links with the same plan and seed lose the same
    requests; another seed loses others."""
    def losses(seed: int) -> list[int]:
        m = sim(tmp_path, [{"kind": "drop_reply", "probability": 0.2}], seed=seed)
        out = []
        for i in range(60):
            try:
                m.request(GAP, 4, i % 6)
            except TmclTimeout:
                out.append(i)
        return out
    first = losses(7)
    assert 3 <= len(first) <= 30
    assert losses(7) == first
    assert losses(8) != first
