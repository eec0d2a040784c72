"""Optional parts of the install (pyproject.toml `[project.optional-dependencies]`, docs/host.md
"Installing"): the base install is the host library, the virtual modules and the servers; the
dashboard needs the ``web`` extra, plots the ``plot`` extra, ``all`` is both.

    require("web", "opentmcl dashboard")   # MissingExtra (an ImportError) naming the extra to install
"""
from __future__ import annotations

import importlib.util

EXTRAS: dict[str, tuple[str, ...]] = {
    "web": ("starlette", "uvicorn", "websockets"),
    "plot": ("matplotlib",),
}
"""Extra -> the import names of its packages (the distributions pyproject.toml lists for it)."""


class MissingExtra(ImportError):
    """A feature whose extra is not installed; the message is one line with the command to run."""

    def __init__(self, extra: str, feature: str, missing: str) -> None:
        super().__init__(f"{feature} needs the '{extra}' extra ({missing} is not installed): "
                         f"pip install 'opentmcl[{extra}]'", name=missing)
        self.extra = extra
        self.feature = feature


def missing(extra: str) -> str | None:
    """The first package of `extra` that cannot be found, or None when all are there."""
    for name in EXTRAS[extra]:
        try:
            if importlib.util.find_spec(name) is None:
                return name
        except (ImportError, ValueError):  # a broken parent package, or a module without a spec
            return name
    return None


def require(extra: str, feature: str) -> None:
    """Raise `MissingExtra` unless every package of `extra` can be imported; `feature` names what
    needs it ("opentmcl plot", "the dashboard")."""
    name = missing(extra)
    if name is not None:
        raise MissingExtra(extra, feature, name)
