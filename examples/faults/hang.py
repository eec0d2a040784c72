"""Cookbook: a firmware that stops answering for a while (docs/faults.md "hang").

A careful host times out, waits a little longer each time, and tries again; after a few rounds it
gives up and says so.
"""
import opentmcl.sim
from opentmcl.host import TmclTimeout

FAULTS = {"seed": 10, "fault": [{"name": "busy", "kind": "hang", "duration": 1.0}]}


def ask_with_backoff(m, tries: int = 6):
    wait = 0.1
    for _ in range(tries):
        try:
            return m.request(10, 66, 0)
        except TmclTimeout:
            m.client.sleep(wait)
            wait *= 2
    raise RuntimeError("the module does not answer")


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.2)
    m.client.transport.faults.trigger("busy")
    assert ask_with_backoff(m).value == 1
    print("answered again after the firmware hung for 1 s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
