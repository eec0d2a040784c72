"""The limit and home switches of one axis (docs/world.md "Stage and switches"): actuated by the
stage or forced, their physical levels, and the logical states AP9-AP11 after swap (AP14),
polarity (AP24/AP25 or GP79) and the PD86-1180 three-switch wiring."""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .axis_world import AxisWorld

NAMES = ("left", "right", "home")


class Switches:
    """The three switch inputs of one axis."""

    def __init__(self, aw: AxisWorld) -> None:
        self.aw = aw
        self.raw = {"left": False, "right": False, "home": False}   # actuated by the stage
        self.forced: dict[str, int] = dict(aw.spec.force)

    def force(self, name: str, level: int | None) -> None:
        """Force a switch input to 1/0; None returns it to the stage."""
        if level is None:
            self.forced.pop(name, None)
        else:
            self.forced[name] = int(bool(level))

    def update(self) -> None:
        """Which switches the stage actuates where it stands now (with hysteresis)."""
        stage, phys, raw = self.aw.stage, self.aw.rotor.phys, self.raw
        for name, sw in stage.switches().items():
            raw[name] = stage.active(sw, phys, raw[name])

    def input_level(self, name: str) -> bool:
        """Level of a switch input: forced, else actuated (inverted for a normally closed switch)."""
        if name in self.forced:
            return bool(self.forced[name])
        sw = self.aw.stage.switches().get(name)
        return self.raw[name] != bool(sw is not None and sw.inverted)

    def inputs(self) -> tuple[bool, bool, bool]:
        """Physical (left, right, home) inputs; on the TMCM-1180 the home switch is wired in
        series with the left switch on REFL (three-switch wiring, PD86-1180 manual 7.1)."""
        left, right, home = (self.input_level(n) for n in NAMES)
        if self.three_switch_wiring:
            left = left or home
        return left, right, home

    @property
    def three_switch_wiring(self) -> bool:
        aw = self.aw
        return aw.caps.reference_input == "REFL" and aw.stage.home is not None

    def logical(self) -> tuple[bool, bool, bool]:
        """Logical (left, right, home) states after swap (AP14) and polarity (AP24/25 or GP79)."""
        aw = self.aw
        left, right, home = self.inputs()
        if aw.p(14):
            left, right = right, left
        if aw.has(24):
            right ^= bool(aw.p(24))
            left ^= bool(aw.p(25))
        elif (0, 79) in aw.vm.profile.global_parameters:
            pol = bool(aw.vm.globals.get_raw(0, 79))
            left ^= pol
            right ^= pol
        if self.three_switch_wiring:
            home = left
        return left, right, home

    def edges(self, phys: int) -> list[int]:
        """Physical positions of the next edges of the switches not forced."""
        stage, out = self.aw.stage, []
        for name, sw in stage.switches().items():
            if name not in self.forced:
                out += stage.edge_candidates(phys, sw, self.raw[name])
        return out
