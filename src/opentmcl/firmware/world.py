"""The physical world around the axes, as the firmware sees it (docs/world.md).

Hooks the VirtualModule calls:
- `next_event()`: absolute tick of the next world event (switch edge, load step, input change,
  deviation limit, search target), computed in closed form with `engine.time_at_position`;
- `service()`: called at every event tick after the engines were brought to `now`;
- `read_axis(axis, number)` for numbers in `axis_numbers`: switch states AP9-11, measured speed
  AP29, actual current AP180, load value AP206, driver flags AP208, encoder AP209, absolute
  encoder AP215;
- `write_axis(axis, number, value)`: AP1 and AP209 writes keep the stage frame and the encoder;
  AP167 = 0 (TOFF) lets the rotor free-wheel.

The world persists across power cycles (`power_up` rebinds it to the new axes). Python API:
`vm.world.axis(n)` -> AxisWorld (force_switch, set_load, physical_position, load_now; its rooms
rotor, switches, encoder, drive, checks, events: firmware/axis_world.py),
`vm.world.set_input(bank, port, value)`.
"""
from __future__ import annotations

import os
from dataclasses import replace
from functools import partial
from typing import TYPE_CHECKING, Any

from ..motion import CLOCK_HZ
from ..motion.scenario import Scenario, ScenarioError, load_scenario
from ..motion.stage import Profile, ceil_ticks
from . import flags as fl
from .axis_world import AxisWorld
from .effects import Effect
from .io import threshold

if TYPE_CHECKING:
    from ..modules.profile import IOPort
    from .motor import Motor
    from .vm import VirtualModule

__all__ = ["AxisWorld", "ScenarioSource", "World"]

_SWITCH_STATES = {11: 0, 10: 1, 9: 2}
"""AP11 left, AP10 right, AP9 home switch state -> its place in `Switches.logical`."""

ScenarioSource = Scenario | dict[str, object] | str | os.PathLike[str] | None
"""What `load_scenario` takes: a Scenario, its parsed dict, a .toml/.yaml path, or None (empty world)."""


def _level(vm: VirtualModule, signal: Profile, port: IOPort) -> int:
    """What `port` reads of `signal` now: its value times the port's counts per unit, rounded, and
    saturated at the port's range (a function, not a closure: a module's copy pickles)."""
    return min(max(round(signal.at(vm.now / CLOCK_HZ) * port.per_unit), port.min), port.max)


