"""The Step/Dir output of the TMC4210 as a stream of timed pin edges (datasheet 6.2.1, 8.1).

The ramp core says *when* a step happens and in which direction; this module
turns that into levels on the STEP (SDO_S) and DIR (SCK_S) pins:

- until en_sd = 1 both outputs stay logic high and no steps are output (6.2.1);
- a step pulse lasts t_STEP = 16 * (1 + STPDIV_4210) clock cycles (8.1);
- the first step after a change of direction is delayed by t_DIR2STP = t_STEP (8.1);
- step_half: the STEP pin toggles once per step instead of pulsing (6.2.1);
- inv_stp / inv_dir invert the idle polarity of STEP / the level of DIR (6.2.1).
"""
from __future__ import annotations

import heapq
from dataclasses import dataclass


@dataclass(frozen=True, order=True)
class Edge:
    """A level change on an output pin; `cycle` counts f_CLK cycles since power-on."""

    cycle: int
    pin: str  # "STEP" or "DIR"
    level: int
    time: float = 0.0  # seconds, cycle / f_CLK


class StepDirOutput:
    """Pin levels and pending edges of the Step/Dir interface."""

    def __init__(self, f_clk: float) -> None:
        self.f_clk = f_clk
        self.en_sd = 0
        self.step_half = 0
        self.inv_stp = 0
        self.inv_dir = 0
        self.t_step = 16 * 16  # STPDIV_4210 = 15 after power-on
        self.capture = False
        self.step_level = 1  # "logic high until configured" (6.2.1)
        self.dir_level = 1
        self._direction = 1  # logical direction of the last step (+1 / -1)
        self._busy_until = -1  # cycle at which the running pulse (or dir delay) has ended
        self._pending: list[tuple[int, int, Edge]] = []  # (cycle, sequence, edge): a heap in time order
        self._seq = 0
        self.steps_out = 0
        self.lost_steps = 0

    # --- configuration --------------------------------------------------------------
    def configure(self, cycle: int, *, en_sd: int, step_half: int, inv_stp: int, inv_dir: int,
                  t_step: int) -> None:
        """Apply IF_CONFIGURATION_4210 / STPDIV_4210 at `cycle`; idle levels change at once."""
        was_enabled = self.en_sd
        self.en_sd, self.step_half, self.inv_stp, self.inv_dir = en_sd, step_half, inv_stp, inv_dir
        self.t_step = t_step
        if not en_sd:
            self._set(cycle, "STEP", 1)
            self._set(cycle, "DIR", 1)
            return
        if not step_half or not was_enabled:
            self._set(cycle, "STEP", inv_stp)
        self._set(cycle, "DIR", self._dir_level(self._direction))

    def _dir_level(self, direction: int) -> int:
        return (1 if direction > 0 else 0) ^ self.inv_dir

    def _set(self, cycle: int, pin: str, level: int) -> None:
        current = self.step_level if pin == "STEP" else self.dir_level
        if current == level:
            return
        if pin == "STEP":
            self.step_level = level
        else:
            self.dir_level = level
        self._emit(cycle, pin, level)

    def _emit(self, cycle: int, pin: str, level: int) -> None:
        if self.capture:
            heapq.heappush(self._pending, (cycle, self._seq, Edge(cycle, pin, level, cycle / self.f_clk)))
            self._seq += 1

    # --- steps ------------------------------------------------------------------------
    def step(self, cycle: int, direction: int) -> None:
        """One step of the pulse generator at `cycle` (+1 / -1)."""
        if not self.en_sd:
            return
        start = cycle
        if direction != self._direction:
            self._direction = direction
            self._set(cycle, "DIR", self._dir_level(direction))
            start = cycle + self.t_step
        elif cycle < self._busy_until:
            # the previous pulse is still active: the driver sees one merged pulse (8.1:
            # STPDIV_4210 "has to be set compatible to the upper step frequency")
            self.lost_steps += 1
            return
        self.steps_out += 1
        if self.step_half:
            level = self.step_level ^ 1
            self.step_level = level
            self._emit(start, "STEP", level)
            self._busy_until = start
            return
        active = 1 ^ self.inv_stp
        self._emit(start, "STEP", active)
        self._emit(start + self.t_step, "STEP", active ^ 1)
        self.step_level = active ^ 1  # level after the pulse
        self._busy_until = start + self.t_step

    def drain(self, until: int | None = None) -> list[Edge]:
        """Edges up to and including cycle `until` (all when None), in time order."""
        out = []
        while self._pending and (until is None or self._pending[0][0] <= until):
            out.append(heapq.heappop(self._pending)[2])
        return out
