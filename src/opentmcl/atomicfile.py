"""Atomic file replacement shared by every layer that persists data (EEPROM, program binaries):
write a temporary file in the same folder, fsync it, rename it over the target. A process killed at
any point leaves the old file or the new one, never a torn one. The folder must exist (a typo in
a path is an error, not a new folder tree); the file gets the mode a plain open() would give it
(an existing file keeps its mode)."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path


def _read_umask() -> int:
    mask = os.umask(0o022)  # the only way to read it; read once, at import (threads may start later)
    os.umask(mask)
    return mask


_UMASK = _read_umask()


def write_atomic(path: str | os.PathLike, data: bytes) -> None:
    target = Path(path)
    directory = target.parent
    if not directory.is_dir():
        raise FileNotFoundError(2, f"folder {directory} does not exist", str(target))
    try:
        mode = target.stat().st_mode & 0o7777
    except OSError:
        mode = 0o666 & ~_UMASK
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=directory)
    try:
        os.chmod(tmp, mode)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
