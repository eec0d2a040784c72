"""A TMCL program debugger over any client connection (TMCM-6212 manual 3.6.36: "Most of these
commands are only used by the TMCL-IDE (in order to implement e.g. the debugging functions ...)").

Everything goes through the control commands: 130 executes one instruction, 135 reports
mode, wait flag, PC, A and X, 128/129/131 stop, run and reset. Breakpoints and "run to label"
are host-side: the debugger single-steps (130) and stops when the PC reaches a breakpoint
address, before that instruction runs. A WAIT that is not yet satisfied keeps the module in
step mode with the wait flag set; the debugger lets time pass (client.sleep) until it ends.
Without breakpoints `cont()` lets the program run freely (129) and polls until it stops.

Watch expressions (case-insensitive): ``a``, ``x``, ``pc``, ``flags``, ``state``,
``varN`` (user variable N), ``outN`` / ``inN`` / ``adcN`` (GIO N on bank 2 / 0 / 1),
``posN`` / ``targetN`` / ``speedN`` (AP1 / AP0 / AP3 of motor N), ``apP.M`` (axis parameter P
of motor M), ``gpN`` or ``gpN.B`` (global parameter N of bank B, default 0).

`Debugger.value` (the debugger's `print`) reads one of these, or an expression in the assembler's
operand syntax over them, ``apP`` (axis parameter P of motor 0) and parameter names of the module
profile (``actual_position``, the manual's title or PyTrinamic's ``ActualPosition``; ``NAME.M``
for motor M).
"""
from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

from ..lang.assembler import ExpressionError, evaluate
from ..lang.binfile import Instruction
from ..protocol.opcodes import GET_APPLICATION_STATUS, Op, format_instruction
from .errors import (
    TmclStatusError,
    TmclTypeError,
    TmclValueError,
    UnknownParameterError,
    check_int,
    check_timeout,
)
from .loader import MODES, AppStatus, Loader
from .module import Module

INSTRUCTION_SECONDS = 0.0001  # one TMCL instruction of the virtual modules (100 µs)
WAIT_SLICE = 0.01             # how long the debugger lets a WAIT run between two looks
POLL = 0.05                   # status polling period while the program runs freely
_GAP, _GGP, _GIO = int(Op.GAP), int(Op.GGP), int(Op.GIO)  # plain ints for the watches' requests

# Bits of the program flags word (layout of firmware/flags.py; Loader.flags).
FLAG_NAMES = ((0x100, "ZE"), (0x200, "EQ"), (0x400, "GT"), (0x800, "LT"),
              (1, "ETO"), (2, "EAL"), (4, "EDV"), (8, "EPO"), (16, "ESD"))


class DebugError(TmclValueError):
    """A debugger command the user got wrong (unknown label, bad watch expression, ...)."""


def describe_flags(flags: int | None) -> str:
    if flags is None:
        return "n/a"
    return " ".join(n for bit, n in FLAG_NAMES if flags & bit) or "-"


@dataclass(frozen=True)
class Watch:
    """A named value read from the module: `read(loader)` returns an int or a short text."""

    name: str
    read: Reader


Reader = Callable[[Loader], int | str]


class SourceText(Protocol):
    """A source line of the program (`lang.assembler.SourceLine`): its text is listed."""

    @property
    def text(self) -> str: ...


def _gio(port: int, bank: int) -> Reader:
    return lambda ld: ld.request(_GIO, port, bank).value


def _gap(param: int, motor: int) -> Reader:
    return lambda ld: ld.request(_GAP, param, motor).value


def _ggp(number: int, bank: int) -> Reader:
    return lambda ld: ld.request(_GGP, number, bank).value


_SIMPLE: dict[str, Reader] = {
    "a": lambda ld: ld.request(GET_APPLICATION_STATUS, 2).value,
    "x": lambda ld: ld.request(GET_APPLICATION_STATUS, 3).value,
    "pc": lambda ld: ld.request(GET_APPLICATION_STATUS, 1).value & 0xFFFF,
    "state": lambda ld: MODES.get((ld.request(GET_APPLICATION_STATUS, 1).value >> 24) & 0xFF, "?"),
}
_INDEXED: dict[str, Callable[[int], Reader]] = {
    "var": lambda n: _ggp(n, 2), "out": lambda n: _gio(n, 2), "in": lambda n: _gio(n, 0),
    "adc": lambda n: _gio(n, 1), "pos": lambda n: _gap(1, n), "target": lambda n: _gap(0, n),
    "speed": lambda n: _gap(3, n),
}


def _flags(ld: Loader) -> str:
    return describe_flags(ld.flags())


