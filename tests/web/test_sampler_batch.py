"""The dashboard's polling reads with one `request_many` per tick (web/sampler.py, web/service.py):
the same values as one GAP/GGP/GIO per value (TMCM-6212 manual 3.6.6, 3.6.8, 3.6.15), a refused read
a gap (None) without losing the others, a lost link all gaps.

A module of any size is read in batches: a profile file may give a module up to 255 axes
(docs/profiles.md), so the axis cards of `sample_slow` (ten GAPs per axis, TMCM-6212 manual 3.6.6)
or the charts of `sample_fast` (GAP 1 and GAP 3 per axis) can need more reads than one
`Client.request_many` takes (`MAX_BATCH`); `Dashboard.read_many` still gives every value (a batch
too long is the client's argument error, not a lost link)."""
from __future__ import annotations

import pytest

from opentmcl.host.client import MAX_BATCH
from opentmcl.host.errors import TmclTimeout
from opentmcl.web import sampler as S

GAP = 6


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


class Counting:
    """Wraps a Module: counts request_many calls and single requests."""

    def __init__(self, module):
        self._m = module
        self.batches: list[int] = []
        self.singles = 0
        self.fail = False

    def request_many(self, requests, **kw):
        self.batches.append(len(requests))
        if self.fail:
            raise TmclTimeout("link down (test)")
        return self._m.request_many(requests, **kw)

    def reply(self, *a, **kw):
        self.singles += 1
        return self._m.reply(*a, **kw)

    def request(self, *a, **kw):
        self.singles += 1
        return self._m.request(*a, **kw)

    def __getattr__(self, name):
        return getattr(self._m, name)


@pytest.fixture
def dash(dash):
    """The shared dashboard (conftest.py), its module's requests counted."""
    dash.module = Counting(dash.module)
    return dash


def test_one_batch_per_chart_tick_with_the_values_of_single_reads(dash):
    module = dash.module
    s = S.Sampler(dash, clock=Clock())
    s._ensure_thread = lambda: None
    module.request(5, 4, 2, 777)     # SAP 4, 2, 777 (manual 3.6.5)
    module.request(9, 3, 2, -12)     # SGP 3, 2, -12: user variable 3
    series = [("axis", 2, 4), ("global", 2, 3), ("io", 0, 1), ("axis", 5, 1)]
    cid = s.subscribe(None, series)
    module.batches.clear()
    module.singles = 0
    s.tick()
    assert module.batches == [4] and module.singles == 0
    row = s.samples(cid, 0)["rows"][-1]
    assert row[2:] == [module._m.reply(6, 4, 2).value, module._m.reply(10, 3, 2).value,
                       module._m.reply(15, 1, 0).value, module._m.reply(6, 1, 5).value]
    assert row[2:4] == [777, -12]


def test_a_refused_read_is_a_gap_the_others_stay(dash):
    """Global parameter 250 of bank 0 does not exist on the TMCM-6212: a status error for it, the others of
    the same tick keep their values."""
    dash.module.request(5, 4, 0, 555)
    values = dash.read_many([(6, 4, 0, 0), (10, 250, 0, 0), (6, 4, 0, 0)])
    assert values == [555, None, 555]
    assert dash.connected


@pytest.mark.parametrize("count", [MAX_BATCH, MAX_BATCH + 1, 3 * MAX_BATCH + 5])
def test_read_many_longer_than_one_batch_gives_every_value(dash, count: int) -> None:
    for motor in range(6):
        dash.module.request(5, 4, motor, 1000 + motor)  # SAP 4 (max. positioning speed)
    reads = [(GAP, 4, i % 6, 0) for i in range(count)]
    assert dash.read_many(reads) == [1000 + i % 6 for i in range(count)]
    assert dash.connected


def test_refused_read_in_a_later_batch_is_a_gap_only(dash) -> None:
    reads = [(GAP, 4, 0, 0)] * (MAX_BATCH + 1) + [(GAP, 4, 6, 0), (GAP, 4, 1, 0)]  # motor 6: status 4
    values = dash.read_many(reads)
    assert values[:MAX_BATCH + 1] == [dash.module.request(GAP, 4, 0).value] * (MAX_BATCH + 1)
    assert values[MAX_BATCH + 1] is None
    assert values[MAX_BATCH + 2] == dash.module.request(GAP, 4, 1).value


def test_a_lost_link_is_all_gaps_and_marks_it(dash):
    dash.module.fail = True
    assert dash.read_many([(6, 1, 0, 0), (6, 3, 0, 0)]) == [None, None]
    assert dash.connected is False and "link down" in dash.last_error


def test_live_status_is_read_in_batches_of_one_turn(dash):
    """`sample_fast` (position and speed of six axes) is one batch of 12; the slow status reads
    its axis cards, ports and user variables in batches of at most `TURN_REQUESTS` each (issue 28:
    a stop waits for at most one batch on the link), no single requests."""
    from opentmcl.web.link import TURN_REQUESTS

    module = dash.module
    module.request(5, 1, 4, 4000)   # actual position of axis 4 (manual 4.1 parameter 1)
    module.batches.clear()
    module.singles = 0
    sample = dash.sample_fast()
    assert module.batches == [12] and module.singles == 0
    assert sample.position[4] == 4000 and sample.position[:4] == [0, 0, 0, 0]
    module.batches.clear()
    state = dash.sample_slow()
    cards = 6 * 10  # six axes, the ten card parameters of the TMCM-6212 (manual 4.1)
    assert module.batches[:cards // TURN_REQUESTS] == [TURN_REQUESTS] * (cards // TURN_REQUESTS)
    assert max(module.batches) <= TURN_REQUESTS and module.singles == 0
    assert state["axes"][4]["position"] == 4000
