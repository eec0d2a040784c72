"""Cookbook: a request garbled on the line (docs/faults.md "corrupt_request").

The module answers status 1, "wrong checksum" (TMCM-6212 manual 3.2.1), and does nothing. A careful
host sends the request again; a careless one takes the TmclStatusError as final (or ignores it).
"""
import opentmcl.sim
from careful import retry

FAULTS = {"seed": 3, "fault": [{"kind": "corrupt_request", "probability": 0.2, "byte": 7}]}
SAP, GAP = 5, 6


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.2)
    for value in range(1000, 1050):
        retry(lambda v=value: m.request(SAP, 5, 0, v))
        assert retry(lambda: m.request(GAP, 5, 0).value) == value
    print(f"50 writes done; {len(m.client.transport.faults.log)} were garbled and answered with status 1")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
