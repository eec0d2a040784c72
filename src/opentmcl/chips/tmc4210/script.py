"""Datagram scripts for the TMC4210 model and the trace printer (`opentmcl tmc4210 trace`).

A script is plain text, one command per line, `#` starts a comment:

    spi $1A000123              raw datagram ($hex, 0xhex, %binary or decimal)
    write V_MAX 1000           register or field by datasheet name
    read X_ACTUAL
    advance 0.25               seconds of virtual time (suffixes s, ms, us allowed)
    inputs ref_l=1 gp_in=0     drive the input pins
    until X_ACTUAL >= 1000 10  advance in 1 ms slices until the condition holds (==, !=, <, <=,
                               >, >=); an error after 10 s (default 60 s)

A `.py` file instead must define `main(chip)`; it is run against a traced chip.
"""
from __future__ import annotations

import operator
import re
import shlex
import sys
import types
from collections.abc import Callable
from pathlib import Path

from . import registers as R
from .chip import TMC4210, ChipError


class ScriptError(ValueError):
    """A script line that cannot be run; the message names the line."""


def parse_int(text: str) -> int:
    """$1A, 0x1A, %1010 or decimal (datasheet 2.1 notations), at most 32 digits (opentmcl.limits)."""
    from ...limits import LiteralTooLong, check_literal, shown

    t = text.strip().replace("_", "")
    digits = t.lstrip("+-")
    try:
        check_literal(digits[2:] if digits[:2].lower() == "0x" else digits[1:] if digits[:1] in "$%" else digits)
    except LiteralTooLong as exc:
        raise ScriptError(str(exc)) from None
    try:
        if t.startswith("$"):
            return int(t[1:], 16)
        if t.lower().startswith(("0x", "-0x")):
            return int(t, 16)
        if t.startswith("%"):
            return int(t[1:], 2)
        return int(t, 10)
    except ValueError:
        raise ScriptError(f"not a number: {shown(text)}") from None


_OPS = {"==": operator.eq, "!=": operator.ne, ">=": operator.ge, "<=": operator.le,
        ">": operator.gt, "<": operator.lt}
_TIME = re.compile(r"^([0-9]*\.?[0-9]+(?:e-?[0-9]+)?)(s|ms|us)?$")


def parse_seconds(text: str) -> float:
    m = _TIME.match(text.strip().lower())
    if not m:
        raise ScriptError(f"not a time: {text!r} (use e.g. 0.5, 20ms, 100us)")
    return float(m.group(1)) * {"s": 1, None: 1, "ms": 1e-3, "us": 1e-6}[m.group(2)]


def format_trace(t: float, word_in: int, word_out: int) -> str:
    """Two lines: the datagram in and the datagram out, both decoded."""
    return (f"{t:12.6f}  > ${word_in:08X}  {R.describe_request(word_in)}\n"
            f"{'':12}  < ${word_out:08X}  {R.describe_reply(word_in, word_out)}")


def run_line(chip: TMC4210, line: str) -> None:
    """Run one script command against `chip`."""
    try:
        words = shlex.split(line, comments=True)
    except ValueError as exc:
        raise ScriptError(str(exc)) from None
    if not words:
        return
    cmd, args = words[0].lower(), words[1:]
    try:
        if cmd == "spi" and len(args) == 1:
            chip.spi(parse_int(args[0]))
        elif cmd == "write" and len(args) == 2:
            chip.write(args[0], parse_int(args[1]))
        elif cmd == "read" and len(args) == 1:
            chip.read(args[0])
        elif cmd == "advance" and len(args) == 1:
            chip.advance(parse_seconds(args[0]))
        elif cmd == "inputs" and args:
            _inputs(chip, args)
        elif cmd == "until" and len(args) in (3, 4) and args[1] in _OPS:
            _until(chip, *args)
        else:
            raise ScriptError(f"cannot understand {line.strip()!r}")
    except ChipError as exc:
        raise ScriptError(str(exc)) from None


def _inputs(chip: TMC4210, args: list[str]) -> None:
    """`inputs ref_l=1 gp_in=0`: drive the named pins."""
    levels = {}
    for a in args:
        name, _, value = a.partition("=")
        if name not in ("ref_l", "ref_r", "gp_in") or not value:
            raise ScriptError(f"inputs takes ref_l=, ref_r=, gp_in=, got {a!r}")
        levels[name] = parse_int(value)
    chip.set_inputs(**levels)


def _until(chip: TMC4210, name: str, op: str, value: str, limit: str | None = None) -> None:
    """`until NAME OP VALUE [LIMIT]`: advance until the register or field compares true."""
    want, test = parse_int(value), _OPS[op]
    limit_s = parse_seconds(limit) if limit is not None else 60.0
    chip.peek(name)  # unknown names fail before any time passes
    if not run_until(chip, lambda: test(chip.peek(name), want), limit_s):
        raise ScriptError(f"{name} {op} {want} not reached within {limit_s:g} s")


def run_until(chip: TMC4210, done: Callable[[], bool], limit_s: float, step_s: float = 0.001) -> bool:
    """Advance in `step_s` slices until done() or `limit_s` seconds have passed."""
    waited = 0.0
    while not done():
        if waited >= limit_s:
            return False
        chip.advance(step_s)
        waited += step_s
    return True


def run_text(chip: TMC4210, text: str, source: str = "<script>") -> None:
    for number, line in enumerate(text.splitlines(), 1):
        try:
            run_line(chip, line)
        except ScriptError as exc:
            raise ScriptError(f"{source}:{number}: {exc}") from None


def run_file(chip: TMC4210, path: str | Path) -> None:
    """Run a text script, or a Python file's main(chip)."""
    p = Path(path)
    if p.suffix == ".py":
        source = _read(p)
        try:
            code = compile(source, str(p), "exec")
        except SyntaxError as exc:
            raise ScriptError(f"{p}:{exc.lineno or '?'}: {exc.msg}") from None
        module = types.ModuleType(f"_tmc4210_script_{p.stem}")
        module.__file__ = str(p)
        sys.modules[module.__name__] = module  # dataclasses and the like look their module up
        try:
            exec(code, module.__dict__)  # noqa: S102 - the user's own script, as `python SCRIPT` runs it
            main = getattr(module, "main", None)
            if not callable(main):
                raise ScriptError(f"{p}: a Python script must define main(chip)")
            main(chip)
        except (ScriptError, ChipError, BrokenPipeError):
            raise
        except Exception as exc:  # the script's own failure, reported in one line
            raise ScriptError(f"{p}: the script stopped with {type(exc).__name__}: {exc}") from None
        finally:
            sys.modules.pop(module.__name__, None)
        return
    run_text(chip, _read(p), str(p))


def _read(p: Path) -> str:
    from ...limits import TEXT_MAX, InputTooLarge, read_text

    try:
        return read_text(p, TEXT_MAX, "trace script")
    except InputTooLarge as exc:
        raise ScriptError(f"{p}: {exc}") from None
    except UnicodeDecodeError:
        raise ScriptError(f"{p}: not a UTF-8 text file") from None
    except OSError as exc:
        raise ScriptError(f"cannot read {p}: {exc.strerror or exc}") from None
