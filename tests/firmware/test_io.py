"""SIO / GIO on every bank (TMCM-6212 manual 3.6.12-3.6.13, PD86-1180 manual 4.6.14-4.6.15)."""
from __future__ import annotations


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
