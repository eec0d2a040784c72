"""Register-exact model of the TMC4210 motion controller (datasheet chapters 5 - 9).

    chip = TMC4210(f_clk=16_000_000)
    back = chip.spi(0x1A000123)       # one datagram in -> the datagram sent back (5.2)
    chip.write("V_MAX", 1000)         # the same through register names
    chip.advance(0.01)                # virtual time in seconds
    chip.set_inputs(ref_l=1)          # REF_L / REF_R / GP_IN pin levels

The ramp generator itself is the shared integer TMC429/TMC4210 core
(`opentmcl.motion.tmc429.Tmc429Ramp`); this module adds what the chip puts
around it: the SPI register file, reference switches, interrupts, position
latch and compare (events.py), power down, and the Step/Dir output stage.

Time is event driven: between two SPI accesses the model jumps from one event
to the next (a ramp phase change, the position reaching the target, the
compare value, the origin, a tolerance or switch-window boundary), never by
small fixed steps.
"""
from __future__ import annotations

import math
from collections.abc import Callable

from ...motion.tmc429 import Tmc429Ramp
from . import registers as R
from .events import HOLD_MODE, POS_BITS, ChipEvents, s24
from .stepdir import Edge, StepDirOutput
from .units import check_f_clk, step_pulse_cycles


def _v12(data: int) -> int:
    """12-bit two's complement velocity; -2048 is taken as -2047 (6.1.12.1: "Range +-2047")."""
    return max(-2047, R.to_signed(data, 12))


class ChipError(ValueError):
    """Bad use of the model (wrong argument types or values)."""


