"""Review of issue 16: the dashboard reads a module of any size in batches.

A profile file may give a module up to 255 axes (docs/profiles.md), so the axis cards of
`sample_slow` (ten GAPs per axis, TMCM-6212 manual 3.6.6) or the charts of `sample_fast` (GAP 1
and GAP 3 per axis) can need more reads than one `Client.request_many` takes (`MAX_BATCH`). Before
issue 16 every value was one request; `Dashboard.read_many` must still give every value (a batch too
long is the client's argument error, not a lost link).
"""
from __future__ import annotations

import pytest

from opentmcl.host.client import MAX_BATCH

GAP = 6


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
