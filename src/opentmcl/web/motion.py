"""Stop-all and the motion tools' read-outs (docs/dashboard.md "Stop all", "Motion").

Stop-all stops the program (command 128, TMCM-6212 manual 3.6.36) and sends MST (3.6.3) to every
axis of every module the dashboard serves, one module after the other, and of every module the
module scan found on the link that the dashboard does not serve (yet); a module that fails does
not keep the others from being stopped. The motion tools send their commands through the console
(`Dashboard.console`), so the console log shows each instruction; `motion_info` gives the page the
velocity unit, the velocity range and the reference search status (RFS STATUS, 3.6.11).
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence

from ..handover import STOP
from ..host import Client, TmclError
from ..host.module import profile_for_version
from ..protocol.opcodes import STOP_APPLICATION, Op
from .link import link_gate
from .service import Dashboard, DashboardError

_MST, _RFS, _GAP = int(Op.MST), int(Op.RFS), int(Op.GAP)  # plain ints for the requests
RFS_STATUS = 2
TARGET_SPEED, MAX_POSITIONING_SPEED, UNIT_MODE = 2, 4, 255
POSITION_KEYS = {"target_position": 0, "position": 1, "actual_speed": 3}


def stop_module(d: Dashboard) -> dict[str, object]:
    """End a download under way, stop `d`'s program (host-side stepping too), then MST on each axis.
    Every axis is tried even after an error; `ok` is False with the first error's text when any
    command failed."""
    errors: list[str] = []
    d.abort_download.set()  # a download holds the module from 132 to 133: it ends at the next instruction
    d.stops += 1  # a Run or Step that arrived before this and is not sent yet is refused (before our 128)
    stepping = d.halt_stepping()  # the host-side stepping ends after its current step; 128 first, not its WAIT
    if STOP_APPLICATION in d.profile.opcodes:
        for _ in range(2 if stepping else 1):  # again after the join: a step sent meanwhile
            try:
                d.act(lambda: d.module.request(STOP_APPLICATION, 0, 0, 0))
            except DashboardError as exc:
                errors.append(f"program stop: {exc}")
            d.cancel_run()
    else:
        d.cancel_run()
    stopped = []
    for axis in range(d.profile.axes):
        try:
            d.act(lambda a=axis: d.module.request(_MST, 0, a, 0))
            stopped.append(axis)
        except DashboardError as exc:
            errors.append(f"MST {axis}: {exc}")
    d.abort_download.clear()
    return {"address": d.module.address, "module": d.profile.name, "ok": not errors,
            "axes_stopped": stopped, "error": errors[0] if errors else "",
            "errors": errors}


def stop_found(client: Client, address: int, version: str) -> dict[str, object]:
    """Stop a module the scan found but the dashboard does not serve: 128 and MST on each axis of
    the profile its version string names (all six of the largest profile when none matches)."""
    errors: list[str] = []
    try:
        profile = profile_for_version(version)
        name, axes, opcodes = profile.name, profile.axes, profile.opcodes
    except TmclError:
        name, axes, opcodes = version, 6, frozenset({STOP_APPLICATION})
    stopped = []
    gate = link_gate(client)
    for command, axis in ([(STOP_APPLICATION, 0)] if STOP_APPLICATION in opcodes else []) + \
            [(_MST, a) for a in range(axes)]:
        try:
            with gate.hold(STOP):
                client.request(command, 0, axis, 0, address=address)
            if command == _MST:
                stopped.append(axis)
        except TmclError as exc:
            errors.append(f"{'program stop' if command == STOP_APPLICATION else f'MST {axis}'}: {exc}")
    return {"address": address, "module": name, "ok": not errors, "axes_stopped": stopped,
            "error": errors[0] if errors else "", "errors": errors}


def stop_all(dashboards: Iterable[Dashboard], client: Client | None = None,
             found: Sequence[tuple[int, str]] = ()) -> dict[str, object]:
    """`stop_module` for every module served, then `stop_found` on `client` for each (address,
    version) the scan found and the dashboard does not serve; {"ok": all stopped, "modules": [...]}."""
    modules = [stop_module(d) for d in dashboards]
    if client is not None:
        modules += [stop_found(client, address, version) for address, version in found]
    return {"ok": all(m["ok"] for m in modules), "modules": modules}


def velocity_unit(d: Dashboard, axis: int) -> str:
    """"pps" or "internal": the profile's velocity_unit capability (docs/profiles.md); a module with
    unit_mode reads AP255 ("0 - the internal units of the TMC5130", "1 - ... pps", manual 4.1)."""
    caps = d.profile.capabilities
    if caps.velocity_unit == "tmc429":
        return "internal"
    if caps.unit_mode and UNIT_MODE in d.profile.axis_parameters:
        mode = d.attempt(lambda: d.module.reply(_GAP, UNIT_MODE, axis).value)
        if mode == 0:
            return "internal"
    return "pps"


def motion_info(d: Dashboard, axis: int) -> dict[str, object]:
    """What the motion tools show for `axis`: unit and range of the velocity (AP2's range), the
    maximum positioning speed (AP4), positions and the reference search status."""
    axis = d.check_axis(axis)
    params = d.profile.axis_parameters
    speed = params.get(TARGET_SPEED)
    out: dict[str, object] = {
        "axis": axis, "unit": velocity_unit(d, axis),
        "velocity_min": 0 if speed is None else max(0, speed.min),
        "velocity_max": 0 if speed is None else speed.max,
        "max_positioning_speed": d.attempt(lambda: d.module.reply(_GAP, MAX_POSITIONING_SPEED, axis).value),
    }
    for key, number in POSITION_KEYS.items():
        out[key] = d.attempt(lambda n=number: d.module.reply(_GAP, n, axis).value) if number in params else None
    out["rfs_status"] = _rfs_status(d, axis)
    return out


def _rfs_status(d: Dashboard, axis: int) -> int | None:
    """RFS STATUS: 0 "no ref. search active", other values "reference search active" (3.6.11)."""
    if Op.RFS not in d.profile.opcodes:
        return None
    try:
        return d.module.reply(_RFS, RFS_STATUS, axis).value
    except TmclError:
        return None
