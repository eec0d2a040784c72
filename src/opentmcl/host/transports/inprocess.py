"""In-process transport: the host talks to virtual modules by plain method calls.

Any object with the VirtualModule interface can sit behind it:
``handle(frame9) -> bytes`` (the reply, b"" when none is due),
``drain_events() -> list[bytes]`` (unsolicited replies such as the command-138
"position reached" reply, TMCM-6212 manual 3.6.35) and ``advance(seconds)``. A module whose
`handle` takes ``as_reply=True`` (VirtualModule does) may hand a reply over as a `Reply` value:
`exchange` hands it on to the client, nothing is packed or decoded.
Several modules may share one transport, like modules on one RS-485 bus: each
request is offered to every module and only the addressed one answers.
This module never imports the firmware: ``sim://`` URLs are turned into
`VirtualModule` objects by `opentmcl.sim`, which sits above both (docs/architecture.md "Layers").

No thread and no socket: time passes only as the clock policy says
(docs/architecture.md "Time"):

- ``"virtual"`` (default): waiting for a reply or an event advances the modules'
  virtual time in slices of `step` seconds (or from one internal event to the
  next, if the modules offer ``next_event_in()``) until the bytes are there or
  the timeout is used up; `sleep(s)` advances `s` seconds at once. Deterministic.
- ``"real"``: the modules follow the wall clock; waiting really waits.
- ``"none"``: time never passes by itself (only through `advance`).
"""
from __future__ import annotations

import inspect
import threading
import time
import urllib.parse
from collections.abc import Callable, Iterable
from typing import ClassVar, Generic, Protocol, TypeVar

from ...faults import FaultBoard
from ...modules.addresses import address_error
from ...protocol.frame import FRAME_LEN, Reply
from ..errors import TmclConnectionError, TmclTimeout, TmclUrlError, TmclValueError, check_timeout
from ..transport import DEBUG, Transport, log, log_frame


class SimulatedModule(Protocol):
    """What the transport needs of a module (`opentmcl.firmware.vm.VirtualModule` has it). Optional:
    ``accepts_address(address) -> bool`` and ``next_event_in() -> float | None``."""

    def handle(self, frame: bytes, /) -> bytes: ...

    def drain_events(self) -> list[bytes]: ...

    # Optional: ``events``, a list of the events waiting (what `drain_events` would answer): looked
    # at to skip the call when nothing waits; ``handle(frame, as_reply=True) -> Reply | bytes``, a
    # reply handed over as a value where the module has it (`exchange` asks for it).

    def advance(self, seconds: float, /) -> object: ...


M = TypeVar("M", bound=SimulatedModule, covariant=True)  # the clocks only read the modules


class Clock:
    """How time passes for the modules behind an `InProcessTransport` (policy ``"none"``)."""

    syncs: ClassVar[bool] = False
    """Whether `sync` does anything: true for every subclass that defines it."""

    def __init_subclass__(cls, **kwargs: object) -> None:
        super().__init_subclass__(**kwargs)
        if "sync" in cls.__dict__:
            cls.syncs = True

    def sync(self, transport: InProcessTransport[SimulatedModule]) -> None:
        """Called before every request (when `syncs`): bring the modules up to date."""

    def wait(self, transport: InProcessTransport[SimulatedModule], ready: Callable[[], bool],
             timeout: float) -> None:
        """Let time pass until `ready()` or `timeout` seconds have passed."""

    def sleep(self, transport: InProcessTransport[SimulatedModule], seconds: float) -> None:
        """Let `seconds` pass. Called without the transport's `lock`: work on the modules takes it
        (`InProcessTransport.advance` does)."""

    def now(self, transport: InProcessTransport[SimulatedModule]) -> float:
        return transport.elapsed


