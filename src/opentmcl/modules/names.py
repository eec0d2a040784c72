"""Parameter names of a profile: ours, the manual's titles and the `aliases` (docs/profiles.md
"Parameter aliases"; the built-in profiles' aliases are PyTrinamic's names for the same numbers).

A name is looked up in this order, the first match winning:

1. our name exactly (``max_positioning_speed``), or written as words in any case
   (``Max positioning speed``), or the manual's title (``Maximum positioning speed``);
2. our name or an alias with case, ``_``, ``-``, ``/``, ``.`` and blanks ignored: ``ActualPosition``,
   ``MaxVelocity`` and ``max_velocity`` all match.
"""
from __future__ import annotations

import re
from collections.abc import Iterable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .profile import Param

HINTS = 4
"""Most "did you mean" suggestions given for an unknown name."""
_SEPARATORS = re.compile(r"[\s_\-/.]+")


def norm(name: str) -> str:
    """Our spelling: lower case, words joined by ``_`` ("Max positioning-speed" -> max_positioning_speed)."""
    return "_".join(name.strip().lower().replace("-", " ").replace("/", " ").split())


def compact(name: str) -> str:
    """The key of the loose match: lower case without separators ("Ref_SwitchTolerance" -> refswitchtolerance)."""
    return _SEPARATORS.sub("", name).lower()


class NameIndex:
    """The names of one table (axis or global parameters) of a profile."""

    def __init__(self, params: Iterable[Param]) -> None:
        self._words: dict[str, Param] = {}
        self._loose: dict[str, Param] = {}
        self._aliases: dict[str, tuple[str, Param]] = {}
        items = list(params)
        for p in items:
            self._words.setdefault(p.name, p)
        for p in items:
            self._words.setdefault(norm(p.title), p)
        for p in items:
            self._loose.setdefault(compact(p.name), p)
        for p in items:
            for alias in p.aliases:
                self._loose.setdefault(compact(alias), p)
                self._aliases.setdefault(compact(alias), (alias, p))
        self._ours = [p.name for p in items]

    def find(self, name: str) -> Param | None:
        """The parameter `name` names, or None."""
        return self._words.get(name) or self._words.get(norm(name)) or self._loose.get(compact(name))

    def suggest(self, name: str) -> list[str]:
        """Close names from both vocabularies, best first: ours as they are, an alias with the name
        it stands for (``MaxVelocity (max_positioning_speed)``)."""
        import difflib  # only for an unknown name

        scored: list[tuple[float, str]] = []
        loose = compact(name)
        for ours in self._ours:
            scored.append((difflib.SequenceMatcher(None, loose, compact(ours)).ratio(), ours))
        for key, (alias, p) in self._aliases.items():
            scored.append((difflib.SequenceMatcher(None, loose, key).ratio(), f"{alias} ({p.name})"))
        good = sorted((s for s in scored if s[0] >= 0.6), key=lambda s: -s[0])
        return [text for _, text in good[:HINTS]]
