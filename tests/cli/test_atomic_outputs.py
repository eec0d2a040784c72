"""Every file the CLI writes is replaced atomically (docs/assumptions.md, "Files we write": EEPROM
images, .bin/listing/symbol files, CSV traces "are replaced atomically"): a new file is renamed over
the old one, so the path gets a new inode, the old content survives a failed write and no temporary
file stays behind. A target that is no regular file (/dev/null behind a link) is written through,
never replaced by a regular file.

Each command runs as a real subprocess."""
from __future__ import annotations

import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenarios"
PROGRAM = "MVP ABS, 0, 2000\nWAIT POS, 0, 0\nSTOP\n"


def cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], cwd=cwd, capture_output=True,
                          text=True, timeout=120, env={**os.environ, "MPLBACKEND": "Agg"})


def replaced(path: Path, run) -> None:
    """`run()` writes `path` (which exists): it must be a new inode, nothing `.NAME.*.tmp` left."""
    path.write_text("old content\n")
    before = path.stat().st_ino
    keep = path.parent / "keep"   # holds the old inode, so the number cannot be reused
    os.link(path, keep)
    result = run()
    assert result.returncode == 0, result.stderr
    assert path.stat().st_ino != before, "written in place, not replaced"
    assert keep.read_text() == "old content\n"
    assert not [p for p in path.parent.iterdir() if p.name.startswith(f".{path.name}.")]


def test_run_csv_is_replaced(tmp_path):
    """`opentmcl run PROGRAM --scenario FILE --csv OUT` (world trace, trace.py to_csv)."""
    out = tmp_path / "run.csv"
    replaced(out, lambda: cli("run", str(EXAMPLES / "stallguard_homing.tmc"), "--scenario",
                              str(EXAMPLES / "tmcm6212_stage.toml"), "-t", "1", "--sample", "0.5",
                              "--csv", str(out), cwd=tmp_path))
    assert out.read_text().startswith("time,")


def test_demo_csv_is_replaced(tmp_path):
    """`opentmcl demo --scenario FILE --csv OUT` (world trace)."""
    out = tmp_path / "demo.csv"
    replaced(out, lambda: cli("demo", "--scenario", str(EXAMPLES / "pd28_1021_home.toml"), "--duration",
                              "0.2", "--csv", str(out), cwd=tmp_path))
    assert out.read_text().startswith("time,")


def test_plot_csv_and_image_are_replaced(tmp_path):
    """`opentmcl plot PROGRAM -o OUT.svg --csv OUT.csv` (plot trace and the rendered image)."""
    src = tmp_path / "p.tmc"
    src.write_text(PROGRAM)
    csv_out, svg = tmp_path / "p.csv", tmp_path / "p.svg"
    svg.write_text("old image\n")
    svg_inode = svg.stat().st_ino
    os.link(svg, tmp_path / "keep_svg")
    replaced(csv_out, lambda: cli("plot", str(src), "-t", "0.2", "-o", str(svg), "--csv", str(csv_out),
                                  cwd=tmp_path))
    assert csv_out.read_text().startswith("# module=")
    assert svg.stat().st_ino != svg_inode and svg.read_text().startswith("<?xml")


def test_asm_listing_and_symbols_are_replaced(tmp_path):
    """`opentmcl asm SRC -o OUT.bin --listing L --symbols S`: the listing is replaced too."""
    src = tmp_path / "p.tmc"
    src.write_text(PROGRAM)
    listing = tmp_path / "p.lst"
    replaced(listing, lambda: cli("asm", str(src), "-o", str(tmp_path / "p.bin"), "--listing", str(listing),
                                  cwd=tmp_path))
    assert "MVP" in listing.read_text()


def test_disasm_output_is_replaced(tmp_path):
    """`opentmcl disasm BIN -o OUT.tmc`."""
    src = tmp_path / "p.tmc"
    src.write_text(PROGRAM)
    assert cli("asm", str(src), "-o", str(tmp_path / "p.bin"), cwd=tmp_path).returncode == 0
    out = tmp_path / "back.tmc"
    replaced(out, lambda: cli("disasm", str(tmp_path / "p.bin"), "-o", str(out), cwd=tmp_path))
    assert "MVP" in out.read_text()


def test_a_link_to_a_device_is_written_through(tmp_path):
    """`asm -o /dev/null` is a common way to check a program: the device must stay a device (as
    root, renaming a regular file over it would replace /dev/null for the whole system). A link to
    /dev/null stands for it here; the link stays a link and nothing else is created."""
    link = tmp_path / "out"
    link.symlink_to(os.devnull)
    src = tmp_path / "p.tmc"
    src.write_text(PROGRAM)
    result = cli("asm", str(src), "-o", str(link), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert link.is_symlink() and os.readlink(link) == os.devnull
    assert stat.S_ISCHR(os.stat(os.devnull).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "p.tmc"]


def test_a_failed_write_keeps_the_old_file(tmp_path):
    """The library level: an exception while the plot trace streams its rows leaves the old CSV
    as it was and no temporary file (plain open() truncated it first)."""
    from opentmcl.trace import Trace

    out = tmp_path / "t.csv"
    out.write_text("old content\n")
    trace = Trace(module="TMCM-6212", axes=[0])
    trace.add(0.0, {(0, "position"): 1.0})

    class Broken:
        """A data row that fails when formatted (stands for a disk that fills up mid-write)."""

        def __float__(self):
            raise OSError(28, "No space left on device")

    trace.data[(0, "position")] = [Broken()]
    with pytest.raises(OSError):
        trace.to_csv(out)
    assert out.read_text() == "old content\n"
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]
