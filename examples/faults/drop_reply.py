"""Cookbook: a reply that never arrives (docs/faults.md "drop_reply").

The module did the request; only the answer was lost. Repeating a relative move (MVP REL) would
move twice as far: a careful host moves with MVP ABS, which is safe to repeat, and reads the
target back.
"""
import opentmcl.sim
from careful import retry, wait_until

FAULTS = {"seed": 2, "fault": [{"kind": "drop_reply", "command": "MVP", "count": 1}]}
MVP, GAP = 4, 6


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.2)
    retry(lambda: m.request(MVP, 0, 0, 5000))        # MVP ABS, 0, 5000: the first reply is lost
    wait_until(lambda: m.request(GAP, 8, 0).value == 1, 10, m.client.sleep)
    assert m.request(GAP, 1, 0).value == 5000          # not 10000, as MVP REL twice would give
    print("moved once to 5000 although the first reply was lost")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
