"""`opentmcl debug PROGRAM`: an interactive, line-oriented TMCL debugger.

The program is downloaded and verified (132/133/134) into the module at --to URL, or into a
virtual module in this process (virtual time: `sleep` and WAITs pass instantly). Commands:

  step [N]          execute N instructions (130); a WAIT is waited out
  next              same as step
  cont              continue to the next breakpoint or, without breakpoints, until STOP
  until LABEL|ADDR  run to a label or address ("run to label")
  break LABEL|ADDR  set a breakpoint (before that instruction runs); `break` lists them
  delete [L|ADDR]   remove one breakpoint, or all
  watch EXPR...     add watches: a x pc flags state varN outN inN adcN posN targetN speedN apP.M gpN[.B]
  unwatch [EXPR]    remove one watch, or all
  info              status, A, X, PC, flags and the watches
  print EXPR        a value now: a watch expression, apP[.M], a parameter name (actual_position,
                    NAME.M for motor M) or an expression of them (a + x, var42 * 2, pos0 - target0)
  list [L|ADDR]     the program around the PC (or an address)
  run [L|ADDR]      start freely (129) from a label/address (default: current)
  stop / reset      128 / 131
  sleep SECONDS     let time pass (virtual modules: instantly)
  set var N VALUE   SGP N, 2, VALUE
  quit              leave (the module keeps its state); so does Ctrl-D (end of input)

Ctrl-C interrupts a running `cont`/`until` and stops the program (128).
"""
from __future__ import annotations

import argparse
import cmd
import contextlib
import shlex
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, TextIO

from ..protocol.opcodes import Op
from . import CliError
from .load import add_connection_options, download, read_program, target_name
from .run import DEFAULT_MODULE, open_target

