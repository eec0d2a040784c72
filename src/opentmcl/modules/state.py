"""Which parameters say where a module is (its state) rather than how it is set up.

One rule for the tools that read a module from outside (docs/capture.md "State at capture start"):
`profile probe` keeps state values out of the defaults it writes, the snapshot of `proxy` and
`conform` reads them, and `replay` compares the values that move with time over an interval
instead of at an instant. Names are the profiles' own (`modules/data/*.toml`); they are the same
in every built-in profile.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

MOVING: Mapping[str, tuple[str, ...]] = {
    "position": ("actual_position", "encoder_position", "absolute_encoder_value", "last_reference_position"),
    "velocity": ("actual_speed", "measured_speed", "actual_acceleration"),
    "load": ("actual_load_value", "smartenergy_actual_current"),
    "timer": ("tick_timer",),
    "flag": ("position_reached", "left_limit_switch", "right_limit_switch", "home_switch",
             "driver_error_flags", "extended_error_flags", "tmcl_program_counter", "tmcl_application_status"),
}
"""Values that move with time, by class (the keys of `replay --tolerance`, `flag` has none)."""

UNREPRODUCIBLE = ("random_number",)
"""Values no twin can reproduce (GGP 133, a random number): never compared."""

READ_CLEARS = ("extended_error_flags",)
"""Values whose reading changes them (AP207 is cleared when read): read once, never sampled."""

SET_STATE = ("target_position", "actual_position", "target_speed", "encoder_position", "tick_timer",
             "random_number")
"""Writable values that are state, not configuration: where the axis is and is going, the
encoder count, the tick timer and the random number (TMCM-6212 manual 4.1 AP0/AP1/AP2/AP209,
5.1 GP132/GP133). A module that has been used reads them as anything; they are never defaults."""


def moving_class(name: str | None) -> str | None:
    """The class of a value that moves with time (`MOVING`), else None."""
    for klass, names in MOVING.items():
        if name in names:
            return klass
    return None


def is_state(name: str | None) -> bool:
    """True for a value that says where the module is: a moving value or a settable state value."""
    return name in SET_STATE or name in UNREPRODUCIBLE or moving_class(name) is not None


SNAPSHOT_TABLES = {"axis_parameter": ("motor", "number"), "global_parameter": ("bank", "number"),
                   "io": ("bank", "port")}
"""The tables of a `[snapshot]` section (profile probe; `replay --initial-state`): rows of
[motor or bank, number or port, value]."""


def snapshot_errors(table: Any) -> list[str]:
    """Schema errors of a `[snapshot]` table, one line each with its key path."""
    if not isinstance(table, dict):
        return ["snapshot: expected a table"]
    errors = []
    for key, rows in table.items():
        if key == "firmware_version":
            if not isinstance(rows, str):
                errors.append("snapshot.firmware_version: expected a string")
            continue
        if key not in SNAPSHOT_TABLES:
            errors.append(f"snapshot.{key}: unknown key (use {', '.join(SNAPSHOT_TABLES)}, firmware_version)")
            continue
        if not isinstance(rows, list):
            errors.append(f"snapshot.{key}: expected a list of [{', '.join(SNAPSHOT_TABLES[key])}, value] rows")
            continue
        for i, row in enumerate(rows):
            if not (isinstance(row, list) and len(row) == 3 and all(type(x) is int for x in row)
                    and 0 <= row[0] <= 255 and 0 <= row[1] <= 255 and -(1 << 31) <= row[2] < (1 << 32)):
                errors.append(f"snapshot.{key}[{i}]: expected [{', '.join(SNAPSHOT_TABLES[key])}, value] "
                              "with bytes and a 32-bit value")
    return errors
