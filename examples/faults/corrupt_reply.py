"""Cookbook: a reply garbled on the line (docs/faults.md "corrupt_reply").

The host library raises TmclChecksumError naming the request; the request itself was done. A read
is safe to repeat: read again.
"""
import opentmcl.sim
from careful import retry

FAULTS = {"seed": 4, "fault": [{"kind": "corrupt_reply", "command": "GAP", "probability": 0.3}]}
GAP = 6


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.2)
    speeds = [retry(lambda a=axis: m.request(GAP, 4, a).value) for axis in range(6)]
    assert speeds == [m.axes[0].param(4).default] * 6
    print(f"read 6 speeds; {len(m.client.transport.faults.log)} replies came garbled")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