if TYPE_CHECKING:
    from ..host.debugger import Debugger
    from ..host.loader import AppStatus


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("debug", help="interactive TMCL debugger: breakpoints, stepping, watches",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("program", help="TMCL source (.tmc) or binary (.bin)")
    add_connection_options(p, required=False)
    p.add_argument("--eeprom", help="file-backed EEPROM of the in-process virtual module")
    p.add_argument("--scenario", metavar="FILE", help="physical-world scenario of the in-process module")
    p.add_argument("-w", "--watch", action="append", default=[], metavar="EXPR[,EXPR...]",
                   help="initial watches (repeatable)")
    p.add_argument("-x", "--commands", metavar="FILE", help="read debugger commands from FILE first")
    p.set_defaults(func=run)


class BoundedLines:
    """The shell's stdin when it is not a terminal (a pipe, a file, /dev/zero): lines of at most
    COMMAND_LINE_MAX characters, so an endless line is a one-line error instead of a growing read."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream

    def readline(self) -> str:
        from ..limits import COMMAND_LINE_MAX

        line = self.stream.readline(COMMAND_LINE_MAX + 1)
        if len(line) > COMMAND_LINE_MAX:
            raise CliError(f"a debugger command line on stdin is longer than {COMMAND_LINE_MAX} characters")
        return line


class DebugShell(cmd.Cmd):
    prompt = "(tmcl) "
    intro = "OpenTMCL debugger - type help for the commands, quit (or Ctrl-D) to leave."

    def __init__(self, debugger: Debugger, *, stdin: BoundedLines | None = None,
                 stdout: TextIO | None = None) -> None:
        # cmd.Cmd reads only stdin.readline() when use_rawinput is off, all BoundedLines offers
        super().__init__(stdin=stdin, stdout=stdout)  # type: ignore[arg-type]
        self.dbg = debugger
        if stdin is not None:
            self.use_rawinput = False

    # --- output helpers ---------------------------------------------------------------------
    def say(self, text: str = "") -> None:
        self.stdout.write(text + "\n")
        self.stdout.flush()

    def show_stop(self, st: AppStatus) -> None:
        from ..host.debugger import describe_flags

        where = {0: "stopped", 1: "running", 2: "paused", 3: "reset"}.get(st.mode, str(st.mode))
        self.say(f"[{where}{', waiting' if st.waiting else ''}] {self.dbg.line(st.pc).strip()}")
        self.say(f"  A={st.accumulator} X={st.x_register} PC={st.pc} flags={describe_flags(st.flags)}")
        for name, value in self.dbg.watch_values():
            self.say(f"  {name} = {value}")

    def onecmd(self, line: str) -> bool:
        from ..host import TmclError
        from ..host.debugger import DebugError

        try:
            return super().onecmd(line)
        except (DebugError, TmclError, ValueError) as exc:
            self.say(f"error: {exc}")
        except KeyboardInterrupt:
            self.dbg.loader.stop()
            self.say("interrupted; program stopped")
            self.show_stop(self.dbg.status())
        return False

    def emptyline(self) -> bool:
        return False

    def default(self, line: str) -> None:
        self.say(f"unknown command {line.split()[0]!r}; type help")

    def do_EOF(self, arg: str) -> bool:  # noqa: N802 - cmd.Cmd's name for end of input
        self.say()
        return True

    def get_names(self) -> list[str]:
        """The names `help` lists: end of input (Ctrl-D) is no command to type (`quit` says so)."""
        return [name for name in super().get_names() if name != "do_EOF"]

    # --- commands ---------------------------------------------------------------------------
    def do_quit(self, arg: str) -> bool:
        """quit: leave the debugger (so does Ctrl-D); the module keeps its state"""
        return True

    do_q = do_quit

    def do_step(self, arg: str) -> None:
        """step [N]: execute N instructions (default 1)"""
        n = _number(arg, "step [N]", minimum=1) if arg.strip() else 1
        self.show_stop(self.dbg.step(n))

    do_s = do_step
    do_next = do_step

    def do_cont(self, arg: str) -> None:
        """cont: continue to the next breakpoint, or until the program stops"""
        with _ctrl_c() as pressed:
            st = self.dbg.cont(on_start=lambda: self.say("running (Ctrl-C stops)"), interrupted=pressed)
        if pressed():
            self.say("interrupted; program stopped")
        self.show_stop(st)

    do_c = do_cont

    def do_until(self, arg: str) -> None:
        """until LABEL|ADDR: run to a label or address"""
        if not arg.strip():
            self.say("usage: until LABEL|ADDR")
            return
        self.show_stop(self.dbg.until(arg))

    def do_break(self, arg: str) -> None:
        """break [LABEL|ADDR]: set a breakpoint, or list them"""
        if not arg.strip():
            for addr in sorted(self.dbg.breakpoints):
                self.say(self.dbg.line(addr))
            if not self.dbg.breakpoints:
                self.say("no breakpoints")
            return
        addr = self.dbg.address(arg)
        self.dbg.breakpoints.add(addr)
        self.say(f"breakpoint at {addr} {self.dbg.where(addr)}".rstrip())

    do_b = do_break

    def do_delete(self, arg: str) -> None:
        """delete [LABEL|ADDR]: remove a breakpoint, or all"""
        if arg.strip():
            self.dbg.breakpoints.discard(self.dbg.address(arg))
        else:
            self.dbg.breakpoints.clear()

    def do_watch(self, arg: str) -> None:
        """watch EXPR...: watch values (a x pc flags state varN outN inN adcN posN targetN speedN apP.M gpN[.B])"""
        from ..host.debugger import parse_watches

        if not arg.strip():
            for name, value in self.dbg.watch_values():
                self.say(f"  {name} = {value}")
            return
        self.dbg.watches.extend(parse_watches(arg))
        for name, value in self.dbg.watch_values():
            self.say(f"  {name} = {value}")

    def do_unwatch(self, arg: str) -> None:
        """unwatch [EXPR]: remove a watch, or all"""
        name = arg.strip().lower()
        self.dbg.watches[:] = [w for w in self.dbg.watches if name and w.name != name]

    def do_info(self, arg: str) -> None:
        """info: status, registers, flags and watches"""
        self.show_stop(self.dbg.status())

    do_i = do_info

    def do_print(self, arg: str) -> None:
        """print EXPR: a value now: a watch expression, apP[.M], a parameter name (NAME.M: motor M), or numbers and those with + - * / % & | ^ ~ << >> ( )"""
        self.say(f"{arg.strip()} = {self.dbg.value(arg)}")

    do_p = do_print

    def do_list(self, arg: str) -> None:
        """list [LABEL|ADDR]: program listing around the PC or an address"""
        center = self.dbg.address(arg) if arg.strip() else self.dbg.status().pc
        end = len(self.dbg.instructions) or center + 1
        for addr in range(max(0, center - 3), min(end, center + 7)):
            marker = ">" if addr == center else " "
            self.say(marker + self.dbg.line(addr))

    do_l = do_list

    def do_run(self, arg: str) -> None:
        """run [LABEL|ADDR]: run freely (129) from a label/address or the current PC"""
        self.dbg.loader.run(self.dbg.address(arg) if arg.strip() else None)
        self.say("running")

    def do_stop(self, arg: str) -> None:
        """stop: stop the program (128)"""
        self.dbg.loader.stop()
        self.show_stop(self.dbg.status())

    def do_reset(self, arg: str) -> None:
        """reset: reset the program (131): PC, stack, A, X and flags to 0"""
        self.dbg.loader.reset()
        self.show_stop(self.dbg.status())

    def do_sleep(self, arg: str) -> None:
        """sleep SECONDS: let time pass"""
        try:
            seconds = float(arg)
        except ValueError:
            raise ValueError("usage: sleep SECONDS (a number >= 0)") from None
        if not 0 <= seconds < float("inf"):
            raise ValueError("seconds must be a finite number >= 0")
        self.dbg.loader.client.sleep(seconds)
        self.show_stop(self.dbg.status())

    def do_set(self, arg: str) -> None:
        """set var N VALUE: set a user variable (SGP N, 2, VALUE)"""
        parts = shlex.split(arg)
        if len(parts) != 3 or parts[0] != "var":
            self.say("usage: set var N VALUE")
            return
        number = _number(parts[1], "set var N VALUE", minimum=0)
        value = _number(parts[2], "set var N VALUE")
        self.dbg.loader.request(Op.SGP, number, 2, value)
        self.say(f"var{number} = {value}")


@contextlib.contextmanager
def _ctrl_c() -> Iterator[Callable[[], bool]]:
    """While a program runs freely, Ctrl-C (SIGINT) only sets a flag that the run loop reads: the
    module is never interrupted in the middle of a request. Yields a callable: was it pressed?"""
    pressed = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield pressed.is_set
        return
    previous = signal.signal(signal.SIGINT, lambda *_: pressed.set())
    try:
        yield pressed.is_set
    finally:
        signal.signal(signal.SIGINT, previous)


def _number(text: str, usage: str, minimum: int | None = None) -> int:
    """An integer argument (decimal or 0x...), else ValueError with the command's usage."""
    from ..limits import LITERAL_DIGITS_MAX

    digits = text.strip().lstrip("+-")
    if len(digits) > LITERAL_DIGITS_MAX + 2:
        raise ValueError(f"number of {len(digits)} characters is too long; usage: {usage}")
    try:
        value = int(text.strip(), 0)
    except ValueError:
        raise ValueError(f"{text.strip()!r} is not a number; usage: {usage}") from None
    if minimum is not None and value < minimum:
        raise ValueError(f"{value} is out of range (>= {minimum}); usage: {usage}")
    return value


def _command_lines(path: str) -> list[str]:
    """The -x FILE, read whole before the first command runs: a bad file is a one-line error."""
    from ..limits import TEXT_MAX, InputTooLarge, read_text

    try:
        return read_text(path, TEXT_MAX, "debugger command file").splitlines()
    except InputTooLarge as exc:
        raise CliError(f"{path}: {exc}") from None
    except OSError as exc:
        raise CliError(f"cannot read {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise CliError(f"{path}: debugger commands must be UTF-8 text") from None


def run(args: argparse.Namespace) -> int:
    from ..host import TmclError
    from ..host.debugger import DebugError, Debugger, parse_watches
    from ..host.loader import Loader

    commands = _command_lines(args.commands) if args.commands else []
    client, name = open_target(args)
    try:
        module = client.module(args.address, name)
        if name is None:
            name = target_name(module, args.module, args.program, args.strict)
        program = read_program(args.program, name or args.module or DEFAULT_MODULE, args.include, strict=args.strict)
        loader = Loader(module)
        try:
            download(loader, program.instructions)
            loader.reset()
            specs = [s for item in args.watch for s in item.split(",") if s.strip()]
            dbg = Debugger(loader, program.instructions, program.labels, program.source,
                           watches=parse_watches(specs), module=module)
        except (TmclError, DebugError) as exc:
            raise CliError(str(exc)) from None
        shell = DebugShell(dbg, stdin=None if sys.stdin.isatty() else BoundedLines(sys.stdin))
        print(f"loaded {len(program.instructions)} instructions from {program.filename}, verified")
        for line in commands:
            if shell.onecmd(line.strip()):
                return 0
        try:
            shell.cmdloop()
        except KeyboardInterrupt:
            print(file=sys.stderr)
    finally:
        client.close()
    return 0
