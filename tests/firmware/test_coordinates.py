"""SCO, GCO, CCO, ACO and MVP COORD (TMCM-6212 manual 3.6.22-3.6.25, 3.6.4)."""
from __future__ import annotations

from opentmcl import VirtualModule

from .conftest import Host


def test_sco_gco_and_mvp_coord(m6212):
    """3.6.22 example "SCO 1, 0, 1000", 3.6.23 "GCO 1, 0", 3.6.4 "MVP COORD, 0, 8"."""
    m6212.ok(30, 1, 0, 1000)
    assert m6212.ok(31, 1, 0) == 1000
    m6212.ok(30, 8, 0, -4000)
    m6212.ok(4, 2, 0, 8)
    m6212.vm.advance(2.0)
    assert m6212.ok(6, 1, 0) == -4000


def test_coordinate_range(m6212):
    """3.6.22: "Up to 20 position values (coordinates) can be stored for every axis" (numbers 0...20)."""
    m6212.ok(30, 20, 5, 1)
    assert m6212(30, 21, 0, 1).status == 3
    assert m6212(4, 2, 0, 21).status == 4


def test_cco_captures_actual_position(m6212):
    """3.6.24 "copies the actual position of the axis to the selected coordinate variable"."""
    m6212.ok(5, 1, 2, 777)
    m6212.ok(32, 3, 2)
    assert m6212.ok(31, 3, 2) == 777


def test_aco_copies_accumulator(m6212):
    """3.6.25 "the actual value of the accumulator is copied to a selected coordinate"."""
    m6212.vm.accumulator = -55
    m6212.ok(39, 1, 0)
    assert m6212.ok(31, 1, 0) == -55


def test_255_forms_copy_between_ram_and_eeprom(tmp_path):
    """3.6.22/3.6.23: "SCO 0, 255, 0 copies all coordinates (except coordinate number 0) from RAM to the
    EEPROM"; "GCO <n>, 255, 0 copies the coordinate selected ... from the EEPROM to the RAM";
    "Coordinate #0 is always stored in RAM only"."""
    path = tmp_path / "ee.json"
    host = Host(VirtualModule("TMCM-6212", eeprom=path))
    host.ok(30, 0, 0, 11)
    host.ok(30, 1, 0, 22)
    host.ok(30, 2, 3, 33)
    host.ok(30, 0, 255, 0)
    host.ok(30, 1, 0, 99)
    host.ok(31, 1, 255, 0)
    assert host.ok(31, 1, 0) == 22
    again = Host(VirtualModule("TMCM-6212", eeprom=path))
    assert again.ok(31, 1, 0) == 0 and again.ok(31, 2, 3) == 0   # GP84 = 0: RAM only at startup
    again.ok(31, 0, 255, 0)                                       # GCO 0, 255, 0: all back from EEPROM
    assert again.ok(31, 0, 0) == 0
    assert again.ok(31, 1, 0) == 22 and again.ok(31, 2, 3) == 33


def test_coordinates_come_back_at_startup_only_with_gp84(tmp_path):
    """TMCM-6212 3.6.22 SCO: "Depending on the global parameter 84, the coordinates are only stored in
    RAM or also stored in the EEPROM and copied back on startup (with the default setting the
    coordinates are stored in RAM only)"; 5.1 GP84 "0 - coordinates are stored in RAM only (but can be
    copied explicitly between RAM and EEPROM)". A coordinate copied to the EEPROM explicitly is not in
    RAM after a restart with GP84 = 0; with GP84 = 1 it is."""
    path = tmp_path / "ee.json"
    host = Host(VirtualModule("TMCM-6212", eeprom=path))
    host.ok(30, 4, 2, 444)
    host.ok(30, 4, 255, 0)                      # SCO 4, 255, 0: this coordinate to the EEPROM
    assert Host(VirtualModule("TMCM-6212", eeprom=path)).ok(31, 4, 2) == 0
    host.ok(9, 84, 0, 1)                        # bank 0 is stored automatically
    assert Host(VirtualModule("TMCM-6212", eeprom=path)).ok(31, 4, 2) == 444


def test_gp84_coordinates_always_in_eeprom(tmp_path):
    """TMCM-6212 5.1 GP84 "1 - coordinates are always also stored in the EEPROM"."""
    path = tmp_path / "ee.json"
    host = Host(VirtualModule("TMCM-6212", eeprom=path))
    host.ok(30, 5, 1, 55)
    host.ok(9, 84, 0, 1)
    host.ok(30, 6, 1, 66)
    again = Host(VirtualModule("TMCM-6212", eeprom=path))
    assert again.ok(31, 5, 1) == 0 and again.ok(31, 6, 1) == 66
