"""Reference search state machines (RFS START/STOP/STATUS, WAIT RFS).

TMCM-6212 manual 3.6.11 and 6.1 (modes 1-8, +64 right switch for 1-4, +128 inverted
home switch for 5-8), PD86-1180 manual 4.6.13 and 7.1 (modes 1-3, mode 3 = three-switch
mode, +128 inverted reference switch); the PD28-1021 uses the TMCM-6212 modes.

Each mode is a generator that drives the axis and yields a condition; the world
(firmware/world.py) re-checks the condition at every switch edge, arrival and stop,
and resumes the generator when it holds. Search speed AP194, calibration speed AP195.

Switching point calibration: after the switch is hit the motor leaves it at AP195
(first switching point), re-enters it (second switching point) and the reference point
is the centre of the two. The motor then drives to the reference point, AP197 takes the
position counter there and the counter and the encoder (AP209) are set to 0. Details
and choices: docs/world.md, docs/assumptions.md.

Copies (copy.deepcopy, pickle) of a module during a search: a generator cannot be copied, so
the search keeps what its program read from the world between its steps (`_readings`) and how
many steps it took; a copy runs its own program again that many steps on those readings, with
no effect on its axis (`_replay`), and goes on from there as the original does.
"""
from __future__ import annotations

from collections.abc import Callable, Generator
from fractions import Fraction
from functools import partial

Cond = Callable[[], bool]
Steps = Generator[Cond, None, int]
"""A phase of a search: yields the conditions it waits for, returns a direction or a position."""
Point = Generator[Cond, None, Fraction]
"""A switching point calibration: returns the reference point (a half microstep possible)."""

LEFT, RIGHT, HOME = "left", "right", "home"


