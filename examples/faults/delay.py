"""Cookbook: replies that come late (docs/faults.md "delay").

A reply within the time-out is just slow. A reply later than the time-out is a TmclTimeout; the
host library then brings the link back in step before its next request, so the late reply is never
taken for the answer to another request (docs/host.md "Lost, late and garbled replies"). A careful
host picks a time-out that fits its link and repeats reads that timed out.
"""
import opentmcl.sim
from careful import retry

FAULTS = {"seed": 5, "fault": [{"kind": "delay", "probability": 0.2, "delay": 0.3, "jitter": 0.2}]}
SAP, GAP = 5, 6


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.4)
    for axis in range(6):
        retry(lambda a=axis: m.request(SAP, 4, a, 20000 + a))
    read = [retry(lambda a=axis: m.request(GAP, 4, a).value) for axis in range(6)]
    assert read == [20000 + a for a in range(6)]
    print(f"every value read is its own axis's; {m.client.stray_replies} late replies were read past")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
