"""Browser dashboard for virtual and real modules (docs/dashboard.md).

    from opentmcl.web import start_dashboard
    handle = start_dashboard(opentmcl.connect("sim://TMCM-6212?clock=real"), "127.0.0.1", 8080)

Needs the ``web`` extra (starlette, uvicorn, websockets).
"""
from __future__ import annotations

__all__ = ["Dashboard", "DashboardError", "DashboardHandle", "DashboardStartError", "serve_dashboards",
           "start_dashboard", "start_dashboard_for_bus"]


def __getattr__(name: str) -> object:
    # Lazy: importing opentmcl.web must not import the web stack until it is used.
    if name in ("Dashboard", "DashboardError"):
        from . import service
        return getattr(service, name)
    if name in ("DashboardHandle", "DashboardStartError", "serve_dashboards", "start_dashboard",
                "start_dashboard_for_bus"):
        from . import server
        return getattr(server, name)
    raise AttributeError(name)
