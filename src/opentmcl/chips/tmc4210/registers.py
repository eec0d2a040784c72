"""TMC4210 register map and 32-bit SPI datagram codec (datasheet 5.2, 5.3, 6).

A datagram sent to the chip is RRS (bit 31), a 6-bit ADDRESS (bits 30..25),
RW (bit 24, 1 = read) and 24 DATA bits. The datagram sent back at the same
time carries eight status bits (bits 31..24) and the read data (bits 23..0).

Addresses here are the 6-bit ADDRESS field: SMDA (2 bits) and IDX/JDX
(4 bits). The axis registers have SMDA = %00, the global parameter registers
SMDA = %11 (chapter 6.2).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TypedDict, Unpack

DATA_MASK = 0xFFFFFF
TYPE_VERSION_4210 = 0x429101
"""TYPE_VERSION register value (5.3: "= $429101 for TMC4210, read-only")."""

# --- status bits of the datagram sent back (5.2.2.2) --------------------------
STATUS_INT = 0x80
STATUS_CDGW = 0x40  # "cover datagram waiting" of the TMC429 sibling; always 0 here
STATUS_R_R = 0x20
STATUS_XEQT3 = 0x10  # axis 3 of the TMC429 sibling (5.2.3 example: "xEQt3=1")
STATUS_GP_IN = 0x08
STATUS_XEQT2 = 0x04  # axis 2 of the TMC429 sibling (5.2.3 example: "xEQt2=1")
STATUS_R_L = 0x02
STATUS_XEQT1 = 0x01

STATUS_BITS = (("INT", STATUS_INT), ("CDGW", STATUS_CDGW), ("R_R", STATUS_R_R), ("xEQt3", STATUS_XEQT3),
               ("GP_IN", STATUS_GP_IN), ("xEQt2", STATUS_XEQT2), ("R_L", STATUS_R_L),
               ("xEQt1", STATUS_XEQT1))

# --- interrupt flag bits (6.1.11, in the order of the datasheet's flag table) -----
INTERRUPTS = ("pos_end", "ref_wrong", "ref_miss", "stop", "stop_left_low", "stop_right_low",
              "stop_left_high", "stop_right_high")
INT_BIT = {name: 1 << i for i, name in enumerate(INTERRUPTS)}

# --- ramp modes (6.1.10.1) --------------------------------------------------------
RAMP_MODES = ("ramp_mode", "soft_mode", "velocity_mode", "hold_mode")


class RegisterError(ValueError):
    """Unknown register or field name, or a value that does not fit the field."""


class DatagramError(ValueError):
    """A datagram that is not a 32-bit unsigned integer."""


def to_signed(raw: int, bits: int) -> int:
    """Two's complement of `bits` bits to a Python int (datasheet 2.4)."""
    raw &= (1 << bits) - 1
    return raw - (1 << bits) if raw >> (bits - 1) else raw


@dataclass(frozen=True)
class Field:
    """One named bit field inside the 24 data bits of a register address."""

    name: str
    address: int
    shift: int
    width: int
    signed: bool = False
    access: str = "rw"  # "rw", "r" (read-only), "w1c" (write 1 to clear), "fixed1" (reads 1)
    reset: int = 0
    doc: str = ""

    @property
    def mask(self) -> int:
        return ((1 << self.width) - 1) << self.shift

    def extract(self, data: int) -> int:
        raw = (data >> self.shift) & ((1 << self.width) - 1)
        return to_signed(raw, self.width) if self.signed else raw

    def encode(self, value: int) -> int:
        """Place `value` into the field's bits; range-checked."""
        if isinstance(value, bool):
            value = int(value)
        if not isinstance(value, int):
            raise RegisterError(f"{self.name}: value must be an integer, got {value!r}")
        lo, hi = self.range
        if not lo <= value <= hi:
            raise RegisterError(f"{self.name}: {value} out of range {lo}..{hi}")
        return (value & ((1 << self.width) - 1)) << self.shift

    @property
    def range(self) -> tuple[int, int]:
        if self.signed:  # positions also take their raw 24-bit pattern (wrap, 6.1.1)
            hi = (1 << self.width) - 1 if self.width == 24 else (1 << (self.width - 1)) - 1
            return -(1 << (self.width - 1)), hi
        return 0, (1 << self.width) - 1


