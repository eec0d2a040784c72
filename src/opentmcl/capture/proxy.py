"""The proxy: relays the bytes of a TMCL link unchanged and decodes a copy on the side.

    proxy = Proxy("tcp://192.168.0.5:4001", log="run.jsonl")
    server = proxy.listen(PtyServer(proxy, link="/tmp/ttyTMCL"))   # the endpoints of `opentmcl serve`
    proxy.start(); ...; proxy.stop()

Host bytes go to the module (the target URL; for can:// see `CanUpstream`) as they arrive and module bytes go back to every
connected host as they arrive: nothing is framed, held back or rewritten on the relay path, so
several addresses on one RS-485 line, late command-138 event replies, ASCII mode and garbage pass
as they are. Each chunk is queued with its arrival time (time.monotonic) and direction; a writer
thread decodes the queue (`Decoder`) and appends the records to the capture file.
"""
from __future__ import annotations

import logging
import queue
import threading
import time
import urllib.parse

from .. import __version__
from ..host.errors import TmclConnectionError, TmclError, TmclStatusError, TmclTimeout, TmclUrlError
from ..protocol.opcodes import GET_FIRMWARE_VERSION
from ..server.app import start_all
from .decode import HOST, MODULE, Decoder
from .format import FAULT, CaptureWriter, fault_record
from .timing import link_record


class ModuleReader:
    """Reading commands to one module over a transport the relay does not use yet (the snapshot):
    each request has a time-out and three tries; an error status reads as None."""

    def __init__(self, transport, address: int, timeout: float = 1.0) -> None:
        from ..host.client import Client

        self.client = Client(transport, address=address, timeout=timeout)
        self.requests = 0

    def _retry(self, call):
        for attempt in range(3):
            try:
                return call()
            except TmclStatusError:
                return None
            except TmclTimeout:
                if attempt == 2:
                    raise
        return None

    def ask(self, command: int, type_: int, motor: int, value: int = 0) -> int | None:
        self.requests += 1
        reply = self._retry(lambda: self.client.reply(command, type_, motor, value))
        return None if reply is None else reply.value

    def read_memory(self, index: int) -> tuple[int, int, int, int] | None:
        self.requests += 1
        m = self._retry(lambda: self.client.read_memory(index))
        return None if m is None else (m.command, m.type, m.motor, m.value)

    def identity(self) -> tuple[str, int | None]:
        """The firmware string (136 type 0) and binary version (136 type 1, None if refused)."""
        reply = self._retry(lambda: self.client.request(GET_FIRMWARE_VERSION, 0, 0, 0))
        if reply is None:
            raise TmclError("the module refuses command 136 (firmware version)")
        return str(reply.text), self.ask(GET_FIRMWARE_VERSION, 1, 0)


class ProxySession:
    """One host link of an endpoint (the pty, a TCP client): what it receives goes to the proxy."""

    interface = "serial"

    def __init__(self, proxy: Proxy, write, *, gap: float = 0.1, pace_bytes: bool = False) -> None:
        self.proxy = proxy
        self._write = write
        self.closed = False
        self.bytes_received = 0
        proxy._attach(self)

    def receive(self, data: bytes, now: float | None = None) -> int:
        self.bytes_received += len(data)
        self.proxy.from_host(data)
        return 0

    def send(self, data: bytes) -> None:
        if not self.closed:
            self._write(data)

    def close(self) -> None:
        self.closed = True
        self.proxy._detach(self)


class _ThreadUpstream:
    """A transport to the module read by a thread (`_loop`); `error` says why it ended."""

    thread_name = "opentmcl-proxy-up"

    def __init__(self, transport, on_bytes) -> None:
        self.transport = transport
        self.on_bytes = on_bytes
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.error: str | None = None

    def start(self) -> None:
        self._thread = threading.Thread(target=self._loop, name=self.thread_name, daemon=True)
        self._thread.start()

    def _loop(self) -> None:
        raise NotImplementedError

    def profile_for(self, address: int):
        return None

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
        self.transport.close()


class StreamUpstream(_ThreadUpstream):
    """A serial port or TCP socket to the module."""

    def _loop(self) -> None:
        while not self._stop.is_set():
            try:
                data = self.transport.read_some(0.2)
            except TmclConnectionError as exc:
                self.error = str(exc)
                return
            if data:
                self.on_bytes(data)

    def send(self, data: bytes) -> None:
        self.transport.send(data)


class SimUpstream:
    """Virtual modules of a sim:// URL served in real time in this process (as `opentmcl serve`)."""

    def __init__(self, url: str, on_bytes) -> None:
        from ..host.transports.inprocess import InProcessTransport
        from ..server import SerialSession, Server
        from ..sim import open_sim

        transport = open_sim(urllib.parse.urlsplit(url))  # parses and builds the modules
        self.server = Server(transport.modules)
        self.faults = transport.faults  # ?faults=FILE (docs/faults.md): on the served link and modules
        if self.faults is not None:
            self.server.faults = self.server.bus.faults = self.faults
            transport = InProcessTransport(transport.modules)  # the snapshot reads past the link faults
        self.transport = transport   # the snapshot reads through it before the server starts
        self.session = SerialSession(self.server.bus, on_bytes)

    def start(self) -> None:
        self.server.start()

    def send(self, data: bytes) -> None:
        self.session.receive(data)

    def profile_for(self, address: int):
        for vm in self.server.modules:
            if vm.accepts_address(address):
                return vm.profile
        return None

    def stop(self) -> None:
        self.session.close()
        self.server.stop()