class ReferenceSearch:
    def __init__(self, axis) -> None:
        self.axis = axis
        self._active = False
        self._drive: tuple | None = None     # (mode, target velocity) of the search's last command
        self._gen: Steps | None = None
        self._cond: Cond | None = None
        self.mode = 0
        self.log: list[tuple] = []
        """Phases of the last search: (what, switch, direction or position), for tests and traces."""
        self._readings: list[object] = []    # what the program read that decides its course
        self._steps = 0                      # next() calls on the program since start()
        self._replay: list[object] | None = None   # readings given back while a copy catches up

    @property
    def condition(self) -> Cond | None:
        """What the search waits for now (None when it waits for nothing)."""
        return self._cond

    @property
    def active(self) -> bool:
        """The search runs. A motion command from outside (MVP, ROR, ROL, MST, a SHUTDOWN stop)
        ends it: the motor no longer does what the search commanded (docs/world.md)."""
        if self._active and self._drive is not None:
            e = self.axis.engine
            if (e.mode, e.target_velocity) != self._drive:
                self.log.append(("interrupted", None, self.pos))
                self._finish()
        return self._active

    @active.setter
    def active(self, value: bool) -> None:
        self._active = value

    def _command(self, action, *args) -> None:
        """An engine command of the search itself; remembered to tell it from outside commands."""
        if not self._live:
            return
        e = self.axis.engine
        action(*args)
        self._drive = (e.mode, e.target_velocity)

    # --- RFS ----------------------------------------------------------------------------------
    def start(self) -> None:
        ax = self.axis
        world = ax.world
        world.vm.sync()
        self.aw = world.axis(ax.index)
        self.aw.rotor.follow()
        self.aw.switches.update()
        self.mode = ax.ram.get(193, 1)
        ax.error_flags = 0              # PD86-1180 4.28: RFS start resets the deviation flags
        self.active = True
        self._drive = None
        self.log = []
        ax.reference_search_active = True
        self._gen = self._program()
        self._cond = None
        self._readings, self._steps = [], 0
        self._resume()

    def stop(self) -> None:
        if self.active:
            self._finish()
            self.axis.engine.stop()

    def abort(self) -> None:
        """Stall or deviation stopped the motor: the search ends where it is."""
        if self.active:
            self._finish()

    def status(self) -> int:
        return int(self.active)

    def _finish(self) -> None:
        self.active = False
        self._drive = None
        self.axis.reference_search_active = False
        self._gen = None
        self._cond = None
        self._readings, self._steps = [], 0
        if getattr(self, "aw", None) is not None:
            self.aw.watch = None

    # --- driving the generator --------------------------------------------------------------
    def poll(self) -> None:
        """Called by the world at every event tick while the search is active."""
        if self._gen is None and self._active and self._steps:
            self._catch_up()
        if self.active and self._cond is not None and self._cond():
            self._resume()

    def _resume(self) -> None:
        while self.active and self._gen is not None:
            try:
                self._steps += 1
                cond = next(self._gen)
            except StopIteration:
                self._finish()
                return
            if not cond():
                self._cond = cond
                return

    # --- copies ---------------------------------------------------------------------------------
    def __getstate__(self) -> dict[str, object]:
        """The program and its condition stay behind (a copy runs its own: `_catch_up`)."""
        state = self.__dict__.copy()
        state.update(_gen=None, _cond=None)
        return state

    def _catch_up(self) -> None:
        """A copy's program, run again to where the original's stood: the same steps on the same
        readings, its effects left out (the copy has them already)."""
        self._replay = list(reversed(self._readings))
        self._gen = self._program()
        try:
            for _ in range(self._steps):
                self._cond = next(self._gen)
        finally:
            left, self._replay = self._replay, None
        assert not left, "a copied reference search read less than the original"

    def _read(self, value):
        """A reading of the world that decides the program's course: kept, or given back."""
        if self._replay is not None:
            return self._replay.pop()
        self._readings.append(value)
        return value

    @property
    def _live(self) -> bool:
        """False while a copy catches up: the program's effects on the axis are left out."""
        return self._replay is None

    def _note(self, entry: tuple) -> None:
        if self._live:
            self.log.append(entry)

    # --- inputs and motions ---------------------------------------------------------------------
    def state(self, name: str) -> bool:
        """Logical switch state for the search (AP12/AP13 do not apply, manual 6.1)."""
        left, right, home = self.aw.switches.logical()
        if self.mode & 128:
            if self.aw.caps.reference_input == "REFL":   # PD86-1180 manual 7.1
                left = not left
            else:
                home = not home
        return {LEFT: left, RIGHT: right, HOME: home}[name]

    @property
    def pos(self) -> int:
        return self.axis.engine.position

    def _speed(self, number: int) -> int | float:
        ax = self.axis
        return abs(ax.to_engine(number, ax.ram.get(number, 0)))

    def _rotate(self, direction: int, number: int) -> None:
        self._command(self.axis.engine.rotate, direction * self._speed(number))

    # The conditions the program yields: bound methods, so a copy of a waiting search (and the
    # world's cache that holds its condition) can be pickled.
    def _stopped(self) -> bool:
        return not self.axis.engine.moving

    def _is(self, name: str, level: bool) -> bool:
        return self.state(name) == level

    def _either(self, name: str, other: str) -> bool:
        return self.state(name) or self.state(other)

    def _passed(self, point: int, direction: int) -> bool:
        return (self.pos - point) * direction >= 0

    def _halt_after_hit(self) -> Steps:
        """The switch was found at search speed: stop (soft if enabled) and wait for standstill."""
        e = self.axis.engine
        self._command(e.stop if self.aw.checks.soft_stop_enabled() else e.hard_stop)
        yield self._stopped
        return 0

    def seek(self, name: str, direction: int, turn_at: str | None = None) -> Steps:
        """Drive at AP194 until switch `name` is active; reverse once at switch `turn_at`.
        Returns the direction the switch was found in."""
        self._note(("seek", name, direction))
        if self._read(self.state(name)):
            self._note(("found", name, self.pos))
            return direction
        self._rotate(direction, 194)
        if turn_at is None:
            yield partial(self._is, name, True)
        else:
            yield partial(self._either, name, turn_at)
            if not self._read(self.state(name)):   # end switch first: turn round
                self._note(("turn", turn_at, self.pos))
                yield from self._halt_after_hit()
                direction = -direction
                self._rotate(direction, 194)
                yield partial(self._is, name, True)
        self._note(("found", name, self.pos))
        yield from self._halt_after_hit()
        return direction

    def _slow_until(self, name: str, direction: int, level: bool) -> Steps:
        self._rotate(direction, 195)
        yield partial(self._is, name, level)
        self._note(("enter" if level else "leave", name, self.pos))
        self._command(self.axis.engine.hard_stop)
        yield self._stopped
        return self._read(self.pos)

    def edge(self, name: str, direction: int) -> Point:
        """Switching point calibration of the switch edge met while moving in `direction`:
        the centre of leaving it (against `direction`) and re-entering it (along it)."""
        if not self._read(self.state(name)):   # stopped beyond a narrow switch: come back into it
            yield from self._slow_until(name, -direction, True)
        first = yield from self._slow_until(name, -direction, False)
        second = yield from self._slow_until(name, direction, True)
        return Fraction(first + second, 2)

    def middle(self, name: str, direction: int) -> Point:
        """Both edges of switch `name` (the first met moving in `direction`); their centre."""
        near = yield from self.edge(name, direction)
        first = yield from self._slow_until(name, direction, False)
        second = yield from self._slow_until(name, -direction, True)
        far = Fraction(first + second, 2)
        return (near + far) / 2

    def goto(self, target: int | Fraction) -> Steps:
        """Drive at AP195 to the reference point (rounded to a whole microstep)."""
        point = round(target)
        here = self._read(self.pos)
        if here != point:
            d = 1 if point > here else -1
            if self._live:
                self.aw.watch = point
            self._rotate(d, 195)
            yield partial(self._passed, point, d)
            self._command(self.axis.engine.hard_stop)
            if self._live:
                self.aw.watch = None
            yield self._stopped
        return self._read(self.pos)

    def zero(self, reference: int | Fraction) -> Steps:
        yield from self.goto(reference)
        ax = self.axis
        self.log.append(("zero", None, self.pos))   # after the last yield: never run by `_catch_up`
        if 197 in ax.params:
            ax.ram[197] = self.pos
        self.aw.rotor.relabel(0)
        self.aw.encoder.set(0)
        # The origin is set on the target too: AP8 reads 1 ("always set when target position and
        # actual position are equal", TMCM-6212 4.1) and MVP REL counts from 0 (docs/world.md).
        self._command(ax.engine.move_to, 0)
        ax.last_target = 0              # TMCM-6212 AP127 = 0: MVP REL from the "last target position"
        return 0

    # --- the modes ------------------------------------------------------------------------------------
    def _program(self) -> Steps:
        mode = self.mode
        base = mode & 0x3F
        if mode & 128 and 1 <= base <= 4 and 64 + base in getattr(self.axis.params.get(193), "values", ()):
            base += 4       # TMCM-6212 6.1.5-6.1.8: 129..132 are modes 5..8 with an inverted home switch
        left, right, d = LEFT, RIGHT, -1
        if mode & 64:                              # +64: the right switch instead of the left one
            left, right, d = RIGHT, LEFT, 1
        ax = self.axis
        if base == 1:
            found = yield from self.seek(left, d)
            ref = yield from self.edge(left, found)
        elif base == 2:
            found = yield from self.seek(right, -d)
            far = yield from self.edge(right, found)
            found = yield from self.seek(left, d)
            ref = yield from self.edge(left, found)
            if self._live:
                ax.ram[196] = round(abs(far - ref))
        elif base == 3:
            # PD86-1180 AP193 row: "search right stop switch, then search left stop switch from both
            # sides"; in three-switch wiring (7.1) the first REFL met moving left is the reference
            # switch, so its middle is the origin. TMCM-6212 6.1.3: "the middle of the left end switch".
            found = yield from self.seek(right, -d)
            far = yield from self.edge(right, found)
            found = yield from self.seek(left, d)
            ref = yield from self.middle(left, found)
            if self._live:
                ax.ram[196] = round(abs(far - ref))
        elif base == 4:
            found = yield from self.seek(left, d)
            ref = yield from self.middle(left, found)
        elif base == 5:
            found = yield from self.seek(HOME, -1, turn_at=LEFT)
            ref = yield from self.edge(HOME, found)
        elif base == 6:
            found = yield from self.seek(HOME, 1, turn_at=RIGHT)
            ref = yield from self.edge(HOME, found)
        elif base in (7, 8):
            found = yield from self.seek(HOME, 1 if base == 7 else -1)
            ref = yield from self.middle(HOME, found)
        else:
            return 0
        yield from self.zero(ref)
        return 0
