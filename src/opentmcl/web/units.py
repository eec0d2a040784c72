"""Physical units of the dashboard (docs/dashboard.md "Units"): what the page needs to show an
axis's velocities, accelerations and positions in pps, rps, rpm or a user scale (mm with a lead and
a gear), its currents in mA and its analog inputs in volts.

The conversions of module units to pps and pps^2 are the host library's (`host/units.py`: TMCM-6212
manual 6.5, the TMC429 formulas of PD86-1180 manual 5, the TMC5130's for AP255 = 0); this module
hands the page one factor per axis, read with GAP, and the profile's current and analog scales.
The page multiplies: one rule, one implementation each.

Each axis's unit setting (`{"kind": "pps" | "rps" | "rpm" | "user", "name", "per_round", "gear"}`)
is given once per axis and kept with the module's parameter export (`attach`, `settings_in`).
"""
from __future__ import annotations

import json
import math
import tomllib

from ..host import units as hu
from .service import READ_COMMANDS, Dashboard, DashboardError

KINDS = ("pps", "rps", "rpm", "user")
FULLSTEPS_DEFAULT = 200    # "with most motors 200 (1.8°)" (TMCM-6212 manual 6.5)
MICROSTEPS, FULLSTEPS, PULSE_DIV, RAMP_DIV, UNIT_MODE = 140, 202, 154, 153, 255
MAX_NAME = 12


def _read(d: Dashboard, axis: int) -> dict[int, int | None]:
    """AP140, 202, 153, 154 and 255 of `axis` where the profile has them (one batch)."""
    have = [n for n in (MICROSTEPS, FULLSTEPS, RAMP_DIV, PULSE_DIV, UNIT_MODE) if n in d.profile.axis_parameters]
    return dict(zip(have, d.read_many([(READ_COMMANDS["axis"], n, axis, 0) for n in have]), strict=True))


def _factors(d: Dashboard, v: dict[int, int | None]) -> tuple[str, float, float]:
    """(unit, pps per unit of AP2/AP3/AP4, pps^2 per unit of AP5) of an axis with values `v`."""
    caps = d.profile.capabilities
    if caps.velocity_unit == "tmc429":
        pulse, ramp = v.get(PULSE_DIV), v.get(RAMP_DIV)
        if pulse is None or ramp is None:
            raise DashboardError("cannot read the pulse and ramp divisors (AP154, AP153)")
        return "internal", hu.tmc429_velocity_to_pps(1, pulse), hu.tmc429_accel_to_pps2(1, pulse, ramp)
    if caps.unit_mode and v.get(UNIT_MODE) == 0:
        return "internal", hu.tmc5130_velocity_to_pps(1), hu.tmc5130_accel_to_pps2(1)
    return "pps", 1.0, 1.0


def axis_units(d: Dashboard, axis: int) -> dict[str, object]:
    """The factors of one axis: microsteps per full step (2^AP140), full steps per round (AP202,
    or 200 where the module has no AP202), pps per velocity unit and pps^2 per acceleration unit."""
    axis = d.check_axis(axis)
    v = _read(d, axis)
    code = v.get(MICROSTEPS)
    unit, vf, af = _factors(d, v)
    fullsteps = v.get(FULLSTEPS)
    if FULLSTEPS not in d.profile.axis_parameters:
        source = f"{FULLSTEPS_DEFAULT}: a 1.8° motor (manual 6.5); {d.profile.name} has no AP202"
    elif not fullsteps:
        source = f"{FULLSTEPS_DEFAULT}: AP202 reads {fullsteps}"
    else:
        source = "AP202"
    return {"axis": axis, "velocity_unit": unit, "pps_per_unit": vf, "pps2_per_unit": af,
            "microstep_code": code, "microsteps": None if code is None else hu.microsteps_per_fullstep(code),
            "fullsteps": fullsteps or FULLSTEPS_DEFAULT, "fullsteps_from": source}


def current_scale(d: Dashboard) -> dict[str, object] | None:
    """The profile's `current_scale` (rms_ma and peak_ma at AP6 = 255, steps 32 or 0 for the
    manual's linear formula, its source), or None when no manual gives one."""
    scale = d.profile.extra.get("current_scale")
    return dict(scale) if isinstance(scale, dict) else None


def analog_scale(d: Dashboard) -> float | None:
    """Volts at the top of the analog inputs' range, or None: none of the manuals gives one."""
    volts = d.profile.extra.get("analog_full_scale_volts")
    return float(volts) if isinstance(volts, (int, float)) else None


def module_units(d: Dashboard) -> dict[str, object]:
    """Every axis's factors, the module's scales and the unit settings given so far."""
    return {"axes": [axis_units(d, a) for a in range(d.profile.axes)], "current": current_scale(d),
            "analog_volts": analog_scale(d), "settings": {str(a): s for a, s in sorted(d.units.items())}}


def check_setting(value: object) -> dict[str, object]:
    """A unit setting as the page sends it, checked; DashboardError otherwise."""
    if not isinstance(value, dict):
        raise DashboardError("a unit setting is {kind, name?, per_round?, gear?}")
    kind = value.get("kind")
    if kind not in KINDS:
        raise DashboardError(f"unit kind must be one of {', '.join(KINDS)}, not {str(kind)[:20]!r}")
    out: dict[str, object] = {"kind": kind}
    if kind == "user":
        name = value.get("name")
        if not isinstance(name, str) or not 0 < len(name.strip()) <= MAX_NAME or not name.strip().isprintable():
            raise DashboardError(f"a user unit needs a name of 1..{MAX_NAME} printable characters (e.g. mm)")
        for key in ("per_round", "gear"):
            x = value.get(key)
            if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) or not 0 < x <= 1e9:
                raise DashboardError(f"{key} must be a positive number, not {str(x)[:20]!r}")
        out.update(name=name.strip(), per_round=float(value["per_round"]), gear=float(value["gear"]))
    return out


def set_setting(d: Dashboard, axis: int, value: object) -> dict[str, object]:
    axis = d.check_axis(axis)
    setting = check_setting(value)
    d.units[axis] = setting
    return setting


# --- kept with the parameter export ---------------------------------------------------------

def attach(text: str, fmt: str, settings: dict[int, dict[str, object]]) -> str:
    """An exported parameter set (`host/paramset.py` text) with the unit settings added: a "units"
    list in JSON, [[units]] tables in TOML (the parameter-set reader ignores both)."""
    if not settings:
        return text
    rows = [{"axis": a, **s} for a, s in sorted(settings.items())]
    if fmt == "json":
        data = json.loads(text)
        data["units"] = rows
        return json.dumps(data, indent=1) + "\n"
    lines = [text.rstrip("\n")]
    for row in rows:
        lines += ["", "[[units]]"] + [f"{k} = {json.dumps(v)}" for k, v in row.items()]
    return "\n".join(lines) + "\n"


def settings_in(text: str, axes: int) -> dict[int, dict[str, object]]:
    """The unit settings a parameter-set file carries (none when it has no valid "units")."""
    try:
        data = json.loads(text) if text.lstrip().startswith("{") else tomllib.loads(text)
    except (ValueError, RecursionError):
        return {}
    rows = data.get("units") if isinstance(data, dict) else None
    out: dict[int, dict[str, object]] = {}
    for row in rows if isinstance(rows, list) else []:
        axis = row.get("axis") if isinstance(row, dict) else None
        if isinstance(axis, int) and not isinstance(axis, bool) and 0 <= axis < axes:
            try:
                out[axis] = check_setting(row)
            except DashboardError:
                continue
    return out
