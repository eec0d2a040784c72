"""Faults of the module and its world (docs/faults.md "Module faults"), applied where they act:

- power loss: the motors stop, the program stops, nothing is answered until the power is back;
  then what the manuals say of a power-up: RAM parameters back to their stored values, the EEPROM
  kept, the stored program started when GP77 = 1 ("Start TMCL application automatically after
  power up", TMCM-6212 manual 5.1; `VirtualModule.power_up`). During a request (e.g. a STAP) the
  request either completed (its store is in the EEPROM) or never ran; either way no reply leaves
  (the EEPROM file is written atomically: a store is never torn, eeprom.py);
- hang: the firmware answers nothing for a while; the motion controller goes on with the ramp
  it has and a running program goes on (docs/assumptions.md);
- overtemperature: AP208 bit 2 "pre-warning overtemperature: threshold is exceeded", and for a
  shutdown bit 1 "driver is shut down due to overtemperature" too (PD86-1180 manual 5, TMC262
  driver error flags): the driver makes no torque, the counter runs on and the stage stands, which
  the encoder and the deviation check (AP212) see; the flags clear when it has cooled down;
- a stuck switch (forced to a level) and a bouncing one (toggling, then back to the stage);
- lost steps under load: a load beyond what the motor holds (`AxisWorld.set_load`, docs/world.md
  "Step loss"), seen by the encoder and the deviation check.

A fault fires at a time (the module's virtual time), on a request the module reads (the n-th
matching one, or by chance), or by name (`trigger`); the Python API fires one now. Every fault
that acts is recorded in `log` (traces read it). `ModuleFaults` watches the module's frames and
advances only once it holds a fault (`VirtualModule.watch`): an untouched module pays nothing.
"""
from __future__ import annotations

import heapq
import math
import random
from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING

from ..faults import Fault, FaultError, FaultLog, FaultPlan, Trigger, load_plan, new_seed, parse_fault, stream
from ..faults.board import FaultBoard
from ..faults.link import describe
from ..motion import CLOCK_HZ
from ..protocol.frame import FRAME_LEN
from .drive import OVERTEMPERATURE, PREWARNING
from .effects import Effect

if TYPE_CHECKING:
    from .axis_world import AxisWorld
    from .vm import VirtualModule

POWER_OFF = 0.1
"""Seconds a power loss keeps the module off unless the fault gives its `duration`."""
HOT = {"prewarning": PREWARNING, "shutdown": OVERTEMPERATURE | PREWARNING}

General = Callable[[bytes, str], bytes]