@dataclass(frozen=True)
class Register:
    """One register address (6-bit ADDRESS) and the fields mapped into it."""

    name: str
    address: int
    fields: tuple[Field, ...]
    doc: str
    read_only: bool = False  # a write has no effect on the data (it may trigger a function)

    @property
    def datagram_address(self) -> int:
        """The byte formed by RRS, ADDRESS and RW=0 (e.g. $7E for the global parameter register)."""
        return self.address << 1


class _FieldOptions(TypedDict, total=False):
    signed: bool
    access: str
    reset: int
    doc: str


class _FieldSpec(_FieldOptions):
    """The arguments of a Field but its address, which `_reg` adds."""

    name: str
    shift: int
    width: int


def _reg(name: str, address: int, doc: str, *fields: _FieldSpec, read_only: bool = False) -> Register:
    return Register(name, address, tuple(Field(address=address, **f) for f in fields), doc, read_only)


def _f(name: str, shift: int, width: int, **options: Unpack[_FieldOptions]) -> _FieldSpec:
    return _FieldSpec(name=name, shift=shift, width=width, **options)


REGISTERS: tuple[Register, ...] = (
    _reg("X_TARGET", 0x00, "6.1.1 target position, 24-bit two's complement",
         _f("X_TARGET", 0, 24, signed=True)),
    _reg("X_ACTUAL", 0x01, "6.1.2 actual position, 24-bit two's complement",
         _f("X_ACTUAL", 0, 24, signed=True)),
    _reg("V_MIN", 0x02, "6.1.3 minimum velocity, 11 bit unsigned", _f("V_MIN", 0, 11)),
    _reg("V_MAX", 0x03, "6.1.4 maximum velocity, 11 bit unsigned", _f("V_MAX", 0, 11)),
    _reg("V_TARGET", 0x04, "6.1.5 target velocity, 12 bit signed", _f("V_TARGET", 0, 12, signed=True)),
    _reg("V_ACTUAL", 0x05, "6.1.6 actual velocity, 12 bit signed (writable in hold_mode only)",
         _f("V_ACTUAL", 0, 12, signed=True)),
    _reg("A_MAX", 0x06, "6.1.7 maximum acceleration, 11 bit unsigned", _f("A_MAX", 0, 11)),
    _reg("A_ACTUAL", 0x07, "6.1.8 actual acceleration, 12 bit signed, read-only",
         _f("A_ACTUAL", 0, 12, signed=True, access="r"), read_only=True),
    _reg("PMUL_PDIV", 0x09, "6.1.9 proportionality factor p = PMUL / 2^(3+PDIV)",
         _f("PMUL", 8, 8, access="fixed1", doc="MSB (bit 15) fixed to 1"), _f("PDIV", 0, 4)),
    _reg("RAMP_MODE_REF_CONF", 0x0A, "6.1.10 lp, REF_CONF and RAMP_MODE",
         _f("lp", 16, 1, access="r"),
         _f("REF_CONF", 8, 4),
         _f("disable_stop_l", 8, 1), _f("disable_stop_r", 9, 1), _f("soft_stop", 10, 1),
         _f("ref_RnL", 11, 1),
         _f("RAMP_MODE", 0, 2)),
    _reg("INTERRUPT", 0x0B, "6.1.11 INTERRUPT_MASK (bits 15..8) and INTERRUPT_FLAGS (bits 7..0)",
         _f("INTERRUPT_MASK", 8, 8),
         *(_f(f"mask_{n}", 8 + i, 1) for i, n in enumerate(INTERRUPTS)),
         _f("INTERRUPT_FLAGS", 0, 8, access="w1c"),
         *(_f(f"int_{n}", i, 1, access="w1c") for i, n in enumerate(INTERRUPTS))),
    _reg("PULSE_DIV_RAMP_DIV", 0x0C, "6.1.12 clock dividers",
         _f("PULSE_DIV", 12, 4), _f("RAMP_DIV", 8, 4)),
    _reg("DX_REF_TOLERANCE", 0x0D, "6.1.13 reference tolerance around the origin, 12 bit",
         _f("DX_REF_TOLERANCE", 0, 12)),
    _reg("X_LATCHED", 0x0E, "6.1.14 position latched on a reference switch edge; a write arms the latch",
         _f("X_LATCHED", 0, 24, signed=True, access="r"), read_only=True),
    _reg("USTEP_COUNT_4210", 0x0F, "5.3 microstep pointer, 8 bit", _f("USTEP_COUNT_4210", 0, 8)),
    _reg("IF_CONFIGURATION_4210", 0x34, "6.2.1 interface configuration",
         _f("IF_CONFIGURATION_4210", 0, 9),
         _f("inv_ref", 0, 1), _f("sdo_int", 1, 1), _f("step_half", 2, 1), _f("inv_stp", 3, 1),
         _f("inv_dir", 4, 1), _f("en_sd", 5, 1), _f("pos_comp_sel", 6, 2), _f("en_refr", 8, 1)),
    _reg("POS_COMP_4210", 0x35, "6.2.1.1 position compare, 24-bit two's complement",
         _f("POS_COMP_4210", 0, 24, signed=True)),
    _reg("POS_COMP_INT_4210", 0x36, "6.2.1.2 position compare interrupt mask (M) and flag (I)",
         _f("POS_COMP_INT_M", 8, 1), _f("POS_COMP_INT_I", 0, 1, access="w1c")),
    _reg("POWER_DOWN", 0x38, "6.2.1.3 a write stops all clocks until the next chip select",
         read_only=True),
    _reg("TYPE_VERSION", 0x39, "6.2.1.4 type and version, read-only",
         _f("TYPE_VERSION", 0, 24, access="r", reset=TYPE_VERSION_4210), read_only=True),
    _reg("REFERENCE_SWITCHES", 0x3E, "6.2.1.5 reference switch and GP_IN read-out",
         _f("r_r", 0, 1, access="r"), _f("r_l", 1, 1, access="r"), _f("gp_in", 3, 1, access="r"),
         read_only=True),
    _reg("GLOBAL_PARAMETERS", 0x3F, "6.2.2 stepper motor global parameter register ($7E)",
         _f("STPDIV_4210", 8, 4, reset=15), _f("mot1r", 21, 1)),
)

