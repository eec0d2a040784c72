"""The parameters and charts views' endpoints (docs/dashboard-parameters.md,
docs/dashboard-charts.md), mounted under a module's /m/{address} prefix by web/app.py, so
`guard.Guard` checks every request (Host, token, Origin and X-OpenTMCL on POST, body limit).

    GET  /api/params/values/{axis}   the values of axis {axis} and of every global parameter
                                     (one request per refresh: the live tables' batched read)
    GET  /api/params/export?format=json|toml
                                     the module's parameter set as a file (opentmcl.host.paramset)
    POST /api/params/diff            {"text": file} -> {"changes": [...], "warnings": [...]}
    POST /api/params/apply           {"text": file} -> {"applied": n, "changes": [...]}
    GET  /api/charts/series, POST /api/charts/subscribe, GET /api/charts/samples (web/sampler.py)

A file that cannot be applied (another module, a value outside the manual's range, ...) is a 400
with {"error": first reason, "problems": [every reason]}; nothing is written.
"""
from __future__ import annotations

import json
from collections.abc import Awaitable, Callable

from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.routing import BaseRoute, Route

from ..host import TmclError, paramset
from . import units
from .lanes import Busy, Lanes
from .sampler import Sampler
from .service import READ_COMMANDS, Dashboard, DashboardError

Json = dict[str, object]
MAX_FILE = paramset.MAX_TEXT


class _Refused(Exception):
    def __init__(self, message: str, problems: list[str] | None = None) -> None:
        super().__init__(message)
        self.problems = problems


def _api(handler: Callable[[Request], Awaitable[object]]) -> Callable[[Request], Awaitable[Response]]:
    """JSON answers; the caller's mistakes are a 400 with {"error": "<one line>"}, too many long
    requests at once a 503 (web/lanes.py)."""
    async def endpoint(request: Request) -> Response:
        try:
            result = await handler(request)
        except Busy as exc:
            return JSONResponse({"error": str(exc)}, status_code=503, headers={"Retry-After": "1"})
        except paramset.ParamSetError as exc:
            return JSONResponse({"error": str(exc)[:300], "problems": exc.problems[:200]}, status_code=400)
        except (_Refused, DashboardError, ValueError) as exc:
            return JSONResponse({"error": " ".join(str(exc).split())[:300]}, status_code=400)
        return result if isinstance(result, Response) else JSONResponse(result)
    endpoint.__name__ = getattr(handler, "__name__", "endpoint")
    return endpoint


async def _body(request: Request) -> Json:
    if request.headers.get("content-type", "").split(";")[0].strip().lower() != "application/json":
        raise _Refused("requests must be JSON (Content-Type: application/json)")
    try:
        data = json.loads(await request.body())
    except (json.JSONDecodeError, UnicodeDecodeError, RecursionError):
        raise _Refused("request body is not JSON") from None
    if not isinstance(data, dict):
        raise _Refused("request body must be a JSON object")
    return data


def _text(data: Json) -> str:
    text = data.get("text")
    if not isinstance(text, str):
        raise _Refused("text must be the parameter-set file as a string")
    return text


def _change(c: paramset.Change) -> Json:
    return {"kind": c.kind, "index": c.index, "number": c.number, "name": c.name,
            "current": c.current, "value": c.value}


