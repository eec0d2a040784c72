"""What the dashboard does on a module, through the host library's `Module` API.

Everything goes over the wire (GAP/SAP, GGP/SGP, SIO/GIO, 128-135 for the program; TMCM-6212
manual 3.6), so the same service drives a real module (`opentmcl dashboard --to URL`) and a
virtual one (`opentmcl serve --web`). Only forcing inputs needs the in-process virtual module
(`vm`), because a real module's inputs are driven by wires, not by commands.

A `Poller` thread samples position and velocity of every axis (the fast set) and, less often,
the rest of the axis state and the program status; the web layer reads the samples.

Every request takes a turn on the link (web/link.py): stops go first, and nothing holds the link
for more than a short batch, except a download from 132 to 133, which a stop ends.
"""
from __future__ import annotations

import contextlib
import itertools
import logging
import re
import threading
import time
from collections import deque
from dataclasses import dataclass

from ..handover import STOP
from ..host import Module, TmclError, TmclStatusError, VersionReply
from ..protocol.frame import Reply
from ..protocol.opcodes import COMMANDS, GLOBAL_PARAMETER, STOP_COMMANDS, Op
from ..protocol.status import message
from .link import TURN_REQUESTS, LinkLoader, LinkModule, link_gate

log = logging.getLogger("opentmcl.web")

FAST_HZ = 25            # position/velocity samples per second (issue 7: at least 20)
HISTORY_SECONDS = 60.0  # samples kept for the live charts
SLOW_EVERY = 5          # full axis state and program status every 5th sample (5 per second)
USER_VARIABLES_SHOWN = 8  # variables 0..7 are always shown, plus those the program uses

# Axis parameters of the axis cards (TMCM-6212 manual 4.1, PD86-1180 manual 5).
CARD_PARAMS = {"target_position": 0, "position": 1, "velocity": 3, "target_reached": 8, "home": 9,
               "right": 10, "left": 11, "load": 206, "current": 180, "max_current": 6}
# plain ints for the requests, which `Client.request` keeps ready to send
_SAP, _GAP, _SGP, _GGP = int(Op.SAP), int(Op.GAP), int(Op.SGP), int(Op.GGP)
_SIO, _GIO = int(Op.SIO), int(Op.GIO)
READ_COMMANDS = {"axis": _GAP, "global": _GGP, "io": _GIO}
"""The command that reads a value of each kind: GAP, GGP, GIO (TMCM-6212 manual 3.6.6, 3.6.8, 3.6.13)."""
USER_BANK = 2


def _names_a_global(command: int, type: int) -> bool:
    """SGP, GGP, STGP, RSGP, AGP: with bank 2 they name a user variable (protocol meanings)."""
    cmd = COMMANDS.get(command)
    return cmd is not None and cmd.naming(GLOBAL_PARAMETER, type) is not None


def _short(text: str, limit: int = 200) -> str:
    """One line of at most `limit` characters (an error must not echo a megabyte of input)."""
    text = " ".join(text.split())
    return text if len(text) <= limit else text[:limit] + "..."


_INCLUDE_RE = re.compile(r"\s*#\s*include\b(.*)", re.IGNORECASE)


def _file_include(source: str) -> int | None:
    """The first line whose #include names a path (a separator, "..", "~") instead of a bundled
    file: the page must not read files on the dashboard's machine. Names are read as the
    assembler reads them ("name", <name> or up to a // comment)."""
    for number, line in enumerate(source.removeprefix("\ufeff").splitlines(), 1):
        m = _INCLUDE_RE.match(line)
        if not m:
            continue
        arg = m.group(1).strip()
        if arg[:1] in ('"', "<"):
            end = arg.find('"' if arg[0] == '"' else ">", 1)
            name = arg[1:end] if end > 0 else arg[1:]
        else:
            name = arg.split("//")[0]
        if any(mark in name for mark in ("/", "\\", "..", "~", "\0")):
            return number
    return None


class DashboardError(ValueError):
    """A request from the page the module or the profile does not allow (shown to the user)."""