class World:
    """All axes' worlds plus the module's inputs, driven by a scenario."""

    axis_numbers: frozenset[int] = frozenset({9, 10, 11, 29, 180, 206, 208, 209, 215})
    """Motor parameter numbers `read_axis` serves (the hot GAP path skips the world for others)."""

    def __init__(self, vm: VirtualModule, scenario: ScenarioSource = None) -> None:
        self.vm = vm
        self.scenario: Scenario = load_scenario(scenario)
        if self.scenario.module is not None:
            from ..modules.profile import load_profile
            try:
                same = load_profile(self.scenario.module).name in (vm.profile.name,
                                                                    *vm.profile.extra.get("based_on", ()))
            except KeyError:
                same = False
            if not same:
                raise ScenarioError(f"the scenario is for {self.scenario.module}, not {vm.profile.name}")
        self.axes_world: list[AxisWorld] = []
        self.inputs: dict[tuple[int, int], Profile] = {(i.bank, i.port): i.signal for i in self.scenario.inputs}
        self.shutdown = self.scenario.shutdown
        self._input_cache: tuple[tuple[int, int, Profile | None], int | None] | None = None  # (inputs key, next change)

    # --- API ----------------------------------------------------------------------------------------
    def axis(self, index: int) -> AxisWorld:
        return self.axes_world[index]

    def set_input(self, bank: int, port: int, value: float | Profile) -> None:
        """Drive an input with a constant or a Profile over time (seconds since power-up of the world)."""
        if (bank, port) not in self.vm.io.ports:
            raise ScenarioError(f"input bank {bank} port {port}: {self.vm.profile.name} has no such port")
        twin = self.vm.io.twins.get((bank, port))
        if twin is not None:  # one line: the newest drive wins
            self.inputs.pop(twin, None)
        self.inputs[(bank, port)] = value if isinstance(value, Profile) else Profile.constant(float(value))
        self._input_cache = None
        self.vm.scheduler.invalidate(Effect.EVENTS)  # a new next input change
        self._drive_input((bank, port))

    def set_shutdown(self, level: int) -> None:
        """The SHUTDOWN pin (PD86-1180 GP80) at a constant level."""
        self.shutdown = Profile.constant(level)
        self._input_cache = None
        self.vm.scheduler.invalidate(Effect.EVENTS)
        self.service()

    # --- hooks --------------------------------------------------------------------------------------
    def power_up(self) -> None:
        vm = self.vm
        for key in self.inputs:
            if key not in vm.io.ports:
                raise ScenarioError(f"input bank {key[0]} port {key[1]}: {vm.profile.name} has no such port")
            twin = vm.io.twins.get(key)
            if twin in self.inputs and twin < key:
                raise ScenarioError(f"input bank {twin[0]} port {twin[1]} and bank {key[0]} port {key[1]} are "
                                    f"one line ({vm.io.ports[key].name}): drive only one of them")
        extra = [i for i in self.scenario.axes if i >= len(vm.axes)]
        if extra:
            raise ScenarioError(f"axis.{extra[0]}: {vm.profile.name} has {len(vm.axes)} axis/axes")
        while len(self.axes_world) < len(vm.axes):
            i = len(self.axes_world)
            self.axes_world.append(AxisWorld(self, i, self.scenario.axis(i)))
        for aw, ax in zip(self.axes_world, vm.axes, strict=False):
            aw.bind(ax)
        self._drive_measures()
        for key in self.inputs:
            self._drive_input(key)

    def _drive_measures(self) -> None:
        """Ports that read a quantity of the world (`IOPort.measures`: the supply voltage, the board
        temperature) follow the scenario's value of it, in counts of the port (docs/scenarios.md)."""
        vm = self.vm
        for key, p in vm.io.ports.items():
            if p.measures:
                vm.io.drive_source(*key, partial(_level, vm, self.scenario.measure(p.measures), p))

    def _drive_input(self, key: tuple[int, int]) -> None:
        """The port reads the signal at the moment it is read, rounded; a signal outside the
        port's range saturates there."""
        vm = self.vm
        vm.io.drive_source(*key, partial(_level, vm, self.inputs[key], replace(vm.io.ports[key], per_unit=1)))

    def _watched_levels(self, key: tuple[int, int]) -> tuple[int, ...]:
        """Levels whose crossing someone can see at once: a digital reading (input-change
        interrupts); an analog value is only read, so it needs no events of its own."""
        io = self.vm.io
        port = io.ports[key]
        if port.kind == "digital":
            return (threshold(port),)
        twin = io.twins.get(key)
        return (threshold(port),) if twin is not None else ()

    def next_event(self, same_axes: bool = False) -> int | None:
        """Absolute tick of the next world event. `same_axes`: nothing was written since the last
        call that can make an axis need events or not (`EventLookup.interesting`)."""
        best = None
        if same_axes:
            watched = self._watched
        else:
            self._watched = watched = [aw for aw in self.axes_world if aw.events.interesting()]
        for aw in watched:
            t = aw.events.next_event()
            if t is not None and (best is None or t < best):
                best = t
        if self.inputs or self.shutdown is not None:
            t = self._next_input_change()
            if t is not None and (best is None or t < best):
                best = t
        return best

    def _next_input_change(self) -> int | None:
        now = self.vm.now
        key = (id(self.inputs), len(self.inputs), self.shutdown)
        cached = self._input_cache
        if cached is not None and cached[0] == key and cached[1] is not None and cached[1] > now:
            return cached[1]
        best = None
        s = now / CLOCK_HZ
        changes = [sig.next_crossing(s, level) for key, sig in self.inputs.items()
                   for level in self._watched_levels(key)]
        if self.shutdown:
            changes.append(self.shutdown.next_integer_change(s))
        for x in changes:
            if x is not None:
                t = max(now + 1, ceil_ticks(x, CLOCK_HZ))
                if best is None or t < best:
                    best = t
        self._input_cache = (key, best)
        return best

    def service(self) -> bool:
        """The checks due at this event tick; True when any ran (the next events may have moved)."""
        vm = self.vm
        acted = False
        if self.shutdown is not None:
            self._check_shutdown()
            acted = True
        now = vm.now
        # the axes that need events, as found by the last look-up while that still holds
        # (Scheduler.limit_held: no write since that can make an axis need them)
        watched = self._watched if vm.scheduler.limit_held() else [aw for aw in self.axes_world if aw.events.interesting()]
        for aw in watched:
            if aw.events.needs_check(now):
                if aw.engine.now < now:
                    vm.sync()
                aw.checks.run()
                acted = True
        return acted

    def quiet(self) -> bool:
        """Does `service` do nothing at a tick that is none of the world's events? Not with a
        SHUTDOWN pin (checked at every tick) nor with a load over time on an axis that needs
        events (checked at every tick too)."""
        if self.shutdown is not None:
            return False
        watched = self._watched if self.vm.scheduler.limit_held() else [aw for aw in self.axes_world if aw.events.interesting()]
        return not any(aw.drive.load.by == "time" for aw in watched)

    _watched: list[AxisWorld] = []
    """The axes found interesting by the last `next_event`."""

    def _check_shutdown(self) -> None:
        """PD86-1180 GP80: 1 high active, 2 low active; an active SHUTDOWN pin stops the motors
        and sets the ESD flag (TMCM-6212 3.6.16 condition 12)."""
        if self.shutdown is None or (0, 80) not in self.vm.profile.global_parameters:
            return
        level = round(self.shutdown.at(self.vm.now / CLOCK_HZ))
        mode = self.vm.globals.get_raw(0, 80)
        active = (mode == 1 and level) or (mode == 2 and not level)
        if active:
            for ax in self.vm.axes:
                if ax.engine.moving:
                    ax.engine.hard_stop()
            self.vm.interpreter.set_error_flag(fl.ESD)

    def read_axis(self, axis: Motor, number: int) -> int | None:
        """GAP of a parameter the world computes (`axis_numbers`), or None for the others."""
        self.vm.sync()
        return self.readings(axis, (number,))[0]

    def readings(self, axis: Motor, numbers: tuple[int, ...], out: list[Any] | None = None,
                 counter: int | None = None) -> list[int | None]:
        """Several of the world's readings of one axis at once, each what GAP answers, appended to
        `out` (a new list by default): the stage follows the counter, the switches are looked at
        and the current in use is found once (the engines are at now). `counter`: the engine's
        position now (AP1), if read already."""
        aw = self.axes_world[axis.index]
        if counter is None:
            counter = aw.engine.position  # the engine's state, read once
        aw.rotor.follow(counter)
        aw.switches.update()
        if out is None:
            out = []
        append = out.append
        states: tuple[bool, bool, bool] | None = None
        use: int | None = None
        direction = 0
        for number in numbers:
            if number in _SWITCH_STATES:
                if states is None:  # the logical states of the three switches, once
                    states = aw.switches.logical()
                append(1 if states[_SWITCH_STATES[number]] else 0)
            elif number == 180 or number == 206:
                drive = aw.drive
                if use is None:  # the current in use, once
                    direction = aw.engine.direction  # moving: not 0 (RampEngine)
                    drive.current.update(aw, direction != 0, counter)
                    use = drive.current.in_use(aw, direction != 0)
                append(use >> 3 if number == 180 else drive.load_value(use, direction))   # AP180: 0..31
            elif number == 209:
                append(aw.encoder.position())
            else:
                append(self._reading(aw, axis, number))
        return out

    @staticmethod
    def _reading(aw: AxisWorld, axis: Motor, number: int) -> int | None:
        drive = aw.drive
        if number == 208:
            return drive.current.driver_status(aw) | drive.fault_flags
        if number == 29:
            return aw.rotor.speed()
        if number == 215:
            return aw.encoder.absolute(axis.params[215].max)
        return None

    def write_axis(self, axis: Motor, number: int, value: int) -> bool:
        aw = self.axes_world[axis.index]
        if number == 209:
            self.vm.sync()
            aw.rotor.follow()
            aw.encoder.set(value)
            return True
        if number == 1:
            self.vm.sync()
            aw.rotor.relabel(value)
            return True
        if number == 167:
            self.vm.sync()
            aw.rotor.set_toff(value)
            return True
        return False
