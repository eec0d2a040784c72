"""The TMC4210 model runs on the fast shared ramp core; driven through SPI it must agree exactly
with the per-tick reference model (tests/motion/tmc429_reference.py) on randomized register
sequences - positions, velocities with their hidden fraction, and every step edge."""
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from opentmcl.chips.tmc4210 import TMC4210
from opentmcl.chips.tmc4210 import registers as R

from ..motion.tmc429_reference import HOLD_MODE, ReferenceRamp

T_STEP = 16  # STPDIV_4210 = 0: shorter than the fastest step period (32 cycles)


class Recording(ReferenceRamp):
    def __init__(self) -> None:
        super().__init__(position_bits=24)
        self.steps: list[tuple[int, int]] = []

    def on_step(self, cycle: int, direction: int) -> None:
        self.steps.append((cycle, direction))


# (datagram address, data, the same write for the reference)
def _w(addr, data, **ref):
    return ("write", addr, data & 0xFFFFFF, ref)


writes = st.one_of(
    st.integers(-4000, 4000).map(lambda x: _w(0x00, x, x_target=x)),
    st.integers(-(2 ** 23), 2 ** 23 - 1).map(lambda x: _w(0x00, x, x_target=x)),
    st.integers(-4000, 4000).map(lambda x: _w(0x01, x, x_actual=x)),
    st.integers(0, 8).map(lambda v: _w(0x02, v, v_min=v)),
    st.one_of(st.integers(0, 2047), st.integers(0, 60)).map(lambda v: _w(0x03, v, v_max=v)),
    st.integers(-2047, 2047).map(lambda v: _w(0x04, v, v_target=v)),
    st.integers(-2047, 2047).map(lambda v: _w(0x05, v, v_actual=v)),
    st.one_of(st.integers(0, 2047), st.integers(1, 40)).map(lambda a: _w(0x06, a, a_max=a)),
    st.tuples(st.integers(128, 255), st.integers(0, 13)).map(
        lambda p: _w(0x09, p[0] << 8 | p[1], pmul=p[0], pdiv=p[1])),
    st.integers(0, 3).map(lambda m: _w(0x0A, m, mode=m)),
    st.tuples(st.integers(0, 4), st.integers(0, 4)).map(
        lambda d: _w(0x0C, d[0] << 12 | d[1] << 8, pulse_div=d[0], ramp_div=d[1])),
    st.sampled_from([("switch", False), ("switch", True)]),
)
script = st.lists(st.tuples(writes, st.lists(st.integers(1, 3000), min_size=1, max_size=4)),
                  min_size=1, max_size=8)


def steps_from_edges(edges) -> list[tuple[int, int]]:
    """Recover (step cycle, direction) from the STEP/DIR edge stream (8.1: a step right after a
    direction change is delayed by t_DIR2STP = t_STEP)."""
    out, direction, dir_at = [], 1, None
    for e in edges:
        if e.pin == "DIR":
            direction, dir_at = (1 if e.level else -1), e.cycle
        elif e.level == 1:
            delayed = dir_at is not None and e.cycle == dir_at + T_STEP
            out.append((e.cycle - T_STEP if delayed else e.cycle, direction))
            dir_at = None
    return out


def compare(chip: TMC4210, ref: ReferenceRamp) -> None:
    assert chip.cycle == ref.now
    assert chip.read("X_ACTUAL") == R.to_signed(ref.x_actual, 24)
    assert chip.read("X_TARGET") == R.to_signed(ref.x_target, 24)
    assert chip.read("V_ACTUAL") == ref.v_actual
    assert chip.ramp.v_internal == ref.v


def run(actions) -> None:
    chip, ref = TMC4210(capture_edges=True), Recording()
    chip.write("STPDIV_4210", 0)
    chip.write("en_sd", 1)
    chip.drain_edges()
    for action, waits in actions:
        if action[0] == "write":
            _, addr, data, regs = action
            chip.spi(R.write_datagram(addr, data))
            if "v_actual" in regs and ref.mode != HOLD_MODE:
                regs = {}
            ref.set(**regs)
        else:
            # a left stop switch closes while moving left (6.1.10.2), opens after the waits
            soft = action[1]
            if ref.v_actual >= 0:
                continue
            chip.write("soft_stop", int(soft))
            chip.set_inputs(ref_l=1)
            ref.stop(soft=soft)
        for w in waits:
            t = chip.cycle + 32 * w
            chip.advance_cycles(32 * w)
            ref.advance(t)
            compare(chip, ref)
        if action[0] == "switch":
            chip.set_inputs(ref_l=0)
    assert steps_from_edges(chip.stepdir.drain()) == ref.steps  # incl. pulses still pending
    assert chip.stepdir.lost_steps == 0


@given(script)
def test_chip_matches_the_per_tick_reference(actions):
    """docs/architecture.md "Time" / issue 6: the fast engine agrees exactly with the per-tick reference;
    TMC4210 datasheet 6.1 register semantics, 6.1.10.2 switch stops, 8.1 step edges."""
    run(actions)


@pytest.mark.slow
@pytest.mark.timeout(3600)
@settings(max_examples=1500, deadline=None)
@given(script)
def test_chip_matches_the_per_tick_reference_long(actions):
    """The same randomized agreement check with many more examples."""
    run(actions)
