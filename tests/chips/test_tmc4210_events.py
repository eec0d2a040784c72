"""Event-driven time must not miss what a clock-by-clock walk sees: flags, latch and stops come
out the same whether the model jumps over a whole move or is advanced one pulse tick at a time
(docs/architecture.md "Time"; datasheet 6.1.10.2, 6.1.11, 6.1.14, 6.2.1.2)."""
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from opentmcl.chips.tmc4210 import TMC4210
from opentmcl.chips.tmc4210 import registers as R

config = st.fixed_dictionaries({
    "mode": st.sampled_from([0, 0, 1, 2, 3]),
    "divs": st.sampled_from([(0, 0), (0, 0), (1, 0), (0, 2), (2, 1)]),
    "target": st.integers(-600, 600),
    "v": st.integers(-2047, 2047),
    "v_max": st.integers(100, 2047),
    "a_max": st.integers(50, 2047),
    "pmul": st.integers(128, 255),
    "pdiv": st.integers(0, 6),
    "ref_conf": st.integers(0, 15),
    "mot1r": st.integers(0, 1),
    "tol": st.integers(0, 80),
    "pos_comp": st.integers(-300, 300),
    "windows": st.lists(st.tuples(st.sampled_from(["ref_l", "ref_r"]), st.integers(-400, 400),
                                  st.integers(0, 60)), max_size=3),
})


def build(cfg) -> TMC4210:
    chip = TMC4210()
    pulse_div, ramp_div = cfg["divs"]
    chip.spi(R.write_datagram(0x0C, pulse_div << 12 | ramp_div << 8))
    chip.write("V_MIN", 3)
    chip.write("V_MAX", cfg["v_max"])
    chip.write("A_MAX", cfg["a_max"])
    chip.spi(R.write_datagram(0x09, cfg["pmul"] << 8 | cfg["pdiv"]))
    chip.write("INTERRUPT_MASK", 0xFF)
    chip.write("POS_COMP_INT_M", 1)
    chip.write("POS_COMP_4210", cfg["pos_comp"])
    chip.write("DX_REF_TOLERANCE", cfg["tol"])
    chip.write("mot1r", cfg["mot1r"])
    for pin, lo, width in cfg["windows"]:
        chip.attach_switch(pin, lo, lo + width)
    chip.write("X_LATCHED", 0)
    chip.write("RAMP_MODE", cfg["mode"])
    chip.spi(R.write_datagram(0x0A, cfg["ref_conf"] << 8 | cfg["mode"]))
    if cfg["mode"] == 3:
        chip.write("V_ACTUAL", cfg["v"])
    elif cfg["mode"] == 2:
        chip.write("V_TARGET", cfg["v"])
    else:
        chip.write("X_TARGET", cfg["target"])
    return chip


@settings(max_examples=15, deadline=None)
@given(config, st.integers(2000, 30000))
def test_one_jump_equals_pulse_tick_steps(cfg, cycles):
    """The same chip advanced in one jump and in 32-cycle steps ends in the same state."""
    jump, walk = build(cfg), build(cfg)
    jump.advance_cycles(cycles)
    for _ in range(cycles // 32):
        walk.advance_cycles(32)
    walk.advance_cycles(cycles % 32)
    assert jump.registers() == walk.registers()
    assert (jump.lp, jump.x_latched, jump.int_flags, jump.pos_comp_i) == \
        (walk.lp, walk.x_latched, walk.int_flags, walk.pos_comp_i)


@pytest.mark.slow
@pytest.mark.timeout(3600)
@settings(max_examples=1500, deadline=None)
@given(config, st.integers(2000, 30000))
def test_one_jump_equals_pulse_tick_steps_long(cfg, cycles):
    """The same jump-versus-walk check with many more examples."""
    test_one_jump_equals_pulse_tick_steps.hypothesis.inner_test(cfg, cycles)