BY_ADDRESS: dict[int, Register] = {r.address: r for r in REGISTERS}
BY_NAME: dict[str, Register] = {r.name: r for r in REGISTERS}
FIELDS: dict[str, Field] = {}
FIELD_REGISTER: dict[str, Register] = {}
for _r in REGISTERS:
    for _fld in _r.fields:
        FIELDS[_fld.name] = _fld
        FIELD_REGISTER[_fld.name] = _r
# single-field registers are reachable by the register name too (X_TARGET, V_MAX, ...)
del _r, _fld

ALIASES = {"STPDIV": "STPDIV_4210", "USTEP_COUNT": "USTEP_COUNT_4210", "POS_COMP": "POS_COMP_4210",
           "IF_CONFIGURATION": "IF_CONFIGURATION_4210", "R_M": "RAMP_MODE"}


def lookup(name: str) -> Field:
    """The field named `name` (datasheet spelling; case-insensitive)."""
    if not isinstance(name, str):
        raise RegisterError(f"register name must be a string, got {name!r}")
    key = ALIASES.get(name, name)
    if key in FIELDS:
        return FIELDS[key]
    folded = {k.lower(): v for k, v in FIELDS.items()}
    alias = {k.lower(): v for k, v in ALIASES.items()}
    key = alias.get(name.lower(), name.lower())
    if key.lower() in folded:
        return folded[key.lower()]
    raise RegisterError(f"unknown TMC4210 register or field {name!r}")


def whole_register(name: object) -> Register | None:
    """The register called `name` when that name is not also a field (PMUL_PDIV, INTERRUPT, ...):
    read and written as its 24 raw data bits."""
    if not isinstance(name, str):
        return None
    reg = BY_NAME.get(name) or BY_NAME.get(name.upper())
    if reg is None or reg.name in FIELDS:
        return None
    return reg


# --- datagrams ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Datagram:
    """A datagram sent to the TMC4210 (5.2.2.1)."""

    rrs: int
    address: int
    read: bool
    data: int

    def encode(self) -> int:
        return (self.rrs & 1) << 31 | (self.address & 0x3F) << 25 | int(self.read) << 24 | (self.data & DATA_MASK)

    @classmethod
    def decode(cls, word: int) -> Datagram:
        check_word(word)
        return cls(word >> 31 & 1, word >> 25 & 0x3F, bool(word >> 24 & 1), word & DATA_MASK)


