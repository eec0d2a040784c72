"""Cookbook (docs/faults.md "A third-party client"): an unmodified PyTrinamic script against a
served module whose link drops 1 % of the replies. PyTrinamic raises RuntimeError("TMCL datagram
timed out") when no reply comes; this script handles it the way a careful host does: it retries
the request (a set and a read are safe to repeat), and counts what happened.

    opentmcl serve -m TMCM-6212 --pty --faults examples/faults/drop_1_percent.toml
    python examples/faults/pytrinamic_timeouts.py /dev/pts/N
"""
import sys

from pytrinamic.connections import ConnectionManager
from pytrinamic.modules import TMCM6212

ROUNDS = 200
TRIES = 5


def retried(call):
    """`call()`, tried again after a time-out (at most TRIES times); the number of time-outs."""
    for attempt in range(TRIES):
        try:
            return call(), attempt
        except RuntimeError as exc:      # PyTrinamic's "TMCL datagram timed out"
            if "timed out" not in str(exc):
                raise
    raise RuntimeError(f"no reply after {TRIES} tries")


def main(port: str) -> int:
    timeouts = 0
    with ConnectionManager(f"--interface serial_tmcl --port {port} --data-rate 9600").connect() as interface:
        interface.set_timeout(0.5)
        motor = TMCM6212(interface).motors[0]
        for i in range(ROUNDS):
            speed = 10000 + i
            _, lost = retried(lambda s=speed: motor.set_axis_parameter(motor.AP.MaxVelocity, s))
            value, lost_read = retried(lambda: motor.get_axis_parameter(motor.AP.MaxVelocity))
            timeouts += lost + lost_read
            if value != speed:
                print(f"wrong value: {value} != {speed}")
                return 1
    print(f"rounds {ROUNDS} timeouts {timeouts}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
