"""Root causes first: knock-on divergences grouped under the divergence that caused them.

Once the module and the twin disagree about an axis (a move that takes longer, a write one of them
refused), every later reading of that axis may disagree for that one reason. So, in time order:

- a divergence about an axis while a chain of that axis is open is a knock-on of the chain's root;
- otherwise it is a root, and it opens a chain of its axis when it can change what the axis does
  later: a moving value, a move duration or event, a refused write or motion command, or a setting
  that drives the ramp engine. A program divergence opens the chain of the programs;
- a chain closes when the module and the twin agree again on the position of its axis at rest,
  and a chain opened by a refused write when the same setting is written again and both agree;
- a divergence like an earlier root (same signature) is that root again, not a knock-on, unless
  it is about motion.

Roots with the same signature (area, axis, request kind and parameter) are one cause seen several
times; a cause lists its first root, its later roots and all their knock-ons.
"""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class Divergence:
    t: float
    request: str
    parameter: str | None
    what: str
    captured: str
    virtual: str
    area: str = "parameters"
    axis: int | None = None
    n: int | None = None
    cause: int | None = None
    """Index of the cause it belongs to (`ReplayReport.causes`)."""
    root: bool = False

    def __str__(self) -> str:
        name = f" [{self.parameter}]" if self.parameter else ""
        return f"t={self.t:.6f}s  {self.request}{name}: {self.what}: captured {self.captured}, virtual {self.virtual}"

    def as_dict(self) -> dict:
        return {"t": round(self.t, 6), "request": self.request, "parameter": self.parameter, "what": self.what,
                "captured": self.captured, "twin": self.virtual, "area": self.area, "axis": self.axis,
                "record": self.n, "cause": self.cause, "root": self.root}


@dataclass
class Check:
    """One comparison: its time, axis, area, verdict; `rest`: a position read with the twin at rest."""

    t: float
    area: str
    ok: bool
    axis: int | None = None
    divergence: Divergence | None = None
    rest: bool = False
    engine: bool = False
    """A read or write of a setting that drives the ramp engine (profile `engine` field)."""
    program: bool = False
    write: tuple | None = None
    """(command, type, motor) of a SAP, SGP or SIO: what a later agreeing write puts right again."""


@dataclass
class Cause:
    """A root divergence, later roots like it, and the knock-on divergences of all of them."""

    root: Divergence
    repeats: list[Divergence] = field(default_factory=list)
    knock_on: list[Divergence] = field(default_factory=list)
    note: str = ""
    """A diagnosis, e.g. the accelerations measured on both sides."""

    @property
    def area(self) -> str:
        return self.root.area

    def title(self) -> str:
        d = self.root
        where = f"axis {d.axis}: " if d.axis is not None else ""
        name = f" [{d.parameter}]" if d.parameter else ""
        times = f" ({1 + len(self.repeats)} times)" if self.repeats else ""
        return f"{d.area}: {where}{d.request}{name}: {d.what}{times}"

    def count(self) -> int:
        return 1 + len(self.repeats) + len(self.knock_on)


MOTION_AREAS = ("ramp shape", "move durations")


def _signature(d: Divergence) -> tuple:
    """Roots alike: every motion root of one axis is one cause (its moves differ); else the area,
    axis, mnemonic, parameter and what differs."""
    if d.area in MOTION_AREAS:
        return ("motion", d.axis)
    head = d.request.split(",")[0].split(" ")[0]   # the mnemonic: MVP, GAP, 136, event ...
    return (d.area, d.axis, head, d.parameter, d.what)


def _opens(check: Check) -> bool:
    d = check.divergence
    assert d is not None
    if check.program:
        return True
    if d.area in MOTION_AREAS:
        return True
    return d.axis is not None and (d.what == "status" or check.engine)


def group(checks: list[Check]) -> list[Cause]:
    """Causes in order of their first root (see the module doc); sets each divergence's `cause`."""
    causes: list[Cause] = []
    by_signature: dict[tuple, int] = {}
    chains: dict[object, tuple[int, tuple | None]] = {}   # key -> (cause, the write that closes it)
    for check in sorted(checks, key=lambda c: c.t):
        key: object = "programs" if check.program else check.axis
        d = check.divergence
        if d is None:
            if key in chains and check.ok and (check.rest or (check.write is not None
                                                              and chains[key][1] == check.write)):
                del chains[key]   # the axis is where the twin says again
            continue
        sig = _signature(d)
        if sig in by_signature and d.area not in MOTION_AREAS:
            d.root, d.cause = True, by_signature[sig]
            causes[d.cause].repeats.append(d)
            continue
        if key == "programs" and key not in chains and chains:
            key = next(reversed(chains))   # a program waits on the motion of an axis that diverges
        if key is not None and key in chains:
            d.cause = chains[key][0]
            causes[d.cause].knock_on.append(d)
            continue
        d.root = True
        if sig in by_signature:
            d.cause = by_signature[sig]
            causes[d.cause].repeats.append(d)
        else:
            d.cause = by_signature[sig] = len(causes)
            causes.append(Cause(d))
        if key is not None and _opens(check):
            chains[key] = (d.cause, check.write if d.what == "status" else None)
    return causes
