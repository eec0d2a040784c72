"""Extension points found by name (docs/architecture.md "Extension points").

A `Registry` maps names (URL schemes, pyserial URL schemes) to targets. A target is an object or
a lazy ``"package.module:attribute"`` reference that is imported on first use, so a layer can
name what a higher layer owns without importing it: the root package registers ``sim`` this way.
A name nobody registered is looked up, once, in the entry-point group of the same name, which is
how an installed third-party distribution adds its own.

This module sits in the lowest layer (standard library only): the root package fills it at
import time without pulling in the host library.
"""
from __future__ import annotations

import importlib
import re
import sys
from collections.abc import Mapping
from types import MappingProxyType
from typing import TYPE_CHECKING, TypeGuard

if TYPE_CHECKING:  # importlib.metadata is imported when entry points are first asked for
    from importlib import metadata

NAME = re.compile(r"[a-z][a-z0-9+.-]*")
"""A registrable name: a URL scheme (RFC 3986 3.1), compared in lower case."""
TARGET = re.compile(r"[A-Za-z_][\w.]*:[A-Za-z_][\w.]*")
"""A lazy target ``package.module:attribute``."""


class Registry:
    """Names -> targets, filled by `register`, with the entry points of `group` as fallback."""

    def __init__(self, group: str) -> None:
        self.group = group
        self._targets: dict[str, object] = {}

    def register(self, name: str, target: object) -> None:
        """Register (or replace) `target` for `name`; ValueError for a bad name or reference."""
        key = check_name(name)
        if isinstance(target, str) and not TARGET.fullmatch(target):
            raise ValueError(f"lazy target must read 'package.module:attribute', got {target!r}")
        self._targets[key] = target

    def forget(self, name: str) -> None:
        """Drop `name` (registered, or found as an entry point and kept); nothing if unknown."""
        self._targets.pop(name.lower(), None)

    def names(self) -> list[str]:
        """The registered names, in registration order."""
        return list(self._targets)

    def targets(self) -> Mapping[str, object]:
        """Read-only live view: name -> target (a lazy reference until first use)."""
        return MappingProxyType(self._targets)

    def available(self) -> list[str]:
        """Registered names, then those the entry-point group offers besides."""
        extra = sorted({ep.name.lower() for ep in self._entry_points()} - set(self._targets))
        return self.names() + extra

    def find(self, name: str) -> object | None:
        """The target for `name`, loaded; None if neither registered nor an entry point.
        ImportError or AttributeError when a lazy target cannot be loaded."""
        key = name.lower()
        if key not in self._targets:
            found = next((ep for ep in self._entry_points() if ep.name.lower() == key), None)
            if found is None:
                return None
            self._targets[key] = found
        target = self._targets[key]
        if isinstance(target, str) or _is_entry_point(target):
            target = load(target)
            self._targets[key] = target
        return target

    def _entry_points(self) -> list[metadata.EntryPoint]:
        from importlib import metadata

        return list(metadata.entry_points(group=self.group))


def _is_entry_point(target: object) -> TypeGuard[metadata.EntryPoint]:
    """An entry point not loaded yet (none exists before importlib.metadata is imported)."""
    md = sys.modules.get("importlib.metadata")
    return md is not None and isinstance(target, md.EntryPoint)


def check_name(name: object) -> str:
    """`name` in lower case if it is a URL scheme; ValueError otherwise."""
    if not isinstance(name, str) or not NAME.fullmatch(name.lower()):
        raise ValueError(f"a name must be a URL scheme (a letter, then letters, digits, '+', '-', '.'), "
                         f"got {name!r}")
    return name.lower()


def load(target: str | metadata.EntryPoint) -> object:
    """Import the object a lazy reference or entry point names."""
    if not isinstance(target, str):
        return target.load()
    module_name, _, attribute = target.partition(":")
    obj: object = importlib.import_module(module_name)
    for part in attribute.split("."):
        obj = getattr(obj, part)
    return obj


TRANSPORTS = "opentmcl.transports"
"""Group of the host library's transports: URL scheme -> factory(urllib.parse.SplitResult) -> Transport."""
SERIAL_URL_HANDLERS = "opentmcl.serial_url_handlers"
"""Group of pyserial URL schemes: scheme -> hook() that makes `serial.serial_for_url` know it."""
PROFILES = "opentmcl.profiles"
"""Group of module profiles: module name -> the path of its TOML profile file, or a function of no
arguments that answers one (modules/profile.py; the name is compared in lower case)."""
ENGINES = "opentmcl.engines"
"""Group of ramp engines: the name a profile's `[module] engine` gives -> the engine class (a
motion.RampEngine made without arguments)."""
ENDPOINTS = "opentmcl.endpoints"
"""Group of serve endpoints: name -> factory(bus, spec, options) -> an object with start() and stop()
(server/endpoints.py; `opentmcl serve --endpoint NAME[:SPEC]`)."""

_REGISTRIES: dict[str, Registry] = {}


def of(group: str) -> Registry:
    """The one registry of entry-point group `group` (created on first use)."""
    if group not in _REGISTRIES:
        _REGISTRIES[group] = Registry(group)
    return _REGISTRIES[group]
