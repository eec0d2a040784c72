"""The dashboard web app (Starlette): a single page, a JSON API and one WebSocket per module.

    GET  /                         redirects to the first module's page
    GET  /api/modules              [{address, module, url}] of every module served
    GET  /static/...               the page's script and style (no build step, no CDN)

Each module lives under /m/{address}; these paths follow that prefix (the page uses relative paths,
so one page serves every module). An unknown address is a 404 with {"error": ...}.

    GET  /                         the module's page
    GET  /api/overview             module type, firmware version, address, connection, I/O map
    GET  /api/state                axis cards, I/O and program status (5 per second)
    GET  /api/params/axis/{n}      axis parameter table with values; POST /api/params/axis sets one
    GET  /api/params/global        global parameter table;              POST /api/params/global
    POST /api/params/store         STAP/RSAP/STGP/RSGP
    POST /api/console              one direct-mode instruction -> reply with status text
    POST /api/io/output, /api/io/force
    POST /api/program/{assemble,download,run,stop,step,reset,breakpoints}; GET /api/program
    WS   /ws                       {"type": "samples"} 25 times a second, {"type": "state"} on change

Every request passes `guard.Guard` first (Host allow-list, token, Origin, X-OpenTMCL header, body limit).
"""
from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from collections.abc import Sequence
from importlib import resources

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.middleware import Middleware
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, RedirectResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from .guard import BODY_TIMEOUT, MAX_BODY, SUBPROTOCOL, Guard
from .service import FAST_HZ, Dashboard, DashboardError

log = logging.getLogger("opentmcl.web")


def static_dir() -> str:
    return str(resources.files("opentmcl.web").joinpath("static"))


class BadRequest(ValueError):
    pass


async def _body(request: Request) -> dict:
    # Only JSON: a cross-site page cannot send it without a CORS preflight, which is never granted,
    # so another web site open in the same browser cannot drive the motors (CSRF).
    if request.headers.get("content-type", "").split(";")[0].strip().lower() != "application/json":
        raise BadRequest("requests must be JSON (Content-Type: application/json)")
    try:
        data = await request.json()
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise BadRequest("request body is not JSON") from None
    if not isinstance(data, dict):
        raise BadRequest("request body must be a JSON object")
    return data


def _one_line(text: str, limit: int = 200) -> str:
    text = " ".join(text.split())
    return text if len(text) <= limit else text[:limit] + "..."


def _int(data: dict, key: str, *, optional: bool = False) -> int | None:
    value = data.get(key)
    if value is None and optional:
        return None
    if isinstance(value, str):
        try:
            value = int(value.strip(), 0)
        except ValueError:
            raise BadRequest(f"{key} must be an integer, got {value!r}") from None
    if isinstance(value, bool) or not isinstance(value, int):
        raise BadRequest(f"{key} must be an integer, got {value!r}")
    return value


def _str(data: dict, key: str) -> str:
    value = data.get(key)
    if not isinstance(value, str):
        raise BadRequest(f"{key} must be a string")
    return value


def create_app(dashboards: Dashboard | Sequence[Dashboard], *, allowed_hosts: Sequence[str] = (),
               token: str | None = None, max_body: int = MAX_BODY,
               body_timeout: float = BODY_TIMEOUT) -> Starlette:
    """The Starlette app for one `Dashboard` or several (one per module, distinct addresses).

    `allowed_hosts`: Host names accepted besides the loopback ones (the bound address, --allow-host);
    `token`: required on every request when given; `max_body`: the largest request body in bytes,
    `body_timeout`: seconds within which it must have arrived.
    (Starlette's TestClient sends Host "testserver": give it base_url="http://127.0.0.1".)"""
    if isinstance(dashboards, Dashboard):
        dashboards = [dashboards]
    by_address: dict[int, Dashboard] = {}
    for d in dashboards:
        if d.module.address in by_address:
            raise ValueError(f"two dashboards for module address {d.module.address}")
        by_address[d.module.address] = d
    if not by_address:
        raise ValueError("the dashboard needs at least one module")

    def listing(request: Request) -> list[dict]:
        root = request.scope.get("root_path", "")
        return [{"address": a, "module": d.profile.name, "url": f"{root}/m/{a}/"} for a, d in by_address.items()]

    async def modules(request: Request) -> Response:
        return JSONResponse(listing(request))

    async def home(request: Request) -> Response:
        return RedirectResponse(listing(request)[0]["url"])

    async def unknown(request: Request) -> Response:
        known = ", ".join(map(str, by_address))
        return JSONResponse({"error": f"no module at address {request.path_params['address']} "
                                      f"(addresses: {known})"}, status_code=404)

    routes = [
        Route("/", home),
        Route("/api/modules", modules),
        *(Mount(f"/m/{a}", routes=_module_routes(d)) for a, d in by_address.items()),
        Route("/m/{address}/{rest:path}", unknown, methods=["GET", "POST", "PUT", "DELETE", "PATCH"]),
        Mount("/static", app=StaticFiles(directory=static_dir()), name="static"),
    ]
    guard = Middleware(Guard, allowed_hosts=allowed_hosts, token=token, max_body=max_body,
                       body_timeout=body_timeout)
    return Starlette(routes=routes, middleware=[guard])


