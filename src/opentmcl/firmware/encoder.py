"""The encoder of one axis (docs/world.md "Encoder and deviation"): it counts the rotor, not the
step counter. TMCM-6212: counts per round AP210 converted with AP202 and AP140 (manual 6.2);
PD86-1180: prescaler AP210 and the null channel (manual 7.2); absolute encoder value AP215."""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .axis_world import AxisWorld
    from .motor import Motor

CLEAR_AT_NULL = 4
"""AP210 bit: clear the encoder at the next null channel (PD86-1180 manual 7.2, prescaler p + 4)."""


class Encoder:
    """Encoder position AP209 (an offset over the counts of the rotor) and its null channel."""

    axis: Motor

    def __init__(self, aw: AxisWorld) -> None:
        self.aw = aw
        self.offset = 0                      # AP209 = quantized(phys) + offset
        self.clear_on_null_armed = False
        self.null_from = 0                   # where the null-channel clear was armed
        self.null_channel_possible = aw.caps.null_channel

    def bind(self, axis: Motor) -> None:
        """Power-up: the encoder counter starts at 0."""
        self.axis = axis
        self.offset = -self.quantized(self.aw.rotor.phys)

    def steps_per_round(self) -> int:
        aw = self.aw
        return aw.spec.fullsteps_per_round * (1 << aw.ram.get(140, 8))

    def quantized(self, phys: int) -> int:
        """Encoder reading (in microsteps) of a physical position, before the offset."""
        aw = self.aw
        ram = aw.ram
        if aw.caps.encoder == "resolution":
            # TMCM-6212 manual 6.2: counts per round AP210 converted with AP202 and AP140. The
            # encoder itself has the scenario's counts per round on a motor of its full steps
            # (without them: exactly what AP210 / AP202 say, so the conversion always matches).
            res = ram.get(210, 51200)
            spr = ram.get(202, 200) * (1 << ram.get(140, 8))
            if res <= 0 or spr <= 0:
                return 0
            real = aw.spec.encoder_counts
            real_spr = self.steps_per_round() if real else spr
            counts = (phys * (real or res)) // real_spr
            return (counts * spr) // res
        # PD86-1180 manual 7.2: prescaler p/512 applied to the encoder's own counts
        cpr = aw.spec.encoder_counts or aw.caps.encoder_counts
        p = ram.get(210, 6400) & ~CLEAR_AT_NULL
        counts = (phys * cpr) // self.steps_per_round()
        return (counts * p) // 512

    def position(self) -> int:
        """AP209."""
        return self.quantized(self.aw.rotor.phys) + self.offset

    def set(self, value: int) -> None:
        """An AP209 write: the encoder reads `value` where the rotor stands."""
        self.offset = value - self.quantized(self.aw.rotor.phys)

    def absolute(self, top: int) -> int:
        """AP215: the angle of the rotor within one round in 0..top (PD86-1180 5: "Absolute
        value of the encoder. 0... 255"), from the physical position; AP209 writes and the
        prescaler do not change it."""
        aw = self.aw
        aw.rotor.follow()
        cpr = aw.spec.encoder_counts or aw.caps.encoder_counts
        counts = (aw.rotor.phys * cpr) // self.steps_per_round()
        return (counts % cpr) * (top + 1) // cpr

    def clear_armed(self) -> bool:
        """AP210 + 4 on a module with a null channel: a clear waits for the next one."""
        return bool(self.null_channel_possible and self.aw.p(210) & CLEAR_AT_NULL)

    def null_channel(self) -> None:
        """PD86-1180 7.2: p + 4 clears the encoder at the next null channel (once per round)."""
        aw = self.aw
        if not aw.caps.null_channel or not aw.p(210) & CLEAR_AT_NULL:
            self.clear_on_null_armed = False
            return
        phys = aw.rotor.phys
        spr = self.steps_per_round()
        if not self.clear_on_null_armed:
            self.clear_on_null_armed = True
            self.null_from = phys
            return
        if phys % spr == 0 and phys != self.null_from:
            self.set(0)
            self.axis.ram[210] = aw.p(210) & ~CLEAR_AT_NULL
            self.clear_on_null_armed = False

    def null_positions(self, phys: int) -> list[int]:
        """Physical positions of the null channels on both sides of `phys` (none while no clear
        is armed)."""
        if not self.clear_armed():
            return []
        spr = self.steps_per_round()
        base = phys - phys % spr
        return [x for x in (base, base + spr) if x != phys]
