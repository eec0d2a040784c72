"""SPI datagrams and the register file of the TMC4210 model (datasheet 5.2, 5.3, 6)."""
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from opentmcl.chips.tmc4210 import TMC4210, ChipError, Datagram, describe_reply, describe_request
from opentmcl.chips.tmc4210 import registers as R


@pytest.fixture
def chip():
    return TMC4210(f_clk=16_000_000)


# --- 5.2.3 worked examples ---------------------------------------------------------------
def test_example_write_datagram_layout():
    """5.2.3: write (RW=0) to a register (RRS=0) at address %001101 the data word
    %0000 0000 0000 0001 0010 0011: RRS, six address bits, RW, 24 data bits = $1A000123."""
    word = R.write_datagram(0b001101, 0b0000_0000_0000_0001_0010_0011)
    assert word == 0b0_001101_0_000000000000000100100011 == 0x1A000123
    assert Datagram.decode(word) == Datagram(rrs=0, address=0b001101, read=False, data=0x000123)


def test_example_write_and_read_back(chip):
    """5.2.3: the write answers with status bits and zero data; reading the register back
    (datagram %0 001101 1 0...0) answers with the data word %...0001 0010 0011. The example's
    status names inactive interrupt (INT=0), switches inactive, axes at target (xEQt3/2/1=1)."""
    back = chip.spi(0x1A000123)
    assert back & 0xFFFFFF == 0
    status = back >> 24
    assert status & R.STATUS_INT == 0
    assert status & (R.STATUS_R_L | R.STATUS_R_R | R.STATUS_GP_IN) == 0
    assert status & (R.STATUS_XEQT1 | R.STATUS_XEQT2 | R.STATUS_XEQT3) == 0b0001_0101
    read = R.read_datagram(0b001101)
    assert read == 0b0_001101_1_000000000000000000000000 == 0x1B000000
    assert chip.spi(read) == status << 24 | 0x000123


def test_example_ram_write_and_read(chip):
    """5.2.3: RRS=1, address %111111: %100001 goes to RAM %1111110 (bits 5..0) and %100011 to
    RAM %1111111 (bits 13..8); reading the address returns both words."""
    word = R.write_datagram(0b111111, 0b100011 << 8 | 0b100001, rrs=1)
    assert word == 0b1_111111_0_0000000000_100011_00_100001
    chip.spi(word)
    assert chip.ram[0b1111110] == 0b100001 and chip.ram[0b1111111] == 0b100011
    assert chip.spi(0b1_111111_1 << 24) & 0xFFFFFF == 0b100011_00_100001


# --- power-on values, widths, access ------------------------------------------------------
def test_power_on_values(chip):
    """5 / 5.3: all register bits are 0 after power-on reset except STPDIV_4210 = 15;
    TYPE_VERSION reads $429101 (6.2.1.4)."""
    for reg in R.REGISTERS:
        data = chip.spi(R.read_datagram(reg.address)) & 0xFFFFFF
        if reg.name == "GLOBAL_PARAMETERS":
            assert data == 15 << 8, reg.name
        elif reg.name == "TYPE_VERSION":
            assert data == 0x429101
        elif reg.name == "PMUL_PDIV":
            assert data == 0x8000  # PMUL's MSB is fixed to 1 (6.1.9.1)
        else:
            assert data == 0, reg.name
    assert chip.read("STPDIV_4210") == 15


@pytest.mark.parametrize("name,bits,signed", [
    ("X_TARGET", 24, True), ("X_ACTUAL", 24, True), ("V_MIN", 11, False), ("V_MAX", 11, False),
    ("V_TARGET", 12, True), ("A_MAX", 11, False), ("DX_REF_TOLERANCE", 12, False),
    ("USTEP_COUNT_4210", 8, False), ("POS_COMP_4210", 24, True),
])
def test_register_width_and_signedness(chip, name, bits, signed):
    """5.3 / 6.1 overview: register widths; X_TARGET, X_ACTUAL, V_TARGET, V_ACTUAL, A_ACTUAL are
    two's complement (2.4), V_MIN, V_MAX, A_MAX unsigned."""
    if name == "V_TARGET":
        chip.write("RAMP_MODE", 2)
    if name == "X_ACTUAL":
        chip.write("RAMP_MODE", 3)
    addr = R.lookup(name).address
    chip.spi(R.write_datagram(addr, 0xFFFFFF))
    raw = chip.spi(R.read_datagram(addr)) & 0xFFFFFF
    assert raw == (1 << bits) - 1
    assert chip.read(name) == (-1 if signed else (1 << bits) - 1)


