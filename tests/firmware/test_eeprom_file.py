"""The EEPROM image file (firmware/eeprom.py, `VirtualModule(eeprom=...)`): what is checked when it is
opened - the module it belongs to, the format, the shape and 32-bit range of every section, the file
keeping its bytes when refused (docs/assumptions.md "EEPROM images are checked when opened",
docs/architecture.md "Errors") - and the temp files of killed writers it removes."""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import textwrap

import pytest

from opentmcl import VirtualModule
from opentmcl.firmware.eeprom import Eeprom, EepromError

from .conftest import Host

_HEAD = '{"format":"opentmcl-eeprom","version":1,"module":"TMCM-6212"'


def test_an_eeprom_file_of_one_module_is_refused_by_another(tmp_path):
    """docs/assumptions.md "EEPROM images are checked when opened": the file a TMCM-6212 wrote (SGP 77,
    bank 0 64..127 "automatically stored in the EEPROM", TMCM-6212 5.1) names its module, so a
    PD86-1180 does not power up from it."""
    ee = tmp_path / "ee.json"
    Host(VirtualModule("TMCM-6212", address=1, eeprom=ee)).ok(9, 77, 0, 1)
    with pytest.raises(EepromError, match="belongs to a TMCM-6212"):
        VirtualModule("PD86-1180", eeprom=ee)


@pytest.mark.parametrize("content", [
    _HEAD + ',"coord":{"1":{"2":"x"}}}',
    _HEAD + ',"coord":[1]}',
    '{"format":"other","version":1,"module":"TMCM-6212"}',
    '{"version":1,"module":"TMCM-6212"}',
    '[1, 2]',
])
def test_a_damaged_coordinate_section_or_a_foreign_file_is_refused(tmp_path, content):
    """docs/architecture.md "Errors" (never a corrupted EEPROM file): coordinates are stored as
    32-bit integers per motor (TMCM-6212 3.6.22 SCO "-2^31 ... 2^31 - 1"), so a coordinate section
    with a text value or of the wrong shape is damaged; a JSON file that is not an OpenTMCL EEPROM
    image (another format, none, not an object) is refused too - both as EepromError, the file
    keeping its bytes."""
    path = tmp_path / "ee.json"
    path.write_text(content)
    with pytest.raises(EepromError, match="EEPROM file"):
        VirtualModule("TMCM-6212", eeprom=path)
    assert path.read_text() == content


def test_a_stored_program_keeps_32_bit_values(tmp_path):
    """TMCM-6212 3.1 Table 2: an instruction is command, type, motor/bank (a byte each) and a
    32-bit value; an EEPROM image whose program holds MVP ABS values beyond a byte (256, 51200)
    and the lowest 32-bit value loads with the values as stored (only the three byte fields are
    limited to 0...255)."""
    path = tmp_path / "ee.json"
    path.write_text(_HEAD + ',"program":[[4,0,0,51200],[4,0,0,-2147483648],[4,0,0,256]]}')
    vm = VirtualModule("TMCM-6212", address=1, eeprom=path)
    assert vm.program.code[:3] == [(4, 0, 0, 51200), (4, 0, 0, -2147483648), (4, 0, 0, 256)]


@pytest.mark.parametrize("axis", ['{"0":5}', '{"0":{"4":"fast"}}', '[1]'])
def test_a_damaged_axis_section_is_refused(tmp_path, axis):
    """docs/architecture.md "Errors": stored axis parameters are 32-bit integers per motor
    (PD86-1180 4.6.7 STAP "transferred to EEPROM"); an axis section of another shape or with a
    text value is a damaged file, refused as EepromError, the file keeping its bytes."""
    path = tmp_path / "ee.json"
    content = _HEAD + f',"axis":{axis}}}'
    path.write_text(content)
    with pytest.raises(EepromError, match="EEPROM file"):
        VirtualModule("TMCM-6212", eeprom=path)
    assert path.read_text() == content


@pytest.mark.parametrize("section", [
    '"global":{"0":{"77":"x"}}', '"global":{"0":{"77":2147483648}}', '"global":{"0":5}',
    '"global":[1]'])
def test_a_damaged_global_section_is_refused(tmp_path, section):
    """docs/assumptions.md "EEPROM images are checked when opened: every section must have the
    shape the module writes (32-bit integers ...) ...; otherwise `EepromError` and the file keeps
    its bytes" (eeprom.py `_whole`: {"bank": {"number": int}} for the global section)."""
    path = tmp_path / "ee.json"
    content = _HEAD + "," + section + "}"
    path.write_text(content)
    with pytest.raises(EepromError, match="damaged"):
        Eeprom(path, "TMCM-6212")
    assert path.read_text() == content


def test_the_last_32_bit_value_of_a_global_section_is_read(tmp_path):
    """The edge of the check above: 2^31 - 1 is a 32-bit integer and reads back as stored."""
    path = tmp_path / "ee.json"
    path.write_text(_HEAD + ',"global":{"0":{"77":2147483647}}}')
    assert Eeprom(path, "TMCM-6212").get_global(0, 77) == 2147483647


def test_an_image_without_a_program_section_loads(tmp_path):
    """eeprom.py `_whole`: "Every section has the shape `flush` writes" - a section that is not
    there has none to break (docs/assumptions.md). An image holding only a stored user variable
    (TMCM-6212 3.6.9 STGP; 5.1 GP85 "0 - user variables are restored (default)") opens: the
    variable is back and there is no program."""
    path = tmp_path / "ee.json"
    path.write_text(_HEAD + ',"user":{"3":7}}')
    vm = VirtualModule("TMCM-6212", address=1, eeprom=path)
    assert Host(vm).ok(10, 3, 2) == 7
    assert vm.program.length == 0


