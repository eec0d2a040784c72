"""Atomic file replacement shared by every layer that persists data (EEPROM, program binaries):
write a temporary file in the same folder, fsync it, rename it over the target (`write_atomic`
for bytes at hand, `open_atomic` for a file object to stream into). A process killed at
any point leaves the old file or the new one, never a torn one. The folder must exist (a typo in
a path is an error, not a new folder tree); the file gets the mode a plain open() would give it
(an existing file keeps its mode).

The temporary file is `.NAME.XXXXXXXX.tmp` (tempfile.mkstemp's 8 random characters) and its writer
holds an flock on it until the rename: `remove_stale(path)` deletes those a killed writer left,
and never one whose writer is still alive."""
from __future__ import annotations

import contextlib
import fcntl
import os
import re
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

_RANDOM = r"[a-z0-9_]{8}"   # tempfile's name alphabet


def _read_umask() -> int:
    mask = os.umask(0o022)  # the only way to read it; read once, at import (threads may start later)
    os.umask(mask)
    return mask


_UMASK = _read_umask()


def write_atomic(path: str | os.PathLike[str], data: bytes) -> None:
    with open_atomic(path) as fh:
        fh.write(data)


@contextlib.contextmanager
def open_atomic(path: str | os.PathLike[str], text: bool = False) -> Iterator[IO[Any]]:
    """A file to write `path` through: the temporary file, renamed over `path` when the block
    ends without an exception, deleted otherwise (`path` keeps its old content). `text=True`:
    a UTF-8 text file without newline translation. A symbolic link is followed (the file it names
    is replaced, the link stays); a target that exists but is no regular file (/dev/null, a FIFO,
    a terminal) is written straight through, never replaced."""
    mode, encoding, newline = ("w", "utf-8", "") if text else ("wb", None, None)
    target = Path(os.path.realpath(path))
    try:
        special = not stat.S_ISREG(target.stat().st_mode)
    except OSError:
        special = False
    if special:
        with open(target, mode, encoding=encoding, newline=newline) as fh:
            yield fh
        return
    directory = target.parent
    if not directory.is_dir():
        raise FileNotFoundError(2, f"folder {directory} does not exist", str(target))
    try:
        permissions = target.stat().st_mode & 0o7777
    except OSError:
        permissions = 0o666 & ~_UMASK
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=directory)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)   # "a writer is alive" for remove_stale
        os.chmod(tmp, permissions)
        with os.fdopen(fd, mode, encoding=encoding, newline=newline) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
            os.replace(tmp, target)      # still locked: renamed before the lock goes
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def stale_pattern(path: str | os.PathLike[str]) -> re.Pattern[str]:
    """Names of the temporary files `write_atomic(path, ...)` creates."""
    return re.compile(rf"\.{re.escape(Path(path).name)}\.{_RANDOM}\.tmp")


def remove_stale(path: str | os.PathLike[str]) -> list[Path]:
    """Delete the temporary files of `path` that a killed writer left next to it (same folder,
    our own name pattern, no writer holding its lock); returns those deleted. Like `open_atomic`,
    it follows a symbolic link to the image."""
    target = Path(os.path.realpath(path))
    pattern = stale_pattern(target)
    try:
        names = os.listdir(target.parent)
    except OSError:
        return []
    removed = []
    for name in names:
        if not pattern.fullmatch(name):
            continue
        tmp = target.parent / name
        try:
            fd = os.open(tmp, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
        except OSError:
            continue                      # gone already, a symlink, or not ours to open
        try:
            if not os.path.isfile(tmp) or os.path.islink(tmp):
                continue
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                continue                  # a live writer holds it
            if os.fstat(fd).st_ino == os.lstat(tmp).st_ino:
                os.unlink(tmp)
                removed.append(tmp)
        except OSError:
            pass
        finally:
            os.close(fd)
    return removed
