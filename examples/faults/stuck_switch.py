"""Cookbook: a limit switch that sticks (docs/faults.md "stuck_switch").

A switch that reads active where the axis cannot be at its end is a wiring or switch fault. A
careful host checks the switch before it relies on it (here: before a reference search to the
left) and stops with a clear message instead of driving blind.
"""
import opentmcl.sim
from careful import retry

FAULTS = {"seed": 12, "fault": [{"kind": "stuck_switch", "switch": "left", "level": 1, "at": 0.0}]}
GAP = 6


class SwitchFault(RuntimeError):
    pass


def check_left_switch(m, axis: int) -> None:
    if retry(lambda: m.request(GAP, 11, axis).value):   # AP11: left limit switch state
        raise SwitchFault(f"axis {axis}: the left switch is active before homing; is it stuck?")


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.2)
    m.client.sleep(0.01)
    try:
        check_left_switch(m, 0)
    except SwitchFault as exc:
        print(f"not homing: {exc}")
        return 0
    raise AssertionError("the stuck switch was not noticed")


if __name__ == "__main__":
    raise SystemExit(main())
