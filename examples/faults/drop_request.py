"""Cookbook: a request that never reaches the module (docs/faults.md "drop_request").

A lost request looks like any time-out to the host. A careful host repeats what is safe to repeat
(a SAP of a value) and reads back what matters; `careful.set_parameter` does both.
"""
import opentmcl.sim
from careful import set_parameter

FAULTS = {"seed": 1, "fault": [{"kind": "drop_request", "command": "SAP", "probability": 0.3}]}


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.2)
    for axis in range(6):
        set_parameter(m, 4, axis, 10000 + axis)     # maximum positioning speed
    assert [m.axes[a].get(4) for a in range(6)] == [10000 + a for a in range(6)]
    print(f"set 6 speeds; {len(m.client.transport.faults.log)} requests were lost on the way")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