class ParamsApi:
    """Batched reads, export, diff and apply of one dashboard's module (on the bulk lane)."""

    def __init__(self, dashboard: Dashboard, lanes: Lanes) -> None:
        self.d = dashboard
        self.lanes = lanes

    def _guarded(self, fn: Callable[[], object]) -> object:
        """`fn`, whose requests take their turns on the link (a stop goes between two of them);
        a link or status error is a DashboardError."""
        try:
            return fn()
        except paramset.ParamSetError:
            raise
        except TmclError as exc:
            raise DashboardError(str(exc)) from None

    # --- batched values ---
    def read_values(self, axis: int) -> Json:
        d, p = self.d, self.d.profile
        if not 0 <= axis < p.axes:
            raise DashboardError(f"{p.name} has axes 0..{p.axes - 1}, not {axis}")
        axis_numbers = [n for n, q in sorted(p.axis_parameters.items()) if q.readable]
        globals_ = [(b, n) for (b, n), q in sorted(p.global_parameters.items()) if q.readable]
        gap, ggp = READ_COMMANDS["axis"], READ_COMMANDS["global"]
        values = d.read_many([(gap, n, axis, 0) for n in axis_numbers] + [(ggp, n, b, 0) for b, n in globals_])
        axis_values = {str(n): v for n, v in zip(axis_numbers, values, strict=False)}
        global_values = {f"{b}:{n}": v for (b, n), v in zip(globals_, values[len(axis_numbers):], strict=True)}
        return {"axis": axis, "values": {"axis": axis_values, "global": global_values},
                "connected": d.connected}

    async def values(self, request: Request) -> object:
        try:
            axis = int(request.path_params["axis"])
        except ValueError:
            raise _Refused("axis must be a number") from None
        return await self.lanes.read(self.read_values, axis)

    # --- export / diff / apply ---
    async def export(self, request: Request) -> object:
        fmt = request.query_params.get("format", "json")
        if fmt not in ("json", "toml"):
            raise _Refused(f"format must be json or toml, not {fmt[:20]!r}")
        ps = await self.lanes.read(self._guarded, lambda: paramset.export_set(self.d.module))
        assert isinstance(ps, paramset.ParamSet)
        text = paramset.to_json(ps) if fmt == "json" else paramset.to_toml(ps)
        text = units.attach(text, fmt, self.d.units)  # each axis's unit setting goes with it
        name = f"{ps.module}-address{self.d.module.address}.{fmt}"
        media = "application/json" if fmt == "json" else "application/toml"
        return Response(text, media_type=media, headers={
            "Content-Disposition": f'attachment; filename="{name}"', "Cache-Control": "no-store"})

    def _diff(self, text: str) -> Json:
        ps = paramset.parse(text)
        changes = paramset.diff(self.d.module, ps)
        warnings = []
        if ps.firmware and ps.firmware != self.d.version:
            warnings.append(f"the file was exported from firmware {ps.firmware}, the module has {self.d.version}")
        return {"module": ps.module, "firmware": ps.firmware, "entries": len(ps.entries),
                "changes": [_change(c) for c in changes], "warnings": warnings,
                "units": units.settings_in(text, self.d.profile.axes)}

    async def diff(self, request: Request) -> object:
        async with self.lanes.cpu.admitted():
            text = _text(await _body(request))
            return await self.lanes.cpu.run(self._guarded, lambda: self._diff(text))

    def _apply(self, text: str) -> Json:
        ps = paramset.parse(text)
        changes = paramset.diff(self.d.module, ps)
        applied = paramset.apply(self.d.module, changes)
        settings = units.settings_in(text, self.d.profile.axes)
        self.d.units.update(settings)
        return {"applied": applied, "changes": [_change(c) for c in changes], "units": settings}

    async def apply(self, request: Request) -> object:
        async with self.lanes.cpu.admitted():
            text = _text(await _body(request))
            return await self.lanes.cpu.run(self._guarded, lambda: self._apply(text))


class ChartsApi:
    """The chart sampler's subscription and polling endpoints."""

    def __init__(self, sampler: Sampler) -> None:
        self.sampler = sampler

    async def series(self, _request: Request) -> object:
        return self.sampler.catalogue()

    async def subscribe(self, request: Request) -> object:
        b = await _body(request)
        client, items = b.get("client"), b.get("series")
        if client is not None and not isinstance(client, str):
            raise _Refused("client must be a string")
        if not isinstance(items, list):
            raise _Refused("series must be a list of {kind, index, number}")
        if len(items) > 64:
            raise _Refused("too many series")
        series = [self.sampler.check(*(i.get(k) for k in ("kind", "index", "number"))) if isinstance(i, dict)
                  else self.sampler.check(None, None, None) for i in items]
        cid = self.sampler.subscribe(client, series)
        return {"client": cid, "series": [f"{k}:{i}:{n}" for k, i, n in series]}

    async def samples(self, request: Request) -> object:
        q = request.query_params
        try:
            since = int(q.get("since", "0"))
        except ValueError:
            raise _Refused("since must be a number") from None
        return self.sampler.samples(q.get("client", "")[:64], since)


def routes(dashboard: Dashboard, lanes: Lanes) -> list[BaseRoute]:
    """The routes to mount beside the module's own (web/app.py ModuleApi.routes)."""
    p, c = ParamsApi(dashboard, lanes), ChartsApi(Sampler(dashboard))
    post = ["POST"]
    return [
        Route("/api/params/values/{axis}", _api(p.values)),
        Route("/api/params/export", _api(p.export)),
        Route("/api/params/diff", _api(p.diff), methods=post),
        Route("/api/params/apply", _api(p.apply), methods=post),
        Route("/api/charts/series", _api(c.series)),
        Route("/api/charts/subscribe", _api(c.subscribe), methods=post),
        Route("/api/charts/samples", _api(c.samples)),
    ]
