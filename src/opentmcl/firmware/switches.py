"""The limit and home switches of one axis (docs/world.md "Stage and switches"): actuated by the
stage or forced, their physical levels, and the logical states AP9-AP11 after swap (AP14),
polarity (AP24/AP25 or GP79) and the PD86-1180 three-switch wiring."""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..motion.stage import Switch
    from .axis_world import AxisWorld

NAMES = ("left", "right", "home")


class Switches:
    """The three switch inputs of one axis."""

    def __init__(self, aw: AxisWorld) -> None:
        self.aw = aw
        self.raw = {"left": False, "right": False, "home": False}   # actuated by the stage
        self.forced: dict[str, int] = dict(aw.spec.force)
        self._kept: tuple[Switch | None, Switch | None, Switch | None, tuple[bool, ...], bool] | None = None
        """`levels`: the stage's (left, right, home) switches, whether each input is inverted
        (normally closed) and `three_switch_wiring`, kept while the switches stay the same."""

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

    def levels(self) -> list[bool]:
        """Levels of the (left, right, home) switch inputs: forced, else actuated (inverted for a
        normally closed switch)."""
        stage = self.aw.stage
        left, right, home = stage.left, stage.right, stage.home
        kept = self._kept
        if kept is None or kept[0] is not left or kept[1] is not right or kept[2] is not home:
            kept = self._kept = (left, right, home, tuple(bool(sw is not None and sw.inverted)
                                                          for sw in (left, right, home)), self.three_switch_wiring)
        inverted, forced, raw = kept[3], self.forced, self.raw
        if not forced:
            return [raw["left"] != inverted[0], raw["right"] != inverted[1], raw["home"] != inverted[2]]
        return [bool(forced[name]) if name in forced else raw[name] != inverted[i]
                for i, name in enumerate(NAMES)]

    def input_level(self, name: str) -> bool:
        """Level of one switch input (`levels`)."""
        return self.levels()[NAMES.index(name)]

    @property
    def three_switch_wiring(self) -> bool:
        aw = self.aw
        return aw.caps.reference_input == "REFL" and aw.stage.home is not None

    def logical(self) -> tuple[bool, bool, bool]:
        """Logical (left, right, home) states of the physical inputs after swap (AP14) and polarity
        (AP24/25 or GP79). On the TMCM-1180 the home switch is wired in series with the left
        switch on REFL (three-switch wiring, PD86-1180 manual 7.1): the left input reads either."""
        aw = self.aw
        ram = aw.ram
        left, right, home = self.levels()
        three = self._kept[4]  # type: ignore[index]  # `three_switch_wiring`, as `levels` found it
        if three:
            left = left or home
        if ram.get(14, 0):
            left, right = right, left
        if 24 in aw.params:
            if ram.get(24, 0):
                right = not right
            if ram.get(25, 0):
                left = not left
        elif (0, 79) in aw.vm.profile.global_parameters:
            pol = bool(aw.vm.globals.get_raw(0, 79))
            left ^= pol
            right ^= pol
        if three:
            home = left
        return left, right, home

    def edges(self, phys: int) -> list[int]:
        """Physical positions of the next edges of the switches not forced."""
        stage, out = self.aw.stage, []
        for name, sw in stage.switches().items():
            if name not in self.forced:
                out += stage.edge_candidates(phys, sw, self.raw[name])
        return out
