"""Random small programs with host commands in between: the cached run (next-event cache, pure
instructions and reads run ahead) gives exactly the trace of the reference run, which looks every
event up afresh and takes one event per instruction (docs/architecture.md "Time"). Programs use
the commands of TMCM-6212 manual 3.6 (GAP, GGP, GIO, SIO, SAP, SGP, MVP, ROR, MST, WAIT, EI, DI,
VECT, RETI, CALC, CALCX, COMP, JC, JA) on a world with a left switch, a digital input that steps
and an analog input that ramps (docs/world.md)."""
from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from .test_next_event_cache import started, state

SCENARIO = {"axis": {"0": {"left": {"position": -1500}}},
            "input": [{"bank": 0, "port": 0, "steps": [[0.004, 1], [0.011, 0], [0.019, 1]]},
                      {"bank": 1, "port": 2, "ramp": [[0, 0], [0.03, 4000]]}]}

BODY = st.sampled_from([
    "GAP 1, 0", "GAP 1, 1", "GAP 8, 0", "GAP 3, 1", "GAP 0, 0", "GAP 11, 0", "GAP 207, 0", "GGP 132, 0",
    "GGP 1, 2", "GIO 0, 0", "GIO 2, 1", "SIO 0, 2, 1", "CALC ADD, 7", "CALCX ADD", "CALCX SWAP", "COMP 100",
    "JC GT, Loop", "JC ZE, Loop", "AGP 1, 2", "AGP 2, 2", "SAP 4, 0, 3000", "SAP 4, 1, 500",
    "MVP ABS, 1, 400", "MVP ABS, 1, 0", "MVP REL, 0, -300", "ROR 0, 900", "ROL 0, 700", "MST 1",
    "SGP 0, 3, 1", "SGP 0, 3, 2", "SGP 1, 3, 3", "SGP 68, 0, 6", "EI 0", "DI 0", "EI 1", "EI 39",
    "WAIT TICKS, 0, 1", "WAIT POS, 1, 2", "GAP 4, 0"])
ISR = st.sampled_from(["GAP 1, 0", "GGP 132, 0", "GIO 2, 1", "CALC ADD, 1", "AGP 3, 2", "CALCX ADD", "SIO 1, 2, 1",
                       "MST 1", "SAP 4, 1, 900"])
HOST = st.sampled_from([
    (6, 1, 0, 0), (5, 4, 0, 2000), (4, 0, 1, 600), (9, 0, 3, 2), (9, 68, 0, 0), (9, 68, 0, 3), (1, 0, 0, 500),
    (3, 0, 1, 0), (25, 0, 0, 0), (26, 0, 0, 0), (128, 0, 0, 0), (129, 0, 0, 0), (130, 0, 0, 0)])


@st.composite
def programs(draw):
    body = draw(st.lists(BODY, min_size=1, max_size=7))
    isr = draw(st.lists(ISR, min_size=0, max_size=3))
    head = ["VECT 0, Isr", "VECT 1, Isr", "VECT 39, Isr", "VECT 27, Isr", "SGP 39, 3, 3", "SGP 27, 3, 1",
            draw(st.sampled_from(["SGP 0, 3, 1", "SGP 0, 3, 0", "SGP 1, 3, 2"])),
            draw(st.sampled_from(["EI 0", "EI 1", "EI 39", "EI 27", "DI 0"])), "EI 255"]
    return "\n".join([*head, "Loop:", *body, "JA Loop", "Isr:", *isr, "RETI"])


steps = st.lists(st.tuples(st.integers(1, 60), st.lists(HOST, max_size=2)), min_size=3, max_size=8)


@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(programs(), steps)
def test_cached_run_equals_one_event_per_instruction(source, plan):
    fast, ref = started(source, SCENARIO), started(source, SCENARIO, reference=True)
    for tenths_ms, host in plan:
        for w in (fast, ref):
            w.vm.advance(tenths_ms / 10_000)
        assert state(fast) == state(ref), source
        for command in host:
            assert fast.vm.handle(_frame(command)) == ref.vm.handle(_frame(command)), command


def _frame(command: tuple[int, int, int, int]) -> bytes:
    from opentmcl.protocol.frame import Request
    return Request(1, *command).encode()
