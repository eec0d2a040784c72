"""Shared set-up for the TMC4210 model tests: the datasheet's 9.1 "Getting Started" sequence."""
from opentmcl.chips.tmc4210 import TMC4210
from opentmcl.chips.tmc4210 import registers as R
from opentmcl.motion.pmulpdiv import registers_for


def setup(chip: TMC4210 | None = None, *, v_min=10, v_max=1000, a_max=100, pulse_div=5, ramp_div=8,
          mode=0, en_sd=1, pmul=None, pdiv=None, f_clk=16_000_000, capture=False) -> TMC4210:
    """9.1: en_sd, V_MIN/V_MAX, PULSE_DIV/RAMP_DIV, A_MAX with PMUL/PDIV, RAMP_MODE."""
    chip = chip or TMC4210(f_clk=f_clk, capture_edges=capture)
    chip.write("en_sd", en_sd)
    chip.write("V_MIN", v_min)
    chip.write("V_MAX", v_max)
    chip.spi(R.write_datagram(0x0C, pulse_div << 12 | ramp_div << 8))
    if pmul is None:
        pmul, pdiv = registers_for(a_max, ramp_div, pulse_div)  # 6.1.9.2.2 with 1 % reduction
    chip.write("A_MAX", a_max)
    chip.spi(R.write_datagram(0x09, pmul << 8 | pdiv))
    chip.write("RAMP_MODE", mode)
    return chip


def run_until_reached(chip: TMC4210, limit_s: float = 100.0, step_s: float = 0.01) -> bool:
    """Poll xEQt1 and V_ACTUAL the way firmware would."""
    waited = 0.0
    while waited < limit_s:
        if chip.spi(R.read_datagram(0x05)) >> 24 & R.STATUS_XEQT1 and chip.read("V_ACTUAL") == 0:
            return True
        chip.advance(step_s)
        waited += step_s
    return False
