"""Issue 11 problem 6: "SIGKILL leaves `.NAME.XXXX.tmp` files next to the EEPROM image that are never
cleaned up".

The EEPROM is written atomically (firmware/eeprom.py: temp file, fsync, rename), so a writer killed
mid-write leaves its temp file. Opening the image removes those - only names of our own pattern
(`.NAME.` + tempfile's 8 characters + `.tmp`) next to our own image, and never the temp file of a
writer that is still alive. The writers are real subprocesses held inside fsync (the one step
between writing the temp file and renaming it) and then SIGKILLed.
"""
import os
import re
import signal
import subprocess
import sys
import textwrap

import pytest

from opentmcl.firmware.eeprom import Eeprom

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

