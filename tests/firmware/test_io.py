"""SIO / GIO on every bank (TMCM-6212 manual 3.6.12-3.6.13, PD86-1180 manual 4.6.14-4.6.15)."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule

from .test_program_support import module


def test_6212_outputs_and_inputs(m6212):
    """3.6.12 example "SIO 3, 2, 1"; bank 2 states read back with GIO; banks 0/1 digital/analog inputs."""
    m6212.ok(14, 3, 2, 1)
    assert m6212.ok(15, 3, 2) == 1
    assert m6212.ok(15, 0, 2) == 0
    m6212.vm.io.drive_input(0, 2, 1)
    assert m6212.ok(15, 2, 0) == 1
    m6212.vm.io.drive_input(1, 3, 40000)
    assert m6212.ok(15, 3, 1) == 40000
    assert m6212(14, 0, 2, 2).status == 4       # outputs are 0/1
    assert m6212(14, 0, 0, 1).status == 3       # inputs cannot be set
    assert m6212(15, 0, 5).status == 4          # no bank 5


def test_1180_all_outputs_at_once(m1180):
    """PD86-1180 4.6.14 "Set the type parameter to 255 and the bank parameter to 2. The value ... where every
    bit represents one output line ... can also be set to -1 ... the lower 8 bits of the accumulator are
    copied to the output pins"; example "SIO 255, 2, 3"."""
    m1180.ok(14, 255, 2, 3)
    assert (m1180.ok(15, 0, 2), m1180.ok(15, 1, 2)) == (1, 1)
    m1180.vm.accumulator = 2
    m1180.ok(14, 255, 2, -1)
    assert (m1180.ok(15, 0, 2), m1180.ok(15, 1, 2)) == (0, 1)


def test_1180_all_inputs_at_once_and_pullups(m1180):
    """PD86-1180 4.6.14 "GIO 255, 0" reads the inputs as a bit field; "SIO 0, 0, <bitmask>" switches the
    pull-up resistors of HOME, STOP_L, STOP_R (0...7)."""
    m1180.vm.io.drive_input(0, 1, 1)
    assert m1180.ok(15, 255, 0) & 0b11 == 0b10
    m1180.ok(14, 0, 0, 5)
    assert m1180.vm.io.pullups == 5
    assert m1180(14, 0, 0, 8).status == 4


def test_6212_all_outputs_at_once_fit_the_four_outputs(m6212):
    """TMCM-6212 3.6.12 "Bank 2 - Digital Outputs": OUT0..OUT3, each 0/1. `SIO 255, 2, <mask>` (the
    PD86-1180 4.6.14 form, one bit per output line) takes 0..15: 15 sets all four, 16 has a bit for
    no output and is status 4 (outputs unchanged); -1 copies the accumulator's bits of the four."""
    m6212.ok(14, 255, 2, 15)
    assert [m6212.ok(15, n, 2) for n in range(4)] == [1, 1, 1, 1]
    assert m6212(14, 255, 2, 16).status == 4
    assert m6212(14, 255, 2, 255).status == 4
    assert [m6212.ok(15, n, 2) for n in range(4)] == [1, 1, 1, 1]
    m6212.vm.accumulator = 0x12
    m6212.ok(14, 255, 2, -1)
    assert [m6212.ok(15, n, 2) for n in range(4)] == [0, 1, 0, 0]


def test_1180_all_outputs_value_range_and_accumulator_low_byte(m1180):
    """PD86-1180 4.6.14: "The value parameter must then be set to a value between 0… 255" (256 is
    status 4) and with -1 "the contents of the lower 8 bits of the accumulator are copied to the
    output pins": an accumulator of 0x103 sets both outputs."""
    m1180.ok(14, 255, 2, 255)
    assert m1180(14, 255, 2, 256).status == 4
    m1180.ok(14, 255, 2, 0)
    m1180.vm.accumulator = 0x103
    m1180.ok(14, 255, 2, -1)
    assert (m1180.ok(15, 0, 2), m1180.ok(15, 1, 2)) == (1, 1)


def test_gio_255_reads_the_digital_bank_but_not_the_analog_one(m6212):
    """TMCM-6212 3.6.13: "Digital lines will read as 0 or 1, while the ADC channels deliver their 16
    bit result"; docs/assumptions.md: "`GIO 255, 0` returns IN0..IN3 as bits 0..3" and "`GIO 255, 1`
    (analog) is not defined: status 3"."""
    m6212.vm.io.drive_input(0, 2, 1)
    assert m6212.ok(15, 255, 0) == 0b0100
    assert m6212(15, 255, 1).status == 3


@pytest.mark.parametrize("bank", [0, 1])
def test_sio_255_on_a_bank_without_outputs_is_wrong_type(bank):
    """TMCM-6212 3.6.12 SIO "<bank number> (2)": the outputs are bank 2 only, so `SIO 255, <bank>`
    (all outputs at once) on the input banks 0 and 1 has no output to set - 3.2.1 Table 4 "3 Wrong
    type", as GIO 255 on the analog bank (docs/assumptions.md) - while `SIO 255, 2, 0` is taken."""
    w = module()
    assert w(14, 255, bank, 0).status == 3
    assert w(14, 255, 2, 0).status == 100


def test_1180_pullups_take_0_to_7():
    """PD86-1180 4.6.14 "COMMAND FOR SWITCHING THE PULL-UP RESISTORS": "SIO 0, 0,<bitmask> 0… 7":
    0 (all off) and 7 (all on) are taken, -1 and 8 are status 4 (3.2.1 "4 Invalid value")."""
    w = module("PD86-1180")
    w.ok(14, 0, 0, 7)
    w.ok(14, 0, 0, 0)
    assert w.vm.io.pullups == 0
    assert (w(14, 0, 0, -1).status, w(14, 0, 0, 8).status) == (4, 4)
    assert w.vm.io.pullups == 0


def test_sio_replies_the_value_the_manual_prints():
    """TMCM-6212 3.6.12 SIO "Reply in Direct Mode: Status 100 - OK, Value 0 (don't care)": the
    manual prints 0 as the reply value of SIO, so SIO 0, 2, 1 answers 0 (and GIO 0, 2
    reads the output back as 1)."""
    vm = VirtualModule("TMCM-6212", address=1)
    reply = vm.request(14, 0, 2, 1)
    assert (reply.status, reply.command, reply.value) == (100, 14, 0)
    assert vm.request(15, 0, 2).value == 1
