"""Where the dashboard's blocking work runs (docs/dashboard.md "Threat model"), so that nothing
can make a stop wait for a thread:

- `StopLane`: a thread of its own for STOP ALL and the stop commands (MST, 128, 131 from the
  console or the program view), never shared with other requests;
- two `BulkLane`s for the long requests, each with a few threads and at most `BULK_WAITING`
  requests waiting; a request beyond that is answered 503 at once (`Busy`), before its body is
  even decoded. `Lanes.cpu` (one thread) computes: assembling, downloads, parameter files;
  `Lanes.reads` (two threads) reads many values: parameter tables, exports, opening a module.
  One thread for the CPU work: each more thread that computes takes the interpreter's lock
  (GIL) from the stop thread and the event loop in turn (with two, STOP ALL under 45 assemble
  requests took three times as long);
- everything else (one or a few requests to the module) on Starlette's thread pool.
"""
from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator, Callable
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    import anyio

T = TypeVar("T")

BULK_WAITING = 16   # requests waiting for a thread of a bulk lane; more are refused with 503


class Busy(Exception):
    """Too many long requests at once: HTTP 503, try again."""


class StopLane:
    """One thread that runs only stops, one after the other."""

    def __init__(self) -> None:
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="dashboard-stop")

    async def run(self, fn: Callable[..., T], *args: object) -> T:
        return await asyncio.wrap_future(self._pool.submit(fn, *args))

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)


class BulkLane:
    """At most `workers` long requests run at once and `waiting` more wait; `admitted()` refuses
    the next one (Busy) before any of its work is done, `run()` runs its blocking part."""

    def __init__(self, workers: int, waiting: int = BULK_WAITING) -> None:
        self.workers, self.waiting = workers, waiting
        self.count = 0          # admitted and not finished; changed only on the event loop
        self._limiter: anyio.CapacityLimiter | None = None  # made inside the event loop on first use

    @contextlib.asynccontextmanager
    async def admitted(self) -> AsyncIterator[None]:
        if self.count >= self.workers + self.waiting:
            raise Busy(f"busy: {self.count} long requests like this one are running or waiting; try again")
        self.count += 1
        try:
            yield
        finally:
            self.count -= 1

    async def run(self, fn: Callable[..., T], *args: object) -> T:
        import anyio

        if self._limiter is None:
            self._limiter = anyio.CapacityLimiter(self.workers)
        return await anyio.to_thread.run_sync(partial(fn, *args), limiter=self._limiter)


class Lanes:
    """The lanes of one dashboard app."""

    def __init__(self) -> None:
        self.stop = StopLane()
        self.cpu = BulkLane(1)
        self.reads = BulkLane(2)

    async def read(self, fn: Callable[..., T], *args: object) -> T:
        """`fn(*args)` admitted to and run on the reads lane (requests without a body to decode)."""
        async with self.reads.admitted():
            return await self.reads.run(fn, *args)

    def close(self) -> None:
        self.stop.close()
