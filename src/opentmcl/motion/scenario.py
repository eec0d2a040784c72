"""Scenario files: the physical world of a virtual module as data (docs/scenarios.md).

    load_scenario("stage.toml")         # TOML (or YAML with PyYAML installed)
    load_scenario({"axis": {"0": {...}}})

returns a `Scenario`. Malformed input raises `ScenarioError` with the key at fault.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

from ..datafile import DocumentError, read_document
from ..faults import FaultError, FaultPlan, parse_faults, parse_seed
from .stage import Load, Profile, Stage, Switch, home_switch, left_switch, right_switch

SWITCH_NAMES = ("left", "right", "home")


class ScenarioError(ValueError):
    """A scenario file or dict does not follow docs/scenarios.md."""


@dataclass
class AxisSpec:
    stage: Stage = field(default_factory=Stage)
    load: Load = field(default_factory=Load)
    encoder_counts: int | None = None        # physical encoder counts per motor round
    fullsteps_per_round: int = 200
    force: dict[str, int] = field(default_factory=dict)
    torque_falloff_speed: float | None = None  # pps at which the available torque reaches 0
    driver_flags: Profile | None = None       # AP208 bits over time (seconds)


MEASURE_DEFAULTS = {"supply_voltage": 24.0, "temperature": 25.0}
"""The world's supply voltage (V) and board temperature (°C) when the scenario does not give them:
a 24 V supply, the nominal voltage of the three modules' manuals, at room temperature."""


@dataclass
class InputSpec:
    bank: int
    port: int
    signal: Profile


@dataclass
class Scenario:
    module: str | None = None
    axes: dict[int, AxisSpec] = field(default_factory=dict)
    inputs: list[InputSpec] = field(default_factory=list)
    shutdown: Profile | None = None
    faults: FaultPlan = field(default_factory=FaultPlan)
    """The scenario's [[fault]] tables and seed (docs/faults.md)."""
    measures: dict[str, Profile] = field(default_factory=dict)
    """`supply_voltage` (V) and `temperature` (°C) over time, where the scenario gives them."""

    def measure(self, name: str) -> Profile:
        """The quantity `name` of MEASURE_DEFAULTS over time: the scenario's, else its default."""
        return self.measures.get(name) or Profile.constant(MEASURE_DEFAULTS[name])

    def axis(self, index: int) -> AxisSpec:
        return self.axes.get(index) or AxisSpec()


