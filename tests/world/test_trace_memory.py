"""Issue 11 problem 5: "Traces grow without bound: about 5.8 KB per recorded row, so `plot --to` /
trace recording of one hour at 10 ms needs about 2 GB".

Deliverable: "compact rows (column arrays or tuples, not dicts per row), a cap ...; one hour at
10 ms must fit in well under 100 MB". 100 MB / 360000 rows is 277 bytes per row; the tests hold
the two traces to 200 bytes per row of six axes, measured with tracemalloc (memory, not time).
The speed and the exact figures are in bench/bench_trace.py.
"""
import gc
import math
import tracemalloc

import pytest

from opentmcl import VirtualModule
from opentmcl.columns import Column
from opentmcl.trace import HOST_CHANNELS, Trace, TraceFull

ROWS = 2000


def held_bytes(build) -> int:
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    keep = build()
    gc.collect()
    held = tracemalloc.get_traced_memory()[0] - before
    tracemalloc.stop()
    assert keep is not None
    return held


def test_world_trace_of_six_moving_axes_stays_under_200_bytes_per_row():
    vm = VirtualModule("TMCM-6212", scenario={"axis": {str(a): {"right": {"position": 90000}} for a in range(6)}})
    for a in range(6):
        vm.request(4, 0, a, 100000 + 1000 * a)
    trace = Trace()
    trace.record(vm, 0.1, 0.01)   # first-use caches of the module

    def more():
        for _ in range(ROWS):
            vm.advance(0.01)
            trace.sample(vm)
        return trace

    per_row = held_bytes(more) / ROWS
    assert per_row < 200, per_row
    last = trace.rows[-1]
    assert last["pos0"] == vm.axes[0].get(1) and len(trace.rows) == ROWS + 11


def test_plot_trace_of_six_axes_stays_under_200_bytes_per_sample():
    axes = list(range(6))

    def fill():
        t = Trace(axes)
        for i in range(ROWS):
            t.add(i * 0.01, {(a, ch): (i * 37 + a if ch == "position" else float(i % 500) if ch == "velocity"
                                       else i % 2) for a in axes for ch in HOST_CHANNELS})
        return t

    per_sample = held_bytes(fill) / ROWS
    assert per_sample < 200, per_sample


def test_world_trace_cap_last_row_and_first_refused():
    """The cap: max_rows rows are kept, the next sample is refused (TraceFull, a ValueError), and
    record() refuses a run that would pass it before it starts."""
    vm = VirtualModule("TMCM-6212")
    trace = Trace(axes=[0], max_rows=3)
    trace.record(vm, 0.2, 0.1)
    assert len(trace.rows) == 3
    with pytest.raises(TraceFull):
        trace.sample(vm)
    assert len(trace.rows) == 3
    fresh = Trace(axes=[0], max_rows=3)
    with pytest.raises(TraceFull):
        fresh.record(vm, 0.3, 0.1)
    assert len(fresh.rows) == 0


@pytest.mark.parametrize(("values", "typecode"), [
    ([0, 1, None, 127], "b"), ([-127, None], "b"), ([-128], "h"), ([None, 32767, -32768], "i"),
    ([2 ** 31 - 1, -(2 ** 31), None], "q"), ([1, 2.5, None], "d"), ([None, 2 ** 70], "d")])
def test_column_widens_to_the_narrowest_type_and_keeps_none(values, typecode):
    """Edges of each width: the sentinel of a type (its smallest value) widens the column."""
    col = Column(values)
    assert col.typecode == typecode
    back = col.tolist()
    assert [v is None for v in back] == [v is None for v in values]
    assert all(b == pytest.approx(v) for b, v in zip(back, values, strict=True) if v is not None)
    assert Column([math.nan]).tolist() == [None]   # documented: NaN reads back as None


@pytest.mark.parametrize(("before", "values"), [
    ([], [0, 1, 127]), ([], [-127, 127]), ([], [-128]), ([5], [32767, -32767]), ([5], [-32768]),
    ([1], [2 ** 31 - 1, -(2 ** 31)]), ([1, None], [2 ** 63 - 1]), ([1], [-(2 ** 63)]), ([1], [2 ** 70]),
    ([2.5], [1, 2]), ([], [True, False]), ([], [1, None, 3]), ([], [1, 2.5]), ([300], []), ([None], [7]),
    ([300], [5, 384]), ([300], [5, -32768])])
def test_column_extend_is_append_in_one_go(before, values):
    """A trace keeps its samples in blocks (opentmcl/trace.py FLUSH_ROWS): `extend` gives the very
    column that appending the values one by one gives - the same type at each width's edge (the
    smallest value of a type is its None) and the same values. [5, 384] in a 16-bit column holds
    the sentinel's two bytes (-32768) across two values: no sentinel, the column stays 16-bit."""
    one_by_one, at_once = Column(before), Column(before)
    for v in values:
        one_by_one.append(v)
    at_once.extend(values)
    assert at_once.typecode == one_by_one.typecode
    assert at_once.tolist() == one_by_one.tolist()