class Stopping(DashboardError):
    """The dashboard stops: work of many requests ends at its next one (`Dashboard.closed`)."""


@dataclass
class Sample:
    seq: int
    t: float
    position: list[int | None]
    velocity: list[int | None]


def _param_info(p, axis_or_bank) -> dict:
    return {"number": p.number, "name": p.name, "title": p.title, "unit": p.unit, "min": p.min, "max": p.max,
            "access": p.access, "description": p.description, "values": list(p.values), "excluded": list(p.excluded),
            "bank": p.bank if p.bank is not None else axis_or_bank, "writable": p.writable,
            "readable": p.readable, "storable": p.storable}


def is_stop(line: str) -> bool:
    """Whether a console line is a stop command (MST, 128, 131: web/link.py STOP_COMMANDS)."""
    from ..lang.direct import parse_direct

    try:
        return parse_direct(line.strip())[0] in STOP_COMMANDS
    except ValueError:  # InstructionError too: the console answers it
        return False


class Dashboard:
    """The dashboard's view of one module. Thread-safe: each request takes a turn on the link's
    gate (`lock`, shared by every dashboard on the same host `Client`; web/link.py)."""

    def __init__(self, module: Module, *, vm=None, vm_lock=None, url: str = "",
                 clock=time.monotonic) -> None:
        self.lock = link_gate(module.client)
        self.module = LinkModule(module, self.lock)  # the same client; requests take turns
        self.vm = vm
        self.faults = getattr(module.client.transport, "faults", None)
        """The armed faults of the link (`opentmcl serve --faults`, sim://...?faults=): web/faults.py."""
        self.vm_lock = vm_lock if vm_lock is not None else threading.RLock()
        self.url = url
        self.clock = clock
        self._state_seq = itertools.count(1)   # orders program states read at different times
        self.start = clock()
        self.connected = True
        self.last_error = ""
        self.samples: deque[Sample] = deque(maxlen=int(HISTORY_SECONDS * FAST_HZ) + FAST_HZ)
        self.seq = 0
        self.state: dict = {}
        self.program = None          # lang Program last assembled/downloaded
        self.source = ""
        self.breakpoints: set[int] = set()
        self._runner: threading.Thread | None = None
        self._cancel = threading.Event()
        self.abort_download = threading.Event()  # set by stop-all: a download ends at its next instruction
        self.downloading: tuple[int, int] | None = None  # (instructions sent, of) while a download runs
        self.stops = 0  # STOP ALLs so far: a Run or Step that arrived before the last one is refused
        self.closed = threading.Event()  # set by stop(): live connections end
        self.units: dict[int, dict] = {}  # unit setting per axis (web/units.py), kept with the export
        self.profile = self.module.profile
        self.version = self.attempt(self.module.firmware_version, "?")

    # --- plumbing --------------------------------------------------------------------
    def attempt(self, fn, default=None):
        """Call fn(); a failing link marks the module disconnected and gives `default`."""
        try:
            out = fn()
            self.connected = True
            return out
        except TmclStatusError:
            return default
        except TmclError as exc:
            self.connected = False
            self.last_error = str(exc)
            return default

    def read_many(self, requests: list[tuple[int, int, int, int]]) -> list[int | None]:
        """The values of several reads (GAP/GGP/GIO) in `request_many` batches of
        `TURN_REQUESTS` (one turn on the link each), in order: None for a read the module refused
        (its status) and for all of a batch when the link failed. DashboardError once the
        dashboard stops (a table or an export of many axes ends at its next batch)."""
        out: list[int | None] = []
        for start in range(0, len(requests), TURN_REQUESTS):
            if self.closed.is_set():
                raise Stopping("the dashboard is stopping")
            batch = requests[start:start + TURN_REQUESTS]

            def run(batch: list[tuple[int, int, int, int]] = batch) -> list[int | None]:
                answers: list[object]
                try:
                    answers = list(self.module.request_many(batch))
                except TmclStatusError as exc:  # the others were read: keep their values
                    answers = list(exc.answers or [None] * len(batch))
                return [a.value if isinstance(a, Reply) else None for a in answers]

            out += self.attempt(run, [None] * len(batch))
        return out

    @contextlib.contextmanager
    def _user_action(self):
        """Errors of a user action: a status error becomes DashboardError with the manual's text; a
        lost link also marks the module unreachable; an operand that does not fit the frame (8-bit
        type/motor, 32-bit value) is a DashboardError too."""
        try:
            yield
        except TmclStatusError as exc:
            raise DashboardError(str(exc)) from None
        except ValueError as exc:  # before TmclError: TmclValueError is both, the link is fine
            raise DashboardError(str(exc)) from None
        except TmclError as exc:
            self.connected = False
            self.last_error = str(exc)
            raise DashboardError(str(exc)) from None

    def act(self, fn):
        """Call fn() for a user action (errors: `_user_action`); its requests take their turns."""
        with self._user_action():
            out = fn()
            self.connected = True
            return out

    def _unless_stopped(self, since: int | None, fn):
        """fn() in one turn on the link, unless a STOP ALL came after the request arrived (`since`:
        `stops` at its arrival). In one turn, so STOP ALL's 128 cannot come between check and send."""
        with self._user_action():
            with self.lock:
                if since is not None and since != self.stops:
                    raise DashboardError("cancelled by STOP ALL")
                out = fn()
            self.connected = True
            return out

    def check_axis(self, number) -> int:
        if isinstance(number, bool) or not isinstance(number, int) or not 0 <= number < self.profile.axes:
            raise DashboardError(f"{self.profile.name} has axes 0..{self.profile.axes - 1}, not {number!r}")
        return number

    # --- overview ------------------------------------------------------------------------
    def overview(self) -> dict:
        from .setup import reference_modes

        p = self.profile
        ports = [{"bank": io.bank, "port": io.port, "name": io.name, "kind": io.kind, "access": io.access,
                  "min": io.min, "max": io.max} for io in sorted(p.io.values(), key=lambda i: (i.bank, i.port))]
        return {"module": p.name, "version": self.version, "address": self.module.address, "url": self.url,
                "axes": p.axes, "connected": self.connected, "last_error": self.last_error,
                "virtual": self.vm is not None, "io": ports, "fast_hz": FAST_HZ,
                "history_seconds": HISTORY_SECONDS,
                "velocity_unit": getattr(p.axis_parameters.get(3), "unit", "") or "pps",
                "has_stap": Op.STAP in p.opcodes, "has_rsap": Op.RSAP in p.opcodes, "has_stgp": Op.STGP in p.opcodes,
                "program_memory": p.program_memory, "reference_modes": reference_modes(p),
                "capabilities": {"encoder": p.capabilities.encoder, "encoder_counts": p.capabilities.encoder_counts,
                                 "null_channel": p.capabilities.null_channel,
                                 "reference_input": p.capabilities.reference_input}}

    # --- sampling --------------------------------------------------------------------------
    def sample_fast(self) -> Sample:
        """Position (axis parameter 1) and actual speed (3) of every axis."""
        values = self.read_many([(_GAP, n, ax, 0) for ax in range(self.profile.axes) for n in (1, 3)])
        pos, vel = values[0::2], values[1::2]
        self.seq += 1
        s = Sample(self.seq, round(self.clock() - self.start, 4), pos, vel)
        self.samples.append(s)
        return s

    def sample_slow(self) -> dict:
        """Axis cards, outputs/inputs and program status."""
        have = self.profile.axis_parameters
        shown = [num for num in CARD_PARAMS.values() if num in have]
        values = iter(self.read_many([(_GAP, num, ax, 0) for ax in range(self.profile.axes) for num in shown]))
        axes = [{key: next(values) if num in have else None for key, num in CARD_PARAMS.items()}
                for _ in range(self.profile.axes)]
        state = {"axes": axes, "io": self.read_io(), "program": self.program_state(),
                 "connected": self.connected, "last_error": self.last_error}
        self.state = state
        return state

    def samples_since(self, seq: int) -> list[Sample]:
        return [s for s in list(self.samples) if s.seq > seq]

    # --- parameters -------------------------------------------------------------------------
    def axis_parameters(self, axis: int) -> list[dict]:
        """The axis parameter table of `axis` with its values (GAP, read in batches)."""
        axis = self.check_axis(axis)
        params = sorted(self.profile.axis_parameters.values(), key=lambda p: p.number)
        values = iter(self.read_many([(_GAP, p.number, axis, 0) for p in params if p.readable]))
        out = []
        for p in params:
            row = _param_info(p, axis)
            row["value"] = next(values) if p.readable else None
            row["can_store"] = p.storable and Op.STAP in self.profile.opcodes
            row["can_restore"] = p.storable and Op.RSAP in self.profile.opcodes
            out.append(row)
        return out

    def global_parameters(self) -> list[dict]:
        """The global parameter table with its values (GGP, read in batches)."""
        params = sorted(self.profile.global_parameters.items())
        values = iter(self.read_many([(_GGP, num, bank, 0) for (bank, num), p in params if p.readable]))
        out = []
        for (bank, _num), p in params:
            row = _param_info(p, bank)
            row["value"] = next(values) if p.readable else None
            row["can_store"] = p.storable and Op.STGP in self.profile.opcodes
            row["can_restore"] = p.storable and Op.RSGP in self.profile.opcodes
            out.append(row)
        return out

    def set_axis_parameter(self, axis: int, number: int, value: int) -> int:
        """SAP, then GAP to show what the module took (manual 3.6.5/3.6.6)."""
        axis = self.check_axis(axis)
        p = self.profile.axis_parameters.get(number)
        if p is None or not p.writable:
            raise DashboardError(f"axis parameter {number} is not writable on {self.profile.name}")
        self.act(lambda: self.module.request(_SAP, number, axis, int(value)))
        return self.act(lambda: self.module.reply(_GAP, number, axis).value) if p.readable else int(value)

    def set_global_parameter(self, bank: int, number: int, value: int) -> int:
        p = self.profile.global_parameters.get((bank, number))
        if p is None or not p.writable:
            raise DashboardError(f"global parameter {number} of bank {bank} is not writable on {self.profile.name}")
        self.act(lambda: self.module.request(_SGP, number, bank, int(value)))
        return self.act(lambda: self.module.reply(_GGP, number, bank).value) if p.readable else int(value)

    def store(self, kind: str, number: int, axis_or_bank: int, restore: bool = False) -> None:
        """STAP/RSAP (axis) or STGP/RSGP (global), manual 3.6.7-3.6.10 / PD86-1180 4.6.7-4.6.8."""
        if kind == "axis":
            command = int(Op.RSAP if restore else Op.STAP)
            axis_or_bank = self.check_axis(axis_or_bank)
        elif kind == "global":
            command = int(Op.RSGP if restore else Op.STGP)
        else:
            raise DashboardError(f"unknown parameter kind {kind!r}")
        if command not in self.profile.opcodes:
            raise DashboardError(f"{self.profile.name} has no command {command} (store/restore)")
        self.act(lambda: self.module.request(command, number, axis_or_bank))

    # --- direct mode console ---------------------------------------------------------------
    def console(self, line: str) -> dict:
        """One instruction as in `opentmcl send` (mnemonic or numbers); the reply with its status text."""
        from ..lang.direct import InstructionError, parse_direct
        from ..protocol.opcodes import format_instruction
        from ..protocol.replies import MemoryReply

        text = line.strip()
        if not text:
            raise DashboardError("empty command")
        try:
            command, type_, motor, value = parse_direct(text)
        except InstructionError as exc:
            raise DashboardError(_short(str(exc))) from None
        except ValueError as exc:  # a number the parser cannot convert (e.g. 5000 digits)
            raise DashboardError(_short(f"{_short(text, 40)}: {exc}")) from None
        out: dict[str, object] = {"line": text, "request": [command, type_, motor, value]}
        try:
            reply = self.module.request(command, type_, motor, value)  # a stop goes first (link.py)
        except TmclStatusError as exc:
            out.update(ok=False, status=exc.status, text=f"status {exc.status}: {message(exc.status)}")
            return out
        except ValueError as exc:  # e.g. "300, 0, 0, 0": command must be 0..255 (a TmclValueError)
            raise DashboardError(f"{text!r}: {exc}") from None
        except TmclError as exc:
            out.update(ok=False, status=None, text=str(exc))
            return out
        if reply is None:
            out.update(ok=True, status=None, text="(no reply)")
        elif isinstance(reply, VersionReply):
            out.update(ok=True, status=100, value=reply.text, text=f"status 100: {message(100)}; {reply.text}")
        elif isinstance(reply, MemoryReply):
            ins = (reply.command, reply.type, reply.motor, reply.value)
            shown = format_instruction(*ins) or ", ".join(map(str, ins))
            out.update(ok=True, status=100, value=list(ins), text=f"{shown}")
        else:
            out.update(ok=True, status=reply.status, value=reply.value,
                       text=f"status {reply.status}: {message(reply.status)}; value {reply.value}")
        return out

    # --- inputs and outputs -----------------------------------------------------------------
    def read_io(self) -> list[dict]:
        out = []
        forced = self._forced()
        ports = sorted(self.profile.io.values(), key=lambda i: (i.bank, i.port))
        values = iter(self.read_many([(_GIO, io.port, io.bank, 0) for io in ports if "R" in io.access]))
        for io in ports:
            value = next(values) if "R" in io.access else None
            out.append({"bank": io.bank, "port": io.port, "name": io.name, "kind": io.kind, "value": value,
                        "forced": forced.get((io.bank, io.port))})
        return out

    def _forced(self) -> dict:
        if self.vm is None:
            return {}
        with self.vm_lock:
            return dict(getattr(self.vm.io, "forced", {}))

    def set_output(self, bank: int, port: int, value: int) -> int:
        io = self.profile.io.get((bank, port))
        if io is None or io.kind != "output":
            raise DashboardError(f"no output port {port} in bank {bank}")
        self.act(lambda: self.module.request(_SIO, port, bank, int(value)))
        return self.act(lambda: self.module.reply(_GIO, port, bank).value)

    def force_input(self, bank: int, port: int, value: int | None) -> None:
        """Virtual modules only: hold an input at `value` (None releases it). No TMCL command
        sets an input, so this reaches into the in-process module (docs/assumptions.md)."""
        if self.vm is None:
            raise DashboardError("inputs can only be forced on a virtual module")
        io = self.profile.io.get((bank, port))
        if io is None or io.kind == "output":
            raise DashboardError(f"no input port {port} in bank {bank}")
        if value is not None and not io.min <= int(value) <= io.max:
            raise DashboardError(f"{io.name} takes {io.min}..{io.max}, not {value}")
        with self.vm_lock:
            if value is None:
                self.vm.io.forced.pop((bank, port), None)
            else:
                self.vm.io.forced[(bank, port)] = int(value)

    # --- TMCL program -----------------------------------------------------------------------
    def assemble(self, source: str) -> dict:
        """Assemble for this module: every error and warning (what this module cannot execute) with
        file, line, column and severity, in source order (docs/dashboard-program.md)."""
        from ..lang import AsmError, assemble

        where = _file_include(source)
        if where is not None:
            bad = {"file": "<editor>", "line": where, "column": 1, "severity": "error", "message":
                   "the dashboard includes only the bundled files (#include <tmcm6212.inc>), not paths"}
            return {"ok": False, "errors": [bad], "warnings": [], "diagnostics": [bad], "more": 0}
        try:
            prog = assemble(source, filename="<editor>", module=self.profile)  # a profile file's too
        except AsmError as exc:
            return {"ok": False, "errors": [d.as_dict() for d in exc.errors],
                    "warnings": [d.as_dict() for d in exc.warnings],
                    "diagnostics": [d.as_dict() for d in exc.diagnostics()], "more": exc.more + exc.warnings_more}
        lines = [src.line if src is not None and src.file == "<editor>" else None for src in prog.source]
        warnings = [d.as_dict() for d in prog.warnings]
        return {"ok": True, "errors": [], "warnings": warnings, "diagnostics": warnings, "more": prog.warnings_more,
                "count": len(prog.instructions), "lines": lines, "labels": prog.labels, "listing": prog.listing(),
                "_program": prog}

    def download(self, source: str) -> dict:
        """Assemble, stop the program, download with verify (132, ..., 133, 134), then reset (131):
        the manuals give 132/133 no effect on the program counter and Run (129 type 0) goes on "from
        current address", so without the reset a freshly downloaded program would start wherever the
        last one stopped (docs/dashboard-program.md)."""
        from ..host.loader import LoaderError

        result = self.assemble(source)
        if not result["ok"]:
            return result
        prog = result.pop("_program")
        self.cancel_run()

        def abort_point(done: int, total: int) -> None:
            self.downloading = (done, total)
            if self.abort_download.is_set():
                raise DashboardError("download cancelled by STOP ALL (download mode left with 133)")
            if self.lock.stops_waiting:
                raise DashboardError("download cancelled by a stop command (download mode left with 133)")
            if self.closed.is_set():
                raise Stopping("download cancelled: the dashboard is stopping (download mode left with 133)")

        def closing(_done: int, _total: int) -> None:
            if self.closed.is_set():
                raise Stopping("verify cancelled: the dashboard is stopping")
        loader = self.loader()
        try:
            # One turn from 132 to 133: a command sent meanwhile would be stored, not executed
            # (manual 3.6.36). A stop ends it between two instructions; verifying (134) takes turns.
            try:
                with self.lock:
                    loader.download(prog.instructions, verify=False, progress=abort_point)
            finally:
                self.downloading = None
            loader.verify(prog.instructions, progress=closing)
            loader.reset()  # 131: program counter, stack, A, X and flags to zero (TMCM-6212 3.6.36)
        except LoaderError as exc:
            raise DashboardError(str(exc)) from None
        except TmclError as exc:
            raise DashboardError(str(exc)) from None
        self.program, self.source = prog, source
        self.breakpoints = {b for b in self.breakpoints if b < len(prog.instructions)}
        return result

    def loader(self) -> LinkLoader:
        return LinkLoader(self.module)

    def set_breakpoints(self, lines: list[int]) -> list[int]:
        """Breakpoints by editor line: the first instruction assembled from each line."""
        if self.program is None:
            raise DashboardError("download a program first")
        lines = set(lines)
        addrs = set()
        for addr, src in enumerate(self.program.source):
            if src is not None and src.file == "<editor>" and src.line in lines:
                if not any(a < addr and self.program.source[a] is not None
                           and self.program.source[a].line == src.line for a in addrs):
                    addrs.add(addr)
        self.breakpoints = addrs
        return sorted(addrs)

    def run(self, since: int | None = None) -> None:
        """129 from the current address; with breakpoints, single-step (130) in a thread until the
        program counter reaches one (host-side breakpoints, as `opentmcl debug` does). `since`:
        `stops` when the request arrived (a STOP ALL after it refuses the Run)."""
        self.cancel_run()
        if not self.breakpoints:
            self._unless_stopped(since, lambda: self.loader().run())
            return
        self._unless_stopped(since, self._start_runner)

    def run_from_start(self, since: int | None = None) -> None:
        """Reset (131: "Reset program counter and stack pointer to zero. Reset accumulator and X
        register to zero. Reset all flags.", TMCM-6212 3.6.36), then Run as `run` does: the program
        from its first instruction, whatever it did before."""
        self.cancel_run()
        self._unless_stopped(since, lambda: self.loader().reset())
        self.run(since)

    def _start_runner(self) -> None:
        """The host-side stepping thread (called under the lock: a STOP ALL's cancel comes after)."""
        self._cancel.clear()
        self._runner = threading.Thread(target=self._run_to_breakpoint, name="dashboard-run", daemon=True)
        self._runner.start()

    def _run_to_breakpoint(self) -> None:
        from ..host.debugger import Debugger

        dbg = Debugger(self.loader())
        while not self._cancel.is_set():
            try:
                # Each request its own turn: a stepped WAIT takes a while and the charts go on meanwhile.
                st = dbg.step()
            except TmclError as exc:
                self.last_error = str(exc)
                return
            if st.mode in (0, 3) or st.pc in self.breakpoints:
                return

    @property
    def runner(self) -> threading.Thread | None:
        """The host-side stepping thread of a Run to a breakpoint (None when none was started)."""
        return self._runner

    def halt_stepping(self) -> bool:
        """End the host-side stepping to a breakpoint after its current step; True when it ran."""
        runner = self._runner
        self._cancel.set()
        return runner is not None and runner.is_alive()

    def cancel_run(self) -> None:
        self._cancel.set()
        runner = self._runner
        if runner is not None and runner is not threading.current_thread():
            runner.join(timeout=5.0)
        self._runner = None

    def stop(self) -> dict:
        """128, then the program state, both as a stop: ahead of other requests on the link."""
        self.cancel_run()
        with self.lock.hold(STOP):
            self.act(lambda: self.loader().stop())
            return self.program_state()

    def step(self, since: int | None = None) -> dict:
        """130 and the instruction waited out; `since` as for `run`."""
        from ..host.debugger import Debugger

        self.cancel_run()
        loader = self.loader()
        self._unless_stopped(since, loader.step)
        with self._user_action():
            Debugger(loader).after_step()  # requests in turns, see _run_to_breakpoint
        return self.program_state()

    def reset(self) -> dict:
        """131, then the program state, both as a stop (see `stop`)."""
        self.cancel_run()
        with self.lock.hold(STOP):
            self.act(lambda: self.loader().reset())
            return self.program_state()

    def program_state(self) -> dict:
        """Mode, PC (135 type 1), A (type 2), X (type 3), flags (type 4) and the user variables."""
        from ..host.debugger import describe_flags

        seq = next(self._state_seq)   # taken before the read: a later state has a larger number
        st = self.attempt(lambda: self.loader().status())
        if st is None:
            return {"mode": None}
        line = None
        prog = self.program
        if prog is not None and 0 <= st.pc < len(prog.source):
            src = prog.source[st.pc]
            if src is not None and src.file == "<editor>":
                line = src.line
        shown = self._variables_shown()
        variables = dict(zip(shown, self.read_many([(_GGP, n, USER_BANK, 0) for n in shown]), strict=True))
        return {"seq": seq, "mode": st.mode, "mode_name": st.mode_name, "waiting": st.waiting, "pc": st.pc, "line": line,
                "a": st.accumulator, "x": st.x_register, "flags": describe_flags(st.flags),
                "variables": variables, "breakpoints": sorted(self.breakpoints),
                "stepping_to_breakpoint": self._runner is not None and self._runner.is_alive()}

    def _variables_shown(self) -> list[int]:
        shown = set(range(min(USER_VARIABLES_SHOWN, self.profile.user_variables)))
        if self.program is not None:
            for ins in self.program.instructions:
                if ins.motor == USER_BANK and _names_a_global(ins.command, ins.type):
                    if 0 <= ins.type < self.profile.user_variables:
                        shown.add(ins.type)
        return sorted(shown)


class Poller:
    """Background sampling: `FAST_HZ` fast samples per second, a slow one every `SLOW_EVERY`."""

    def __init__(self, dashboard: Dashboard, hz: float = FAST_HZ) -> None:
        self.dashboard = dashboard
        self.period = 1.0 / hz
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="dashboard-poller", daemon=True)

    def start(self) -> Poller:
        self._thread.start()
        return self

    def _loop(self) -> None:
        n = 0
        next_t = time.monotonic()
        while not self._stop.is_set():
            try:
                self.dashboard.sample_fast()
                if n % SLOW_EVERY == 0:
                    self.dashboard.sample_slow()
            except Stopping:
                return
            except Exception:  # a bug must not stop the charts; link errors are handled in Dashboard
                log.exception("dashboard sampling failed")
            n += 1
            next_t += self.period
            delay = next_t - time.monotonic()
            if delay < 0:  # fell behind (slow link): do not try to catch up
                next_t = time.monotonic()
                delay = 0
            self._stop.wait(delay)

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
