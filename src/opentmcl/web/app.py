"""The dashboard web app (Starlette): a single page, a JSON API and one WebSocket per module.

    GET  /                         redirects to the first module's page
    GET  /api/modules              [{address, module, url}] of every module served
    POST /api/stop-all             cancels a scan; program stop (128) and MST on every axis of every
                                   module served or found by the scan
    GET  /api/scan                 the module scan's progress and findings; POST starts one
    POST /api/scan/cancel, /api/scan/open {address}: stop the scan; serve a module it found
    GET  /static/...               the page's script and style (no build step, no CDN)

Each module lives under /m/{address}; these paths follow that prefix (the page uses relative paths,
so one page serves every module). An unknown address is a 404 with {"error": ...}.

    GET  /                         the module's page
    GET  /api/overview             module type, firmware version, address, connection, I/O map
    GET  /api/state                axis cards, I/O and program status (5 per second)
    GET  /api/motion/{n}           velocity unit and range, positions, RFS STATUS of axis n
    GET  /api/params/axis/{n}      axis parameter table with values; POST /api/params/axis sets one
    GET  /api/params/global        global parameter table;              POST /api/params/global
    POST /api/params/store         STAP/RSAP/STGP/RSGP
    POST /api/console              one direct-mode instruction -> reply with status text
    POST /api/io/output, /api/io/force
    POST /api/program/{assemble,download,run,run_from_start,stop,step,reset,breakpoints}; GET /api/program
    GET  /api/faults; POST /api/faults/trigger {name}   named faults of the served plan (web/faults.py)
    WS   /ws                       {"type": "samples"} 25 times a second, {"type": "state"} on change

Every request passes `guard.Guard` first (Host allow-list, token, Origin, X-OpenTMCL header, body limit).
Stops run on a thread of their own, long requests on bounded lanes (web/lanes.py).
"""
from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable, Sequence
from functools import partial
from importlib import resources

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.middleware import Middleware
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, RedirectResponse, Response
from starlette.routing import BaseRoute, Mount, Route, Router, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.types import Receive, Scope, Send
from starlette.websockets import WebSocket, WebSocketDisconnect

from ..host import TmclError
from . import motion
from . import params as data_views
from .api import BadRequest, Json, json_api
from .api import body as _body
from .api import int_field as _int
from .api import line_numbers as _line_numbers
from .api import number_field as _number
from .api import optional_int as _optional_int
from .api import str_field as _str
from .connlimits import STOP_ALL_PATH
from .faults import FaultsApi
from .guard import BODY_TIMEOUT, MAX_BODY, SUBPROTOCOL, Guard
from .lanes import Lanes
from .scan import TIMEOUT_DEFAULT, TIMEOUT_MAX, Scanner
from .service import FAST_HZ, Dashboard, DashboardError, Poller, is_stop
from .tools import ToolsApi

log = logging.getLogger("opentmcl.web")

# A WebSocket that ends, however it ends: the browser left, the server closes, the socket broke.
CLOSED = (WebSocketDisconnect, RuntimeError, ConnectionError)


def static_dir() -> str:
    return str(resources.files("opentmcl.web").joinpath("static"))


# --- the app -----------------------------------------------------------------------------------

