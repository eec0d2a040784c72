"""Virtual modules on one bus, in real time (docs/architecture.md "Time": real time).

`ModuleBus` owns one or more virtual modules that share a bus, as several
modules share one RS-485 line or CAN bus (TMCM-6212 manual 3: "any collision
on the bus will be avoided when there are more than two nodes connected to a
single bus"). Every access goes through one lock, and before each access the
modules' virtual time is advanced to the wall clock, so virtual time is paced
to real time however many endpoints talk to the modules at once.

The modules filter addresses themselves (a module returns b"" for a frame
addressed to another module); to spare that call to every module, a serial
frame goes only to the modules an address map names for its address byte
(RS485 address GP66 and secondary address GP87, TMCM-6212 manual 5.1), the
modules in ASCII mode left out. The map is built again after anything that
may change it: a command that `protocol.opcodes.keeps_addressing` does not keep
(SGP to bank 0, RSGP, command 137, 139, program control), time passing (a TMCL
program may SGP 66), ASCII input, a frame to an address the map does not
know, and a mapped module that stays silent and no longer has the address.
A link that stands for USB (the address byte is ignored) and modules
without `accepts_address` and `globals.get_raw` get every frame, as before.

Time (docs/architecture.md "Real time"): a request brings the modules to the
wall clock when that costs at most `pacing.REQUEST_BUDGET` (without a runner:
by at most one slice of that), and `RealTimeRunner`, the background thread,
simulates the rest in bounded slices
(`pacing.SLICE_BUDGET`), giving the bus to every waiting request between two
of them (`handover`); it also hands unsolicited replies (the command-138
"target position reached" reply, manual 3.6.35) to the endpoint through which
the module was last addressed. Requests that stop motion or a program (MST,
128, 131) take the bus before every other waiting request. When the
simulation cannot keep up, the modules' clock lags (`ModuleBus.clock_report`),
never the replies.
"""
from __future__ import annotations

import inspect
import logging
import math
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from functools import partial
from typing import NamedTuple, Protocol

from ..faults import FaultBoard
from ..handover import BACKGROUND, REQUEST, STOP, HandoverLock
from ..protocol.opcodes import ENTER_DOWNLOAD_MODE, STOP_COMMANDS, keeps_addressing
from . import canmap, vmapi
from .downloads import Downloads
from .pacing import FIRST_SLICE, REQUEST_BUDGET, SLICE_BUDGET, ClockReport, Pacer


class AsciiOutput(NamedTuple):
    """What a module in ASCII mode sends back, and the received bytes it left to binary framing."""

    data: bytes
    leftover: bytes


class Channel(Protocol):
    """An endpoint that can carry unsolicited replies back to its host."""

    interface: str
    """The link the channel stands for: "serial", "rs232" or "rs485" (modules filter by address),
    "usb" (the address byte is ignored, TMCL on USB) or "can"."""

    def deliver(self, vm, reply: bytes) -> None:
        """Send an unsolicited 9-byte reply of `vm` to the host."""


USB = "usb"
"""Channel.interface of a link that ignores the address byte (TMCL over USB)."""
SERIAL_INTERFACES = ("usb", "rs485", "rs232")
"""What a serial endpoint can stand for (`opentmcl serve --pty --interface`)."""


def default_interface(modules, paced: bool = False) -> str:
    """USB when the link carries one module that has a USB port (its profile's capability `usb`),
    RS-485 for a bus of several, a paced line or a module without USB (the PD28-1021, whose manual
    lists RS485 as its interface; docs/endpoints.md)."""
    return USB if len(modules) == 1 and not paced and has_usb(modules[0]) else "rs485"


def has_usb(module) -> bool:
    """Whether a module (a VirtualModule, or the (profile name, address) of an ``opentmcl://`` URL)
    has a USB port: its profile's capability `usb`; True when it has no profile to ask."""
    profile = getattr(module, "profile", None)
    if profile is None and isinstance(module, tuple):
        from ..modules.profile import load_profile
        try:
            profile = load_profile(module[0])
        except (KeyError, ValueError, OSError):
            return True  # the unknown name is reported where the module is made
    return bool(getattr(getattr(profile, "capabilities", None), "usb", True))


