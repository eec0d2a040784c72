"""Faults on demand from the dashboard (docs/faults.md "Triggering by name", docs/dashboard.md
"Faults"), mounted under a module's /m/{address} prefix, so `guard.Guard` checks every request.

    GET  /api/faults                {"names": [...], "seed": N, "fired": [...]}; names [] without faults
    POST /api/faults/trigger {name} fire the named fault now (a link fault: on the next request)

The page can only trigger the faults the served plan names (`opentmcl serve --faults FILE --web`,
or a ``sim://...?faults=FILE`` link): nothing else about the faults can be set from a browser.
"""
from __future__ import annotations

from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.routing import BaseRoute, Route

from ..faults import FaultBoard, FaultError
from .api import body, json_api, str_field
from .service import Dashboard, DashboardError

FIRED_SHOWN = 20
"""The most recent records the page shows."""


class FaultsApi:
    def __init__(self, dashboard: Dashboard) -> None:
        self.d = dashboard

    def routes(self) -> list[BaseRoute]:
        return [Route("/api/faults", json_api(self.list)),
                Route("/api/faults/trigger", json_api(self.trigger), methods=["POST"])]

    def board(self) -> FaultBoard | None:
        return getattr(self.d, "faults", None)

    def state(self) -> dict[str, object]:
        board = self.board()
        if board is None:
            return {"names": [], "seed": None, "fired": []}
        fired = board.log.since(max(0, len(board.log) - FIRED_SHOWN))
        return {"names": board.names(), "seed": board.seed, "fired": [f.text() for f in fired]}

    async def list(self, _request: Request) -> object:
        return self.state()

    def _trigger(self, name: str) -> dict[str, object]:
        board = self.board()
        if board is None:
            raise DashboardError("no faults are armed here (opentmcl serve --faults FILE, or a sim:// URL "
                                 "with ?faults=FILE)")
        try:
            board.trigger(name)
        except FaultError as exc:
            raise DashboardError(str(exc)) from None
        return self.state()

    async def trigger(self, request: Request) -> object:
        name = str_field(await body(request), "name")
        return await run_in_threadpool(self._trigger, name)
