"""Homing with the position latch, datasheet 7.3 "Homing Procedure", from the microcontroller's side.

The axis has a reference switch on REF_L, active between x1 and x2 (unknown to the firmware).
The firmware latches x2 on the way in (the switch also stops the motor there), moves the origin
into the switch so that DX_REF_TOLERANCE lets it drive through, latches x1 on the way out and
finally makes x_ref = (x1 + x2) / 2 the new zero.

Run it:                 python examples/tmc4210_homing.py
Watch every datagram:   opentmcl tmc4210 trace examples/tmc4210_homing.py
"""
from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tmc4210_getting_started import (  # noqa: E402  (the 9.1 driver next to this file)
    RAMP_MODE_REF_CONF,
    X_ACTUAL,
    X_TARGET,
    TMC4210Driver,
)

X_LATCHED, DX_REF_TOLERANCE = 0x0E, 0x0D
LP = 1 << 16               # 6.1.10.2 read-only status bit lp in RAMP_MODE_REF_CONF
VELOCITY_MODE, RAMP_MODE = 2, 0


def home(drv: TMC4210Driver, x_max: int = 100_000, tolerance: int = 2000) -> int:
    """7.3 steps 1-7; returns the measured switch width x2 - x1."""
    drv.write(X_LATCHED, 0)                                  # 1. dummy write arms the latch
    drv.write(X_TARGET, -x_max)                              # 2. move towards the switch
    while drv.read(RAMP_MODE_REF_CONF) & LP:                 # 3. x2 is latched on the way in
        drv.delay(0.01)
    x2 = drv.read(X_LATCHED, signed=True)
    while drv.read(0x05, signed=True) != 0:                  # 4. the stop switch stops the motor
        drv.delay(0.01)
    here = drv.read(X_ACTUAL, signed=True)
    drv.write(RAMP_MODE_REF_CONF, VELOCITY_MODE)             # 6.1.2: overwrite X_ACTUAL outside ramp_mode
    drv.write(X_ACTUAL, here - x2)                           # 5. origin at x2, so that DX_REF_TOLERANCE
    drv.write(X_TARGET, here - x2)                           #    allows motion inside the switch
    drv.write(RAMP_MODE_REF_CONF, RAMP_MODE)
    drv.write(DX_REF_TOLERANCE, tolerance)
    drv.write(X_LATCHED, 0)                                  # 6. latch x1 on the way out
    drv.write(X_TARGET, -tolerance + 1)
    while drv.read(RAMP_MODE_REF_CONF) & LP:
        drv.delay(0.01)
    x1 = drv.read(X_LATCHED, signed=True)
    # 7. x_ref = (x1 + x2) / 2; x2 is 0 now, and the latch on the way out holds the first
    #    position outside the switch, so the switch's last active position is x1 + 1
    x_ref = (x1 + 1) // 2
    drv.move_to(x_ref)
    drv.write(RAMP_MODE_REF_CONF, VELOCITY_MODE)
    drv.write(X_ACTUAL, 0)
    drv.write(X_TARGET, 0)
    drv.write(RAMP_MODE_REF_CONF, RAMP_MODE)
    return -x1


def main(chip=None) -> None:
    if chip is None:
        sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
        from opentmcl.chips.tmc4210 import TMC4210
        chip = TMC4210(f_clk=16_000_000)
    # the mechanics: a reference switch 23000..23800 steps left of where the motor starts
    chip.attach_switch("ref_l", -23_800, -23_000)
    drv = TMC4210Driver(chip.spi, chip.advance)
    drv.start(v_min=10, v_max=1000, pulse_div=5, ramp_div=8, a_max=100)
    width = home(drv)
    print(f"switch width {width} steps; the origin is now the switch centre")
    for x in (-(width // 2) - 1, -(width // 2), 0, width // 2, width // 2 + 1):
        drv.move_to(x)
        print(f"X_ACTUAL {x:5d}: REF_L {'active' if drv.status & 0x02 else 'inactive'}")
    drv.move_to(0)


if __name__ == "__main__":
    main()
