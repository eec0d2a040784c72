"""Which module a replay plays, at which address (docs/capture.md "Replay").

The module the capture identified (its identity records, its snapshot), the profile file of its
`sim://` target, else the built-in profile of the same module number as `profile probe` picks it
(firmware string or binary version, 136 type 0/1). The twins are fresh `VirtualModule`s of it.
"""
from __future__ import annotations

import os
from typing import TYPE_CHECKING

from ..protocol.opcodes import Op
from .format import Capture
from .snapshot import snapshot_of
from .tolerance import ReplayError

if TYPE_CHECKING:
    from ..firmware.vm import VirtualModule
    from ..motion.scenario import Scenario


def first_address(cap: Capture) -> int | None:
    """The address of the first request that got a reply, else of the first request."""
    answered = {r.get("request") for r in cap.frames if r["kind"] != "request"}
    for rec in cap.frames:
        if rec["kind"] == "request" and rec["n"] in answered:
            return rec["address"]
    for rec in cap.frames:
        if rec["kind"] == "request":
            return rec["address"]
    return None


def sim_profile_file(target, address: int | None) -> str | None:
    """The profile file of a `sim://` capture target (at `address`, else the first), if any."""
    import urllib.parse

    from ..host.errors import TmclConnectionError
    from ..host.transports.inprocess import parse_modules
    from ..modules.profile_file import looks_like_path

    if not isinstance(target, str) or not target.startswith("sim://"):
        return None
    url = urllib.parse.urlsplit(target)
    spec = url.netloc + url.path if ".toml" in url.path.lower() else (url.netloc or url.path.lstrip("/"))
    try:
        specs = parse_modules(spec, 1)
    except TmclConnectionError:  # a target the proxy could not have opened: keep the identity
        return None
    for name, at in specs:
        if looks_like_path(name) and (address is None or at == address):
            return name
    return None


def binary_version(cap: Capture) -> int | None:
    """The value of the first successful reply to 136 type 1 (the binary version), if any."""
    requests = {r["n"]: r for r in cap.frames if r["kind"] == "request"}
    for rec in cap.frames:
        req = requests.get(rec.get("request")) if rec["kind"] == "reply" else None
        if req is not None and req["command"] == Op.GET_FIRMWARE_VERSION and req["type"] == 1 and rec.get("status") == 100:
            return int(rec["value"])
    return None


def captured_module(cap: Capture, address: int | None, notes: list[str]) -> str:
    """The module the capture identified, the profile file of its `sim://` target, else the
    built-in profile of the same module number (firmware string or 136 type 1), as `profile probe`."""
    from ..host.probe import closest_builtin
    from ..modules.profile import module_names

    snap = snapshot_of(cap, address)
    module = cap.module_name() or (snap.module if snap is not None else None)
    if module is None or module not in module_names():  # e.g. proxy --to sim:///path/my.toml
        module = sim_profile_file(cap.header.get("target"), address) or module
    if module is not None and (module in module_names() or module.lower().endswith(".toml")):
        return module
    versions = [i.get("firmware_version") for i in cap.identities if isinstance(i.get("firmware_version"), str)]
    versions += [r["version"] for r in cap.frames if r["kind"] == "version" and isinstance(r.get("version"), str)]
    if snap is not None and snap.firmware_version:
        versions.append(snap.firmware_version)
    binary = binary_version(cap)
    base = closest_builtin(versions[0] if versions else None, binary)
    if base is None:
        raise ReplayError(f"{cap.path}: the capture does not identify its module; name one (--module)")
    seen = repr(versions[0]) if versions else f"binary version {binary:#x}"
    notes.append(f"firmware {seen} matches no built-in profile: replaying against {base.name}, the same "
                 "module number (give --module to choose)")
    return base.name


def virtual_module(module: str | os.PathLike, address: int, eeprom: str | os.PathLike | None,
                   scenario: Scenario | str | os.PathLike | None) -> VirtualModule:
    """A fresh virtual module for the replay; ReplayError (one line) if it cannot be built."""
    from ..firmware.eeprom import EepromError
    from ..firmware.vm import VirtualModule

    if isinstance(scenario, (str, os.PathLike)):
        from ..motion.scenario import load_scenario

        scenario = load_scenario(scenario)
    try:
        return VirtualModule(os.fspath(module), address=address, eeprom=eeprom, scenario=scenario)
    except KeyError as exc:
        raise ReplayError(str(exc.args[0]) if exc.args else f"unknown module {module!r}") from None
    except (EepromError, ValueError) as exc:
        raise ReplayError(str(exc)) from None