class CanUpstream(_ThreadUpstream):
    """A module on CAN behind a serial-framed host link: a gateway, the one place that reframes.

    CAN carries no serial byte stream (TMCM-6212 manual 3.1/3.2: the address byte and the checksum
    are left out, the CAN ID is the address), so host frames are cut at nine bytes and sent as
    eight data bytes (command, type, motor, value, checksum) to the URL's `id`; a 7-byte reply on
    `reply_id` goes back as a serial reply with `reply_id` as its reply address and the checksum
    added; an 8-byte reply (136 type 0) as `reply_id` + the eight characters. The capture records
    the serial side, which is what the host saw."""

    thread_name = "opentmcl-proxy-can"

    def __init__(self, transport, on_bytes, gap: float = 0.1) -> None:
        from ..server.framer import SerialFramer

        super().__init__(transport, on_bytes)
        self.framer = SerialFramer(gap)

    def send(self, data: bytes) -> None:
        for frame in self.framer.feed(data, time.monotonic()):
            self.transport.send(frame[1:])

    def _loop(self) -> None:
        from ..protocol.can import decode_reply
        from ..protocol.frame import Reply

        bus, reply_id = self.transport.bus, self.transport.reply_id
        while not self._stop.is_set():
            try:
                msg = bus.recv(0.2)
            except Exception as exc:  # python-can's errors (the adapter went away)
                self.error = f"{self.transport.name}: receive failed: {exc}"
                return
            if msg is None or msg.is_error_frame or msg.is_remote_frame or msg.arbitration_id != reply_id:
                continue
            data = bytes(msg.data)
            if len(data) == 7:  # the serial reply: the CAN-ID as reply address (manual 3.2 note)
                r = decode_reply(data)
                self.on_bytes(Reply(reply_id & 0xFF, r.module_address, r.status, r.command, r.value).encode())
            elif len(data) == 8:  # 136 type 0: the version string, no checksum (PD86-1180 4.6.39)
                self.on_bytes(bytes([reply_id & 0xFF]) + data)


def open_upstream(url: str, on_bytes):
    """The link to the module behind `url` (serial://, tcp://, sim://, can://); TmclConnectionError if not."""
    from ..host.connect import open_transport, split_url

    scheme = split_url(url).scheme
    if scheme == "sim":
        try:
            return SimUpstream(url, on_bytes)
        except (KeyError, ValueError) as exc:
            raise TmclUrlError(f"cannot open {url}: {exc.args[0] if exc.args else exc}") from None
    if scheme == "can":
        return CanUpstream(open_transport(url), on_bytes)
    return StreamUpstream(open_transport(url), on_bytes)


def link_of(target: str, upstream, baud: int | None = None) -> dict:
    """The header's `link` for the module behind `target`: serial ports at their baud rate, CAN at
    its bit rate (if the URL gives it), TCP at `baud` when the host says what line is behind it."""
    scheme = target.partition(":")[0].lower()
    rate = baud
    if scheme == "serial" and rate is None:
        rate = getattr(upstream.transport, "baud", None)
    elif scheme == "can" and rate is None:
        query = dict(urllib.parse.parse_qsl(urllib.parse.urlsplit(target).query))
        rate = int(query["bitrate"]) if query.get("bitrate", "").isdigit() else None
    return link_record(scheme if scheme in ("serial", "tcp", "can", "sim") else "unknown", rate or None)


