"""Helpers of the packaging tests (issue 32): a snapshot of the source tree, the sdist built from
it, and the Python interpreters of this machine.

The sdist is built with `python -m build --sdist --no-isolation` from a copy of the files git
tracks (a fresh clone's files): the test extra brings `build` and setuptools >= 77, the
build-system's requirement, so nothing is downloaded for the build itself.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tarfile
import tomllib
import zipfile
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
UNTRACKED = shutil.ignore_patterns(".git", ".venv", "__pycache__", "*.py[cod]", "*.so", "*.egg-info", "build",
                                   "dist", ".*_cache", ".hypothesis", "mutants", "test-artifacts", "results")
"""What a copy of a tree that is not a git checkout leaves out (.gitignore's entries)."""
LEFTOVERS = ("tests/__pycache__/conftest.cpython-311.pyc", "src/opentmcl/_accel.cpython-311-x86_64-linux-gnu.so",
             "bench/results/latest.json", "examples/__pycache__/test_with_tmcl_module.cpython-311.pyc")
"""Files a developer's tree has after `pip install -e` (the compiled accelerator in place), a test
run and `python bench/run.py`, none of them tracked: the sdist must not carry them."""


@dataclass(frozen=True)
class Built:
    """A distribution built from `tree`: its `path` and the names of its files."""

    tree: Path
    path: Path

    def names(self) -> set[str]:
        """Member files, relative to the archive's top folder (an sdist) or its root (a wheel)."""
        if self.path.suffix == ".whl":
            with zipfile.ZipFile(self.path) as archive:
                return {n for n in archive.namelist() if not n.endswith("/")}
        with tarfile.open(self.path) as archive:
            return {m.name.split("/", 1)[1] for m in archive.getmembers() if m.isfile() and "/" in m.name}

    def read(self, name: str) -> str:
        """The text of member `name` (relative, as `names` gives it)."""
        if self.path.suffix == ".whl":
            with zipfile.ZipFile(self.path) as archive:
                return archive.read(name).decode("utf-8")
        with tarfile.open(self.path) as archive:
            top = archive.getnames()[0].split("/", 1)[0]
            member = archive.extractfile(f"{top}/{name}")
            assert member is not None, name
            return member.read().decode("utf-8")


def claimed_versions() -> list[tuple[int, int]]:
    """The Python versions the package claims: its `Programming Language :: Python :: 3.N` classifiers."""
    found = (re.fullmatch(r"Programming Language :: Python :: (\d+)\.(\d+)", c) for c in PROJECT["classifiers"])
    return sorted((int(m.group(1)), int(m.group(2))) for m in found if m)


def clean_env() -> dict[str, str]:
    """The environment for a child that must see only its own installation (no PYTHONPATH)."""
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}


def _version_of(python: str) -> tuple[int, int] | None:
    try:
        out = subprocess.run([python, "-c", "import sys; print(*sys.version_info[:2])"], capture_output=True,
                             text=True, timeout=60, env=clean_env())
    except OSError:
        return None
    parts = out.stdout.split()
    return (int(parts[0]), int(parts[1])) if out.returncode == 0 and len(parts) == 2 else None


def interpreter(version: tuple[int, int]) -> str | None:
    """A Python of `version` on this machine: this one, `python3.N` on PATH (a pyenv shim of a
    version that is not selected fails, so each is asked), or pyenv's newest 3.N.x."""
    if sys.version_info[:2] == version:
        return sys.executable
    name = f"python{version[0]}.{version[1]}"
    candidates = [shutil.which(name)]
    pyenv = Path(os.environ.get("PYENV_ROOT") or Path.home() / ".pyenv") / "versions"
    if pyenv.is_dir():
        found = [p for p in pyenv.glob(f"{version[0]}.{version[1]}.*/bin/{name}")
                 if re.fullmatch(r"\d+\.\d+\.\d+", p.parents[1].name)]
        candidates += [str(p) for p in sorted(found, key=lambda p: int(p.parents[1].name.split(".")[2]), reverse=True)]
    return next((c for c in candidates if c and _version_of(c) == version), None)


def snapshot(dest: Path) -> Path:
    """A copy of the tree as a fresh clone has it: the files git tracks (or, outside a git
    checkout, the tree without what .gitignore names)."""
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, timeout=60)
    if (ROOT / ".git").exists() and listed.returncode == 0:
        for name in listed.stdout.decode().split("\0"):
            if name and (ROOT / name).is_file():
                (dest / name).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(ROOT / name, dest / name)
    else:
        shutil.copytree(ROOT, dest, ignore=UNTRACKED, dirs_exist_ok=True)
    return dest


def with_leftovers(tree: Path) -> Path:
    """`tree` with the untracked LEFTOVERS of a developer's working tree added."""
    for name in LEFTOVERS:
        (tree / name).parent.mkdir(parents=True, exist_ok=True)
        (tree / name).write_bytes(b"not for the sdist\n")
    return tree


def build(tree: Path, outdir: Path, kind: str) -> Path:
    """`python -m build --KIND --no-isolation` of `tree`; the one file it made in `outdir`."""
    done = subprocess.run([sys.executable, "-m", "build", f"--{kind}", "--no-isolation", "--outdir", str(outdir),
                           str(tree)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    (made,) = outdir.iterdir()
    return made
