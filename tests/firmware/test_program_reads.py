"""A program's GAP, GGP, GIO and AGP through their pre-bound reads and stores (`Interpreter._bound`,
dispatch.program_read / program_store) do exactly what `commands.execute` does for them: TMCM-6212
manual 3.5.5 (a reading command loads the accumulator, 3.5.6.4 the zero flag follows), 3.6.6 GAP,
3.6.10 GGP, 3.6.13 GIO, 3.6.35 AGP (the accumulator to a global parameter or user variable), and
the status of an invalid type, motor or bank recorded as the program's last error.

Each random program runs twice on the same world, once as it is and once with every instruction
sent through `execute` (`_bound` answering None): the same trace of states."""
from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from opentmcl.firmware.interpreter import Interpreter

from .test_next_event_cache import started, state

SCENARIO = {"axis": {"0": {"left": {"position": -1500}}},
            "input": [{"bank": 0, "port": 0, "steps": [[0.004, 1], [0.011, 0], [0.019, 1]]},
                      {"bank": 1, "port": 2, "ramp": [[0, 0], [0.03, 4000]]}]}

READ = st.sampled_from([
    "GAP 1, 0", "GAP 1, 1", "GAP 8, 0", "GAP 8, 1", "GAP 3, 1", "GAP 2, 0", "GAP 0, 0", "GAP 4, 1", "GAP 11, 0",
    "GAP 10, 0", "GAP 207, 0", "GAP 209, 0", "GAP 206, 1", "GAP 140, 0", "GAP 255, 0", "GAP 1, 6", "GAP 250, 0",
    "GGP 0, 2", "GGP 1, 2", "GGP 255, 2", "GGP 132, 0", "GGP 130, 0", "GGP 0, 3", "GGP 66, 0", "GGP 68, 0",
    "GGP 1, 7", "GIO 0, 0", "GIO 2, 1", "GIO 1, 2", "GIO 9, 0", "GIO 255, 0",
    "AGP 0, 2", "AGP 1, 2", "AGP 255, 2", "AGP 200, 2", "AGP 68, 0", "AGP 0, 3", "AGP 1, 7"])
OTHER = st.sampled_from(["CALC ADD, 7", "CALC SUB, 9000", "CALCX SWAP", "MVP ABS, 1, 400", "MVP REL, 0, -300",
                         "ROR 0, 900", "MST 1", "SAP 4, 1, 500", "SAP 1, 0, 123", "COMP 100", "JC GT, Loop"])


@settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.one_of(READ, READ, OTHER), min_size=1, max_size=10), st.lists(st.integers(20, 300), min_size=2,
                                                                                 max_size=5))
def test_bound_reads_and_stores_equal_execute(body, advances):
    source = "\n".join(["Loop:", *body, "JA Loop"])
    fast = started(source, SCENARIO)
    slow = started(source, SCENARIO)
    slow.vm.interpreter._bound = lambda *args: None  # type: ignore[method-assign]
    for tenths_ms in advances:
        for w in (fast, slow):
            w.vm.advance(tenths_ms / 10_000)
        assert state(fast) == state(slow), source
        assert fast.vm.interpreter.last_error == slow.vm.interpreter.last_error, source
        assert fast.vm.globals.ram == slow.vm.globals.ram, source
    assert fast.vm.interpreter.executed > 10


def test_a_read_of_position_reached_loads_an_int():
    """GAP 8 (position reached) loads 1 or 0 into the accumulator as `Axis.get` answers it, not a
    bool (the compiled and property reads answer True/False)."""
    w = started("GAP 8, 0\nSTOP")
    w.vm.advance(0.01)
    assert w.vm.accumulator == 1 and type(w.vm.accumulator) is int


def test_the_bound_ops_are_dropped_with_the_tables():
    """SGP to another bank drops the module's pre-bound tables (GP66/76/87 are in the replies):
    the program's bound reads go with them and are bound again on their next use."""
    w = started("Loop:\nGAP 1, 0\nAGP 3, 2\nJA Loop")
    w.vm.advance(0.005)
    compiled = w.vm.interpreter._compiled
    assert (6, 1, 0, 0) in compiled and (35, 3, 2, 0) in compiled
    w.vm.forget_requests()
    assert compiled == {}
    w.vm.advance(0.005)
    assert (6, 1, 0, 0) in compiled
    assert isinstance(w.vm.interpreter, Interpreter)
