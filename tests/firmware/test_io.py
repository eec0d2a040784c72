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