# Issue 11 problem 6: "SIGKILL leaves `.NAME.XXXX.tmp` files next to the EEPROM image that are never
# cleaned up".
#
# The EEPROM is written atomically (firmware/eeprom.py: temp file, fsync, rename), so a writer killed
# mid-write leaves its temp file. Opening the image removes those - only names of our own pattern
# (`.NAME.` + tempfile's 8 characters + `.tmp`) next to our own image, and never the temp file of a
# writer that is still alive. The writers are real subprocesses held inside fsync (the one step
# between writing the temp file and renaming it) and then SIGKILLed.

WRITER = textwrap.dedent("""
    import os, sys, time
    from opentmcl.firmware.eeprom import Eeprom
    ee = Eeprom(sys.argv[1], "TMCM-6212")
    def held(fd):          # stay inside the write: temp file written, not yet renamed
        print("writing", flush=True)
        time.sleep(600)
    os.fsync = held
    ee.set_user(3, 7)
""")
OURS = re.compile(r"\.ee\.json\.[a-z0-9_]{8}\.tmp")


def start_writer(image):
    p = subprocess.Popen([sys.executable, "-c", WRITER, str(image)], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "writing"
    return p


def temp_files(folder):
    return sorted(n for n in os.listdir(folder) if OURS.fullmatch(n))


@pytest.fixture
def writers():
    procs = []
    yield procs
    for p in procs:
        if p.poll() is None:
            p.kill()
        p.wait(timeout=10)
        p.stdout.close()


def test_killed_writers_temp_file_is_removed_live_one_and_decoys_stay(tmp_path, writers):
    image = tmp_path / "ee.json"
    live = start_writer(image)
    writers.append(live)
    live_tmp = temp_files(tmp_path)
    assert len(live_tmp) == 1
    killed = start_writer(image)          # its own start-up keeps the live writer's temp file
    writers.append(killed)
    killed.send_signal(signal.SIGKILL)
    assert killed.wait(timeout=10) == -signal.SIGKILL
    left = temp_files(tmp_path)
    assert len(left) == 2 and live_tmp[0] in left      # the problem: a leftover of the killed writer

    decoys = [".ee.json.tmp", "ee.json.abcd1234.tmp", ".other.json.abcd1234.tmp",
              ".ee.json.abcd1234.tmp.bak", ".ee.json.ABCD1234.tmp", ".ee.json.abc123.tmp"]
    for name in decoys:
        (tmp_path / name).write_text("not ours")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / ".ee.json.abcd1234.tmp").write_text("another folder")
    (tmp_path / "target.txt").write_text("a file a link points to")
    (tmp_path / ".ee.json.link1234.tmp").symlink_to(tmp_path / "target.txt")

    ee = Eeprom(image, "TMCM-6212")       # start-up of a module with this image
    assert ee.get_user(3) is None          # neither held write reached the image
    link = ".ee.json.link1234.tmp"         # our pattern, but a symbolic link: not a temp file of ours
    assert temp_files(tmp_path) == sorted(live_tmp + [link])
    for name in decoys:
        assert (tmp_path / name).read_text() == "not ours"
    assert (tmp_path / "sub" / ".ee.json.abcd1234.tmp").exists()
    assert (tmp_path / ".ee.json.link1234.tmp").is_symlink() and (tmp_path / "target.txt").exists()

    live.send_signal(signal.SIGKILL)
    live.wait(timeout=10)
    Eeprom(image, "TMCM-6212")
    assert temp_files(tmp_path) == [link]


def test_a_served_store_is_written_by_the_writer_not_under_the_bus_lock(tmp_path):
    """Issue 28 ("host requests are never queued behind" other work): with `on_change` set (a
    server's writer thread, server/eeprom_writer.py) a store (STGP, TMCM-6212 manual 3.6.9) only
    marks the image changed and calls it; the file is written from a `snapshot`. Two writers that
    race keep the newer content: a snapshot older than the one written last is not written."""
    import json

    path = tmp_path / "m.eeprom"
    eeprom = Eeprom(path, "TMCM-6212")
    calls: list[int] = []
    eeprom.on_change = lambda: calls.append(1)
    eeprom.set_user(0, 1)
    assert calls == [1] and eeprom.dirty
    assert json.loads(path.read_text())["user"] == {}          # not written by the store
    older = eeprom.snapshot()
    eeprom.set_user(0, 2)
    newer = eeprom.snapshot()
    assert not eeprom.dirty and eeprom.snapshot() is None    # nothing changed since
    eeprom.write(newer)
    eeprom.write(older)                                      # late: skipped
    assert json.loads(path.read_text())["user"] == {"0": 2}
    eeprom.on_change = None
    eeprom.set_program([[4, 0, 0, 1000], [28, 0, 0, 0]])
    eeprom.set_user(0, 3)                                    # without a writer: written at once
    assert json.loads(path.read_text())["user"] == {"0": 3}
    assert path.read_text() == json.dumps(                   # the same bytes as one json.dumps
        {"format": "opentmcl-eeprom", "version": 1, "module": "TMCM-6212", **eeprom.data},
        separators=(",", ":"), sort_keys=True)