def create_app(dashboards: Dashboard | Sequence[Dashboard], *, allowed_hosts: Sequence[str] = (),
               token: str | None = None, max_body: int = MAX_BODY,
               body_timeout: float = BODY_TIMEOUT) -> Starlette:
    """The Starlette app for one `Dashboard` or several (one per module, distinct addresses).

    `allowed_hosts`: Host names accepted besides the loopback ones (the bound address, --allow-host);
    `token`: required on every request when given; `max_body`: the largest request body in bytes,
    `body_timeout`: seconds within which it must have arrived.
    (Starlette's TestClient sends Host "testserver": give it base_url="http://127.0.0.1".)"""
    index = ModuleIndex([dashboards] if isinstance(dashboards, Dashboard) else dashboards)
    post = ["POST"]
    routes: list[BaseRoute] = [
        Route("/", index.home),
        Route("/favicon.ico", favicon),
        Route("/api/modules", index.modules),
        Route(STOP_ALL_PATH, json_api(index.stop_all), methods=post),
        Route("/api/scan", json_api(index.scan_status)),
        Route("/api/scan", json_api(index.scan_start), methods=post),
        Route("/api/scan/cancel", json_api(index.scan_cancel), methods=post),
        Route("/api/scan/open", json_api(index.scan_open), methods=post),
        Route("/api/bus", json_api(index.bus)),
        Mount("/m/{address:int}", app=index.dispatch),
        Route("/m/{address}/{rest:path}", index.unknown, methods=["GET", "POST", "PUT", "DELETE", "PATCH"]),
        Mount("/static", app=StaticFiles(directory=static_dir()), name="static"),
    ]
    guard = Middleware(Guard, allowed_hosts=allowed_hosts, token=token, max_body=max_body,
                       body_timeout=body_timeout)
    app = Starlette(routes=routes, middleware=[guard])
    app.state.index = index
    return app


async def favicon(_request: Request) -> Response:
    """Browsers ask for /favicon.ico whatever the page links: the page's own SVG icon."""
    return FileResponse(f"{static_dir()}/favicon.svg", media_type="image/svg+xml")


