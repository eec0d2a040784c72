"""Size limits for everything OpenTMCL reads from a file or stdin, and for number literals.

A file named by a path must be a regular file: `open_regular` opens it without blocking and
refuses a FIFO, a device, a socket or a directory (`NotRegularFile`, an OSError), so a FIFO
without a writer cannot hang a reader and /dev/zero cannot fill memory. Stdin ('-' where a
command takes it) may be a pipe. A reader takes at most cap + 1 bytes, so an endless stdin ends
in `InputTooLarge`. The caps (docs/assumptions.md, "Bounded inputs") are
far above any real input: the largest program memory of the three modules is 6144 instructions
(TMCM-6212 manual 1, "up to 6144 TMCL commands"), 49152 bytes as a binary image.
"""
from __future__ import annotations

import errno
import os
import stat
import sys
from typing import BinaryIO

KIB, MIB = 1024, 1024 * 1024
IMAGE_MAX = 1 * MIB          # binary program images (.bin): 131072 records, 21x the largest memory
TEXT_MAX = 4 * MIB           # program sources (each file), EEPROM images, scenarios, scripts, label tables
CSV_MAX = 256 * MIB          # CSV traces for `plot` (read line by line)
LINE_MAX = 64 * KIB          # one line of a CSV trace
COMMAND_LINE_MAX = 4 * KIB   # one debugger command read from a pipe or file on stdin
LITERAL_DIGITS_MAX = 32      # digits of a number literal after sign and prefix: every 32-bit value in binary


class InputTooLarge(ValueError):
    """A file, pipe or stdin that is longer than its documented cap."""


class NotRegularFile(OSError):
    """A path to read that names a FIFO, a device or a socket (its `strerror` says which)."""


class LiteralTooLong(ValueError):
    """A number literal with more digits than LITERAL_DIGITS_MAX (Python's int() would refuse
    4300 digits with an untyped ValueError, and a long one is never a 32-bit value)."""


def size_text(n: int) -> str:
    return f"{n // MIB} MiB" if n % MIB == 0 else f"{n // KIB} KiB" if n % KIB == 0 else f"{n} bytes"


_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def open_regular(path: str | os.PathLike[str]) -> BinaryIO:
    """`path` opened for reading in binary mode if it is a regular file (symbolic links followed).
    Opened with O_NONBLOCK, so a FIFO without a writer or a terminal returns at once; then
    IsADirectoryError for a directory, NotRegularFile for anything else that is not a regular file
    (message e.g. "a FIFO (named pipe), not a regular file"). OSError as open() raises it."""
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_BINARY", 0)
    fd = os.open(path, flags)
    try:
        mode = os.fstat(fd).st_mode
        if stat.S_ISDIR(mode):
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), os.fspath(path))
        if not stat.S_ISREG(mode):
            kind = next((name for test, name in _KINDS if test(mode)), "a special file")
            raise NotRegularFile(errno.EINVAL, f"{kind}, not a regular file", os.fspath(path))
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_bytes(path: str | os.PathLike[str], cap: int, what: str = "file", *, stdin: bool = False) -> bytes:
    """The whole content of `path` (with stdin=True, '-' is stdin), at most `cap` bytes, else
    InputTooLarge (its message names `what` and the cap, not the path). `path` must be a regular
    file (`open_regular`). OSError as open() raises it."""
    if stdin and str(path) == "-":
        data = sys.stdin.buffer.read(cap + 1)
    else:
        with open_regular(path) as fh:
            data = fh.read(cap + 1)
    if len(data) > cap:
        raise InputTooLarge(f"{what} is larger than the {size_text(cap)} limit")
    return data


def read_text(path: str | os.PathLike[str], cap: int, what: str = "file", errors: str = "strict", *,
              stdin: bool = False) -> str:
    """`read_bytes` decoded as UTF-8 (UnicodeDecodeError with errors='strict')."""
    return read_bytes(path, cap, what, stdin=stdin).decode("utf-8", errors=errors)


def shown(text: str, n: int = 60) -> str:
    """`text` for an error message: repr, cut to about n characters."""
    return repr(text) if len(text) <= n else repr(text[:n]) + f"... ({len(text)} characters)"


def check_literal(digits: str) -> None:
    """LiteralTooLong if a literal's digit string (no sign, no prefix) is longer than the cap."""
    if len(digits) > LITERAL_DIGITS_MAX:
        raise LiteralTooLong(f"number literal of {len(digits)} digits is too long "
                             f"(at most {LITERAL_DIGITS_MAX} digits after the sign and $/0x/0b/%)")
