"""Cookbook: a link that is down for a while (docs/faults.md "link_down"): a USB adapter that drops
out, a cable pulled and put back.

A careful host does not hammer a dead link for ever: it times out, tries a few times, then stops
what it was doing and says so; later it tries again.
"""
import opentmcl.sim
from careful import GaveUp, retry

FAULTS = {"seed": 8, "fault": [{"name": "unplugged", "kind": "link_down", "duration": 2.0}]}


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.2)
    m.client.transport.faults.trigger("unplugged")
    try:
        retry(lambda: m.request(10, 66, 0))          # 5 tries of 0.2 s: still down
    except GaveUp as exc:
        print(f"stopped: {exc}")
    m.client.sleep(1.5)                              # later: the link is back
    assert retry(lambda: m.request(10, 66, 0)).value == 1
    print("link back")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