class TMC4210(ChipEvents):
    """One TMC4210 chip with its SPI interface, ramp generator and Step/Dir output."""

    def __init__(self, f_clk: int | float = 16_000_000, *, capture_edges: bool = False) -> None:
        try:
            self.f_clk = check_f_clk(f_clk)
        except ValueError as exc:
            raise ChipError(str(exc)) from None
        self._ramp = Tmc429Ramp(position_bits=POS_BITS)
        self._ext = 0  # external time in CLK cycles (runs on in power down)
        self._seconds = 0.0  # external time requested through advance(), seconds
        self._offset = 0  # _ext - ramp.now: cycles during which the chip clock stood still
        self.stepdir = StepDirOutput(self.f_clk)
        self.stepdir.capture = capture_edges
        self._trace: list[Callable[[float, int, int], None]] = []
        self.reset()

    # ------------------------------------------------------------------------------------
    # power-on state (5: "All register bits are initialized with 0 ... except STPDIV_4210 = 15")
    def reset(self) -> None:
        """Power-on reset: registers as after power-up; time, pins and switches are kept."""
        if hasattr(self, "_pins"):
            self._axis_offset += self.x_actual  # X_ACTUAL restarts at 0; the motor stays
        self._ramp = Tmc429Ramp(position_bits=POS_BITS)
        self._offset = self._ext - self._ramp.now
        self.ref_conf = 0
        self.lp = 0
        self.int_mask = 0
        self.int_flags = 0
        self.dx_ref_tolerance = 0
        self.x_latched = 0
        self._ustep_base = 0
        self._ustep_x = 0
        self.if_conf = 0
        self.pos_comp = 0
        self.pos_comp_m = 0
        self.pos_comp_i = 0
        self.stpdiv = 15
        self.mot1r = 0
        self.ram = [0] * 128
        self.powered_down = False
        if not hasattr(self, "_pins"):
            self._pins = {"ref_l": 0, "ref_r": 0, "gp_in": 0}
            self._windows: dict[str, list[tuple[int, int]]] = {"ref_l": [], "ref_r": []}
            self._axis_offset = 0  # axis position of the motor = X_ACTUAL + _axis_offset
        self._stopping = False
        self._apply_stepdir()
        self._seen = self._observe()

    # ------------------------------------------------------------------------------------
    # SPI (5.2)
    def spi(self, datagram: int) -> int:
        """Send one 32-bit datagram; return the 32-bit datagram sent back at the same time.

        Bits 31..24 of the answer are the status bits (INT, R_R, GP_IN, R_L, xEQt1;
        5.2.2.2), bits 23..0 the read data (zero for a write access).
        """
        try:
            d = R.Datagram.decode(datagram)
        except R.DatagramError as exc:
            raise ChipError(str(exc)) from None
        if self.powered_down:  # 6.2.1.3: clocks run again from the chip select on
            self.powered_down = False
            self._evaluate()
        status = self.status_byte()
        data = 0
        if d.read:
            data = self._read_ram(d.address) if d.rrs else self._read(d.address)
        sdo_disabled = self.if_conf >> 1 & 1
        if d.rrs:
            if not d.read:
                self.ram[2 * d.address] = d.data & 0x3F
                self.ram[2 * d.address + 1] = d.data >> 8 & 0x3F
        elif not d.read:
            self._write(d.address, d.data)
            if d.address in (0x00, 0x01, 0x35):
                # a write is no arrival: pos_end, ref_miss and POS_COMP need a step (notes)
                fresh = self._observe()
                self._seen.update({k: fresh[k] for k in ("x", "xt", "xeq", "comp", "zero")})
            self._evaluate()
        if sdo_disabled:
            # SDO_INT=1: nINT drives the pin for the whole datagram (5.2.2.2 "disables the SPI output")
            reply = 0 if status & R.STATUS_INT else 0xFFFFFFFF
        else:
            reply = status << 24 | data
        for hook in self._trace:
            hook(self._ext / self.f_clk, datagram, reply)
        return reply

    def status_byte(self) -> int:
        """Status bits of the next datagram sent back (5.2.2.2)."""
        s = R.STATUS_XEQT2 | R.STATUS_XEQT3  # the sibling's axes 2 and 3 idle at target (5.2.3)
        if self.interrupt:
            s |= R.STATUS_INT
        if not self.mot1r and self._active("ref_r"):
            s |= R.STATUS_R_R  # 5.2.2.2: "r_r is visible here only, while mot1r has not yet been set"
        if self._pins["gp_in"]:
            s |= R.STATUS_GP_IN
        if self._active("ref_l"):
            s |= R.STATUS_R_L
        if self.x_actual == self.x_target:
            s |= R.STATUS_XEQT1
        return s

    def add_trace(self, hook: Callable[[float, int, int], None]) -> None:
        """Call hook(time_s, datagram_in, datagram_out) after every spi()."""
        self._trace.append(hook)

    # ------------------------------------------------------------------------------------
    # access by name
    def write(self, name: str, value: int) -> int:
        """Write one register or field by its datasheet name; returns the datagram sent back.

        Fields that share an address (PMUL/PDIV, REF_CONF/RAMP_MODE, ...) are written
        read-modify-write; interrupt flags are never cleared by accident. The name of a register
        holding several fields (PMUL_PDIV, INTERRUPT, ...) writes its 24 data bits as they are.
        """
        whole = R.whole_register(name)
        if whole is not None:  # PMUL_PDIV, INTERRUPT, ..., POWER_DOWN: the raw 24 data bits
            if whole.read_only and whole.name != "POWER_DOWN":
                raise ChipError(f"{whole.name} is read-only")
            if isinstance(value, bool) or not isinstance(value, int):
                raise ChipError(f"{whole.name}: value must be an integer, got {value!r}")
            if not 0 <= value <= R.DATA_MASK:
                raise ChipError(f"{whole.name}: {value} out of range 0..{R.DATA_MASK} (24 data bits)")
            return self.spi(R.write_datagram(whole.address, value))
        try:
            f = R.lookup(name)
        except R.RegisterError as exc:
            raise ChipError(str(exc)) from None
        reg = R.FIELD_REGISTER[f.name]
        if f.access == "r" and reg.name != "X_LATCHED":
            raise ChipError(f"{f.name} is read-only")
        try:
            bits = f.encode(value)
        except R.RegisterError as exc:
            raise ChipError(str(exc)) from None
        data = 0
        for other in reg.fields:
            if other.access in ("rw", "fixed1"):
                data |= self._read(reg.address) & other.mask
        data = data & ~f.mask | bits
        return self.spi(R.write_datagram(reg.address, data))

    def read(self, name: str) -> int:
        """Read one register or field by its datasheet name (signed where the datasheet says so);
        a register holding several fields (PMUL_PDIV, INTERRUPT, ...) reads as its 24 data bits."""
        whole = R.whole_register(name)
        if whole is not None:
            return self.spi(R.read_datagram(whole.address)) & R.DATA_MASK
        f = self._field(name)
        reply = self.spi(R.read_datagram(f.address))
        return f.extract(reply & R.DATA_MASK)

    @staticmethod
    def _field(name: str) -> R.Field:
        try:
            return R.lookup(name)
        except R.RegisterError as exc:
            raise ChipError(str(exc)) from None

    def peek(self, name: str) -> int:
        """Like read() but without a datagram (no trace, no power-down wake up)."""
        whole = R.whole_register(name)
        if whole is not None:
            return self._read(whole.address)
        f = self._field(name)
        return f.extract(self._read(f.address))

    def registers(self) -> dict[str, int]:
        """All registers by name, as read() would return them (no datagrams)."""
        return {r.name: r.fields[0].extract(self._read(r.address)) if len(r.fields) == 1 else self._read(r.address)
                for r in R.REGISTERS if r.fields}

    # ------------------------------------------------------------------------------------
    # pins
    def set_inputs(self, *, ref_l: int | None = None, ref_r: int | None = None, gp_in: int | None = None) -> None:
        """Drive the REF_L, REF_R and GP_IN pins (electrical levels 0/1) at the present time."""
        for name, level in (("ref_l", ref_l), ("ref_r", ref_r), ("gp_in", gp_in)):
            if level is None:
                continue
            if level not in (0, 1) or isinstance(level, float):
                raise ChipError(f"{name} level must be 0 or 1, got {level!r}")
            self._pins[name] = int(level)
        if not self.powered_down:
            self._evaluate()

    def attach_switch(self, pin: str, first: int, last: int) -> None:
        """Mount a switch on the axis: `pin` ("ref_l"/"ref_r") is high while the motor is between
        `first` and `last`, given as X_ACTUAL values at the time of the call.

        The switch stays where it is on the axis when X_ACTUAL is overwritten later (homing,
        7.3). Several windows on one pin are OR-ed (switches in series, 7.2); the static level
        from set_inputs() is OR-ed as well.
        """
        if pin not in self._windows:
            raise ChipError(f"pin must be 'ref_l' or 'ref_r', got {pin!r}")
        for v in (first, last):
            if isinstance(v, bool) or not isinstance(v, int) or not -(1 << 23) <= v < 1 << 23:
                raise ChipError(f"switch window bounds must be 24-bit positions, got {v!r}")
        if first > last:
            raise ChipError("switch window: first must be <= last")
        self._windows[pin].append((first + self._axis_offset, last + self._axis_offset))
        self._evaluate()

    def detach_switches(self) -> None:
        self._windows = {"ref_l": [], "ref_r": []}
        self._evaluate()

    def pin_level(self, pin: str) -> int:
        """Electrical level of an input pin (static level OR switch windows)."""
        if pin not in self._pins:
            raise ChipError(f"pin must be 'ref_l', 'ref_r' or 'gp_in', got {pin!r}")
        level = self._pins[pin]
        x = self.x_actual + self._axis_offset
        for lo, hi in self._windows.get(pin, ()):
            if lo <= x <= hi:
                level = 1
        return level

    def _active(self, pin: str) -> bool:
        """Reference switch `pin` is active, after inv_ref (6.2.1)."""
        return bool(self.pin_level(pin) ^ (self.if_conf & 1))

    @property
    def interrupt(self) -> bool:
        """Internal interrupt status INT (6.1.11); the nINT pin is its inverse."""
        return bool(self.int_flags & self.int_mask) or bool(self.pos_comp_i and self.pos_comp_m)

    @property
    def n_int(self) -> int:
        return 0 if self.interrupt else 1

    # ------------------------------------------------------------------------------------
    # time
    @property
    def time(self) -> float:
        """Virtual time in seconds since power-on."""
        return self._ext / self.f_clk

    @property
    def cycle(self) -> int:
        """Virtual time in CLK cycles since power-on (runs on during power down)."""
        return self._ext

    def advance(self, seconds: float) -> None:
        """Let `seconds` of virtual time pass."""
        if isinstance(seconds, bool) or not isinstance(seconds, (int, float)) or not math.isfinite(seconds) \
                or seconds < 0:
            raise ChipError(f"seconds must be a finite number >= 0, got {seconds!r}")
        self._seconds += seconds
        target = max(self._ext, round(self._seconds * self.f_clk))
        self._run(target)

    def advance_cycles(self, cycles: int) -> None:
        """Let exactly `cycles` CLK cycles pass."""
        if isinstance(cycles, bool) or not isinstance(cycles, int) or cycles < 0:
            raise ChipError(f"cycles must be an integer >= 0, got {cycles!r}")
        self._run(self._ext + cycles)
        self._seconds = self._ext / self.f_clk

    def drain_edges(self) -> list[Edge]:
        """Step/Dir edges up to the present time (needs capture_edges=True)."""
        return self.stepdir.drain(self._ext)

    @property
    def capture_edges(self) -> bool:
        return self.stepdir.capture

    @capture_edges.setter
    def capture_edges(self, on: bool) -> None:
        self.stepdir.capture = bool(on)

    # ------------------------------------------------------------------------------------
    # motion state shortcuts
    @property
    def x_actual(self) -> int:
        return s24(self._ramp.x_actual)

    @property
    def x_target(self) -> int:
        return s24(self._ramp.x_target)

    @property
    def v_actual(self) -> int:
        return self._ramp.v_actual

    @property
    def mode(self) -> int:
        return self._ramp.mode

    @property
    def ramp(self) -> Tmc429Ramp:
        """The shared ramp core (read it; write through the registers)."""
        return self._ramp

    # ------------------------------------------------------------------------------------
    # register file
    def _read(self, a: int) -> int:
        """The 24 data bits a read of address `a` answers (5.3); unused addresses read as zero."""
        if a < 0x10:  # SMDA = %00
            return self._read_axis_register(a)
        return self._read_global_register(a)

    def _read_axis_register(self, a: int) -> int:
        """Axis parameter registers, IDX %0000 - %1111 (6.1)."""
        r = self._ramp
        if a == 0x00:
            return r.x_target & R.DATA_MASK
        if a == 0x01:
            return r.x_actual & R.DATA_MASK
        if a == 0x02:
            return r.v_min
        if a == 0x03:
            return r.v_max
        if a == 0x04:
            return r.v_target & 0xFFF
        if a == 0x05:
            return r.v_actual & 0xFFF
        if a == 0x06:
            return r.a_max
        if a == 0x07:
            return r.a_actual & 0xFFF
        if a == 0x09:
            return (r.pmul | 0x80) << 8 | r.pdiv
        if a == 0x0A:
            return self.lp << 16 | self.ref_conf << 8 | r.mode
        if a == 0x0B:
            return self.int_mask << 8 | self.int_flags
        if a == 0x0C:
            return r.pulse_div << 12 | r.ramp_div << 8
        if a == 0x0D:
            return self.dx_ref_tolerance
        if a == 0x0E:
            return self.x_latched & R.DATA_MASK
        if a == 0x0F:
            return self.ustep_count
        return 0  # IDX %1000 is unused

    def _read_global_register(self, a: int) -> int:
        """Global parameter registers, SMDA = %11 (6.2); the other SMDA values (the TMC429's
        axes 2 and 3) and POWER_DOWN read as zero."""
        if a == 0x34:
            return self.if_conf
        if a == 0x35:
            return self.pos_comp & R.DATA_MASK
        if a == 0x36:
            return self.pos_comp_m << 8 | self.pos_comp_i
        if a == 0x39:
            return R.TYPE_VERSION_4210
        if a == 0x3E:
            return (int(self._active("ref_r")) | int(self._active("ref_l")) << 1
                    | self._pins["gp_in"] << 3)
        if a == 0x3F:
            return self.stpdiv << 8 | self.mot1r << 21
        return 0

    def _read_ram(self, a: int) -> int:
        return self.ram[2 * a] | self.ram[2 * a + 1] << 8

    @property
    def ustep_count(self) -> int:
        """USTEP_COUNT_4210: the microstep pointer follows every step (mod 256)."""
        return (self._ustep_base + self._ramp.x_actual - self._ustep_x) & 0xFF

    def _write(self, a: int, data: int) -> None:
        """A write of the 24 data bits `data` to address `a` (5.3); a write to a read-only or
        unused address has no effect."""
        if a < 0x10:  # SMDA = %00
            self._write_axis_register(a, data)
        else:
            self._write_global_register(a, data)

    def _write_axis_register(self, a: int, data: int) -> None:
        """Axis parameter registers, IDX %0000 - %1111 (6.1)."""
        r = self._ramp
        if a == 0x00:
            r.set(x_target=s24(data))
        elif a == 0x01:
            self._ustep_base = self.ustep_count
            self._axis_offset += self.x_actual - s24(data)  # the motor does not move
            r.set(x_actual=s24(data))
            self._ustep_x = r.x_actual
        elif a == 0x02:
            r.set(v_min=data & 0x7FF)
        elif a == 0x03:
            r.set(v_max=data & 0x7FF)
        elif a == 0x04:
            r.set(v_target=_v12(data))
        elif a == 0x05:
            if r.mode == HOLD_MODE:  # 6.1.6: read-write in hold_mode only
                r.set(v_actual=_v12(data))
        elif a == 0x06:
            r.set(a_max=data & 0x7FF)
        elif a == 0x09:
            r.set(pmul=data >> 8 & 0xFF | 0x80, pdiv=data & 0xF)  # 6.1.9.1: PMUL's MSB is fixed 1
        elif a == 0x0A:
            self.ref_conf = data >> 8 & 0xF
            mode = data & 3
            if mode != r.mode:
                r.set(mode=mode)
        elif a == 0x0B:
            self.int_mask = data >> 8 & 0xFF
            self.int_flags &= ~data & 0xFF & self.int_mask  # 6.1.11: write 1 to clear, masked -> 0
        elif a == 0x0C:
            r.set(pulse_div=data >> 12 & 0xF, ramp_div=data >> 8 & 0xF)
        elif a == 0x0D:
            self.dx_ref_tolerance = data & 0xFFF
        elif a == 0x0E:
            self.lp = 1  # 6.1.14: a dummy write arms the position latch
        elif a == 0x0F:
            self._ustep_base = data & 0xFF
            self._ustep_x = r.x_actual
        # A_ACTUAL (IDX %0111) is read-only, IDX %1000 unused

    def _write_global_register(self, a: int, data: int) -> None:
        """Global parameter registers, SMDA = %11 (6.2); TYPE_VERSION_4210 and REFERENCE
        SWITCHES are read-only, the other SMDA values (the TMC429's axes 2 and 3) unused."""
        if a == 0x34:
            self.if_conf = data & 0x1FF
            self._apply_stepdir()
        elif a == 0x35:
            self.pos_comp = s24(data)
        elif a == 0x36:
            self.pos_comp_m = data >> 8 & 1
            if data & 1 or not self.pos_comp_m:
                self.pos_comp_i = 0
        elif a == 0x38:
            self.powered_down = True  # 6.2.1.3
        elif a == 0x3F:
            self.stpdiv = data >> 8 & 0xF
            self.mot1r = data >> 21 & 1
            self._apply_stepdir()

    def _apply_stepdir(self) -> None:
        c = self.if_conf
        self.stepdir.configure(self._ext, en_sd=c >> 5 & 1, step_half=c >> 2 & 1, inv_stp=c >> 3 & 1,
                               inv_dir=c >> 4 & 1, t_step=step_pulse_cycles(self.stpdiv))
