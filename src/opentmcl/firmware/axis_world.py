"""The world of one axis: stage and switches, load, encoder, currents, and the checks made
at every event (limit stops, stall, step loss, deviation). Model: docs/world.md."""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..modules.profile import Capabilities
from ..motion import CLOCK_HZ
from ..motion.scenario import AxisSpec
from ..motion.stage import Load, Profile, ceil_ticks
from ..motion.stallguard import CurrentModel, load_value
from . import flags as fl

if TYPE_CHECKING:
    from ..motion import RampEngine
    from .axis import Axis
    from .world import World

STALL, DEVIATION = 15, 21            # interrupt numbers + axis (firmware/interrupts.py)
SG_EXTENDED, DEV_EXTENDED = 1, 2     # AP207 bits
END_LOAD = 100.0                     # a mechanical end: far more than any current can hold


def _sign(x) -> int:
    return (x > 0) - (x < 0)


DEFAULT_FALLOFF_RPS = 30
"""Speed (full-step revolutions per second) at which the torque has fallen to 0 unless the
scenario sets `torque_falloff_speed`: about half the torque at 15 rev/s, as a typical stepper."""
FULLSTEPS = 200


class AxisWorld:
    """Stage, load, encoder and drive currents of one axis."""

    _axis: Axis
    """The bound axis (`axis` once `bind` ran; the checks and scans run only then)."""
    engine: RampEngine

    def __init__(self, world: World, index: int, spec: AxisSpec) -> None:
        self.world = world
        self.index = index
        self.spec = spec
        self.stage = spec.stage
        self.load = spec.load
        self.phys = spec.stage.start          # physical position (microsteps)
        self.offset = 0                       # phys = counter + offset while no step is lost
        self.slipping = 0                     # direction of the commanded motion while steps are lost
        self.raw = {"left": False, "right": False, "home": False}
        self.forced: dict[str, int] = dict(spec.force)
        self.enc_offset = 0
        self.clear_on_null_armed = False
        self.watch: int | None = None          # counter position the reference search waits for
        self.current = CurrentModel()
        self.axis: Axis | None = None
        self._due_at = -2
        self._due_streak = 0
        self._due_plan: object = None
        self._cache: tuple | None = None
        self._static = False
        self.caps: Capabilities = world.vm.profile.capabilities
        self._null_channel_possible = self.caps.null_channel
        self._engine_wake: int | None = None

    # --- binding ----------------------------------------------------------------------------
    def bind(self, axis: Axis) -> None:
        self.axis = axis
        self._axis = axis
        self.engine = axis.engine
        self.offset = self.phys - self.engine.position
        self.slipping = 0
        self.enc_offset = -self._quantized(self.phys)   # the encoder counter starts at 0
        self.current = CurrentModel()
        self._update_static()
        self.update_raw()

    @property
    def vm(self):
        return self.world.vm

    def p(self, number: int, default: int = 0) -> int:
        return self._axis.ram.get(number, default) if number in self._axis.params else default

    def has(self, number: int) -> bool:
        return number in self._axis.params

    # --- Python API -------------------------------------------------------------------------------
    def force_switch(self, name: str, level: int | None) -> None:
        """Force a switch input (left/right/home) to 1/0; None returns it to the stage."""
        if name not in self.raw:
            raise ValueError(f"no switch {name!r} (left, right, home)")
        self.vm.sync()
        if level is None:
            self.forced.pop(name, None)
        else:
            self.forced[name] = int(bool(level))
        self.check()

    def set_load(self, load: float | Load | Profile, by: str = "position") -> None:
        """Load torque: a constant fraction of the full-current torque, a Profile or a Load."""
        if by not in ("position", "time"):
            raise ValueError(f"a load is given by 'position' or 'time', not {by!r}")
        self.vm.sync()
        if isinstance(load, Load):
            self.load = load
        elif isinstance(load, Profile):
            self.load = Load(load, by)
        else:
            self.load = Load(Profile.constant(float(load)), "position")
        self._update_static()
        self.check()

    @property
    def physical_position(self) -> int:
        self.vm.sync()
        self.follow()
        return self.phys

    # --- state ------------------------------------------------------------------------------------
    def driver_off(self) -> bool:
        """AP167 (TOFF) = 0: "completely disables all driver transistors and the motor can
        free-wheel" (TMCM-6212 4.1): the step counter runs on, the rotor does not follow it."""
        return self.has(167) and self.p(167, 1) == 0

    def follow(self) -> None:
        """Bring the physical position up to the counter (unless steps are being lost or the
        driver is off; then the stage stays and the frame offset follows the counter)."""
        counter = self.engine.position
        if self.driver_off():
            self.slipping = 0
            self.offset = self.phys - counter
        elif self.slipping:
            if self.heading() != self.slipping or not (self._blocked(self.slipping) or self._overloaded()):
                self.slipping = 0          # stopped, reversed or the load fell: the rotor follows again
                self.offset = self.phys - counter
        else:
            self.phys = counter + self.offset

    def update_raw(self) -> None:
        for name, sw in self.stage.switches().items():
            self.raw[name] = self.stage.active(sw, self.phys, self.raw[name])

    def input_level(self, name: str) -> bool:
        """Level of a switch input: forced, else actuated (inverted for a normally closed switch)."""
        if name in self.forced:
            return bool(self.forced[name])
        sw = self.stage.switches().get(name)
        return self.raw[name] != bool(sw is not None and sw.inverted)

    def inputs(self) -> tuple[bool, bool, bool]:
        """Physical (left, right, home) inputs; on the TMCM-1180 the home switch is wired in
        series with the left switch on REFL (three-switch wiring, PD86-1180 manual 7.1)."""
        left, right, home = (self.input_level(n) for n in ("left", "right", "home"))
        if self.three_switch_wiring:
            left = left or home
        return left, right, home

    @property
    def three_switch_wiring(self) -> bool:
        return self.caps.reference_input == "REFL" and self.stage.home is not None

    def logical(self) -> tuple[bool, bool, bool]:
        """Logical (left, right, home) states after swap (AP14) and polarity (AP24/25 or GP79)."""
        left, right, home = self.inputs()
        if self.p(14):
            left, right = right, left
        if self.has(24):
            right ^= bool(self.p(24))
            left ^= bool(self.p(25))
        elif (0, 79) in self.vm.profile.global_parameters:
            pol = bool(self.vm.globals.get_raw(0, 79))
            left ^= pol
            right ^= pol
        if self.three_switch_wiring:
            home = left
        return left, right, home

    def heading(self) -> int:
        """Direction of motion, or of the motion about to start (0 when there is none)."""
        e = self.engine
        v = e.direction
        if v:
            return v
        if e.mode.value == "velocity":
            return _sign(e.target_velocity)
        return _sign(((e.target_position - e.position + 2**31) % 2**32) - 2**31)

    def set_toff(self, value: int) -> None:
        """SAP 167: the stage follows up to now under the old setting; after re-enabling it
        continues from where it stands."""
        self.follow()
        self._axis.ram[167] = value
        self.follow()

    def speed(self) -> int:
        """Speed of the rotor (stage) in the unit of AP3: 0 at rest, while steps are lost or the
        driver is off; signed like AP3 (TMCM-6212 AP29 "Speed measured by the motor driver")."""
        self.follow()
        if self.slipping or self.driver_off():
            return 0
        return self._axis.from_engine(29, self.engine.velocity)

    def absolute_encoder(self, top: int) -> int:
        """AP215: the angle of the rotor within one round in 0..top (PD86-1180 5: "Absolute
        value of the encoder. 0... 255"), from the physical position; AP209 writes and the
        prescaler do not change it."""
        self.follow()
        cpr = self.spec.encoder_counts or self.caps.encoder_counts
        counts = (self.phys * cpr) // self._steps_per_round()
        return (counts % cpr) * (top + 1) // cpr

    def relabel(self, counter: int) -> None:
        """Overwrite the position counter (AP1, reference point); the stage stays where it is."""
        self.follow()
        self.engine.set_position(counter)
        self.offset = self.phys - self.engine.position

    # --- encoder ----------------------------------------------------------------------------------
    def _steps_per_round(self) -> int:
        return self.spec.fullsteps_per_round * (1 << self.p(140, 8))

    def _quantized(self, phys: int) -> int:
        """Encoder reading (in microsteps) of a physical position, before the offset."""
        spr = self._steps_per_round()
        if self.caps.encoder == "resolution":
            # TMCM-6212 manual 6.2: counts per round AP210 converted with AP202 and AP140. The
            # encoder itself has the scenario's counts per round on a motor of its full steps
            # (without them: exactly what AP210 / AP202 say, so the conversion always matches).
            res = self.p(210, 51200)
            spr = self.p(202, 200) * (1 << self.p(140, 8))
            if res <= 0 or spr <= 0:
                return 0
            if self.spec.encoder_counts:
                real = self.spec.encoder_counts
                real_spr = self.spec.fullsteps_per_round * (1 << self.p(140, 8))
            else:
                real, real_spr = res, spr
            counts = (phys * real) // real_spr
            return (counts * spr) // res
        # PD86-1180 manual 7.2: prescaler p/512 applied to the encoder's own counts
        cpr = self.spec.encoder_counts or self.caps.encoder_counts
        p = self.p(210, 6400) & ~4
        counts = (phys * cpr) // spr
        return (counts * p) // 512

    def encoder(self) -> int:
        return self._quantized(self.phys) + self.enc_offset

    def set_encoder(self, value: int) -> None:
        self.enc_offset = value - self._quantized(self.phys)

    # --- load and currents ----------------------------------------------------------------------
    def load_now(self) -> float:
        """Load torque now; pushing into a mechanical end adds END_LOAD."""
        load = self.load.at(self.phys, self.vm.now / CLOCK_HZ)
        d = self.slipping or self.heading()
        if d and self._blocked(d):
            load += END_LOAD
        return load

    def _pps(self, v) -> float:
        if self.caps.velocity_unit == "tmc429":
            div = self.p(154)  # AP154 pulse divisor (PD86-1180 manual 5)
            return float(v) * CLOCK_HZ / ((1 << div) * 2048 * 32)
        return float(v)

    def falloff(self) -> float:
        """Share of the torque left at the present speed: falls linearly to 0 at the scenario's
        `torque_falloff_speed` (pps), by default DEFAULT_FALLOFF_RPS of a 200-step motor."""
        fall = self.spec.torque_falloff_speed
        if not fall:
            fall = DEFAULT_FALLOFF_RPS * FULLSTEPS * (1 << self.p(140, 8))
        return max(0.0, 1.0 - abs(self._pps(self.engine.velocity)) / fall)

    def capacity(self) -> float:
        """Torque the motor can make now, as a fraction of the torque at 100 % current."""
        return self.current.fraction(self) * self.falloff()

    def load_value(self) -> int:
        """AP206 (docs/world.md, stallGuard2 model)."""
        return load_value(self.load_now(), self.capacity(), self.p(174))

    def _overloaded(self) -> bool:
        return self.load_now() > self.capacity()

    def _blocked(self, direction: int) -> bool:
        """At a mechanical end and pushing into it."""
        lo, hi = self.stage.ends
        return (direction > 0 and hi is not None and self.phys >= hi) or \
               (direction < 0 and lo is not None and self.phys <= lo)

    # --- the checks made at every event -----------------------------------------------------------
    def check(self) -> None:
        if self.axis is None:
            return
        self.follow()
        self.update_raw()
        self.current.update(self)
        search = self.vm.reference_search(self._axis)
        if search.active:
            search.poll()
        else:
            self._limit_stops()
        if not self.driver_off():
            self._stall()
            self._step_loss()
        self._deviation()
        self._null_channel()

    def _stop(self, soft: bool) -> None:
        e = self.engine
        if soft:
            if not (e.mode.value == "velocity" and e.target_velocity == 0):
                e.stop()
        else:
            e.hard_stop()

    def soft_stop_enabled(self) -> bool:
        if self.has(26):
            return bool(self.p(26))
        if self.has(149):
            return bool(self.p(149))
        return False

    def _limit_due(self) -> bool:
        """A limit switch in the direction of motion is active (AP12/AP13 not set) and the
        motor is not already braking for it."""
        d = self.heading()
        if not d:
            return False
        left, right, _ = self.logical()
        if d > 0:
            hit = right and not self.p(12)
        else:
            hit = left and not self.p(13)
            tol = self.p(141)
            if hit and self.three_switch_wiring and tol and abs(self.engine.position) <= tol \
                    and not self.input_level("left"):
                hit = False  # PD86-1180 AP141: the reference switch inside the tolerance range
        if not hit:
            return False
        e = self.engine
        return not (self.soft_stop_enabled() and e.mode.value == "velocity" and e.target_velocity == 0)

    def _limit_stops(self) -> None:
        """Stop only for the switch in the direction of motion."""
        if self._limit_due():
            self._stop(self.soft_stop_enabled())

    def _stall(self) -> None:
        limit = self.p(181)
        if not limit or not self.engine.moving:
            return
        v = abs(self.engine.velocity)
        if v < self._axis.engine_speed(181, limit):
            return
        if self.load_value() == 0:
            self.engine.hard_stop()
            self._axis.error_flags |= SG_EXTENDED
            self.vm.interpreter.set_error_flag(fl.EPO)
            self.vm.interrupts.trigger(STALL + self.index)
            self._end_search()

    def _end_search(self) -> None:
        """A stall or deviation stop ends a running reference search (docs/world.md)."""
        search = self.vm.reference_search(self._axis)
        if search.active:
            search.abort()

    def _step_loss(self) -> None:
        d = self.heading()           # moving, or about to move
        if self.slipping or not d:
            return
        if self._blocked(d) or self._overloaded():
            lo, hi = self.stage.ends
            if d > 0 and hi is not None and self.phys > hi:
                self.phys = hi
            if d < 0 and lo is not None and self.phys < lo:
                self.phys = lo
            self.slipping = d

    def _deviation(self) -> None:
        limit = self.p(212)
        if not limit:
            return
        if abs(self.engine.position - self.encoder()) > limit:
            if self.engine.moving or self.heading():  # also a motion commanded at this tick
                self.engine.hard_stop()
            if not self._axis.error_flags & DEV_EXTENDED:
                self._axis.error_flags |= DEV_EXTENDED
                self.vm.interpreter.set_error_flag(fl.EDV)
                self.vm.interrupts.trigger(DEVIATION + self.index)
            self._end_search()

    def _null_channel(self) -> None:
        """PD86-1180 7.2: p + 4 clears the encoder at the next null channel (once per round)."""
        if not self.caps.null_channel or not self.p(210) & 4:
            self.clear_on_null_armed = False
            return
        spr = self._steps_per_round()
        if not self.clear_on_null_armed:
            self.clear_on_null_armed = True
            self._null_from = self.phys
            return
        if self.phys % spr == 0 and self.phys != self._null_from:
            self.set_encoder(0)
            self._axis.ram[210] = self.p(210) & ~4
            self.clear_on_null_armed = False

    def due_now(self) -> bool:
        """Would a check at this tick change anything (a command just started a motion into an
        active switch or into an overload)?"""
        if self.axis is None or not self.heading():
            return False
        if not self.vm.reference_search(self._axis).active and self._limit_due():
            return True
        e = self.engine
        if not self.slipping and not self.driver_off() and (self._blocked(self.heading()) or self._overloaded()):
            return True
        dev = self.p(212)
        if dev and abs(e.position - self.encoder()) > dev:  # a deviation the motion starts with
            return True
        if not e.moving:
            return False
        limit = self.p(181)
        return bool(limit and not self.driver_off() and abs(e.velocity) >= self._axis.engine_speed(181, limit)
                    and self.load_value() == 0)

    # --- events -------------------------------------------------------------------------------------
    def interesting(self) -> bool:
        """Can anything happen on this axis that needs an event? (cheap; checked very often)"""
        if self._static or self.forced or self.watch is not None:
            return True
        ram = self._axis.ram
        return bool(ram.get(181) or ram.get(212) or (self._null_channel_possible and ram.get(210, 0) & 4))

    def _update_static(self) -> None:
        st, prof = self.stage, self.load.profile
        self._static = bool(st.left or st.right or st.home or not prof.is_constant or prof.before
                            or st.ends != (None, None) or self.spec.torque_falloff_speed)

    SIGNATURE_PARAMS = (6, 7, 12, 13, 14, 24, 25, 26, 140, 141, 149, 167, 172, 174, 181, 182, 200, 202, 210, 212)

    def _signature(self) -> tuple:
        """Everything the next world event depends on besides time (for the cache)."""
        eng = self.engine.plan_token
        ram = self._axis.ram
        search = self.vm.reference_search(self._axis)
        gp79 = self.vm.globals.ram.get((0, 79), 0)
        return (eng, self.offset, self.slipping, tuple(self.raw.values()), tuple(sorted(self.forced.items())),
                self.watch, self.load, tuple(ram.get(n, 0) for n in self.SIGNATURE_PARAMS), gp79,
                search.active, search.condition)

    def next_event(self) -> int | None:
        """Absolute tick of this axis's next world event (callers check `interesting()` first)."""
        now = self.vm.now
        e = self.engine
        if e.now < now:
            self.vm.sync()
        sig = self._signature()
        cached = self._cache
        if cached is not None and cached[0] == sig and (cached[1] is None or cached[1] > now) \
                and self.load.by != "time":
            self._engine_wake = e.next_event()
            return cached[1]
        t = self._next_event(now)
        self._cache = (sig, t)
        self._engine_wake = e.next_event()
        return t

    def needs_check(self, now: int) -> bool:
        """At this event tick: is it one of this axis's own events or an engine phase change?"""
        if self._cache is None or self.load.by == "time":
            return True
        return now == self._cache[1] or now == self._engine_wake

    def _next_event(self, now: int) -> int | None:
        """The earliest tick after `now` at which a check can change something: a position the
        counter reaches (switch edges, load steps, ends, null channel, deviation limit, the
        reference search's watch), a step of a load over time, or the stop-on-stall speed."""
        self.follow()
        if self._due_again(now):
            return now + 1
        off = self.driver_off()
        if not self.slipping and not off:
            counters = self._stage_counters()
        else:
            counters = self._deviation_counters()
        if self.watch is not None:
            counters.append(self.watch)
        best = self._first_arrival(counters, now)
        if self.load.by == "time":
            t = self._next_time(self.load.profile)
            if t is not None and (best is None or t < best):
                best = t
        t = None if off else self._stall_speed_time()
        if t is not None and t > now and (best is None or t < best):
            best = t
        return best

    def _due_again(self, now: int) -> bool:
        """A check is due at the next tick; not more than 4 ticks in a row, since a check that
        cannot resolve it must not stall time."""
        if not self.due_now():
            return False
        plan = self.engine.plan_token  # a command since the last due tick re-creates the condition
        again = self._due_at == now - 1 and plan == self._due_plan
        self._due_streak = self._due_streak + 1 if again else 0
        self._due_at, self._due_plan = now, plan
        return self._due_streak < 4

    def _stage_counters(self) -> list[int]:
        """Counter positions at which the stage, following the counter, meets something: a switch
        edge, a step of a load over position, a mechanical end, the encoder's null channel."""
        phys, offset = self.phys, self.offset
        out = self._switch_edges(phys)
        if self.load.by == "position":
            out += self._load_steps(phys)
        lo, hi = self.stage.ends
        out += [x for x in (lo, hi) if x is not None and x != phys]
        if self._null_channel_possible and self.p(210) & 4:
            spr = self._steps_per_round()
            base = phys - phys % spr
            out += [x for x in (base, base + spr) if x != phys]
        return [x - offset for x in out]

    def _switch_edges(self, phys: int) -> list[int]:
        """Physical positions of the next edges of the switches not forced."""
        out: list[int] = []
        for name, sw in self.stage.switches().items():
            if name not in self.forced:
                out += self.stage.edge_candidates(phys, sw, self.raw[name])
        return out

    def _load_steps(self, phys: int) -> list[int]:
        """Physical positions on both sides of each breakpoint of a load over position."""
        out = []
        for x in self.load.profile.breakpoints():
            for c in (int(-(-x // 1)), int(-(-x // 1)) - 1):
                if c != phys:
                    out.append(c)
        return out

    def _deviation_counters(self) -> list[int]:
        """The stage stands (steps lost, driver off): only the deviation limit AP212 can be crossed."""
        lim = self.p(212)
        if not lim:
            return []
        enc = self.encoder()
        return [enc + lim + 1, enc - lim - 1]

    def _first_arrival(self, counters: list[int], now: int) -> int | None:
        """First tick after `now` at which the counter reaches one of `counters`."""
        best = None
        e = self.engine
        here = e.position
        for c in counters:
            if c == here or not -2**31 <= c < 2**31:
                continue
            t = e.time_at_position(c)
            if t is not None and t > now and (best is None or t < best):
                best = t
        return best

    def _stall_speed_time(self) -> int | None:
        """Tick at which the speed reaches the stop-on-stall limit AP181 (None: off or never)."""
        limit = self.p(181)
        if not limit:
            return None
        return self.engine.time_at_speed(self._axis.engine_speed(181, limit))

    def _next_time(self, profile: Profile) -> int | None:
        """Next tick at which a load given over time changes (steps: breakpoints; ramps: every ms)."""
        now = self.vm.now
        nxt = next((t for x in profile.breakpoints() if (t := ceil_ticks(x, CLOCK_HZ)) > now), None)
        pts = profile.points
        if profile.kind == "ramp" and pts and pts[0][0] <= now / CLOCK_HZ < pts[-1][0]:
            step = now + CLOCK_HZ // 1000
            nxt = step if nxt is None else min(nxt, step)
        return nxt
