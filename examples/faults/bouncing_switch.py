"""Cookbook: a switch that bounces (docs/faults.md "bouncing_switch").

Right after it is actuated a mechanical switch opens and closes a few times. A careful host does
not act on one reading: it takes a level only when several readings a few milliseconds apart agree.
"""
import opentmcl.sim
from careful import retry

FAULTS = {"seed": 13, "fault": [{"name": "bounce", "kind": "bouncing_switch", "switch": "home", "bounces": 6,
                                 "period": 0.002}]}
GAP = 6


def debounced(m, axis: int, readings: int = 5, apart: float = 0.005) -> int:
    """The home switch state (AP9) once `readings` readings `apart` seconds apart agree."""
    seen: list[int] = []
    while len(seen) < readings or len(set(seen[-readings:])) > 1:
        seen.append(retry(lambda: m.request(GAP, 9, axis).value))
        m.client.sleep(apart)
    return seen[-1]


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.2)
    m.client.transport.faults.trigger("bounce")
    assert debounced(m, 0) == 0      # the stage is nowhere near the home switch
    print("debounced: home switch released")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
