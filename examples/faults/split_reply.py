"""Cookbook: a reply that arrives in pieces (docs/faults.md "split_reply").

A USB adapter or an Ethernet converter may hand a reply over in several chunks. A host must read
until it has nine bytes (within its time-out), not take the first chunk for the reply: the host
library (and pyserial's `read(9)`, which PyTrinamic uses) does.
"""
import opentmcl.sim

FAULTS = {"seed": 7, "fault": [{"kind": "split_reply", "probability": 1.0, "pieces": 4, "gap": 0.02}]}
GAP = 6


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.5)
    assert m.request(GAP, 4, 0).value == m.axes[0].param(4).default
    print("a reply in 4 pieces read whole")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