class ModuleFaults:
    """The faults of one `VirtualModule`: `vm.faults`."""

    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm
        self.log = FaultLog(lambda: vm.time)
        """What fired, in the module's virtual seconds (or the server's clock: `load(board=)`)."""
        self.seed: int | None = None
        self.triggers: list[Trigger] = []   # the faults that fire on a request
        self.named: dict[str, Trigger] = {}
        self.timeline: list[tuple[int, int, Callable[[], None]]] = []  # (tick, order, action)
        self.powered = True
        self.silent_until = -1
        """The tick before which the firmware answers nothing (a hang)."""
        self._order = 0
        self.link_plan = FaultPlan()
        """The link faults of the plans loaded here (a scenario's, `VirtualModule(faults=)`): a
        server serving this module applies them on its links (`Server.arm`)."""
        self._ends: dict[tuple, float] = {}     # a held state (power off, a hot driver, ...) -> its end tick
        self._before: dict[tuple, object] = {}  # what a held state restores when it ends

    # --- loading ----------------------------------------------------------------------------------
    def load(self, faults: object, *, board: FaultBoard | None = None) -> None:
        """Arm the module faults of a plan (a file, a dict, a list of faults, a `FaultPlan`); link
        faults are kept for the link (`link_plan`). With `board`, its seed, streams and log (a
        server, sim://)."""
        if board is not None:
            pairs = board.module_faults(self.vm.address)
            self.log, self.seed = board.log, board.seed
            board.attach(self)
        else:
            plan = load_plan(faults)
            self.link_plan = self.link_plan.merged(FaultPlan(plan.link_faults, plan.seed))
            self.seed = plan.seed if plan.seed is not None else new_seed()
            pairs = [(f, stream(self.seed, "module", self.vm.address, i, f.kind))
                     for i, f in enumerate(plan.faults) if not f.link]
        for fault, rng in pairs:
            self.add(fault, rng)

    def add(self, fault: Fault | dict, rng: random.Random | None = None) -> Fault:
        """Arm one module fault (a `Fault` or its table, docs/faults.md); returns it."""
        f = parse_fault(fault)
        if f.link:
            raise FaultError(f"{f.kind} is a link fault: give it to the link (a sim:// URL's faults, "
                             "opentmcl serve --faults), not to the module")
        if f.axis >= len(self.vm.axes) and f.kind not in ("power_loss", "hang"):
            raise FaultError(f"{f.label}: {self.vm.profile.name} has no axis {f.axis}")
        trig = Trigger(f, rng or stream(self.seed or 0, "module", len(self.named), f.kind))
        if f.name:
            self.named[f.name] = trig
        if f.timed:
            self._at(round(f.at * CLOCK_HZ) if f.at is not None else 0, lambda: self.fire(trig, "at its time"))
        elif f.probability is not None or f.count is not None or f.at is not None:
            self.triggers.append(trig)
        self.vm.watch(self)
        return f

    @property
    def address(self) -> int:
        return self.vm.address

    def names(self) -> list[str]:
        return list(self.named)

    def trigger(self, name: str, t: float | None = None) -> bool:
        """Fire the named fault now; False when this module has none of that name."""
        trig = self.named.get(name)
        if trig is None:
            return False
        self.vm.watch(self)
        self.fire(trig, "triggered by name")
        return True

    # --- the hooks (VirtualModule.watch) ---------------------------------------------------------
    def handle(self, frame: bytes, interface: str, general: General) -> bytes:
        """A frame for the module: nothing while it is off or hung; faults that fire on it act."""
        vm = self.vm
        if not self.powered or vm.now < self.silent_until:
            return b""
        fields = self._request(frame, interface)
        if fields is None or not self.triggers:
            return general(frame, interface)
        t = vm.time
        for trig in self.triggers:
            if trig.fires(fields[0], fields[1], fields[2], t):
                f = trig.fault
                if f.kind == "power_loss":
                    return self._lose_power_during(trig, frame, interface, general, describe(fields))
                self.fire(trig, f"at {describe(fields)}")
                if f.kind == "hang":
                    return b""
        return general(frame, interface)

    def _request(self, frame: bytes, interface: str) -> tuple[int, int, int, int] | None:
        """(command, type, motor, value) of a frame the module takes as its request, else None."""
        if len(frame) != FRAME_LEN or sum(frame[:8]) & 0xFF != frame[8]:
            return None
        if interface != "usb" and not self.vm.accepts_address(frame[0]):
            return None
        return frame[1], frame[2], frame[3], int.from_bytes(frame[4:8], "big", signed=True)

    def advance_to(self, until: int) -> None:
        """Advance the module to tick `until`, acting at every fault's tick on the way."""
        scheduler = self.vm.scheduler
        timeline = self.timeline
        while timeline and timeline[0][0] <= until:
            tick, _, action = heapq.heappop(timeline)
            if tick > scheduler.now:
                scheduler.advance_to(tick)
            action()
        scheduler.advance_to(until)

    def next_event_in(self) -> float | None:
        """Seconds to the module's next event or fault action, or None."""
        nxt = self.vm.scheduler.next_event_in()
        if self.timeline:
            due = max(0.0, (self.timeline[0][0] - self.vm.now) / CLOCK_HZ)
            nxt = due if nxt is None else min(nxt, due)
        return nxt

    def _at(self, tick: int, action: Callable[[], None]) -> None:
        self._order += 1
        heapq.heappush(self.timeline, (max(tick, self.vm.now), self._order, action))

    def _after(self, seconds: float | None, action: Callable[[], None]) -> None:
        if seconds is not None:
            self._at(self.vm.now + round(seconds * CLOCK_HZ), action)

    def _hold(self, key: tuple, seconds: float | None, release: Callable[[], None], before: object = None) -> None:
        """A state that faults hold on `key` for `seconds` (None: for good). Faults that overlap on
        one key end together, when the last of them ends: `release` of that one runs then, once.
        `before` (what the state restores) is kept from the first of them."""
        end = math.inf if seconds is None else self.vm.now + round(seconds * CLOCK_HZ)
        if key not in self._ends:
            self._before[key] = before
        self._ends[key] = max(self._ends.get(key, end), end)
        if seconds is not None:
            self._at(int(end), partial(self._end, key, end, release))

    def _end(self, key: tuple, end: float, release: Callable[[], None]) -> None:
        if self._ends.get(key) == end:
            del self._ends[key]
            release()

    # --- firing -----------------------------------------------------------------------------------
    def fire(self, trig: Trigger, why: str) -> None:
        """Let the fault act now (`why`: what set it off, for the log)."""
        f = trig.fault
        if f.kind == "power_loss":
            self.power_loss(f.duration if f.duration is not None else POWER_OFF, fault=f, why=why)
        elif f.kind == "hang":
            self.hang(f.duration or 0.0, fault=f, why=why)
        elif f.kind == "overtemperature":
            self.overtemperature(f.axis, str(f.level), f.duration, fault=f, why=why)
        elif f.kind == "stuck_switch":
            self.stuck_switch(f.axis, f.switch, int(f.level or 0), f.duration, fault=f, why=why)
        elif f.kind == "bouncing_switch":
            self.bouncing_switch(f.axis, f.switch, f.bounces, f.period, fault=f, why=why)
        else:
            self.step_loss(f.axis, f.load, f.duration, fault=f, why=why)

    def _record(self, fault: Fault | None, kind: str, detail: str) -> None:
        """Record what acted; from now on these faults see every frame and advance (a power loss
        or a hang must keep the module silent, a timed release must come)."""
        self.vm.watch(self)
        self.log.record(fault if fault is not None else kind, detail)

    def _lose_power_during(self, trig: Trigger, frame: bytes, interface: str, general: General,
                           text: str) -> bytes:
        f = trig.fault
        complete = f.store == "complete" or (f.store == "either" and trig.rng.random() < 0.5)
        if complete:
            general(frame, interface)
        what = "completed" if complete else "never ran"
        self.power_loss(f.duration if f.duration is not None else POWER_OFF, fault=f,
                        why=f"during {text}: the request {what}, its reply never left")
        return b""

    # --- the Python API: each acts now ----------------------------------------------------------
    def power_loss(self, duration: float = POWER_OFF, *, fault: Fault | None = None,
                   why: str = "on demand") -> None:
        """The power goes for `duration` seconds (0: a reset): motors and program stop, nothing is
        answered; then the module powers up (RAM from the EEPROM, GP77 auto start)."""
        vm = self.vm
        vm.scheduler.prepare(Effect.ENGINES)
        for axis in vm.axes:
            axis.engine.hard_stop()
        vm.interpreter.stop()
        vm.events.clear()
        vm.eeprom.deferred = False   # what was written is in the EEPROM (a download in progress too)
        vm.eeprom.flush()
        self.powered = False
        self._record(fault, "power_loss", f"power lost for {duration:g} s ({why})")
        if duration > 0:   # off until the last of overlapping power losses ends
            self._hold(("power",), duration, partial(self._power_up, fault))
        else:
            self._ends.pop(("power",), None)
            self._power_up(fault)

    def _power_up(self, fault: Fault | None) -> None:
        vm = self.vm
        self.powered = True
        self.silent_until = -1
        vm.power_up()
        vm.events.clear()
        self.log.record(fault if fault is not None else "power_loss", "power back: RAM parameters from the EEPROM"
                        + (", stored program started (GP77)" if vm.application_status == 1 else ""))

    def hang(self, duration: float, *, fault: Fault | None = None, why: str = "on demand") -> None:
        """The firmware answers nothing for `duration` seconds."""
        self.silent_until = max(self.silent_until, self.vm.now + round(duration * CLOCK_HZ))
        self._record(fault, "hang", f"firmware silent for {duration:g} s ({why})")

    def _axis(self, axis: int) -> AxisWorld:
        if not 0 <= axis < len(self.vm.axes):
            raise FaultError(f"{self.vm.profile.name} has no axis {axis}")
        return self.vm.world.axis(axis)

    def overtemperature(self, axis: int = 0, level: str = "shutdown", duration: float | None = None, *,
                        fault: Fault | None = None, why: str = "on demand") -> None:
        """The driver of `axis` overheats: AP208 pre-warning, or shutdown (driver off), until it has
        cooled down after `duration` seconds (None: it stays hot)."""
        if level not in HOT:
            raise FaultError(f"overtemperature level: one of {', '.join(HOT)}, got {level!r}")
        aw = self._axis(axis)
        aw.set_driver_flags(aw.drive.fault_flags | HOT[level])
        self._record(fault, "overtemperature", f"axis {axis}: {level} (AP208 {HOT[level]:#04x}; {why})"
                     + (", driver off" if aw.drive.shut_down else ""))
        self._hold(("hot", axis, level), duration, partial(self._cool, aw, axis, level, fault))

    def _cool(self, aw: AxisWorld, axis: int, level: str, fault: Fault | None) -> None:
        """`level` is over on `axis`; the flags of a level still held stay (a shutdown implies the
        pre-warning)."""
        keep = 0
        for other, flags in HOT.items():
            if ("hot", axis, other) in self._ends:
                keep |= flags
        aw.set_driver_flags(aw.drive.fault_flags & ~(HOT[level] & ~keep))
        left = aw.drive.fault_flags & (OVERTEMPERATURE | PREWARNING)
        self._record(fault, "overtemperature", f"axis {axis}: {level} over, "
                     + (f"AP208 {left:#04x} still" if left else "flags clear")
                     + (", driver off" if aw.drive.shut_down else ", driver on"))

    def stuck_switch(self, axis: int, switch: str, level: int = 1, duration: float | None = None, *,
                     fault: Fault | None = None, why: str = "on demand") -> None:
        """The `switch` input of `axis` sticks at `level` for `duration` seconds (None: for good)."""
        aw = self._axis(axis)
        key = ("switch", axis, switch)
        before = aw.switches.forced.get(switch)
        aw.force_switch(switch, level)
        self._record(fault, "stuck_switch", f"axis {axis} {switch} switch stuck at {level} ({why})")
        self._hold(key, duration, partial(self._release, aw, axis, switch, key, fault, "stuck_switch"), before)

    def _release(self, aw: AxisWorld, axis: int, switch: str, key: tuple, fault: Fault | None, kind: str) -> None:
        aw.force_switch(switch, self._before.pop(key, None))  # type: ignore[arg-type]
        self._record(fault, kind, f"axis {axis} {switch} switch follows the stage again")

    def bouncing_switch(self, axis: int, switch: str, bounces: int = 4, period: float = 0.001, *,
                        fault: Fault | None = None, why: str = "on demand") -> None:
        """The `switch` input of `axis` toggles `bounces` times, `period` seconds apart (the first
        now), then follows the stage again."""
        aw = self._axis(axis)
        aw.switches.update()
        key = ("switch", axis, switch)
        before = aw.switches.forced.get(switch)
        level = int(not aw.switches.input_level(switch))
        self._record(fault, "bouncing_switch", f"axis {axis} {switch} switch bounces {bounces} times, "
                     f"{period:g} s apart ({why})")
        aw.force_switch(switch, level)
        for i in range(1, bounces):
            self._after(i * period, partial(aw.force_switch, switch, (level + i) % 2))
        self._hold(key, bounces * period, partial(self._release, aw, axis, switch, key, fault, "bouncing_switch"),
                   before)

    def step_loss(self, axis: int = 0, load: float = 2.0, duration: float | None = None, *,
                  fault: Fault | None = None, why: str = "on demand") -> None:
        """A load of `load` (times the torque at 100 % current) on `axis` for `duration` seconds:
        beyond what the motor holds, steps are lost while it moves (docs/world.md)."""
        aw = self._axis(axis)
        key = ("load", axis)
        before = aw.drive.load
        aw.set_load(load)
        self._record(fault, "step_loss", f"axis {axis}: load {load:g} ({why})")
        self._hold(key, duration, partial(self._unload, aw, axis, key, fault), before)

    def _unload(self, aw: AxisWorld, axis: int, key: tuple, fault: Fault | None) -> None:
        aw.set_load(self._before.pop(key, None))  # type: ignore[arg-type]
        self._record(fault, "step_loss", f"axis {axis}: load back to the scenario's")
