"""One motor of a virtual module (the "motor" field of the TMCL commands): its axis-parameter RAM
bound to its ramp engine. (The host library's `Axis`, host/module.py, is what a program talks to;
this is what answers it inside the virtual module.)

Implements the axis-parameter semantics of SAP/GAP (TMCM-6212 manual 4.1,
PD86-1180 manual 5): reads of live values come from the engine, writes of
ramp parameters reconfigure it, AP0/AP1/AP2 writes act like MVP ABS, a
position overwrite and ROR/ROL. Velocity units follow the engine: pps for
the TMC5130-style and linear engines (with AP255 = 0 selecting TMC5130
internal units on the TMCM-6212), TMC429 internal units on the PD86-1180.
"""
from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from functools import partial
from operator import attrgetter
from typing import TYPE_CHECKING, cast

from ..modules.profile import ModuleProfile, Param
from ..modules.profile_file import ProfileError
from ..motion import Mode, RampEngine
from ..motion.units import (
    internal_acceleration_from_pps2,
    internal_velocity_from_pps,
    pps2_from_internal_acceleration,
    pps_from_internal_velocity,
    round_half_away,
)
from ..protocol.frame import to_int32
from .engines import make_engine
from .status import TmclStatus

if TYPE_CHECKING:
    from .world import World

ENGINE_READS = {0: "target_position", 1: "position", 8: "position_reached",
                135: "actual_acceleration", 138: "ramp_mode"}
"""Motor parameters read from the ramp engine (AP138: "Automatically set when using ROR, ROL, MST and MVP")."""
VELOCITY_PARAMS = {2, 3, 4, 16, 19, 20, 22, 23, 29, 181, 182, 186, 194, 195}
ACCEL_PARAMS = {5, 15, 17, 18}
# Internal-unit ranges of the TMC5130 registers (TMC5130 datasheet; docs/motion.md) used when AP255 = 0.
INTERNAL_VMAX = 2**23 - 512
INTERNAL_AMAX = 2**16 - 1