class Proxy:
    """Relay between host endpoints and the module at `target`; optional capture file `log`.

    `snapshot` ("full" or "state", capture/snapshot.py) reads the module at `address` before the
    relay starts and writes it to the capture (`snapshot_program`: its program memory too, 134);
    `baud`: the line speed behind a TCP converter, for the header's `link`."""

    def __init__(self, target: str, *, log: str | None = None, gap: float = 0.1, baud: int | None = None,
                 snapshot: str | None = None, address: int = 1, snapshot_program: bool = False,
                 snapshot_module: str | None = None) -> None:
        self.target = target
        self.t0 = time.monotonic()
        self._sessions: list[ProxySession] = []
        self._lock = threading.Lock()
        self.endpoints: list = []
        self.upstream = open_upstream(target, self._from_module)
        self.upstream.error = None
        self._profiles: dict[int, object] = {}
        self.decoder = Decoder(self._profile_for, gap)
        self.link = link_of(target, self.upstream, baud)
        self.snapshot_scope, self.address = snapshot, address
        self.snapshot_program, self.snapshot_module = snapshot_program, snapshot_module
        self.snapshot = None
        self.writer = CaptureWriter(log, target=target, gap=gap, tool=f"opentmcl {__version__}",
                                    link=self.link) if log else None
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._writer_thread: threading.Thread | None = None
        self.chunks = 0
        faults = getattr(self.upstream, "faults", None)
        if faults is not None and self.writer is not None:  # recorded as they fire (docs/faults.md)
            faults.log.listeners.append(lambda fired: self._queue.put((time.monotonic(), FAULT, fired)))

    # -- the relay path: no decoding here ---------------------------------------------------
    def from_host(self, data: bytes) -> None:
        if self.writer is not None:  # queued first: a virtual module answers inside send()
            self._queue.put((time.monotonic(), HOST, bytes(data)))
        try:
            self.upstream.send(data)
        except TmclConnectionError as exc:  # the module's link broke: `opentmcl proxy` ends with it
            self.upstream.error = str(exc)

    def _from_module(self, data: bytes) -> None:
        if self.writer is not None:  # queued first: the host may answer before send() returns
            self._queue.put((time.monotonic(), MODULE, bytes(data)))
        with self._lock:
            sessions = list(self._sessions)
        for session in sessions:
            session.send(data)

    def _attach(self, session: ProxySession) -> None:
        with self._lock:
            self._sessions.append(session)

    def _detach(self, session: ProxySession) -> None:
        with self._lock:
            if session in self._sessions:
                self._sessions.remove(session)

    # -- endpoints and life cycle -----------------------------------------------------------
    def listen(self, endpoint):
        """Add an endpoint built with this proxy as its bus and `session=ProxySession`."""
        self.endpoints.append(endpoint)
        return endpoint

    def start(self) -> None:
        """Take the snapshot (if asked; TmclError if the module does not answer), then relay."""
        if self.snapshot_scope is not None:
            try:
                self.take_snapshot()
            except BaseException:
                self.stop()
                raise
        self.upstream.start()
        if self.writer is not None:
            self._writer_thread = threading.Thread(target=self._write_loop, args=(self.writer,),
                                                   name="opentmcl-capture", daemon=True)
            self._writer_thread.start()
        try:
            start_all(self.endpoints)
        except BaseException:
            self.stop()
            raise

    def stop(self) -> None:
        for endpoint in reversed(self.endpoints):
            try:
                endpoint.stop()
            except OSError:
                pass
        self.endpoints = []
        self.upstream.stop()
        if self._writer_thread is not None:
            self._queue.put(None)
            self._writer_thread.join(timeout=10)
            self._writer_thread = None
        if self.writer is not None:
            t = time.monotonic() - self.t0
            for rec in self.decoder.flush(t):
                self.writer.write({"record": "frame", **rec})
            self.writer.close(t)
            self.writer = None

    def take_snapshot(self):
        """Read the module's state through the upstream link (before the relay starts)."""
        from .snapshot import snapshot_records, take_snapshot

        reader = ModuleReader(self.upstream.transport, self.address)
        version, binary = reader.identity()
        profile = self._snapshot_profile(version, binary)
        snap = take_snapshot(reader.ask, profile, self.address, scope=self.snapshot_scope or "full",
                             program=self.snapshot_program, read_memory=reader.read_memory, version=version)
        snap.t = time.monotonic() - self.t0
        if self.writer is not None:
            for rec in snapshot_records(snap, snap.t):
                self.writer.write(rec)
        self.snapshot = snap
        return snap

    def _snapshot_profile(self, version: str, binary: int | None):
        from ..host.probe import closest_builtin
        from ..modules.profile import load_profile

        if self.snapshot_module is not None:
            return load_profile(self.snapshot_module)
        profile = self.upstream.profile_for(self.address) or closest_builtin(version, binary)
        if profile is None:
            raise TmclError(f"no module profile for firmware {version!r}: give the module for the snapshot "
                            "(--snapshot-module) or leave it out (--no-snapshot)")
        return profile

    # -- the side channel --------------------------------------------------------------------
    def _profile_for(self, address: int):
        return self._profiles.get(address) or self.upstream.profile_for(address)

    def _write_loop(self, writer: CaptureWriter) -> None:
        while True:
            item = self._queue.get()
            if item is None:
                return
            t, direction, data = item
            if direction == FAULT:  # a fault that fired (docs/faults.md)
                writer.write(fault_record(t - self.t0, data))
                continue
            self.chunks += 1
            try:
                for rec in self.decoder.feed(t - self.t0, direction, data):
                    writer.write({"record": "frame", **rec})
                    if rec["kind"] == "version":
                        self._identify(rec, writer)
            except Exception:  # a decoder bug must not stop the capture (the relay never depends on it)
                logging.getLogger("opentmcl.capture").exception("cannot decode %s", data.hex(" "))

    def _identify(self, rec: dict, writer: CaptureWriter) -> None:
        from ..modules.profile import load_profile, module_names

        ident = {"record": "identity", "t": rec["t"], "address": rec["address"],
                 "firmware_version": rec["version"]}
        for name in module_names():
            prof = load_profile(name)
            if prof.firmware_version == rec["version"]:
                ident["module"] = prof.name
                self._profiles.setdefault(rec["address"], prof)
        sim = self.upstream.profile_for(rec["address"])
        if "module" not in ident and sim is not None:
            ident["module"] = sim.name
        writer.write(ident)
