"""What a replay found (`ReplayReport`): the counts, divergences and their causes, the area
scores, the moves, the notes and the traces for the plots (docs/capture.md "Reports").

The files written from it are in capture/report.py (JSON, JUnit XML) and capture/html.py.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .causes import Cause, Divergence
from .moves import Move
from .tolerance import Tolerance

AREAS = ("identity", "parameters", "status codes", "move durations", "ramp shape", "programs")
"""The areas scored in the report (an agreement score each)."""


@dataclass
class ReplayReport:
    """The result of `replay` for one capture and module address (module doc)."""

    capture: str
    module: str
    address: int
    compared: int = 0
    skipped: int = 0
    events: int = 0
    divergences: list[Divergence] = field(default_factory=list)
    causes: list[Cause] = field(default_factory=list)
    areas: dict[str, list[int]] = field(default_factory=lambda: {a: [0, 0] for a in AREAS})
    """area -> [checks that agree, checks]."""
    moves: list[Move] = field(default_factory=list)
    accelerations: dict[int, dict[str, tuple[float, float]]] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    """How the replay started (snapshot, inferred values) and what it could not reproduce."""
    link: dict = field(default_factory=dict)
    tolerance: Tolerance = field(default_factory=Tolerance)
    traces: dict[int, dict[str, Any]] = field(default_factory=dict)
    """axis -> {"module": {"position": [(t, x)], "speed": [(t, v)]}, "twin": [(t, x, v)]}: the plots."""

    @property
    def ok(self) -> bool:
        return not self.divergences

    @property
    def parameters(self) -> list[str]:
        """Names of the parameters that diverged, in order, without repeats."""
        return list(dict.fromkeys(d.parameter for d in self.divergences if d.parameter))

    def score(self, area: str) -> float | None:
        """Share of the checks of `area` that agree (None: nothing checked there)."""
        ok, total = self.areas[area]
        return ok / total if total else None

    def summary(self) -> str:
        verdict = "all replies agree" if self.ok else \
            f"{len(self.divergences)} divergences from {len(self.causes)} root causes"
        return (f"{self.capture}: {self.compared} replies and {self.events} events compared against "
                f"{self.module} at address {self.address}, {self.skipped} records skipped: {verdict}")

    def text(self) -> str:
        """Root causes first, each with its repeats and knock-ons indented; notes; area scores; summary."""
        lines = [f"note: {n}" for n in self.notes]
        for i, cause in enumerate(self.causes, 1):
            if cause.note:
                lines.append(f"cause {i}: {cause.note}")
            lines.append(str(cause.root))
            lines += [f"    {d}  (again)" for d in cause.repeats]
            lines += [f"    {d}  (knock-on)" for d in cause.knock_on]
        scores = [f"{a} {ok}/{total}" for a, (ok, total) in self.areas.items() if total]
        if scores:
            lines.append("agreement: " + ", ".join(scores))
        lines.append(self.summary())
        return "\n".join(lines)
