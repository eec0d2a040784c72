"""Cookbook: lost steps under load (docs/faults.md "step_loss").

When the load is more than the motor can hold, steps are lost: the position counter (AP1) runs on,
the encoder (AP209) follows the motor. With a maximum deviation (AP212) the module stops the motor
itself and sets the deviation flag (AP207 bit 2, TMCM-6212 manual 4.1). A careful host checks
counter and encoder after a move, and on a deviation sets the counter to where the motor is and
reports it (a real machine would home again).
"""
import opentmcl.sim
from careful import retry, wait_until

FAULTS = {"seed": 14, "fault": [{"kind": "step_loss", "command": "MVP", "count": 1, "load": 3.0, "duration": 0.5}]}
MVP, SAP, GAP = 4, 5, 6


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.2)
    retry(lambda: m.request(SAP, 212, 0, 2000))
    retry(lambda: m.request(MVP, 0, 0, 100000))
    wait_until(lambda: retry(lambda: m.request(GAP, 8, 0).value or m.request(GAP, 207, 0).value & 2),
               10, m.client.sleep)                   # arrived, or stopped by the deviation check
    counter, encoder = m.request(GAP, 1, 0).value, m.request(GAP, 209, 0).value
    assert abs(counter - encoder) > 2000, (counter, encoder)
    retry(lambda: m.request(SAP, 1, 0, encoder))     # the counter to where the motor is
    print(f"steps lost: the counter said {counter}, the encoder {encoder}; counter set to the encoder")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
