"""What a careful host does on a bad day (docs/faults.md "Cookbook"): the small routines the
cookbook's examples share. Written against the host API only, so they run unchanged on a real
module.

- A request that timed out may or may not have been done (its reply or the request was lost):
  only repeat what is safe to repeat (a SAP of a value, MVP ABS), and read back what matters.
- Status 1 means the module saw a garbled request (wrong checksum, manual 3.2.1): send it again.
- A garbled reply (TmclChecksumError) says nothing about the request: read again.
- Give up after a few tries and say so, instead of waiting for ever.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from typing import TypeVar

from opentmcl.host import TmclChecksumError, TmclStatusError, TmclTimeout

T = TypeVar("T")
TRIES = 5
GAP, SAP = 6, 5


class GaveUp(RuntimeError):
    """The module did not answer after TRIES tries: the caller stops what it was doing."""


def retry(call: Callable[[], T], tries: int = TRIES) -> T:
    """`call()`, tried again after a time-out, a garbled reply or status 1 ("wrong checksum")."""
    for _ in range(tries):
        try:
            return call()
        except (TmclTimeout, TmclChecksumError):
            continue
        except TmclStatusError as exc:
            if exc.status != 1:
                raise
    raise GaveUp(f"no good reply after {tries} tries")


def set_parameter(m, number: int, axis: int, value: int) -> None:
    """SAP until GAP reads `value` back (a SAP is safe to repeat)."""
    for _ in range(TRIES):
        retry(lambda: m.request(SAP, number, axis, value))
        if retry(lambda: m.request(GAP, number, axis).value) == value:
            return
    raise GaveUp(f"axis parameter {number} of axis {axis} does not take {value}")


def wait_until(check: Callable[[], bool], seconds: float, sleep: Callable[[float], None] = time.sleep,
               step: float = 0.05) -> None:
    """Poll `check()` until it is true; GaveUp after `seconds` (measured by the sleeps)."""
    waited = 0.0
    while not check():
        if waited >= seconds:
            raise GaveUp(f"not done within {seconds:g} s")
        sleep(step)
        waited += step