class ModuleIndex:
    """The modules served, by address: the listing, the root redirect, the 404 of an unknown one,
    stop-all over every module and the module scan of the link (that of the first module)."""

    def __init__(self, dashboards: Sequence[Dashboard]) -> None:
        self.lanes = Lanes()
        self.by_address: dict[int, Dashboard] = {}
        self.routers: dict[int, Router] = {}
        for d in dashboards:
            self.add(d)
        if not self.by_address:
            raise ValueError("the dashboard needs at least one module")
        first = next(iter(self.by_address.values()))
        self.scanner = Scanner(first.module.client, lambda: list(self.by_address))
        self.opened: list[Poller] = []   # pollers of the modules opened from the scan

    def add(self, d: Dashboard) -> None:
        if d.module.address in self.by_address:
            raise ValueError(f"two dashboards for module address {d.module.address}")
        self.by_address[d.module.address] = d
        self.routers[d.module.address] = Router(routes=ModuleApi(d, self.lanes).routes())

    async def dispatch(self, scope: Scope, receive: Receive, send: Send) -> None:
        """/m/{address}/...: the module's own routes, or the 404 of an address not served."""
        router = self.routers.get(scope["path_params"]["address"])
        if router is None:
            response = await self.unknown(Request(scope, receive))
            await response(scope, receive, send)
            return
        await router(scope, receive, send)

    def close(self) -> None:
        """Stop the scan, the pollers of the modules opened from it and the stop lane's thread."""
        self.scanner.cancel()
        self.scanner.join()
        for poller in self.opened:
            poller.dashboard.closed.set()
            poller.stop()
        self.lanes.close()

    # --- stop-all and the scan ---
    async def stop_all(self, _request: Request) -> object:
        return await self.lanes.stop.run(self._stop_all)  # its own thread: nothing queues ahead

    def _stop_all(self) -> Json:
        """A running scan is cancelled first; the served modules are stopped at once (their stops
        go ahead of the scan's next turn on the link, a baud-rate scan lends the link back at its
        own rate); the modules the scan found are stopped once it has ended."""
        scanning = bool(self.scanner.status()["running"])
        self.scanner.cancel()
        out = motion.stop_all(list(self.by_address.values()))
        self.scanner.join(2 * TIMEOUT_MAX + 1.0)  # the current address: version and GGP 66 requests
        link = self.scanner.client
        found = [(int(f["address"]), str(f["version"])) for f in self.scanner.status()["found"]  # type: ignore[attr-defined]
                 if f["address"] not in self.by_address and f["baud"] in (None, getattr(link.transport, "baud", None))]
        more = motion.stop_all((), link, found)
        out["modules"] = [*out["modules"], *more["modules"]]  # type: ignore[misc]
        out["ok"] = bool(out["ok"]) and bool(more["ok"])
        out["scan_cancelled"] = scanning
        return out

    async def scan_status(self, _request: Request) -> object:
        return self.scanner.status()

    async def scan_start(self, request: Request) -> object:
        b = await _body(request)
        first, last = _int(b, "first"), _int(b, "last")
        timeout = _number(b, "timeout", TIMEOUT_DEFAULT)
        bauds = b.get("bauds", [])
        if not isinstance(bauds, list) or not all(isinstance(x, int) and not isinstance(x, bool) for x in bauds):
            raise BadRequest("bauds must be a list of baud rates")
        self.scanner.start(first, last, timeout, bauds)
        return self.scanner.status()

    async def scan_cancel(self, _request: Request) -> object:
        self.scanner.cancel()
        return self.scanner.status()

    async def scan_open(self, request: Request) -> object:
        """Serve the module found at `address` on this link (a page of its own, polled)."""
        address = _int(await _body(request), "address")
        if address not in self.by_address:
            found = [f for f in self.scanner.status()["found"] if f["address"] == address]  # type: ignore[attr-defined]
            if not found:
                raise DashboardError(f"the scan found no module at address {address}")
            link = self.scanner.client.transport
            if found[0]["baud"] not in (None, getattr(link, "baud", None)):
                raise DashboardError(f"module {address} answered at {found[0]['baud']} baud; "
                                     "connect the dashboard at that rate to open it")
            d = await self.lanes.read(self._open, address)
            self.opened.append(Poller(d).start())
        return {"address": address, "url": f"{request.scope.get('root_path', '')}/m/{address}/"}

    def _open(self, address: int) -> Dashboard:
        client = self.scanner.client
        try:
            with self.scanner.gate:  # its version string too in a turn (not during a baud-rate scan)
                d = Dashboard(client.module(address), url=f"scan (address {address})")
            d.profile.name  # noqa: B018 - the profile from the version string, or the error now
        except TmclError as exc:
            raise DashboardError(f"cannot open module {address}: {exc}") from None
        if address not in self.by_address:
            self.add(d)
        return self.by_address[address]

    async def bus(self, request: Request) -> object:
        """Every module on the link side by side: those served with their axes' last polled state
        (no request of its own), and those the scan found that are not served (yet)."""
        root = request.scope.get("root_path", "")
        served = []
        for a, d in list(self.by_address.items()):
            state = d.state or {}
            program = state.get("program") or {}
            served.append({"address": a, "module": d.profile.name, "version": d.version, "url": f"{root}/m/{a}/",
                           "served": True, "connected": d.connected, "axes": state.get("axes", []),
                           "program": program.get("mode_name")})
        found = [{"address": f["address"], "module": f["module"], "version": f["version"], "served": False,
                  "url": None, "axes": [], "baud": f["baud"]}
                 for f in self.scanner.status()["found"] if f["address"] not in self.by_address]  # type: ignore[attr-defined]
        return {"modules": sorted(served + found, key=lambda m: m["address"])}

    def listing(self, request: Request) -> list[Json]:
        root = request.scope.get("root_path", "")
        return [{"address": a, "module": d.profile.name, "url": f"{root}/m/{a}/"}
                for a, d in self.by_address.items()]

    async def modules(self, request: Request) -> Response:
        return JSONResponse(self.listing(request))

    async def home(self, request: Request) -> Response:
        return RedirectResponse(str(self.listing(request)[0]["url"]))

    async def unknown(self, request: Request) -> Response:
        known = ", ".join(map(str, self.by_address))
        return JSONResponse({"error": f"no module at address {request.path_params['address']} "
                                      f"(addresses: {known})"}, status_code=404)