def check_word(word: int) -> int:
    if isinstance(word, bool) or not isinstance(word, int):
        raise DatagramError(f"a datagram is a 32-bit unsigned integer, got {word!r}")
    if not 0 <= word <= 0xFFFFFFFF:
        raise DatagramError(f"datagram ${word:X} does not fit 32 bits" if word >= 0
                            else f"datagram {word} is negative")
    return word


def write_datagram(address: int, data: int, *, rrs: int = 0) -> int:
    return Datagram(rrs, address, False, data).encode()


def read_datagram(address: int, *, rrs: int = 0) -> int:
    return Datagram(rrs, address, True, 0).encode()


def describe_status(status: int) -> str:
    """The status byte as the datasheet names its bits (5.2.2.2)."""
    return " ".join(f"{n}={int(bool(status & b))}" for n, b in STATUS_BITS if n not in ("CDGW", "xEQt3", "xEQt2"))


def describe_request(word: int) -> str:
    """One-line decoding of a datagram sent to the chip."""
    d = Datagram.decode(word)
    op = "read " if d.read else "write"
    if d.rrs:
        if d.read:
            return f"{op} RAM[{d.address * 2}..{d.address * 2 + 1}]"
        return f"{op} RAM[{d.address * 2}]=%{d.data & 0x3F:06b} RAM[{d.address * 2 + 1}]=%{d.data >> 8 & 0x3F:06b}"
    reg = BY_ADDRESS.get(d.address)
    if reg is None:
        return f"{op} unused address %{d.address:06b}" + ("" if d.read else f" data=${d.data:06X}")
    if d.read:
        return f"{op} {reg.name}"
    return f"{op} {reg.name} " + describe_fields(reg, d.data, write=True)


def describe_fields(reg: Register, data: int, *, write: bool = False) -> str:
    """The fields of `data` by name; `write` leaves out read-only fields."""
    if not reg.fields:
        return f"(dummy ${data:06X})"
    fields = [f for f in reg.fields if not _is_sub_field(reg, f) and not (write and f.access == "r")]
    if not fields:
        return f"(dummy ${data:06X})"
    if len(fields) == 1 and fields[0].name == reg.name and not _bits_of(reg, fields[0]):
        f = fields[0]
        if reg.name == "TYPE_VERSION":
            return f"${data:06X}"
        return f"{f.extract(data)} (${data:06X})"
    parts = []
    for f in fields:
        bits = _bits_of(reg, f)
        if bits:
            on = "[" + ",".join(b.name for b in bits if b.extract(data)) + "]"
            parts.append(on if f.name == reg.name else f"{f.name}={on}")
        elif f.name == "RAMP_MODE":
            parts.append(f"RAMP_MODE={RAMP_MODES[f.extract(data)]}")
        else:
            parts.append(f"{f.name}={f.extract(data)}")
    return " ".join(parts) + f" (${data:06X})"


def _bits_of(reg: Register, field: Field) -> list[Field]:
    """The single-bit fields named inside a wider field (en_sd inside IF_CONFIGURATION_4210)."""
    return [b for b in reg.fields
            if b is not field and b.width == 1 and field.mask & b.mask == b.mask and field.width > 1]


def _is_sub_field(reg: Register, field: Field) -> bool:
    """A single-bit alias inside a wider field of the same register (e.g. en_sd in IF_CONFIGURATION)."""
    for other in reg.fields:
        if other is not field and other.width > field.width and other.mask & field.mask == field.mask:
            return True
    return False


def describe_reply(request: int, reply: int) -> str:
    """One-line decoding of the datagram sent back for `request`."""
    d = Datagram.decode(request)
    status = reply >> 24
    text = f"status=${status:02X} [{describe_status(status)}]"
    if d.read:
        data = reply & DATA_MASK
        if d.rrs:
            text += f" RAM[{d.address * 2}]=%{data & 0x3F:06b} RAM[{d.address * 2 + 1}]=%{data >> 8 & 0x3F:06b}"
        else:
            reg = BY_ADDRESS.get(d.address)
            text += " " + (describe_fields(reg, data) if reg else f"data=${data:06X}")
    return text
