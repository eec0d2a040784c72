"""The world of one axis (docs/world.md), made of rooms with one job each:

- `rotor` (firmware/rotor.py): the stage following the step counter, lost steps, driver off;
- `switches` (firmware/switches.py): switch inputs and their logical states AP9-AP11;
- `encoder` (firmware/encoder.py): AP209, AP210 resolution or prescaler, null channel, AP215;
- `drive` (firmware/drive.py): load torque, current in use, torque fall-off, load value AP206;
- `checks` (firmware/world_checks.py): limit stops, stall, step loss, deviation at every event;
- `events` (firmware/world_events.py): the axis's next event and its cache.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..motion.scenario import AxisSpec
from ..motion.stage import Load, Profile
from .drive import Drive, as_load, check_by
from .encoder import Encoder
from .rotor import Rotor
from .switches import NAMES, Switches
from .world_checks import Checks
from .world_events import EventLookup

if TYPE_CHECKING:
    from ..modules.profile import Capabilities, Param
    from ..motion import RampEngine
    from .motor import Motor
    from .vm import VirtualModule
    from .world import World


class AxisWorld:
    """Stage, switches, encoder, load and drive of one axis, bound to the module's axis."""

    _axis: Motor
    """The bound axis (`axis` once `bind` ran; the checks and scans run only then)."""
    engine: RampEngine

    def __init__(self, world: World, index: int, spec: AxisSpec) -> None:
        self.world = world
        self.vm: VirtualModule = world.vm
        self.scheduler = world.vm.scheduler
        """The module's scheduler: its clock `now` (ticks), read by every reading."""
        self.index = index
        self.spec = spec
        self.stage = spec.stage
        self.caps: Capabilities = world.vm.profile.capabilities
        self.axis: Motor | None = None
        self.watch: int | None = None          # counter position the reference search waits for
        self.rotor = Rotor(self)
        self.switches = Switches(self)
        self.encoder = Encoder(self)
        self.drive = Drive(self)
        self.checks = Checks(self)
        self.events = EventLookup(self)

    def bind(self, axis: Motor) -> None:
        """Power-up: the world (which persists) meets the module's new axis."""
        self.axis = axis
        self._axis = axis
        self.ram, self.params = axis.ram, axis.params  # read on every check: looked up once
        self.engine = axis.engine
        self.rotor.bind(axis)
        self.encoder.bind(axis)
        self.drive.bind()
        self.checks.bind(axis)
        self.events.bind(axis)
        self.switches.update()

    ram: dict[int, int]
    """The bound axis's parameters in RAM (every one the module has): `p`, or ``ram.get(n, 0)``
    where a reading is hot."""
    params: dict[int, Param]

    def p(self, number: int, default: int = 0) -> int:
        """Motor parameter `number` in RAM; `default` on a module that does not have it."""
        return self.ram.get(number, default)  # the RAM holds every parameter the module has

    def has(self, number: int) -> bool:
        """Does the module have axis parameter `number` (a feature that comes with a parameter)?"""
        return number in self.params

    # --- Python API (docs/scenarios.md "Python API") --------------------------------------------
    def force_switch(self, name: str, level: int | None) -> None:
        """Force a switch input (left/right/home) to 1/0; None returns it to the stage."""
        if name not in NAMES:
            raise ValueError(f"no switch {name!r} (left, right, home)")
        self.vm.sync()
        self.switches.force(name, level)
        self.checks.run()

    def set_load(self, load: float | Load | Profile, by: str = "position") -> None:
        """Load torque: a constant fraction of the full-current torque, a Profile or a Load."""
        check_by(by)
        self.vm.sync()
        self.drive.load = as_load(load, by)
        self.events.update_static()
        self.checks.run()

    def set_driver_flags(self, bits: int) -> None:
        """AP208 driver error flags 1-6 (TMC262 layout, PD86-1180 manual 5) set by a fault, e.g.
        overtemperature (2 | 4) or its pre-warning (4); overtemperature and a short shut the
        driver down: the motor makes no torque, the counter runs on and the stage stands."""
        self.vm.sync()
        self.rotor.set_driver_flags(bits)
        self.events.update_static()
        self.checks.run()

    @property
    def physical_position(self) -> int:
        """Where the stage really is (microsteps)."""
        self.vm.sync()
        self.rotor.follow()
        return self.rotor.phys

    def load_now(self) -> float:
        """Load torque now, as a fraction of the torque at 100 % current."""
        return self.drive.load_now()