def parse_watch(spec: str, verb: str = "watch") -> Watch:
    """One watch expression (see the module docstring); DebugError if it cannot be read."""
    if not isinstance(spec, str):
        raise TmclTypeError(f"a watch expression is a string, got {spec!r}")
    text = spec.strip().lower()
    if any(int(n) > 255 for n in re.findall(r"\d+", text)):  # type and motor/bank are bytes (manual 3.1)
        raise DebugError(f"cannot {verb} {spec!r}: numbers must be 0..255")
    if text in _SIMPLE:
        return Watch(text, _SIMPLE[text])
    if text == "flags":
        return Watch(text, _flags)
    m = re.fullmatch(r"(var|out|in|adc|pos|target|speed)(\d+)", text)
    if m:
        return Watch(text, _INDEXED[m.group(1)](int(m.group(2))))
    m = re.fullmatch(r"ap(\d+)\.(\d+)", text)
    if m:
        return Watch(text, _gap(int(m.group(1)), int(m.group(2))))
    m = re.fullmatch(r"gp(\d+)(?:\.(\d+))?", text)
    if m:
        return Watch(text, _ggp(int(m.group(1)), int(m.group(2) or 0)))
    raise DebugError(f"cannot {verb} {spec!r}: use a, x, pc, flags, state, varN, outN, inN, adcN, "
                     f"posN, targetN, speedN, apP.M or gpN[.B]")


def parse_watches(specs: str | Sequence[str]) -> list[Watch]:
    if isinstance(specs, str):
        specs = [s for s in re.split(r"[,\s]+", specs) if s]
    elif not isinstance(specs, Sequence):
        raise TmclTypeError(f"watch expressions are a string or a sequence of strings, got {specs!r}")
    return [parse_watch(s) for s in specs]


def read_watch(loader: Loader, watch: Watch) -> int | str:
    try:
        return watch.read(loader)
    except TmclStatusError as exc:
        return f"<status {exc.status}>"


