"""Shared by the fault tests: plans as files, sim:// links with faults, TMCL command numbers."""
from __future__ import annotations

from pathlib import Path

import yaml

import opentmcl

ROR, MST, MVP, SAP, GAP, STAP, RSAP, SGP, GGP, STGP, GIO = 1, 3, 4, 5, 6, 7, 8, 9, 10, 11, 15


def plan_file(tmp_path: Path, faults: list[dict], seed: int = 1, name: str = "faults.yaml") -> Path:
    """A fault plan file (YAML: `dict`s written as they are given)."""
    path = tmp_path / name
    path.write_text(yaml.safe_dump({"seed": seed, "fault": faults}), encoding="utf-8")
    return path


def sim(tmp_path: Path, faults: list[dict], module: str = "TMCM-6212", timeout: float = 0.5,
        seed: int = 1) -> opentmcl.Module:
    """``opentmcl.connect("sim://MODULE?faults=FILE")`` in virtual time."""
    path = plan_file(tmp_path, faults, seed)
    return opentmcl.connect(f"sim://{module}?faults={path}", timeout=timeout)


def vm_of(m: opentmcl.Module):
    return m.client.transport.modules[0]


def now(m: opentmcl.Module) -> float:
    """The link's clock (virtual seconds)."""
    return m.client.transport.monotonic()
