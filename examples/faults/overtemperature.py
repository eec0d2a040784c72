"""Cookbook: the driver gets hot (docs/faults.md "overtemperature").

AP208 (PD86-1180 manual 5, TMC262 driver error flags): bit 2 "pre-warning overtemperature", bit 1
"driver is shut down due to overtemperature". A careful host watches AP208 while it moves: on the
pre-warning it lowers the run current (AP6), on a shutdown it stops the motor and waits until the
driver has cooled down before it goes on.
"""
import opentmcl.sim
from careful import retry, wait_until

FAULTS = {"seed": 11, "fault": [
    {"kind": "overtemperature", "level": "prewarning", "at": 0.5, "duration": 3.0},
    {"kind": "overtemperature", "level": "shutdown", "at": 1.0, "duration": 1.0}]}
ROR, MST, SAP, GAP = 1, 3, 5, 6
SHUTDOWN, PREWARNING = 0x02, 0x04


def main() -> int:
    m = opentmcl.sim.connect("TMCM-6212", faults=FAULTS, timeout=0.2)
    retry(lambda: m.request(ROR, 0, 0, 20000))
    lowered = stopped = False
    for _ in range(40):
        m.client.sleep(0.05)
        flags = retry(lambda: m.request(GAP, 208, 0).value)
        if flags & PREWARNING and not lowered:
            retry(lambda: m.request(SAP, 6, 0, 100))  # less current, less heat
            lowered = True
        if flags & SHUTDOWN:
            retry(lambda: m.request(MST, 0, 0))
            stopped = True
            break
    assert lowered and stopped
    wait_until(lambda: not retry(lambda: m.request(GAP, 208, 0).value) & SHUTDOWN, 5, m.client.sleep)
    print("pre-warning: current lowered; shutdown: stopped, waited until it cooled down")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