@dataclass
class Debugger:
    """Debugging session on the module behind `loader` for a program with `labels` and, per
    address, its `source` line (objects with .file, .line, .text, or None)."""

    loader: Loader
    instructions: Sequence[Instruction] = field(default_factory=list)
    labels: dict[str, int] = field(default_factory=dict)
    source: Sequence[SourceText | None] = field(default_factory=list)
    breakpoints: set[int] = field(default_factory=set)
    watches: list[Watch] = field(default_factory=list)
    module: Module | None = None
    """The module behind `loader`, for parameters by name in `value` (none: numbers only)."""

    # --- addresses ----------------------------------------------------------------------------
    def address(self, text: str) -> int:
        """A label name or a number."""
        if not isinstance(text, str):
            raise TmclTypeError(f"an address is a label or a number as text, got {text!r}")
        t = text.strip()
        if t in self.labels:
            return self.labels[t]
        lower = {k.lower(): v for k, v in self.labels.items()}
        if t.lower() in lower:
            return lower[t.lower()]
        try:
            value = int(t, 0)
        except ValueError:
            raise DebugError(f"no label {t!r}") from None
        if value < 0:
            raise DebugError(f"address must be >= 0, got {value}")
        return value

    def where(self, address: int) -> str:
        """``Label`` or ``Label+3`` for an address (nearest label at or before it)."""
        best = None
        for name, addr in self.labels.items():
            if addr <= address and (best is None or addr > best[1] or (addr == best[1] and name < best[0])):
                best = (name, addr)
        if best is None:
            return ""
        return best[0] if best[1] == address else f"{best[0]}+{address - best[1]}"

    def line(self, address: int) -> str:
        """One listing line: address, label, instruction text (source text when known)."""
        text = ""
        src = self.source[address] if address < len(self.source) else None
        if src is not None:
            text = src.text.strip()
            text = re.sub(r"^\s*[A-Za-z_]\w*\s*:\s*", "", text)  # the label is shown separately
        elif address < len(self.instructions):
            ins = self.instructions[address]
            names = {a: n for n, a in sorted(self.labels.items(), reverse=True)}
            text = format_instruction(*ins, labels=names) or f"RAW {', '.join(map(str, ins))}"
        mark = "*" if address in self.breakpoints else " "
        where = self.where(address)
        return f"{mark}{address:5d}  {where:<16} {text}".rstrip()

    # --- execution ------------------------------------------------------------------------------
    def status(self) -> AppStatus:
        return self.loader.status()

    def _settle(self, st: AppStatus) -> AppStatus:
        """Let time pass while a stepped WAIT is still waiting."""
        while st.waiting and st.mode in (1, 2):
            self.loader.client.sleep(WAIT_SLICE)
            st = self.loader.status()
        return st

    def step(self, count: int = 1) -> AppStatus:
        """Execute `count` instructions (130), each waited out if it is a WAIT."""
        check_int(count, "count")
        st = self.status()
        for _ in range(max(1, count)):
            self.loader.step()
            st = self.after_step()
            if st.mode in (0, 3):
                break
        return st

    def after_step(self) -> AppStatus:
        """The state once the step (130) just sent has run; a WAIT is waited out."""
        self.loader.client.sleep(INSTRUCTION_SECONDS)
        return self._settle(self.status())

    def run_to(self, stops: set[int], *, max_steps: int | None = None) -> AppStatus:
        """Single-step until the PC is in `stops` (before that instruction runs) or the program
        stops; the instruction at the current PC is always executed first."""
        if max_steps is not None:
            check_int(max_steps, "max_steps")
        steps = 0
        while True:
            st = self.step()
            steps += 1
            if st.mode in (0, 3) or st.pc in stops:
                return st
            if max_steps is not None and steps >= max_steps:
                return st

    def cont(self, *, max_seconds: float | None = None,
             on_start: Callable[[], None] | None = None,
             interrupted: Callable[[], bool] | None = None) -> AppStatus:
        """Continue: to the next breakpoint by stepping, or freely (129) until the program stops
        (`on_start` is called once the program runs freely). When `interrupted()` turns true
        the program is stopped (128) and its status returned."""
        if max_seconds is not None:
            check_timeout(max_seconds, "max_seconds")
        if self.breakpoints:
            return self.run_to(self.breakpoints)
        self.loader.run()
        if on_start is not None:
            on_start()
        waited = 0.0
        while True:
            if interrupted is not None and interrupted():
                self.loader.stop()
                return self.status()
            self.loader.client.sleep(POLL)
            waited += POLL
            st = self.status()
            if st.mode != 1 or (max_seconds is not None and waited >= max_seconds):
                return st

    def until(self, target: str) -> AppStatus:
        """Run to a label or address (a temporary breakpoint)."""
        return self.run_to({self.address(target)} | self.breakpoints)

    def watch_values(self) -> list[tuple[str, int | str]]:
        return [(w.name, read_watch(self.loader, w)) for w in self.watches]

    # --- print ------------------------------------------------------------------------------------
    def value(self, text: str) -> int | str:
        """What ``print TEXT`` shows: one watch expression as it is (flags and state as text), else
        the value of an expression in the assembler's operand syntax whose names are watch
        expressions without text, ``apP`` (motor 0) and parameter names (``NAME.M``: motor M)."""
        if not isinstance(text, str):
            raise TmclTypeError(f"an expression is a string, got {text!r}")
        spec = text.strip()
        if not spec:
            raise DebugError("usage: print EXPR (a, x, pc, varN, apP[.M], a parameter name, ... with + - * / ...)")
        try:
            return parse_watch(spec, "print").read(self.loader)
        except DebugError:
            pass
        dotted: dict[str, tuple[str, int]] = {}

        def undot(m: re.Match[str]) -> str:  # NAME.M is no name of the expression syntax
            key = f"_{len(dotted)}_"
            dotted[key] = (m.group(1), int(m.group(2)))
            return key

        plain = _DOTTED.sub(undot, spec)
        try:
            return evaluate(plain, lambda name: self._term(*dotted.get(name, (name, None))))
        except ExpressionError as exc:
            raise DebugError(f"cannot print {spec!r}: {exc}") from None

    def _term(self, name: str, index: int | None) -> int:
        """One name of a `value` expression, read from the module now."""
        spec = name if index is None else f"{name}.{index}"
        if index is None and re.fullmatch(r"ap\d+", name.lower()):   # apP: motor 0
            spec = f"{spec}.0"
        try:
            watch = parse_watch(spec, "print")
        except DebugError:
            return self._parameter(name, index)
        got = watch.read(self.loader)
        if isinstance(got, str):
            raise DebugError(f"{spec} is text ({got}), not a number: print it alone")
        return got

    def _parameter(self, name: str, index: int | None) -> int:
        """An axis parameter (of motor `index`, default 0) or a global parameter by its name."""
        if self.module is None:
            raise DebugError(f"cannot print {name!r}: parameter names need the module's profile")
        axis = self.module.axis(index or 0)     # AxisNumberError for a motor the module lacks
        try:
            return axis.get(name)
        except UnknownParameterError as axis_error:
            try:
                self.module.global_param(name)
            except UnknownParameterError:
                raise DebugError(f"cannot print {name!r}: no register, variable or parameter of "
                                 f"{self.module.name} has that name ({axis_error.args[0]})") from None
        if index is not None:
            raise DebugError(f"cannot print {name}.{index}: {name} is a global parameter, its name implies its bank")
        return self.module.get_global(name)


_DOTTED = re.compile(r"\b([A-Za-z_]\w*)\.(\d+)\b")
"""``NAME.M``: a parameter of motor M or bank M in a `Debugger.value` expression."""
