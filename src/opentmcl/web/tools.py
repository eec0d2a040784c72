"""The tuning bench's endpoints (docs/dashboard.md "Tuning", "Set-up wizards", "Units"), mounted
under a module's /m/{address} prefix by web/app.py, so `guard.Guard` checks every request first.

    GET  /api/units                     every axis's unit factors, the current and analog scales,
                                        the unit settings (web/units.py)
    POST /api/units {axis, setting}     an axis's unit setting (kept with the parameter export)
    POST /api/setup/read {values}       [{kind, index, number}] -> [{..., value}]   (web/setup.py)
    POST /api/setup/apply {writes, store?, module?}
                                        SAP/SGP all or none, then STAP/STGP when `store`
    GET  /api/world/load/{axis}         {"virtual", "load"}: the load torque of a virtual module's axis
    POST /api/world/load {axis, load}   set it (null: back to the scenario's); virtual modules only
    POST /api/program/readback {source} program memory read with 134, disassembled and compared
"""
from __future__ import annotations

import math

from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.routing import BaseRoute, Route

from . import readback, setup
from . import units as unit_rules
from .api import BadRequest, body, int_field, json_api, optional_int, str_field
from .lanes import Lanes
from .service import Dashboard, DashboardError

MAX_LOAD = 10.0   # ten times the torque at 100 % current: far beyond a stall (docs/world.md)


class ToolsApi:
    def __init__(self, dashboard: Dashboard, lanes: Lanes) -> None:
        self.d = dashboard
        self.lanes = lanes

    def routes(self) -> list[BaseRoute]:
        post = ["POST"]
        return [
            Route("/api/units", json_api(self.units)),
            Route("/api/units", json_api(self.set_units), methods=post),
            Route("/api/setup/read", json_api(self.read), methods=post),
            Route("/api/setup/apply", json_api(self.apply), methods=post),
            Route("/api/world/load/{axis}", json_api(self.load)),
            Route("/api/world/load", json_api(self.set_load), methods=post),
            Route("/api/program/readback", json_api(self.readback), methods=post),
        ]

    # --- units ---
    async def units(self, _request: Request) -> object:
        return await self.lanes.read(unit_rules.module_units, self.d)

    async def set_units(self, request: Request) -> object:
        b = await body(request)
        return {"setting": unit_rules.set_setting(self.d, int_field(b, "axis"), b.get("setting"))}

    # --- wizards and tools ---
    async def read(self, request: Request) -> object:
        values = (await body(request)).get("values")
        return {"values": await run_in_threadpool(setup.read, self.d, values)}

    async def apply(self, request: Request) -> object:
        b = await body(request)
        shown = optional_int(b, "module")
        if shown is not None and shown != self.d.module.address:
            raise BadRequest(f"the wizard ran on the page of module {shown}; this is module "
                             f"{self.d.module.address}: nothing written")
        return await run_in_threadpool(setup.apply, self.d, b.get("writes"), bool(b.get("store", False)))

    # --- the world of a virtual module ---
    def _axis_world(self, axis: int):
        """The world of `axis` of the virtual module served in this process, or DashboardError: a
        module on a link (a real one, or one behind TCP) has no load the dashboard could set."""
        axis = self.d.check_axis(axis)
        world = getattr(self.d.vm, "world", None)
        if world is None:
            raise DashboardError("a load can be applied only to a virtual module served in this process "
                                 "(opentmcl serve --web, or opentmcl dashboard --to sim://...)")
        return world.axis(axis)

    def _load_now(self, axis: int) -> dict[str, object]:
        if self.d.vm is None:
            return {"axis": axis, "virtual": False, "load": None}
        aw = self._axis_world(axis)
        with self.d.vm_lock:
            return {"axis": axis, "virtual": True, "load": round(aw.load_now(), 6)}

    def _set_load(self, axis: int, load: float | None) -> dict[str, object]:
        aw = self._axis_world(axis)
        with self.d.vm_lock:
            aw.set_load(aw.spec.load if load is None else load)  # None: the scenario's own load
        return self._load_now(axis)

    async def load(self, request: Request) -> object:
        try:
            axis = int(request.path_params["axis"])
        except ValueError:
            raise BadRequest("axis must be a number") from None
        return await run_in_threadpool(self._load_now, self.d.check_axis(axis))

    async def set_load(self, request: Request) -> object:
        b = await body(request)
        axis, load = int_field(b, "axis"), b.get("load")
        if load is not None and (isinstance(load, bool) or not isinstance(load, (int, float))
                                 or not math.isfinite(load) or not 0 <= load <= MAX_LOAD):
            raise BadRequest(f"load must be 0..{MAX_LOAD:g} (a fraction of the torque at 100 % current) or null")
        return await run_in_threadpool(self._set_load, axis, None if load is None else float(load))

    # --- program read-back ---
    async def readback(self, request: Request) -> object:
        async with self.lanes.reads.admitted():
            source = str_field(await body(request), "source")
            return await self.lanes.reads.run(readback.read_back, self.d, source)
