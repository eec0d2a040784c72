"""A microcontroller-side TMC4210 driver, written in Python, following datasheet 9.1 "Getting Started".

The driver only ever talks to the chip through one function, `transfer(datagram) -> datagram`,
exactly like firmware talks through its SPI peripheral, and waits through `delay(seconds)`.
Against the model both come from `opentmcl.chips.tmc4210.TMC4210`; on real hardware they
would be an SPI transfer with chip select and a timer.

Run it:                 python examples/tmc4210_getting_started.py
Watch every datagram:   opentmcl tmc4210 trace examples/tmc4210_getting_started.py
"""
from __future__ import annotations

from collections.abc import Callable

# --- register addresses (datasheet 5.3): SMDA %00 axis registers, SMDA %11 global ones ---------
X_TARGET, X_ACTUAL, V_MIN, V_MAX, V_TARGET, V_ACTUAL, A_MAX = 0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06
PMUL_PDIV, RAMP_MODE_REF_CONF, INTERRUPT, PULSE_DIV_RAMP_DIV = 0x09, 0x0A, 0x0B, 0x0C
IF_CONFIGURATION_4210, TYPE_VERSION, GLOBAL_PARAMETERS = 0x34, 0x39, 0x3F

RAMP_MODE = 0       # 6.1.10.1 %00 ramp_mode
EN_SD = 1 << 5      # 6.2.1 IF_CONFIGURATION_4210 bit 5
MOT1R = 1 << 21     # 6.2.2 global parameter register bit 21
STATUS_XEQT1 = 0x01  # 5.2.2.2 status bit: target position reached
STATUS_INT = 0x80


def pmul_pdiv(a_max: int, ramp_div: int, pulse_div: int, p_reduction: float = 0.01) -> tuple[int, int]:
    """6.1.9.2.2, as a microcontroller would compute it: PMUL = p_reduced * 2^3 * 2^PDIV."""
    p = a_max / (128.0 * 2.0 ** (ramp_div - pulse_div)) * (1.0 - p_reduction)
    best = None
    for pdiv in range(14):
        pmul = int(p * 8.0 * 2.0 ** pdiv)
        if 128 <= pmul <= 255:
            best = (pmul, pdiv)
    if best is None:
        raise ValueError(f"no PMUL/PDIV for A_MAX={a_max} (datasheet 6.1.7.1.1 limits)")
    return best


class TMC4210Driver:
    """Register access and the 9.1 start-up sequence over a 32-bit SPI transfer."""

    def __init__(self, transfer: Callable[[int], int], delay: Callable[[float], None]) -> None:
        self.transfer = transfer
        self.delay = delay
        self.status = 0

    def write(self, address: int, data: int) -> None:
        """5.2.2.1: RRS=0, ADDRESS, RW=0, 24 data bits."""
        self.status = self.transfer(address << 25 | (data & 0xFFFFFF)) >> 24

    def read(self, address: int, signed: bool = False) -> int:
        """5.2.2.1: RW=1; the answer carries the status byte and 24 data bits."""
        back = self.transfer(address << 25 | 1 << 24)
        self.status, data = back >> 24, back & 0xFFFFFF
        return data - (1 << 24) if signed and data & 0x800000 else data

    def start(self, *, v_min: int, v_max: int, pulse_div: int, ramp_div: int, a_max: int,
              both_switches: bool = True) -> None:
        """Datasheet 9.1, steps 1 to 6."""
        if self.read(TYPE_VERSION) != 0x429101:
            raise RuntimeError("no TMC4210 answers on this SPI bus")
        self.write(IF_CONFIGURATION_4210, EN_SD)                          # 1. en_sd = 1
        self.write(V_MIN, v_min)                                          # 2. V_MIN, V_MAX
        self.write(V_MAX, v_max)
        self.write(PULSE_DIV_RAMP_DIV, pulse_div << 12 | ramp_div << 8)   # 3. PULSE_DIV, RAMP_DIV
        pmul, pdiv = pmul_pdiv(a_max, ramp_div, pulse_div)                # 4. A_MAX with PMUL/PDIV
        self.write(A_MAX, a_max)
        self.write(PMUL_PDIV, pmul << 8 | pdiv)
        self.write(RAMP_MODE_REF_CONF, RAMP_MODE)                         # 5. ramp_mode
        stpdiv = self.read(GLOBAL_PARAMETERS) & 0xF00                     # 6. mot1r, keep STPDIV
        self.write(GLOBAL_PARAMETERS, stpdiv | (MOT1R if both_switches else 0))

    def move_to(self, position: int, timeout_s: float = 60.0, poll_s: float = 0.01) -> int:
        """7. write X_TARGET, then poll xEQt1 in the status byte until the motor stands on target."""
        self.write(X_TARGET, position)
        waited = 0.0
        while waited < timeout_s:
            self.delay(poll_s)
            waited += poll_s
            v = self.read(V_ACTUAL, signed=True)
            if self.status & STATUS_XEQT1 and v == 0:
                return self.read(X_ACTUAL, signed=True)
        raise TimeoutError(f"target {position} not reached in {timeout_s} s")


def main(chip=None) -> None:
    """Position the motor to a few targets and print where it is."""
    if chip is None:
        import sys
        from pathlib import Path
        sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
        from opentmcl.chips.tmc4210 import TMC4210
        chip = TMC4210(f_clk=16_000_000)
    drv = TMC4210Driver(chip.spi, chip.advance)
    # 16 MHz, PULSE_DIV 5: V_MAX 1000 = 7.6 kHz; RAMP_DIV 8, A_MAX 100: 5.8 kHz/s (6.1.12)
    drv.start(v_min=10, v_max=1000, pulse_div=5, ramp_div=8, a_max=100)
    for target in (20_000, -5_000, 0):
        at = drv.move_to(target)
        print(f"t = {chip.time:8.3f} s   X_ACTUAL = {at}")


if __name__ == "__main__":
    main()