def test_v_actual_is_writable_in_hold_mode_only(chip):
    """6.1.6: V_ACTUAL is read-only, "in hold_mode only, this register is a read-write register"."""
    chip.spi(R.write_datagram(0x05, 100))
    assert chip.read("V_ACTUAL") == 0
    chip.write("RAMP_MODE", 3)
    chip.write("V_ACTUAL", -5)
    assert chip.read("V_ACTUAL") == -5
    chip.write("V_ACTUAL", 0)  # "Writing zero to the register V_ACTUAL immediately stops"
    assert chip.read("V_ACTUAL") == 0


def test_read_only_registers_ignore_writes(chip):
    """5.3: some addresses are read-only (A_ACTUAL, TYPE_VERSION, reference switches)."""
    for addr in (0x07, 0x39, 0x3E):
        before = chip.spi(R.read_datagram(addr)) & 0xFFFFFF
        chip.spi(R.write_datagram(addr, 0x5A5A5A))
        assert chip.spi(R.read_datagram(addr)) & 0xFFFFFF == before
    with pytest.raises(ChipError, match="read-only"):
        chip.write("A_ACTUAL", 1)
    with pytest.raises(ChipError, match="read-only"):
        chip.write("TYPE_VERSION", 1)


def test_pmul_msb_is_fixed_to_one(chip):
    """6.1.9.1: "The MSB of PMUL is fixed set to 1 and cannot be changed"; PDIV 4 bits."""
    chip.spi(R.write_datagram(0x09, 0x05 << 8 | 0x3))
    assert chip.read("PMUL") == 0x85 and chip.read("PDIV") == 3


def test_ramp_mode_ref_conf_and_lp_layout(chip):
    """6.1.10: RAMP_MODE bits 1..0, REF_CONF disable_stop_l/disable_stop_r/soft_stop/ref_RnL,
    lp read-only (set by a dummy write to X_LATCHED, 6.1.14)."""
    chip.spi(R.write_datagram(0x0A, 1 << 16 | 0b1010 << 8 | 0b10))
    assert chip.read("lp") == 0
    assert chip.read("RAMP_MODE") == 2 and chip.read("REF_CONF") == 0b1010
    assert chip.read("disable_stop_r") == 1 and chip.read("ref_RnL") == 1
    chip.spi(R.write_datagram(0x0E, 0x123456))  # dummy write arms the latch
    assert chip.read("lp") == 1
    assert chip.read("X_LATCHED") == 0


def test_pulse_div_ramp_div_layout(chip):
    """6.1.12 / 5.3: PULSE_DIV bits 15..12, RAMP_DIV bits 11..8, the low bits read 0."""
    chip.spi(R.write_datagram(0x0C, 0x7 << 12 | 0xB << 8 | 0x3))
    assert chip.spi(R.read_datagram(0x0C)) & 0xFFFFFF == 0x7B00
    assert (chip.read("PULSE_DIV"), chip.read("RAMP_DIV")) == (7, 11)


def test_global_parameter_register_is_7e(chip):
    """6.2.2: absolute address of the stepper motor global parameter register is %01111110 = $7E;
    STPDIV_4210 in it (four bits), mot1r."""
    assert R.BY_NAME["GLOBAL_PARAMETERS"].datagram_address == 0x7E
    chip.spi(0x7E << 24 | 1 << 21 | 3 << 8)
    assert chip.read("mot1r") == 1 and chip.read("STPDIV_4210") == 3


def test_if_configuration_bits(chip):
    """6.2.1: inv_ref, step_half, inv_stp, inv_dir, en_sd of IF_CONFIGURATION_4210."""
    for name, bit in (("inv_ref", 0), ("step_half", 2), ("inv_stp", 3), ("inv_dir", 4), ("en_sd", 5)):
        chip.write(name, 1)
        assert chip.read("IF_CONFIGURATION_4210") & (1 << bit)
    assert chip.read("IF_CONFIGURATION_4210") == 0b111101


def test_unused_addresses_read_zero(chip):
    """5.3: addresses without a register (e.g. IDX %1000, SMDA %01) hold nothing."""
    for addr in (0x08, 0x10, 0x20, 0x30, 0x3D):
        chip.spi(R.write_datagram(addr, 0xFFFFFF))
        assert chip.spi(R.read_datagram(addr)) & 0xFFFFFF == 0