def _module_routes(d: Dashboard) -> list:
    """The page, API and WebSocket of one module, relative to its /m/{address} prefix."""

    def api(handler):
        async def endpoint(request: Request) -> Response:
            try:
                result = await handler(request)
            except (BadRequest, DashboardError) as exc:
                return JSONResponse({"error": str(exc)}, status_code=400)
            except ValueError as exc:  # e.g. a number literal too long to convert: still the input's fault
                return JSONResponse({"error": _one_line(f"bad request: {exc}")}, status_code=400)
            except RecursionError:
                return JSONResponse({"error": "bad request: input nested too deeply"}, status_code=400)
            return JSONResponse(result if result is not None else {"ok": True})
        return endpoint

    async def index(_request: Request) -> Response:
        return FileResponse(f"{static_dir()}/index.html", headers={"Cache-Control": "no-store"})

    async def overview(_r):
        return await run_in_threadpool(d.overview)

    async def state(_r):
        return d.state or await run_in_threadpool(d.sample_slow)

    async def axis_params(r: Request):
        try:
            n = int(r.path_params["axis"])
        except ValueError:
            raise BadRequest("axis must be a number") from None
        return {"axis": n, "params": await run_in_threadpool(d.axis_parameters, n)}

    async def global_params(_r):
        return {"params": await run_in_threadpool(d.global_parameters)}

    async def set_axis_param(r):
        b = await _body(r)
        value = await run_in_threadpool(d.set_axis_parameter, _int(b, "axis"), _int(b, "number"), _int(b, "value"))
        return {"value": value}

    async def set_global_param(r):
        b = await _body(r)
        value = await run_in_threadpool(d.set_global_parameter, _int(b, "bank"), _int(b, "number"), _int(b, "value"))
        return {"value": value}

    async def store(r):
        b = await _body(r)
        await run_in_threadpool(d.store, _str(b, "kind"), _int(b, "number"), _int(b, "index"),
                                bool(b.get("restore", False)))

    async def console(r):
        b = await _body(r)
        return await run_in_threadpool(d.console, _str(b, "line"))

    async def output(r):
        b = await _body(r)
        return {"value": await run_in_threadpool(d.set_output, _int(b, "bank"), _int(b, "port"), _int(b, "value"))}

    async def force(r):
        b = await _body(r)
        await run_in_threadpool(d.force_input, _int(b, "bank"), _int(b, "port"), _int(b, "value", optional=True))

    async def assemble(r):
        b = await _body(r)
        result = await run_in_threadpool(d.assemble, _str(b, "source"))
        result.pop("_program", None)
        return result

    async def download(r):
        b = await _body(r)
        return await run_in_threadpool(d.download, _str(b, "source"))

    async def breakpoints(r):
        b = await _body(r)
        lines = b.get("lines")
        if not isinstance(lines, list) or not all(isinstance(x, int) and not isinstance(x, bool) for x in lines):
            raise BadRequest("lines must be a list of line numbers")
        return {"addresses": await run_in_threadpool(d.set_breakpoints, lines)}

    def action(fn):
        async def handler(_r):
            out = await run_in_threadpool(fn)
            return out if isinstance(out, dict) else await run_in_threadpool(d.program_state)
        return handler

    async def program(_r):
        st = await run_in_threadpool(d.program_state)
        return {"source": d.source, "state": st,
                "lines": None if d.program is None else
                [s.line if s is not None and s.file == "<editor>" else None for s in d.program.source]}

    async def ws(websocket: WebSocket) -> None:
        await websocket.accept(subprotocol=SUBPROTOCOL)  # Guard checked Origin and the subprotocol
        gone = asyncio.Event()

        async def reader() -> None:
            # The page sends nothing; reading notices the browser going away.
            try:
                while (await websocket.receive())["type"] != "websocket.disconnect":
                    pass
            except (WebSocketDisconnect, RuntimeError, ConnectionError):
                pass
            gone.set()

        reading = asyncio.create_task(reader())
        last_seq = d.samples[-1].seq - 1 if d.samples else 0
        last_state = None
        try:
            await websocket.send_json({"type": "hello", "overview": await run_in_threadpool(d.overview)})
            while not gone.is_set() and not d.closed.is_set():
                new = d.samples_since(last_seq)
                if new:
                    last_seq = new[-1].seq
                    await websocket.send_json({"type": "samples", "samples": [
                        {"seq": s.seq, "t": s.t, "p": s.position, "v": s.velocity} for s in new]})
                if d.state and d.state is not last_state:
                    last_state = d.state
                    await websocket.send_json({"type": "state", "state": last_state})
                await asyncio.sleep(1.0 / (FAST_HZ * 2))
        except (WebSocketDisconnect, RuntimeError, ConnectionError):
            pass
        finally:
            reading.cancel()
            if not gone.is_set():
                with contextlib.suppress(RuntimeError, ConnectionError):
                    await websocket.close(1001)

    return [
        Route("/", index),
        Route("/api/overview", api(overview)),
        Route("/api/state", api(state)),
        Route("/api/params/axis/{axis}", api(axis_params)),
        Route("/api/params/global", api(global_params)),
        Route("/api/params/axis", api(set_axis_param), methods=["POST"]),
        Route("/api/params/global", api(set_global_param), methods=["POST"]),
        Route("/api/params/store", api(store), methods=["POST"]),
        Route("/api/console", api(console), methods=["POST"]),
        Route("/api/io/output", api(output), methods=["POST"]),
        Route("/api/io/force", api(force), methods=["POST"]),
        Route("/api/program", api(program)),
        Route("/api/program/assemble", api(assemble), methods=["POST"]),
        Route("/api/program/download", api(download), methods=["POST"]),
        Route("/api/program/breakpoints", api(breakpoints), methods=["POST"]),
        Route("/api/program/run", api(action(d.run)), methods=["POST"]),
        Route("/api/program/stop", api(action(d.stop)), methods=["POST"]),
        Route("/api/program/step", api(action(d.step)), methods=["POST"]),
        Route("/api/program/reset", api(action(d.reset)), methods=["POST"]),
        WebSocketRoute("/ws", ws),
    ]
