"""The ramp engine of a profile: `[module] engine` names it in the engine registry
(registry.ENGINES: the built-in sixpoint, linear and tmc429 engines of motion/, and any an installed
distribution adds with an entry point in the group "opentmcl.engines"; docs/architecture.md
"Extension points"). Which axis parameters configure it is profile data (the `engine` field of an
axis parameter, ModuleProfile.engine_params; docs/profiles.md)."""
from __future__ import annotations

from .. import registry
from ..motion import RampEngine


def make_engine(kind: str) -> RampEngine:
    """A new engine of the kind a profile names; ValueError when no engine has that name."""
    try:
        engine_class = registry.of(registry.ENGINES).find(kind)
    except ValueError:
        engine_class = None
    if engine_class is None:
        raise ValueError(f"unknown motion engine {kind!r}; known: {', '.join(engine_names())}")
    engine = engine_class()  # type: ignore[operator]
    if not isinstance(engine, RampEngine):
        raise ValueError(f"motion engine {kind!r} is not a RampEngine: {type(engine).__name__}")
    return engine


def engine_names() -> list[str]:
    return registry.of(registry.ENGINES).available()