# --- interrupts --------------------------------------------------------------------------
def test_interrupt_flags_write_one_to_clear_and_masking(chip):
    """6.1.11: flags are reset by writing 1 at their position, 0 leaves them; flags are forced
    to 0 while their mask bit is 0; the status bit INT shows an active flag."""
    chip.write("INTERRUPT_MASK", 0xF0)  # the four switch edges
    chip.write("mot1r", 1)
    chip.set_inputs(ref_l=1, ref_r=1)
    assert chip.read("INTERRUPT_FLAGS") == R.INT_BIT["stop_left_high"] | R.INT_BIT["stop_right_high"]
    assert chip.spi(R.read_datagram(0x0B)) >> 31 == 1
    chip.spi(R.write_datagram(0x0B, 0xF0 << 8 | R.INT_BIT["stop_left_high"]))
    assert chip.read("INTERRUPT_FLAGS") == R.INT_BIT["stop_right_high"]
    chip.spi(R.write_datagram(0x0B, 0x00))  # mask off: flags forced to 0
    assert chip.read("INTERRUPT_FLAGS") == 0
    assert chip.spi(R.read_datagram(0x0B)) >> 31 == 0
    chip.set_inputs(ref_l=0)
    assert chip.read("INTERRUPT_FLAGS") == 0  # masked conditions do not set flags


def test_writing_the_mask_by_name_keeps_pending_flags(chip):
    """6.1.11 + access layer: writing INTERRUPT_MASK read-modify-writes with flag bits 0
    ("Writing a 0 to the corresponding position leaves the interrupt flag untouched")."""
    chip.write("mask_stop_left_high", 1)
    chip.set_inputs(ref_l=1)
    chip.write("mask_stop_left_low", 1)
    assert chip.read("int_stop_left_high") == 1
    chip.write("int_stop_left_high", 1)
    assert chip.read("int_stop_left_high") == 0


# --- switches read-out ---------------------------------------------------------------------
def test_reference_switch_readout_and_status_bits(chip):
    """6.2.1.5 / 5.2.2.2: r_r, r_l, gp_in in the REFERENCE SWITCHES register and as status bits;
    R_R is visible in the status only while mot1r has not been set; inv_ref inverts the switches."""
    chip.set_inputs(ref_l=1, ref_r=1, gp_in=1)
    assert (chip.read("r_l"), chip.read("r_r"), chip.read("gp_in")) == (1, 1, 1)
    status = chip.spi(R.read_datagram(0x3E)) >> 24
    assert status & R.STATUS_R_L and status & R.STATUS_R_R and status & R.STATUS_GP_IN
    chip.write("mot1r", 1)
    assert not chip.spi(R.read_datagram(0x3E)) >> 24 & R.STATUS_R_R
    chip.write("inv_ref", 1)
    assert (chip.read("r_l"), chip.read("r_r"), chip.read("gp_in")) == (0, 0, 1)


def test_sdo_int_disables_the_spi_output(chip):
    """5.2.2.2: "Do not set SDO_INT=1 because this setting disables the SPI output" - the pin
    then shows nINT for the whole datagram."""
    chip.spi(R.write_datagram(0x34, 0b10))
    assert chip.spi(R.read_datagram(0x39)) == 0xFFFFFFFF


# --- power down ----------------------------------------------------------------------------
def test_power_down_stops_the_clock_until_chip_select(chip):
    """6.2.1.3: a write to POWER_DOWN stops all internal clocks until the next falling edge of
    nSCS_C; register contents are preserved."""
    chip.write("RAMP_MODE", 3)
    chip.write("V_ACTUAL", 1000)
    chip.advance(0.001)
    x0 = chip.peek("X_ACTUAL")
    chip.write("POWER_DOWN", 0)
    chip.advance(0.01)
    assert chip.peek("X_ACTUAL") == x0 and chip.powered_down
    assert chip.read("X_ACTUAL") == x0  # the datagram wakes the chip
    chip.advance(0.001)
    assert chip.read("X_ACTUAL") > x0


# --- access layer and bad input ------------------------------------------------------------
def test_access_by_name(chip):
    """Issue contract: chip.write("V_MAX", 1000) / chip.read(...) by datasheet names."""
    chip.write("V_MAX", 1000)
    chip.write("PDIV", 5)
    chip.write("PMUL", 200)
    assert chip.read("V_MAX") == 1000 and chip.read("PMUL") == 200 and chip.read("PDIV") == 5
    chip.write("X_TARGET", -1)
    assert chip.spi(R.read_datagram(0x00)) & 0xFFFFFF == 0xFFFFFF


@pytest.mark.parametrize("call", [
    lambda c: c.spi(-1), lambda c: c.spi(1 << 32), lambda c: c.spi("1A000123"), lambda c: c.spi(1.0),
    lambda c: c.write("NO_SUCH", 1), lambda c: c.write("V_MAX", 2048), lambda c: c.write("V_MAX", -1),
    lambda c: c.write("V_TARGET", 2048), lambda c: c.read(None), lambda c: c.advance(-1),
    lambda c: c.advance(float("inf")), lambda c: c.set_inputs(ref_l=2), lambda c: c.advance_cycles(1.5),
    lambda c: c.pin_level("REF_X"), lambda c: c.attach_switch("gp_in", 0, 1),
])
def test_bad_input_raises_chip_error(chip, call):
    with pytest.raises(ChipError):
        call(chip)


