"""Cookbook: the module loses its power (docs/faults.md "power_loss").

After a power-up the RAM parameters are back to their stored values (SAP without STAP is lost),
the EEPROM is kept, the position counter starts at 0, and with GP77 = 1 the stored program starts.
A careful host notices the reset (here: a user variable above the stored range, which powers up as
0, PD86-1180 manual 6 "user variables"), and sets up the module again before it goes on.
"""
import opentmcl.sim
from careful import retry, set_parameter

FAULTS = {"seed": 9, "fault": [{"name": "cut", "kind": "power_loss", "duration": 0.5}]}
SGP, GGP, USER, MARK = 9, 10, 2, 200   # user variable 200 is not stored: 0 after a power-up
CONFIG = {4: 1500, 5: 800}             # maximum speed and acceleration, RAM only


def set_up(m) -> None:
    for number, value in CONFIG.items():
        set_parameter(m, number, 0, value)
    retry(lambda: m.request(SGP, MARK, USER, 1))


def was_reset(m) -> bool:
    return retry(lambda: m.request(GGP, MARK, USER).value) == 0


def main() -> int:
    m = opentmcl.sim.connect("PD86-1180", faults=FAULTS, timeout=0.2)
    set_up(m)
    m.client.transport.faults.trigger("cut")
    m.client.sleep(0.6)
    if was_reset(m):
        print("the module was reset: setting it up again")
        set_up(m)
    assert all(m.axes[0].get(number) == value for number, value in CONFIG.items())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