class VirtualClock(Clock):
    """Virtual time that advances only while the host waits."""

    def __init__(self, step: float = 0.001) -> None:
        self.step = check_timeout(step, "virtual clock step")

    def wait(self, transport: InProcessTransport[SimulatedModule], ready: Callable[[], bool],
             timeout: float) -> None:
        left = max(0.0, float(timeout))
        while not ready() and left > 0:
            dt = min(self._jump(transport), left)
            transport.advance(dt)
            left -= dt

    def _jump(self, transport: InProcessTransport[SimulatedModule]) -> float:
        """Seconds to advance next: up to the modules' next internal event when every module
        tells it (optional ``next_event_in() -> float | None``), else one `step`."""
        nearest = transport.next_arrival_in()
        for m in transport.modules:
            probe: Callable[[], float | None] | None = getattr(m, "next_event_in", None)
            if probe is None:
                return self.step
            t = probe()
            if t is not None and (nearest is None or t < nearest):
                nearest = t
        if nearest is None:
            return float("inf")  # nothing will happen: the whole timeout passes at once
        return nearest if nearest > 0 else self.step

    def sleep(self, transport: InProcessTransport[SimulatedModule], seconds: float) -> None:
        if seconds > 0:
            transport.advance(seconds)


class RealClock(Clock):
    """The modules follow the wall clock, advanced lazily at each access."""

    def __init__(self, poll: float = 0.002) -> None:
        self.poll = check_timeout(poll, "real clock poll interval")
        self._last: float | None = None

    def sync(self, transport: InProcessTransport[SimulatedModule]) -> None:
        now = time.monotonic()
        if self._last is not None and now > self._last:
            transport.advance(now - self._last)
        self._last = now

    def wait(self, transport: InProcessTransport[SimulatedModule], ready: Callable[[], bool],
             timeout: float) -> None:
        deadline = time.monotonic() + max(0.0, timeout)
        self.sync(transport)
        while not ready():
            left = deadline - time.monotonic()
            if left <= 0:
                return
            time.sleep(min(self.poll, left))
            self.sync(transport)

    def sleep(self, transport: InProcessTransport[SimulatedModule], seconds: float) -> None:
        if seconds > 0:
            time.sleep(seconds)  # without holding the transport's lock
        with transport.lock:
            self.sync(transport)

    def now(self, transport: InProcessTransport[SimulatedModule]) -> float:
        return time.monotonic()


CLOCKS: dict[str, Callable[[], Clock]] = {"virtual": VirtualClock, "real": RealClock, "none": Clock}


def make_clock(clock: str | Clock) -> Clock:
    if isinstance(clock, Clock):
        return clock
    try:
        return CLOCKS[clock]()
    except (KeyError, TypeError):
        raise TmclValueError(f"unknown clock policy {clock!r}; use one of {', '.join(CLOCKS)}") from None


def _takes_as_reply(module: object) -> bool:
    """Whether the module's `handle` takes ``as_reply`` (a reply handed over as a `Reply`)."""
    try:
        return "as_reply" in inspect.signature(module.handle).parameters  # type: ignore[attr-defined]
    except (TypeError, ValueError):  # a callable without a signature Python can read
        return False


def _answers(module: object, address: int) -> bool:
    accepts: Callable[[int], bool] | None = getattr(module, "accepts_address", None)
    return accepts is not None and accepts(address)