class Motor:
    world: World
    """The module's world, set by VirtualModule at power-up (firmware/world.py)."""

    def __init__(self, index: int, profile: ModuleProfile, ram: dict[int, int]) -> None:
        self.index = index
        self.params = profile.axis_parameters
        self.ram = ram
        self.engine: RampEngine = make_engine(profile.engine)
        self.engine_keys = profile.engine_params
        self._unit_mode = profile.capabilities.unit_mode
        self.readable = frozenset(n for n, p in self.params.items() if p.readable)
        self._readers: dict[int, Callable[[], int]] = {}
        self.last_target = 0
        self.error_flags = 0
        self.reference_search_active = False
        try:
            self._configure_all()
        except (TypeError, ValueError) as exc:   # an engine keyword or default of the profile it refuses
            raise ProfileError([f"{profile.name}: the {profile.engine} ramp engine refuses the profile's "
                                f"settings: {exc}"]) from None

    # --- units --------------------------------------------------------------
    @property
    def internal_units(self) -> bool:
        """TMCM-6212 AP255 = 0: velocities and accelerations in TMC5130 units."""
        return self._internal()

    def _internal(self) -> bool:
        return self._unit_mode and self.ram.get(255, 1) == 0

    def to_engine(self, number: int, value: int) -> int | Fraction:
        """A parameter value in the engine's unit (exact: a Fraction of pps in internal units)."""
        if self.internal_units:
            if number in VELOCITY_PARAMS:
                return pps_from_internal_velocity(value)
            if number in ACCEL_PARAMS:
                return pps2_from_internal_acceleration(value)
        return value

    def engine_speed(self, number: int, value: int) -> int | Fraction:
        """|to_engine|: a speed threshold (AP181, AP182) as a magnitude in engine units."""
        v = self.to_engine(number, value)
        return -v if v < 0 else v

    def from_engine(self, number: int, value: int | float | Fraction) -> int:
        if self._internal():
            if number in VELOCITY_PARAMS:
                return internal_velocity_from_pps(value)
            if number in ACCEL_PARAMS:
                return internal_acceleration_from_pps2(value)
        return int(value)

    def _convert_units(self) -> None:
        """AP255 changed: the ramp registers keep their values, so the stored velocity and
        acceleration parameters are re-expressed in the new unit (the motion is unchanged)."""
        to_internal = self.internal_units
        for n in VELOCITY_PARAMS | ACCEL_PARAMS:
            if n not in self.ram:
                continue
            v = self.ram[n]
            if n in VELOCITY_PARAMS:
                self.ram[n] = internal_velocity_from_pps(v) if to_internal else \
                    round_half_away(pps_from_internal_velocity(v))
            else:
                self.ram[n] = internal_acceleration_from_pps2(v) if to_internal else \
                    round_half_away(pps2_from_internal_acceleration(v))

    def _configure_all(self) -> None:
        self.engine.configure(**{name: self.to_engine(num, self.ram[num])
                                 for num, name in self.engine_keys.items() if num in self.ram})

    # --- parameter access (status raised as TmclStatus) ------------------------
    def param(self, number: int) -> Param:
        p = self.params.get(number)
        if p is None:
            raise TmclStatus(3)
        return p

    def check_value(self, p: Param, value: int) -> None:
        if self.internal_units and p.number in VELOCITY_PARAMS | ACCEL_PARAMS:
            top = INTERNAL_VMAX if p.number in VELOCITY_PARAMS else INTERNAL_AMAX
            low = -top if p.min < 0 else 0
            if not low <= value <= top:
                raise TmclStatus(4)
        elif not p.accepts(value):
            raise TmclStatus(4)

    def get(self, number: int) -> int:
        """GAP `number` (TMCM-6212 3.6.6): the value now; TmclStatus(3) if it cannot be read."""
        value = self.reader(number)()
        return int(value) if value.__class__ is bool else value

    def reader(self, number: int) -> Callable[[], int]:
        """The read of axis parameter `number`, bound to this axis: the one rule of GAP, which the
        request path and programs bind ahead (requests.py). TmclStatus(3) if it cannot be read.
        AP8 reads as the engine's flag, a bool (1 or 0 on the wire)."""
        read = self._readers.get(number)
        if read is None:
            if number not in self.readable:
                raise TmclStatus(3)
            read = self._readers[number] = self._make_reader(number)
        return read

    def _make_reader(self, number: int) -> Callable[[], int]:
        if number in self.world.axis_numbers:
            return partial(self._world_value, number)
        e = self.engine
        if number in (2, 3):  # velocities: the unit follows AP255 at every read
            velocity = attrgetter("target_velocity" if number == 2 else "velocity")
            return lambda: self.from_engine(number, velocity(e))
        attribute = ENGINE_READS.get(number)
        if attribute is not None and (number < 135 or hasattr(e, attribute)):
            return partial(attrgetter(attribute), e)
        if number == 207:
            return self._take_error_flags
        return cast("Callable[[], int]", partial(self.ram.get, number, self.params[number].default))

    def __getstate__(self) -> dict[str, object]:
        """A copy (copy.deepcopy, pickle) makes its own readers: these are bound to this axis."""
        return {**self.__dict__, "_readers": {}}

    def _world_value(self, number: int) -> int:
        value = self.world.read_axis(self, number)
        return self.ram.get(number, self.params[number].default) if value is None else value

    def _take_error_flags(self) -> int:
        """AP207: the extended error flags, cleared by the read."""
        flags, self.error_flags = self.error_flags, 0
        return flags

    def set(self, number: int, value: int) -> None:
        p = self.param(number)
        if not p.writable:
            raise TmclStatus(3)
        self.check_value(p, value)
        if self.world.write_axis(self, number, value):
            return
        if number == 0:
            self.move_to(value)
        elif number == 1:
            self.engine.set_position(to_int32(value))
        elif number == 2:
            # "The desired speed in velocity mode. Not valid in position mode" (TMCM-6212 4.1):
            # in position mode (a move running or done, power-up) the write changes no motion.
            if self.engine.mode is not Mode.POSITION:
                self.rotate(value)
        elif number == 3:  # actual speed writable (PD86-1180 5: TMC429 hold mode); else a rotation
            self.error_flags = 0
            hold = getattr(self.engine, "hold", None)
            if hold is not None:
                hold(value)
            else:
                self.rotate(value)
        else:
            was_internal = self.internal_units
            self.ram[number] = value
            if number == 255:
                if self.internal_units != was_internal:
                    self._convert_units()
                self._configure_all()
            elif number in self.engine_keys:
                self.engine.configure(**{self.engine_keys[number]: self.to_engine(number, value)})

    # --- motion commands --------------------------------------------------------
    def move_to(self, target: int) -> None:
        target = to_int32(target)
        self.last_target = target
        self.error_flags = 0
        e = self.engine
        if e.mode is Mode.POSITION and e.target_position == target and not self.reference_search_active:
            return  # already heading there (programs re-issue the same target in tight loops)
        e.move_to(target)

    def rotate(self, velocity: int) -> None:
        self.error_flags = 0
        self.engine.rotate(self.to_engine(2, velocity))

    def stop(self) -> None:
        self.engine.stop()

    def relative_origin(self) -> int:
        """Start of MVP REL: AP127 on the TMCM-6212 (0 last target, 1 actual, 2 encoder)."""
        if 127 not in self.params:  # PD86-1180 manual 4.6.4: offset to the actual position
            return self.engine.position
        option = self.ram.get(127, 0)
        if option == 1:
            return self.engine.position
        if option == 2:
            return self.get(209)  # the live encoder position (world model), not the last SAP 209
        return self.last_target