def interface_error(interface: str, modules: Sequence[object], paced: bool) -> str | None:
    """Why a serial endpoint cannot stand for `interface` with `modules` (as for
    `default_interface`), or None."""
    if interface not in SERIAL_INTERFACES:
        return f"interface must be one of {', '.join(SERIAL_INTERFACES)}, got {interface!r}"
    if interface == USB and len(modules) != 1:
        return "a USB link carries one module; use rs485 for a bus of several"
    if interface == USB and not has_usb(modules[0]):
        return "the module has no USB port (its profile's capability usb = false); use rs485"
    if interface == USB and paced:
        # GP65 is the "RS485 baud rate" (TMCM-6212 5.1); a module's USB port has no baud rate.
        return "a USB link has no baud rate to pace at (GP65 is the RS485 baud rate); use rs485 or rs232"
    return None


MIN_STEP = 0.002
"""Seconds of wall time below which a request does not advance the modules' clocks: advancing
costs the same however short the step, so a burst of requests shares one advance. The modules
lag the wall clock by at most this much (docs/assumptions.md)."""


ENTER_DOWNLOAD = bytes((ENTER_DOWNLOAD_MODE,))
"""The command byte of 132, which opens a download (server/downloads.py)."""

RUNNING = 1
"""`application_status` of a module whose TMCL program runs (firmware/program.py; TMCM-6212
manual 3.6.36, command 135): only a running program can change an address while time passes."""

def _changes_map(frame: bytes) -> bool:
    """Can the module that handled `frame` have changed its address (GP66/GP87) or mode?"""
    return not keeps_addressing(frame[1], frame[3])


def urgency(data: bytes) -> int:
    """`handover.STOP` when received bytes hold a request that stops motion or a program (a command
    byte of `STOP_COMMANDS` at a frame position), else `handover.REQUEST`."""
    for command in data[1::9]:
        if command in STOP_COMMANDS:
            return STOP
    return REQUEST


def _mappable(vm) -> bool:
    return callable(getattr(vm, "accepts_address", None)) and callable(
        getattr(getattr(vm, "globals", None), "get_raw", None))


def _takes_interface(vm) -> bool:
    try:
        return "interface" in inspect.signature(vm.handle).parameters
    except (TypeError, ValueError):
        return False


def _bound_handle(vm, takes: bool, interface: str):
    """`vm.handle` for frames of `interface`: the bound method itself when that is its default
    (no keyword to pass on the hot path), else with the keyword bound."""
    if not takes:
        return vm.handle
    try:
        default = inspect.signature(vm.handle).parameters["interface"].default
    except (TypeError, ValueError, KeyError):
        default = None
    return vm.handle if default == interface else partial(vm.handle, interface=interface)