class InProcessTransport(Transport, Generic[M]):
    """Transport to one or more VirtualModule-like objects (`SimulatedModule`) in this process."""

    frame_format = "serial"
    window = 1 << 16  # a whole batch is handed over at once: nothing is lost in between
    _lock: threading.RLock

    def __init__(self, modules: M | Iterable[M], clock: str | Clock = "virtual") -> None:
        if isinstance(modules, Iterable):
            self.modules: list[M] = list(modules)
        else:
            self.modules = [modules]
        if not self.modules:
            raise TmclValueError("InProcessTransport needs at least one module")
        self.clock = make_clock(clock)
        """The clock policy, fixed when the transport is made."""
        self._syncs = self.clock.syncs
        self.elapsed = 0.0  # virtual seconds advanced through this transport
        self._rx = bytearray()
        self._closed = False
        self._lock = threading.RLock()  # `lock`: the modules are not thread-safe; one caller at a time
        self._only: M | None = self.modules[0] if len(self.modules) == 1 else None  # `exchange`; None once closed
        # a module that keeps its waiting events in a list `events` (VirtualModule does): looked at
        # before `drain_events` is called, which then only runs when something waits
        waiting = getattr(self._only, "events", None)
        self._waiting: list[bytes] | None = waiting if isinstance(waiting, list) else None
        # `exchange`'s module: the one module, if it keeps its events in a list and its `handle`
        # takes `as_reply`
        self._exchanged: M | None = self._only if waiting is not None and _takes_as_reply(self._only) else None

    def __init_subclass__(cls, **kwargs: object) -> None:
        """A subclass that watches `send` or `recv` sees every frame there: its `send_many`,
        `exchange` and `exchange_many` are `Transport`'s, which go through `send` and leave the
        replies to `recv`."""
        super().__init_subclass__(**kwargs)
        if "send" in cls.__dict__ or "recv" in cls.__dict__:
            for name in ("send_many", "exchange", "exchange_many"):
                if name not in cls.__dict__:
                    setattr(cls, name, getattr(Transport, name))

    @property
    def module(self) -> M:
        """The first (often the only) module."""
        return self.modules[0]

    def _check_open(self) -> None:
        if self._closed:
            raise TmclConnectionError("in-process transport is closed")

    faults: FaultBoard | None = None
    """The faults of a ``sim://...?faults=FILE`` link (docs/faults.md): trigger one by name with
    ``faults.trigger(name)``; ``faults.log`` lists what fired. None without faults."""

    def next_arrival_in(self) -> float | None:
        """Seconds until bytes on their way arrive (a link with faults delays them), or None."""
        return None

    def local_module(self, address: int) -> M | None:
        return next((m for m in self.modules if _answers(m, address)), None)

    def _collect_events(self) -> None:
        waiting = self._waiting
        if waiting is not None and not waiting:  # the one module: none waiting
            return
        for m in self.modules:
            for event in m.drain_events():
                self._rx += event

    def advance(self, seconds: float) -> None:
        """Advance every module by `seconds` of virtual time, collecting their events."""
        lock = self._lock
        lock.acquire()
        try:
            self._check_open()
            for m in self.modules:
                m.advance(seconds)
            self.elapsed += seconds
            if self._waiting != []:  # (the one module's list: none waiting)
                self._collect_events()
        finally:
            lock.release()

    def send(self, data: bytes) -> None:
        self._send_frames([data])

    def send_many(self, frames: list[bytes]) -> None:
        """Hand the frames to every module in turn, after one time sync for all of them."""
        self._send_frames(frames)

    def exchange_many(self, frames: list[bytes]) -> list[bytes] | None:
        """`send_many`, returning the replies as they are when every frame got exactly one 9-byte
        reply, no event arrived and nothing was waiting to be read (one module, DEBUG logging off).
        Otherwise everything is in the receive buffer in arrival order, as `send_many` leaves it,
        and None is returned."""
        return self._send_frames(frames, at_hand=True)

    def exchange(self, frame: bytes) -> Reply | bytes | None:
        """`exchange_many` of one frame, short: the common case of a request (one module that keeps
        its events in a list, nothing waiting, no event, one reply, DEBUG logging off) is one
        `handle` call after the clock's sync if it has one. The reply comes as the module handed
        it over: a `Reply` value (``as_reply``) or 9 bytes."""
        module = self._exchanged
        waiting = self._waiting
        rx = self._rx
        if module is None or waiting or rx or log.isEnabledFor(DEBUG):
            replies = self._send_frames([frame], at_hand=True)
            return None if replies is None else replies[0]
        if self._syncs:
            self.clock.sync(self)
            if waiting or rx:  # an event (or one collected by the sync) goes before the reply
                self._collect_events()
                self._deliver(frame)
                return None
        reply: Reply | bytes = module.handle(frame, True)  # type: ignore[call-arg]  # as_reply
        if waiting:  # events came with the reply: the reply, then the events, as bytes arrive
            rx += reply.encode() if reply.__class__ is Reply else reply  # type: ignore[arg-type]
            self._collect_events()
            return None
        if reply.__class__ is Reply or len(reply) == FRAME_LEN:
            return reply
        rx += reply  # type: ignore[arg-type]  # no reply, or one of another length (the version string)
        return None

    def _send_frames(self, frames: list[bytes], *, at_hand: bool = False) -> list[bytes] | None:
        """One time sync, then each frame to every module with the events collected before and
        after it; with `at_hand`, the replies as `exchange_many` returns them."""
        with self._lock:
            self._check_open()
            debug = log.isEnabledFor(DEBUG)
            if self.clock.syncs:
                self.clock.sync(self)
            self._collect_events()
            rx = self._rx
            module = self._only
            replies: list[bytes] | None = [] if at_hand and module is not None and not debug and not rx else None
            for data in frames:
                if debug:
                    log_frame("->", data, self.frame_format)
                frame = data if data.__class__ is bytes else bytes(data)
                if replies is None or module is None:
                    self._deliver(frame)
                    continue
                reply = module.handle(frame)
                events = module.drain_events()
                if events or len(reply) != FRAME_LEN:
                    for done in replies:
                        rx += done
                    rx += reply
                    for event in events:
                        rx += event
                    replies = None
                else:
                    replies.append(reply)
            return replies

    def _deliver(self, frame: bytes) -> None:
        """`frame` to every module: the replies, then the events, into the receive buffer."""
        for m in self.modules:
            reply = m.handle(frame)
            if reply:
                self._rx += reply
        self._collect_events()

    def recv(self, n: int, timeout: float) -> bytes:
        with self._lock:
            self._check_open()
            self._collect_events()
            if len(self._rx) < n:
                self.clock.wait(self, lambda: len(self._rx) >= n, timeout)
            if len(self._rx) < n:
                raise TmclTimeout(f"no reply within {timeout:g} s ({len(self._rx)} of {n} bytes received)")
            out = bytes(self._rx[:n])
            del self._rx[:n]
            if log.isEnabledFor(DEBUG):
                log_frame("<-", out, self.frame_format)
            return out

    def reset_input(self) -> None:
        with self._lock:
            self._rx.clear()

    def sleep(self, seconds: float) -> None:
        """Let `seconds` pass as the clock says (virtual: advance at once; real: wait, then
        catch up; none: nothing)."""
        self._check_open()
        self.clock.sleep(self, seconds)

    def monotonic(self) -> float:
        return self.clock.now(self)

    def close(self) -> None:
        self._closed = True
        self._only = None
        self._exchanged = None


def parse_modules(netloc: str, default_address: int) -> list[tuple[str, int]]:
    """``TMCM-6212`` or ``TMCM-6212@1,PD86-1180@2`` -> [(name, address), ...]."""
    out = []
    names = [p for p in urllib.parse.unquote(netloc).split(",") if p.strip()]
    if not names:
        raise TmclUrlError("sim:// URL names no module, e.g. sim://TMCM-6212")
    for i, part in enumerate(names):
        name, sep, addr = part.strip().partition("@")
        if sep:
            try:
                address = int(addr, 0)
            except ValueError:
                raise TmclUrlError(f"bad module address {addr!r} in sim:// URL") from None
        else:
            address = default_address + i
        out.append((name.strip(), address))
    problem = address_error([address for _, address in out])  # the rule of `opentmcl serve`
    if problem:
        raise TmclUrlError(f"sim://: {problem}")
    return out
