"""The charts view's samples (docs/dashboard-charts.md): any readable axis parameter (GAP), global
parameter (GGP) or I/O port (GIO) a browser subscribed to, read on the server at the live rate.

    GET  /api/charts/series          what can be charted: {"axis": [...], "global": [...], "io": [...]}
    POST /api/charts/subscribe       {"client"?: id, "series": [{"kind", "index", "number"}, ...]}
                                     -> {"client": id, "series": [key, ...]}
    GET  /api/charts/samples?client=ID&since=SEQ
                                     -> {"series": [key, ...], "rows": [[seq, t, v0, v1, ...], ...]}

A series is ("axis", axis, number), ("global", bank, number) or ("io", bank, port); its key is
"axis:0:206" etc. A client holds at most `MAX_SERIES` series and at most `MAX_CLIENTS` clients are
kept; one that has not polled for `IDLE_SECONDS` is dropped, and with no client left the sampling
thread ends. Each client keeps the last `HISTORY_SECONDS` of rows; t is the dashboard's clock, the
same as the WebSocket samples'. Row numbers (seq) count the ticks of this sampler, shared by all
clients, so a page may keep its `since` across a new subscription.
"""
from __future__ import annotations

import itertools
import logging
import secrets
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

from .service import FAST_HZ, HISTORY_SECONDS, READ_COMMANDS, Dashboard, DashboardError, Stopping

log = logging.getLogger("opentmcl.web")

MAX_SERIES = 16         # series per client
MAX_CLIENTS = 8         # clients per module
IDLE_SECONDS = 15.0     # a client that has not polled for this long is dropped
ROWS_KEPT = int(HISTORY_SECONDS * FAST_HZ) + FAST_HZ

Series = tuple[str, int, int]   # (kind, axis/bank, number/port)
Row = list[float | int | None]  # [seq, t, value per series]


def key(s: Series) -> str:
    return f"{s[0]}:{s[1]}:{s[2]}"


@dataclass
class Client:
    series: list[Series]
    last_poll: float
    rows: deque[Row] = field(default_factory=lambda: deque(maxlen=ROWS_KEPT))


class Sampler:
    """Subscriptions and samples of one dashboard. `tick()` reads one row for every client; the
    thread calls it `hz` times a second while anyone is subscribed (tests call it directly)."""

    def __init__(self, dashboard: Dashboard, hz: float = FAST_HZ,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.d = dashboard
        self.period = 1.0 / hz
        self.clock = clock
        self.clients: dict[str, Client] = {}
        self.lock = threading.Lock()
        self.seq = itertools.count(1)
        self._thread: threading.Thread | None = None

    # --- what can be charted ---------------------------------------------------------------
    def catalogue(self) -> dict[str, object]:
        p = self.d.profile
        axis = [{"number": q.number, "name": q.name, "title": q.title, "unit": q.unit}
                for _, q in sorted(p.axis_parameters.items()) if q.readable]
        glob = [{"bank": b, "number": n, "name": q.name, "title": q.title, "unit": q.unit}
                for (b, n), q in sorted(p.global_parameters.items()) if q.readable]
        io = [{"bank": i.bank, "port": i.port, "name": i.name, "kind": i.kind}
              for _, i in sorted(p.io.items()) if "R" in i.access]
        return {"axis": axis, "global": glob, "io": io, "axes": p.axes, "max_series": MAX_SERIES}

    def check(self, kind: object, index: object, number: object) -> Series:
        """A series the profile can read, or DashboardError."""
        if kind not in READ_COMMANDS or not all(isinstance(x, int) and not isinstance(x, bool) for x in (index, number)):
            raise DashboardError(f"a series is {{kind: axis|global|io, index, number}}, not {kind!r}, {index!r}, {number!r}"[:200])
        assert isinstance(kind, str) and isinstance(index, int) and isinstance(number, int)
        p = self.d.profile
        if kind == "axis":
            q = p.axis_parameters.get(number)
            ok = 0 <= index < p.axes and q is not None and q.readable
        elif kind == "global":
            g = p.global_parameters.get((index, number))
            ok = g is not None and g.readable
        else:
            io = p.io.get((index, number))
            ok = io is not None and "R" in io.access
        if not ok:
            raise DashboardError(f"{kind} {index}/{number} cannot be read on {p.name}")
        return (kind, index, number)

    # --- subscriptions --------------------------------------------------------------------
    def subscribe(self, client: str | None, series: list[Series]) -> str:
        """Set `client`'s series (a new client when None or unknown); its id."""
        if len(series) > MAX_SERIES:
            raise DashboardError(f"at most {MAX_SERIES} series per page, not {len(series)}")
        now = self.clock()
        with self.lock:
            self._expire(now)
            old = self.clients.get(client) if client else None
            if old is None:
                if len(self.clients) >= MAX_CLIENTS:
                    raise DashboardError(f"at most {MAX_CLIENTS} pages chart this module at once")
                client = secrets.token_hex(8)
                self.clients[client] = Client(list(series), now)
            elif old.series != series:
                old.series, old.last_poll = list(series), now
                old.rows.clear()
        self._ensure_thread()
        assert client is not None
        return client

    def samples(self, client: str, since: int) -> dict[str, object]:
        with self.lock:
            c = self.clients.get(client)
            if c is None:
                raise DashboardError("unknown chart client: subscribe again")
            c.last_poll = self.clock()
            rows = [r for r in c.rows if isinstance(r[0], int) and r[0] > since]
            return {"series": [key(s) for s in c.series], "rows": rows}

    def _expire(self, now: float) -> None:
        for cid in [c for c, v in self.clients.items() if now - v.last_poll > IDLE_SECONDS]:
            del self.clients[cid]

    # --- sampling -------------------------------------------------------------------------
    def tick(self) -> int:
        """Read every subscribed series once (each distinct one once) and append a row to each
        client; the number of clients left."""
        with self.lock:
            self._expire(self.clock())
            wanted = {s: None for c in self.clients.values() for s in c.series}
        values = dict(zip(wanted, self.d.read_many([(READ_COMMANDS[s[0]], s[2], s[1], 0) for s in wanted]), strict=True))
        t = round(self.d.clock() - self.d.start, 4)
        seq = next(self.seq)
        with self.lock:
            for c in self.clients.values():
                c.rows.append([seq, t, *(values.get(s) for s in c.series)])
            return len(self.clients)

    def _ensure_thread(self) -> None:
        with self.lock:
            if self._thread is not None and self._thread.is_alive():
                return
            self._thread = threading.Thread(target=self._loop, name="dashboard-sampler", daemon=True)
            self._thread.start()

    def _loop(self) -> None:
        next_t = time.monotonic()
        while not self.d.closed.is_set():
            try:
                self.tick()
            except Stopping:
                return
            except Exception:  # a bug must not stop the charts (link errors: Dashboard.attempt)
                log.exception("chart sampling failed")
            with self.lock:
                if not self.clients:  # under the lock: a new subscriber starts a new thread
                    self._thread = None
                    return
            next_t += self.period
            delay = next_t - time.monotonic()
            if delay < 0:  # fell behind (slow link): do not try to catch up
                next_t, delay = time.monotonic(), 0.0
            self.d.closed.wait(delay)