def test_clock_frequency_range():
    """13.3: f_CLK 0 .. 32 MHz."""
    TMC4210(f_clk=32_000_000)
    for bad in (0, -1, 33_000_000, "16MHz"):
        with pytest.raises(ChipError):
            TMC4210(f_clk=bad)


def test_decoding_for_the_trace():
    assert describe_request(0x1A000123) == "write DX_REF_TOLERANCE 291 ($000123)"
    assert describe_request(0x1B000000) == "read  DX_REF_TOLERANCE"
    assert describe_request(0x7E000F00).startswith("write GLOBAL_PARAMETERS STPDIV_4210=15 mot1r=0")
    assert "xEQt1=1" in describe_reply(0x1B000000, 0x15000123)
    assert describe_reply(0x1B000000, 0x15000123).endswith("291 ($000123)")


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 0xFFFFFFFF), st.integers(0, 20_000),
                          st.sampled_from([None, "ref_l", "ref_r", "gp_in"])), max_size=40))
def test_any_datagram_sequence_is_accepted(steps):
    """5.2: every 32-bit datagram is a valid transfer - reserved bits, unused addresses, read-only
    registers, RAM, POWER_DOWN - and the chip keeps answering 32-bit datagrams."""
    chip = TMC4210()
    for word, cycles, pin in steps:
        back = chip.spi(word)
        assert 0 <= back <= 0xFFFFFFFF
        if pin:
            chip.set_inputs(**{pin: 1 - chip._pins[pin]})
        chip.advance_cycles(cycles)
    regs = chip.registers()
    assert regs["TYPE_VERSION"] == 0x429101 and -(1 << 23) <= regs["X_ACTUAL"] < 1 << 23


def test_the_issue_contract_calls(chip):
    """The contract of issue 6: spi() returns the 32-bit answer ($0D000123 is a read of A_MAX:
    RRS=0, ADDRESS=%000110, RW=1, data bits don't care), advance() and set_inputs() work."""
    chip.write("A_MAX", 77)
    assert chip.spi(0x0D000123) == 0x15 << 24 | 77
    chip.advance(0.01)
    chip.set_inputs(ref_l=1)
    assert chip.spi(0x0D000123) >> 24 & R.STATUS_R_L


@pytest.mark.parametrize("name,address,data", [
    ("PMUL_PDIV", 0x09, 0xC608), ("RAMP_MODE_REF_CONF", 0x0A, 0x0502),
    ("PULSE_DIV_RAMP_DIV", 0x0C, 0x5800), ("POS_COMP_INT_4210", 0x36, 0x0100),
    ("GLOBAL_PARAMETERS", 0x3F, 1 << 21 | 3 << 8),
])
def test_registers_holding_several_fields_by_register_name(chip, name, address, data):
    """5.3 register mapping: "Some addresses select a couple of registers mapped together into the
    24 data bit space" - by the register's own name read/write/peek move those 24 data bits,
    the same as a datagram to its address."""
    chip.write(name, data)
    assert chip.spi(R.read_datagram(address)) & 0xFFFFFF == data
    assert chip.read(name) == data == chip.peek(name) == chip.registers()[name]


def test_whole_register_names_keep_the_register_semantics(chip):
    """6.1.9.1 PMUL's MSB is fixed to 1; 6.1.11 writing 1 clears a flag; 6.2.1.5 the reference
    switch read-out is read-only; 6.2.1.3 POWER_DOWN is a write trigger."""
    chip.write("PMUL_PDIV", 0x4608)
    assert chip.read("PMUL_PDIV") == 0xC608
    chip.write("mask_stop_left_high", 1)
    chip.set_inputs(ref_l=1)
    assert chip.read("INTERRUPT") == R.INT_BIT["stop_left_high"] * 0x101
    chip.write("INTERRUPT", 0xFF00 | R.INT_BIT["stop_left_high"])
    assert chip.read("INTERRUPT") == 0xFF00
    with pytest.raises(ChipError, match="read-only"):
        chip.write("REFERENCE_SWITCHES", 0)
    assert chip.read("REFERENCE_SWITCHES") == 0b10  # r_l
    for bad in (-1, 1 << 24, "1", 1.0):
        with pytest.raises(ChipError):
            chip.write("PMUL_PDIV", bad)
    chip.write("POWER_DOWN", 0)
    assert chip.powered_down
