"""Cookbook: a request that crosses the line in pieces (docs/faults.md "split_request").

A TMCL frame has no start marker (manual 3.1): a module finds frames by counting bytes and drops a
partial frame after a silence longer than its frame gap (0.1 s, server/framer.py). Pieces closer
than that are one frame; a longer pause loses the request, which a careful host repeats.
"""
import opentmcl.sim
from careful import set_parameter

FAULTS = {"seed": 6, "fault": [{"kind": "split_request", "probability": 0.2, "gap": 0.05},
                               {"kind": "split_request", "probability": 0.1, "gap": 0.2}]}


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.5)
    for axis in range(6):
        set_parameter(m, 5, axis, 3000 + axis)
    print(f"6 accelerations set; {len(m.client.transport.faults.log)} requests came in pieces")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
