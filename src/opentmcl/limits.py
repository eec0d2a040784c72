"""Size limits for everything OpenTMCL reads from a file, a pipe or stdin, and for number literals.

A reader takes at most cap + 1 bytes, so /dev/zero, a FIFO or an endless pipe ends in
`InputTooLarge` instead of filling memory. The caps (docs/assumptions.md, "Bounded inputs") are
far above any real input: the largest program memory of the three modules is 6144 instructions
(TMCM-6212 manual 1, "up to 6144 TMCL commands"), 49152 bytes as a binary image.
"""
from __future__ import annotations

import os
import sys

KIB, MIB = 1024, 1024 * 1024
IMAGE_MAX = 1 * MIB          # binary program images (.bin): 131072 records, 21x the largest memory
TEXT_MAX = 4 * MIB           # program sources (each file), EEPROM images, scenarios, scripts, label tables
CSV_MAX = 256 * MIB          # CSV traces for `plot` (read line by line)
LINE_MAX = 64 * KIB          # one line of a CSV trace
COMMAND_LINE_MAX = 4 * KIB   # one debugger command read from a pipe or file on stdin
LITERAL_DIGITS_MAX = 32      # digits of a number literal after sign and prefix: every 32-bit value in binary


class InputTooLarge(ValueError):
    """A file, pipe or stdin that is longer than its documented cap."""


class LiteralTooLong(ValueError):
    """A number literal with more digits than LITERAL_DIGITS_MAX (Python's int() would refuse
    4300 digits with an untyped ValueError, and a long one is never a 32-bit value)."""


def size_text(n: int) -> str:
    return f"{n // MIB} MiB" if n % MIB == 0 else f"{n // KIB} KiB" if n % KIB == 0 else f"{n} bytes"


def read_bytes(path: str | os.PathLike[str], cap: int, what: str = "file", *, stdin: bool = False) -> bytes:
    """The whole content of `path` (with stdin=True, '-' is stdin), at most `cap` bytes, else
    InputTooLarge (its message names `what` and the cap, not the path). OSError as open() raises it."""
    if stdin and str(path) == "-":
        data = sys.stdin.buffer.read(cap + 1)
    else:
        with open(path, "rb") as fh:
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