# --- parsing ---------------------------------------------------------------------------------
def _int(value: object, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ScenarioError(f"{where}: expected an integer, got {value!r}")
    return value


def _num(value: object, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ScenarioError(f"{where}: expected a number, got {value!r}")
    return float(value)


def _position(value: object, where: str) -> int:
    """A stage position: an integer the 32-bit position counter can reach."""
    p = _int(value, where)
    if not -2**31 <= p < 2**31:
        raise ScenarioError(f"{where}: {p} is outside the 32-bit position range")
    return p


def _table(value: object, where: str) -> dict:
    if not isinstance(value, dict):
        raise ScenarioError(f"{where}: expected a table, got {value!r}")
    return value


def _known(d: dict, keys: set[str], where: str) -> None:
    extra = set(d) - keys
    if extra:
        raise ScenarioError(f"{where}: unknown key(s) {', '.join(sorted(map(str, extra)))}")


def parse_profile(value, where: str) -> Profile:
    """A number, or {steps = [[x, v], ...]} / {ramp = [[x, v], ...]} (optionally `before`)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return Profile.constant(_num(value, where))
    d = _table(value, where)
    _known(d, {"steps", "ramp", "before", "by", "value"}, where)
    if "value" in d:
        return Profile.constant(_num(d["value"], f"{where}.value"))
    kinds = [k for k in ("steps", "ramp") if k in d]
    if len(kinds) != 1:
        raise ScenarioError(f"{where}: give exactly one of 'value', 'steps' or 'ramp'")
    kind = kinds[0]
    pts = d[kind]
    if not isinstance(pts, list) or not pts:
        raise ScenarioError(f"{where}.{kind}: expected a list of [x, value] pairs")
    out = []
    for i, pt in enumerate(pts):
        if not isinstance(pt, (list, tuple)) or len(pt) != 2:
            raise ScenarioError(f"{where}.{kind}[{i}]: expected [x, value]")
        out.append((_num(pt[0], f"{where}.{kind}[{i}]"), _num(pt[1], f"{where}.{kind}[{i}]")))
    return Profile(out, kind, _num(d.get("before", 0), f"{where}.before"))


def _switch(name: str, d, where: str) -> Switch:
    d = _table(d, where)
    _known(d, {"position", "width", "hysteresis", "inverted"}, where)
    if "position" not in d:
        raise ScenarioError(f"{where}: 'position' is required")
    pos = _position(d["position"], f"{where}.position")
    width = d.get("width")
    width = None if width is None else _int(width, f"{where}.width")
    hyst = _int(d.get("hysteresis", 0), f"{where}.hysteresis")
    if (width is not None and width < 0) or hyst < 0:
        raise ScenarioError(f"{where}: width and hysteresis must not be negative")
    inv = d.get("inverted", False)
    if not isinstance(inv, bool):
        raise ScenarioError(f"{where}.inverted: expected true or false")
    if name == "left":
        return left_switch(pos, width, hyst, inv)
    if name == "right":
        return right_switch(pos, width, hyst, inv)
    if width is None:
        raise ScenarioError(f"{where}: the home switch needs a 'width'")
    return home_switch(pos, width, hyst, inv)


AXIS_KEYS = {"type", "start", "steps_per_turn", "ends", "load", "encoder", "fullsteps_per_round", "force",
             "torque_falloff_speed", "driver_flags", "index", *SWITCH_NAMES}


def _positive(value: object, where: str) -> int:
    """An integer > 0."""
    out = _int(value, where)
    if out <= 0:
        raise ScenarioError(f"{where} must be positive")
    return out


def _ends(value: object, where: str) -> tuple[int | None, int | None]:
    """[left end, right end] of the mechanical travel, either may be absent (null)."""
    if not isinstance(value, list) or len(value) != 2:
        raise ScenarioError(f"{where}: expected [left end, right end]")
    lo, hi = (None if e is None else _position(e, where) for e in value)
    if lo is not None and hi is not None and lo >= hi:
        raise ScenarioError(f"{where}: the left end must lie left of the right end")
    return lo, hi


def _stage(d: dict, where: str) -> Stage:
    """The geometry keys of an axis table: type, start, steps_per_turn, switches, ends."""
    kind = d.get("type", "linear")
    if kind not in ("linear", "circular"):
        raise ScenarioError(f"{where}.type: 'linear' or 'circular', got {kind!r}")
    st = Stage()
    st.start = _position(d.get("start", 0), f"{where}.start")
    if kind == "circular":
        if "steps_per_turn" not in d:
            raise ScenarioError(f"{where}: a circular axis needs 'steps_per_turn'")
        st.steps_per_turn = _positive(d["steps_per_turn"], f"{where}.steps_per_turn")
        if "left" in d or "right" in d or "ends" in d:
            raise ScenarioError(f"{where}: a circular axis has a home switch only")
    for name in SWITCH_NAMES:
        if name in d:
            setattr(st, name, _switch(name, d[name], f"{where}.{name}"))
    if "ends" in d:
        st.ends = _ends(d["ends"], f"{where}.ends")
    if st.left and st.right and st.left.hi >= st.right.lo:
        raise ScenarioError(f"{where}: the left switch must lie left of the right switch")
    return st


def _load(value: object, where: str) -> Load:
    by = value.get("by", "position") if isinstance(value, dict) else "position"
    if by not in ("position", "time"):
        raise ScenarioError(f"{where}.by: 'position' or 'time', got {by!r}")
    return Load(parse_profile(value, where), by)


def _encoder_counts(value: object, where: str) -> int | None:
    enc = _table(value, where)
    _known(enc, {"counts_per_round"}, where)
    if "counts_per_round" not in enc:
        return None
    return _positive(enc["counts_per_round"], f"{where}.counts_per_round")


def _force(value: object, where: str) -> dict[str, int]:
    force = _table(value, where)
    _known(force, set(SWITCH_NAMES), where)
    levels = {k: _int(v, f"{where}.{k}") for k, v in force.items()}
    if any(v not in (0, 1) for v in levels.values()):
        raise ScenarioError(f"{where}: levels are 0 or 1")
    return levels


def parse_axis(d, where: str) -> AxisSpec:
    """One axis table of docs/scenarios.md."""
    d = _table(d, where)
    _known(d, AXIS_KEYS, where)
    spec = AxisSpec(stage=_stage(d, where))
    if "load" in d:
        spec.load = _load(d["load"], f"{where}.load")
    if "encoder" in d:
        spec.encoder_counts = _encoder_counts(d["encoder"], f"{where}.encoder")
    spec.fullsteps_per_round = _positive(d.get("fullsteps_per_round", 200), f"{where}.fullsteps_per_round")
    if "force" in d:
        spec.force = _force(d["force"], f"{where}.force")
    if "torque_falloff_speed" in d:
        spec.torque_falloff_speed = _num(d["torque_falloff_speed"], f"{where}.torque_falloff_speed")
        if spec.torque_falloff_speed <= 0:
            raise ScenarioError(f"{where}.torque_falloff_speed must be positive")
    if "driver_flags" in d:
        spec.driver_flags = parse_profile(d["driver_flags"], f"{where}.driver_flags")
    return spec


def parse_scenario(data: dict) -> Scenario:
    d = _table(data, "scenario")
    _known(d, {"module", "axis", "input", "shutdown", "description", "fault", "seed", *MEASURE_DEFAULTS},
           "scenario")
    sc = Scenario(module=d.get("module"))
    axes = d.get("axis", {})
    if isinstance(axes, list):
        items = [(a.get("index", i) if isinstance(a, dict) else i, a) for i, a in enumerate(axes)]
    else:
        items = list(_table(axes, "axis").items())
    for key, spec in items:
        try:
            index = int(key)
        except (TypeError, ValueError):
            raise ScenarioError(f"axis.{key}: axis keys are axis numbers") from None
        if index < 0:
            raise ScenarioError(f"axis.{key}: negative axis number")
        if index in sc.axes:
            raise ScenarioError(f"axis.{key}: axis {index} is given twice")
        sc.axes[index] = parse_axis(spec, f"axis.{key}")
    inputs = d.get("input", [])
    if not isinstance(inputs, list):
        raise ScenarioError("input: expected a list of tables ([[input]])")
    for i, item in enumerate(inputs):
        where = f"input[{i}]"
        item = _table(item, where)
        _known(item, {"bank", "port", "value", "steps", "ramp", "before"}, where)
        if "bank" not in item or "port" not in item:
            raise ScenarioError(f"{where}: 'bank' and 'port' are required")
        sig = {k: v for k, v in item.items() if k not in ("bank", "port")}
        sc.inputs.append(InputSpec(_int(item["bank"], f"{where}.bank"), _int(item["port"], f"{where}.port"),
                                   parse_profile(sig, where)))
    if "shutdown" in d:
        sc.shutdown = parse_profile(d["shutdown"], "shutdown")
    try:
        sc.faults = FaultPlan(parse_faults(d.get("fault", []), "fault"), parse_seed(d.get("seed")))
    except FaultError as exc:
        raise ScenarioError(str(exc)) from None
    for name in MEASURE_DEFAULTS:
        if name in d:
            sc.measures[name] = parse_profile(d[name], name)
    return sc


def load_scenario(source) -> Scenario:
    """A Scenario from a path (.toml, .yaml/.yml), a dict, a Scenario, or None (empty world)."""
    if source is None:
        return Scenario()
    if isinstance(source, Scenario):
        return source
    if isinstance(source, dict):
        return parse_scenario(source)
    if not isinstance(source, (str, os.PathLike)):
        raise ScenarioError(f"a scenario is a file path or a dict, not {type(source).__name__}")
    try:
        data = read_document(source, "scenario")
    except DocumentError as exc:
        raise ScenarioError(str(exc)) from None
    return parse_scenario(data if data is not None else {})