class ModuleApi:
    """The page, JSON API and WebSocket of one module (its `Dashboard`), relative to its
    /m/{address} prefix. Each API method reads the request and answers a JSON object (None: ok);
    the `Dashboard` calls talk to the module, so they run in a thread: stops on the stop lane,
    long requests on the cpu or reads lane, the others in Starlette's thread pool (web/lanes.py)."""

    def __init__(self, dashboard: Dashboard, lanes: Lanes) -> None:
        self.d = dashboard
        self.lanes = lanes

    def routes(self) -> list[BaseRoute]:
        post = ["POST"]
        return [
            Route("/", self.index),
            Route("/api/overview", json_api(self.overview)),
            Route("/api/state", json_api(self.state)),
            Route("/api/motion/{axis}", json_api(self.motion)),
            Route("/api/params/axis/{axis}", json_api(self.axis_parameters)),
            Route("/api/params/global", json_api(self.global_parameters)),
            Route("/api/params/axis", json_api(self.set_axis_parameter), methods=post),
            Route("/api/params/global", json_api(self.set_global_parameter), methods=post),
            Route("/api/params/store", json_api(self.store), methods=post),
            Route("/api/console", json_api(self.console), methods=post),
            Route("/api/io/output", json_api(self.set_output), methods=post),
            Route("/api/io/force", json_api(self.force_input), methods=post),
            Route("/api/program", json_api(self.program)),
            Route("/api/program/assemble", json_api(self.assemble), methods=post),
            Route("/api/program/download", json_api(self.download), methods=post),
            Route("/api/program/breakpoints", json_api(self.set_breakpoints), methods=post),
            Route("/api/program/run", json_api(self.run), methods=post),
            Route("/api/program/run_from_start", json_api(self.run_from_start), methods=post),
            Route("/api/program/stop", json_api(self.stop), methods=post),
            Route("/api/program/step", json_api(self.step), methods=post),
            Route("/api/program/reset", json_api(self.reset), methods=post),
            WebSocketRoute("/ws", self.live),
            *data_views.routes(self.d, self.lanes),  # parameter sets and chart samples (web/params.py)
            *ToolsApi(self.d, self.lanes).routes(),   # units, wizards, world load, read-back (web/tools.py)
            *FaultsApi(self.d).routes(),               # trigger a named fault (web/faults.py)
        ]

    async def index(self, _request: Request) -> Response:
        return FileResponse(f"{static_dir()}/index.html", headers={"Cache-Control": "no-store"})

    # --- module and parameters ---
    async def overview(self, _request: Request) -> object:
        return await run_in_threadpool(self.d.overview)

    async def state(self, _request: Request) -> object:
        state = self.d.state or await run_in_threadpool(self.d.sample_slow)
        return {**state, "download": self.d.downloading}  # [sent, of] while a download runs, else null

    async def motion(self, request: Request) -> object:
        try:
            n = int(request.path_params["axis"])
        except ValueError:
            raise BadRequest("axis must be a number") from None
        return await run_in_threadpool(motion.motion_info, self.d, n)

    async def axis_parameters(self, request: Request) -> object:
        try:
            n = int(request.path_params["axis"])
        except ValueError:
            raise BadRequest("axis must be a number") from None
        return {"axis": n, "params": await self.lanes.read(self.d.axis_parameters, n)}

    async def global_parameters(self, _request: Request) -> object:
        return {"params": await self.lanes.read(self.d.global_parameters)}

    def _shown_module(self, b: Json) -> None:
        """A write names the module its page shows (`module`: the address, optional for scripts):
        another module's page must not write here (docs/dashboard-parameters.md)."""
        shown = _optional_int(b, "module")
        if shown is not None and shown != self.d.module.address:
            raise BadRequest(f"the value was typed on the page of module {shown}; this is module "
                             f"{self.d.module.address}: nothing written")

    async def set_axis_parameter(self, request: Request) -> object:
        b = await _body(request)
        axis, number, value = _int(b, "axis"), _int(b, "number"), _int(b, "value")
        self._shown_module(b)
        return {"value": await run_in_threadpool(self.d.set_axis_parameter, axis, number, value)}

    async def set_global_parameter(self, request: Request) -> object:
        b = await _body(request)
        bank, number, value = _int(b, "bank"), _int(b, "number"), _int(b, "value")
        self._shown_module(b)
        return {"value": await run_in_threadpool(self.d.set_global_parameter, bank, number, value)}

    async def store(self, request: Request) -> object:
        b = await _body(request)
        kind, number, index = _str(b, "kind"), _int(b, "number"), _int(b, "index")
        self._shown_module(b)
        await run_in_threadpool(self.d.store, kind, number, index, bool(b.get("restore", False)))
        return None

    async def console(self, request: Request) -> object:
        line = _str(await _body(request), "line")
        if is_stop(line):  # MST, 128, 131: on the stop lane, never behind other requests
            return await self.lanes.stop.run(self.d.console, line)
        return await run_in_threadpool(self.d.console, line)

    # --- I/O ---
    async def set_output(self, request: Request) -> object:
        b = await _body(request)
        bank, port, value = _int(b, "bank"), _int(b, "port"), _int(b, "value")
        return {"value": await run_in_threadpool(self.d.set_output, bank, port, value)}

    async def force_input(self, request: Request) -> object:
        b = await _body(request)
        bank, port, value = _int(b, "bank"), _int(b, "port"), _optional_int(b, "value")
        await run_in_threadpool(self.d.force_input, bank, port, value)
        return None

    # --- the program ---
    async def program(self, _request: Request) -> object:
        state = await run_in_threadpool(self.d.program_state)
        program = self.d.program
        lines = None if program is None else \
            [s.line if s is not None and s.file == "<editor>" else None for s in program.source]
        return {"source": self.d.source, "state": state, "lines": lines}

    async def assemble(self, request: Request) -> object:
        async with self.lanes.cpu.admitted():  # refused before the body is decoded when busy
            b = await _body(request)
            result = await self.lanes.cpu.run(self.d.assemble, _str(b, "source"))
        result.pop("_program", None)
        return result

    async def download(self, request: Request) -> object:
        async with self.lanes.cpu.admitted():
            b = await _body(request)
            return await self.lanes.cpu.run(self.d.download, _str(b, "source"))

    async def set_breakpoints(self, request: Request) -> object:
        lines = _line_numbers(await _body(request), "lines")
        return {"addresses": await run_in_threadpool(self.d.set_breakpoints, lines)}

    async def run(self, _request: Request) -> object:
        return await self._program_action(partial(self.d.run, self.d.stops))  # stops at arrival

    async def run_from_start(self, _request: Request) -> object:
        return await self._program_action(partial(self.d.run_from_start, self.d.stops))

    async def stop(self, _request: Request) -> object:
        return await self._program_action(self.d.stop, stop=True)

    async def step(self, _request: Request) -> object:
        return await self._program_action(partial(self.d.step, self.d.stops))

    async def reset(self, _request: Request) -> object:
        return await self._program_action(self.d.reset, stop=True)

    async def _program_action(self, action: Callable[[], object], stop: bool = False) -> object:
        """Run `action` (128 and 131 on the stop lane); its own answer when it has one (step),
        else the program state."""
        out = await (self.lanes.stop.run(action) if stop else run_in_threadpool(action))
        return out if isinstance(out, dict) else await run_in_threadpool(self.d.program_state)

    # --- the live WebSocket ---
    async def live(self, websocket: WebSocket) -> None:
        """hello with the overview, then samples and state as they come, until either side leaves."""
        await websocket.accept(subprotocol=SUBPROTOCOL)  # Guard checked Origin and the subprotocol
        gone = asyncio.Event()
        watching = asyncio.create_task(_watch_for_disconnect(websocket, gone))
        last_seq = self.d.samples[-1].seq - 1 if self.d.samples else 0  # the latest sample is sent too
        try:
            await websocket.send_json({"type": "hello", "overview": await run_in_threadpool(self.d.overview)})
            await self._push_updates(websocket, gone, last_seq)
        except CLOSED:
            pass
        finally:
            watching.cancel()
            if not gone.is_set():
                with contextlib.suppress(RuntimeError, ConnectionError):
                    await websocket.close(1001)

    async def _push_updates(self, websocket: WebSocket, gone: asyncio.Event, last_seq: int) -> None:
        """Samples after `last_seq` and a changed state, polled at twice the sample rate, until the
        browser is `gone` or the dashboard closes."""
        d = self.d
        last_state = None
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


async def _watch_for_disconnect(websocket: WebSocket, gone: asyncio.Event) -> None:
    """The page sends nothing; reading notices the browser going away and sets `gone`."""
    try:
        while (await websocket.receive())["type"] != "websocket.disconnect":
            pass
    except CLOSED:
        pass
    gone.set()