class ModuleBus:
    """Virtual modules sharing one bus; thread-safe; time paced to `clock`."""

    faults: FaultBoard | None = None
    """The fault plan the bus is served with (`Server(faults=...)`): its links take their link
    faults from it (server/linkfaults.py)."""

    def __init__(self, modules: Iterable, *, clock: Callable[[], float] = time.monotonic,
                 min_step: float = MIN_STEP, pacer: Pacer | None = None) -> None:
        self.modules = list(modules)
        if not self.modules:
            raise ValueError("a bus needs at least one module")
        if min_step < 0:
            raise ValueError("min_step must not be negative")
        self.lock = HandoverLock()
        self._clock = clock
        self.pacer = Pacer(clock) if pacer is None else pacer
        self.min_step = min_step
        self._route: dict[int, Channel] = {}
        self._interface_kw = {id(vm): _takes_interface(vm) for vm in self.modules}
        # (module, its handle() for serial / USB frames) looked up once: the per-frame path is hot.
        self._serial_handlers, self._usb_handlers = (
            [(vm, id(vm), _bound_handle(vm, self._interface_kw[id(vm)], interface))
             for vm in self.modules] for interface in ("serial", USB))
        self._map: dict[int, list] | None = None  # address byte -> [(vm, key, handle)], built on use
        self._always = [entry for entry in self._serial_handlers if not _mappable(entry[0])]
        self.downloads = Downloads(clock)
        """Which link each open program download belongs to (server/downloads.py)."""
        self._owners = self.downloads.owners  # looked at on every frame: empty unless a download is open

    # -- the address map -------------------------------------------------
    def invalidate(self) -> None:
        """Build the address map again before the next frame (call after changing a module's
        GP66/GP87 or ASCII mode other than through the bus)."""
        self._map = None

    def _build_map(self) -> dict[int, list]:
        table: dict[int, list] = {}
        for entry in self._serial_handlers:
            vm = entry[0]
            if getattr(vm, "ascii_mode", False) is True or not _mappable(vm):
                continue  # ASCII mode reads the line as text (server/stream.py); unmapped: `_always`
            get = vm.globals.get_raw
            primary, secondary = get(0, vmapi.GP_SERIAL_ADDRESS), get(0, vmapi.GP_SERIAL_SECONDARY)
            table.setdefault(primary, []).append(entry)
            if secondary and secondary != primary:
                table.setdefault(secondary, []).append(entry)
        self._map = table
        return table

    def _targets(self, address: int) -> list:
        """The (vm, key, handle) a frame to `address` goes to, in module order."""
        table = self._map
        entries = None if table is None else table.get(address)
        if entries is None:  # not built, or no module had the address when it was: look again
            entries = self._build_map().get(address, [])
        if self._always:
            order = {id(e[0]): i for i, e in enumerate(self._serial_handlers)}
            entries = sorted([*entries, *self._always], key=lambda e: order[id(e[0])])
        return entries

    def _after_silent(self, silent: tuple, frame: bytes, channel: Channel | None) -> tuple[list, list | None]:
        """(entries still to offer `frame` to, tried) after the mapped module `silent` stayed silent."""
        vm = silent[0]
        if self._addressed(vm, frame[0]):
            if channel is not None:  # addressed but silent (GP255): reachable for its events
                self._route[silent[1]] = channel
            return [], None
        # the map was stale: look again
        return [e for e in self._build_map().get(frame[0], []) if e[0] is not vm], [silent]

    def _binary_frame(self, frame: bytes, channel: Channel | None, catch: bool = True,
                      silent: tuple | None = None) -> list[tuple[object, bytes, str]]:
        """A 9-byte frame to the modules of its address (the map): [(module, reply, "binary")].
        A module that raises is logged and skipped when `catch`, else the error propagates.
        `silent`: the one mapped (vm, key, handle) the caller already offered the frame to,
        which did not answer (`request`'s fast path)."""
        out: list[tuple[object, bytes, str]] = []
        tried: list | None = None
        entries: list | None
        if silent is not None:
            entries, tried = self._after_silent(silent, frame, channel)
        else:
            entries = self._targets(frame[0])
        while entries:
            for vm, key, handle in entries:
                try:
                    reply = handle(frame)
                except Exception:  # a module bug: bad input is answered with a status code
                    self._map = None
                    if not catch:
                        raise
                    logging.getLogger("opentmcl.server").exception("module failed on frame %s", frame.hex(" "))
                    continue
                if reply:
                    out.append((vm, reply, "binary"))
                    if channel is not None:
                        self._route[key] = channel
                elif self._addressed(vm, frame[0]):
                    if channel is not None:  # addressed but silent (GP255): reachable for its events
                        self._route[key] = channel
                elif tried is None:
                    tried = []  # the map was stale: look again below
            if tried is None:
                break
            tried.extend(entries)
            seen = {id(e[0]) for e in tried}
            entries = [e for e in self._build_map().get(frame[0], []) if id(e[0]) not in seen]
        if _changes_map(frame):
            self._map = None
        return out

    # -- time -----------------------------------------------------------
    runner_attached = False
    """A `RealTimeRunner` works the lag off: requests then take only a lag they can take whole."""

    _slicing = False
    """A slice is under way: some modules are advanced, the others not yet (`_advance`)."""

    def sync(self, budget: float = REQUEST_BUDGET, whole: bool | None = None, *,
             between: bool = False) -> None:
        """Advance every module's virtual time towards the wall clock by at most `budget` CPU seconds
        of simulation (by the cost estimate), unless less than `min_step` has passed (then the
        modules stay at most that far behind). With `whole` (the default while a runner is
        attached: a host request), a lag that costs more is left to the clock thread; else one
        slice of `budget` is simulated. With `between` (the clock thread), the stops and requests
        that wait go first between two modules of the slice. Nothing while a slice is under way."""
        dt = self._clock() - self.pacer.at
        if dt <= 0 or dt < self.min_step:
            return  # the common case on a busy link: no lock needed to find it out
        if whole is None:
            whole = self.runner_attached
        with self.lock:
            now = self._clock()
            if now - self.pacer.at >= self.min_step and not self._slicing:
                first = FIRST_SLICE if self.runner_attached else math.inf
                self._advance(self.pacer.step(now, budget, whole, first), now, between)

    def _advance(self, seconds: float, now: float, between: bool = False) -> None:
        """Every module `seconds` ahead; with `between`, the requests waiting are served after each
        module (a bus of many costly modules must not hold them for the whole slice): those for a
        module not advanced yet are answered at its time, at most one slice behind."""
        if seconds <= 0:
            return
        work = self.pacer.work_clock()
        running = False
        modules = self.modules
        last = len(modules) - 1
        self._slicing = True
        try:
            for i, vm in enumerate(modules):
                running = running or getattr(vm, "application_status", RUNNING) == RUNNING
                vm.advance(seconds)
                if between and i < last and self.lock.waiting():
                    if running:
                        self._map = None  # a TMCL program may have changed an address (SGP 66)
                    self.lock.yield_to_waiting()
        finally:
            self._slicing = False
        self.pacer.advanced(seconds, self.pacer.work_clock() - work, now)
        if running:
            self._map = None

    @property
    def lag(self) -> float:
        """Seconds the modules' clock is behind the wall clock."""
        return self.pacer.lag()

    def clock_report(self) -> ClockReport:
        """Lag now, worst lag, seconds dropped, and the cost of simulating (pacing.ClockReport)."""
        return self.pacer.report()

    # -- requests -------------------------------------------------------
    def _handle(self, vm, frame: bytes, interface: str) -> bytes:
        if self._interface_kw.get(id(vm)):
            return vm.handle(frame, interface=interface)
        return vm.handle(frame)

    def request(self, frame: bytes, channel: Channel | None = None, *,
                link: object = None) -> list[tuple[object, bytes]]:
        """Offer a 9-byte frame to every module in binary mode; return (module, reply) for each reply.
        `link`: the link the frame came over, when it is not `channel` (the served dashboard, which
        takes no unsolicited replies: server/downloads.py)."""
        replies = []
        with self.lock.hold(urgency(frame)):
            self.sync()
            if len(frame) == 9 and getattr(channel, "interface", None) != USB and not (
                    self._owners or frame[1] == ENTER_DOWNLOAD_MODE):  # else: a download is open or opens
                table = self._map
                entries = None if table is None or self._always else table.get(frame[0])
                if entries is not None and len(entries) == 1:  # one module has the address: the usual bus
                    vm, key, handle = entry = entries[0]
                    try:
                        reply = handle(frame)
                    except Exception:
                        self._map = None
                        raise
                    if not reply:
                        return [(vm, reply) for vm, reply, _kind in
                                self._binary_frame(frame, channel, catch=False, silent=entry)]
                    if channel is not None:
                        self._route[key] = channel
                    if _changes_map(frame):
                        self._map = None
                    return [(vm, reply)]
                return [(vm, reply) for vm, reply, _kind in self._binary_frame(frame, channel, catch=False)]
            for vm in self.modules:
                if getattr(vm, "ascii_mode", False) is True:
                    continue  # reads the line as text (server/stream.py)
                reply = self.serial_frame(vm, frame, channel, link)
                if reply:
                    replies.append((vm, reply))
        return replies

    def serial_frames(self, frame: bytes, channel: Channel | None = None) -> list[tuple[object, bytes, str]]:
        """One 9-byte frame to every module, all in binary mode: [(module, reply, "binary")] for
        each reply. The fast path of `SerialStream`; the caller holds `lock` and has synced."""
        usb = getattr(channel, "interface", None) == USB
        if not usb and len(frame) == 9 and not (self._owners or frame[1] == ENTER_DOWNLOAD_MODE):
            return self._binary_frame(frame, channel)
        if self._owners or frame[1:2] == ENTER_DOWNLOAD:  # a download is open or opens
            return self._download_frames(frame, channel)
        out = []
        route = self._route
        for vm, key, handle in self._usb_handlers if usb else self._serial_handlers:
            try:
                reply = handle(frame)
            except Exception:  # a module bug: bad input is answered with a status code
                logging.getLogger("opentmcl.server").exception("module failed on frame %s", frame.hex(" "))
                continue
            if reply:
                out.append((vm, reply, "binary"))
                if channel is not None:
                    route[key] = channel
            elif channel is not None and (usb or self._addressed(vm, frame[0])):
                route[key] = channel
        return out

    def serial_frame(self, vm, frame: bytes, channel: Channel | None = None, link: object = None) -> bytes:
        """One 9-byte frame to one module (binary mode); the caller holds `lock` and has synced.
        `link`: the link the frame came over, when it is not `channel`."""
        usb = getattr(channel, "interface", None) == USB
        if self._owners or frame[1:2] == ENTER_DOWNLOAD:  # a download is open or opens
            reply = self.downloads.exchange(vm, frame, USB if usb else "serial",
                                            channel if link is None else link, self._handle)
        else:
            reply = self._handle(vm, frame, USB if usb else "serial")
        if len(frame) == 9 and _changes_map(frame):
            self._map = None
        if channel is not None and (reply or usb or (frame and self._addressed(vm, frame[0]))):
            # A module that was addressed but stayed silent (reply suppressed)
            # still becomes reachable for its events through this channel.
            self._route[id(vm)] = channel
        return reply

    def serial_text(self, vm, data: bytes, channel: Channel | None = None) -> AsciiOutput:
        """Bytes for a module in ASCII mode (PD28-1021 manual 3.4): its echo and reply text, and the
        bytes after a BIN line that are binary again. The caller holds `lock` and has synced."""
        out = vm.feed_ascii(data)
        self._map = None  # ASCII commands may change an address, BIN the mode
        leftover = b"" if getattr(vm, "ascii_mode", False) is True else bytes(vm.ascii.leftover)
        if out and channel is not None:
            self._route[id(vm)] = channel
        return AsciiOutput(out, leftover)

    def _addressed(self, vm, address: int) -> bool:
        accepts = getattr(vm, "accepts_address", None)
        if callable(accepts):
            return bool(accepts(address))
        return address in self._serial_addresses(vm)

    def _serial_addresses(self, vm) -> tuple[int, ...]:
        primary = vmapi.global_param(vm, vmapi.GP_SERIAL_ADDRESS)
        secondary = vmapi.global_param(vm, vmapi.GP_SERIAL_SECONDARY)
        return (primary, secondary) if secondary else (primary,)

    def can_request(self, can_id: int, data: bytes,
                    channel: Channel | None = None) -> list[tuple[object, int, bytes]]:
        """Offer a CAN request to the modules whose CAN ID (GP 71) or secondary
        CAN ID (GP 83) is `can_id`; return (module, reply ID (GP 70), payload).

        Manual 3.1/3.2: on CAN the address byte and the checksum are left out;
        the CAN ID is the module address. Frames that are not 7 or 8 bytes
        long are ignored.
        """
        if len(data) not in (7, 8):
            return []
        replies = []
        with self.lock.hold(STOP if data[0] in STOP_COMMANDS else REQUEST):
            self.sync()
            for vm in self.modules:
                ids = {vmapi.global_param(vm, vmapi.GP_CAN_ID)}
                secondary = vmapi.global_param(vm, vmapi.GP_CAN_SECONDARY)
                if secondary:
                    ids.add(secondary)
                if can_id not in ids:
                    continue
                if channel is not None:
                    self._route[id(vm)] = channel
                address = vmapi.global_param(vm, vmapi.GP_SERIAL_ADDRESS)
                frame = canmap.request_to_frame(data, address)
                if self._owners or data[0] == ENTER_DOWNLOAD_MODE:  # a download is open or opens
                    reply = self.downloads.exchange(vm, frame, "can", channel, self._handle)
                else:
                    reply = self._handle(vm, frame, "can")
                if reply:
                    payload = canmap.reply_to_payload(reply, data)
                    replies.append((vm, vmapi.global_param(vm, vmapi.GP_CAN_REPLY_ID), payload))
        return replies

    # -- unsolicited replies ---------------------------------------------
    def poll(self, budget: float = SLICE_BUDGET) -> list[tuple[Channel, object, bytes]]:
        """Advance time by one slice of at most `budget` CPU seconds and collect (channel, module,
        reply) for pending events."""
        with self.lock.hold(BACKGROUND):
            self.sync(budget, whole=False)
            return self._events()

    def step(self) -> tuple[list[tuple[Channel, object, bytes]], float]:
        """One slice of the clock thread (`SLICE_BUDGET`), taken only when no request waits:
        (the pending events, the seconds the modules still lag behind the wall clock)."""
        with self.lock.hold(BACKGROUND):
            self.sync(SLICE_BUDGET, whole=False, between=True)
            events = self._events()
            lag = self._clock() - self.pacer.at
        return events, lag

    def _events(self) -> list[tuple[Channel, object, bytes]]:
        out = []
        for vm in self.modules:
            drain = getattr(vm, "drain_events", None)
            events = drain() if callable(drain) else []
            channel = self._route.get(id(vm))
            for event in events:
                if channel is not None:
                    out.append((channel, vm, event))
        return out

    def forget(self, channel: object) -> None:
        """Stop routing events to a channel (or link) that went away; its program downloads have
        no owner from now on (server/downloads.py)."""
        with self.lock:
            for key in [k for k, c in self._route.items() if c is channel]:
                del self._route[key]
            if self._owners:
                self.downloads.forget(channel, self.modules)

    def _download_frames(self, frame: bytes, channel: Channel | None) -> list[tuple[object, bytes, str]]:
        """`serial_frames` while a program download is open or opens: the frame to each module in
        binary mode (`serial_frame`; the modules filter addresses themselves), so that the one whose
        download another link owns takes it as a direct-mode request (server/downloads.py). A
        module that raises is logged and skipped."""
        out: list[tuple[object, bytes, str]] = []
        for vm in self.modules:
            try:
                reply = self.serial_frame(vm, frame, channel)
            except Exception:  # a module bug: bad input is answered with a status code
                logging.getLogger("opentmcl.server").exception("module failed on frame %s", frame.hex(" "))
                continue
            if reply:
                out.append((vm, reply, "binary"))
        return out


class RealTimeRunner:
    """Background thread: keeps virtual time moving and delivers events."""

    def __init__(self, bus: ModuleBus, tick: float = 0.01) -> None:
        self.bus = bus
        self.tick = tick
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.errors: list[BaseException] = []
        self.failures = 0

    def start(self) -> None:
        self.bus.runner_attached = True
        self._thread = threading.Thread(target=self._run, name="opentmcl-clock", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        behind = False
        while not (self._stop.is_set() if behind else self._stop.wait(self.tick)):
            try:
                events, lag = self.bus.step()
                behind = lag >= self.tick
                for channel, vm, event in events:
                    channel.deliver(vm, event)
            except Exception as exc:  # keep time running; record for diagnostics
                behind = False
                self.failures += 1
                if self.failures <= 3:  # do not flood the log at the tick rate
                    logging.getLogger("opentmcl.server").exception("clock thread")
                self.errors.append(exc)
                del self.errors[:-10]
            if behind:
                time.sleep(0)  # let the threads of the endpoints take the interpreter

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        self.bus.runner_attached = False
