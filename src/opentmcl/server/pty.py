"""Pseudo-terminal endpoint: the bus appears as a serial port (POSIX only).

Any serial-port program (pyserial, PyTrinamic, a terminal) opens the slave
path printed by `opentmcl serve --pty` and talks 9-byte TMCL frames to it, as
to a module on RS-232/RS-485/USB (TMCM-6212 manual 3.1, 3.2).

The server keeps its own handle on the slave side open and in raw mode, so
clients may open and close the port any number of times without the master
seeing a hang-up. Replies written while nobody reads pile up in the terminal
buffer up to its size and are then dropped, never blocking the server.
"""
from __future__ import annotations

import errno
import os
import select
import threading
import time
from pathlib import Path

from .bus import default_interface, interface_error
from .framer import DEFAULT_GAP
from .session import SerialSession

POLL = 0.2


class PtyServer:
    """Serve the bus on a new pseudo-terminal; `path` is the slave device."""

    def __init__(self, bus, *, link: str | os.PathLike | None = None, gap: float = DEFAULT_GAP,
                 pace_bytes: bool = False, interface: str | None = None, session=SerialSession) -> None:
        if session is SerialSession:  # the proxy's own session relays bytes and filters nothing
            if interface is None:
                interface = default_interface(bus.modules, pace_bytes)
            problem = interface_error(interface, bus.modules, pace_bytes)
            if problem:
                raise ValueError(problem)
        self.interface = interface
        """What the port stands for: "usb" (any address byte is answered), "rs485" or "rs232"."""
        self.bus = bus
        self.link = Path(link) if link is not None else None
        self.gap = gap
        self.pace_bytes = pace_bytes
        self._session_class = session  # what handles the received bytes (the proxy passes its own)
        self.master: int | None = None
        self.slave: int | None = None
        self.path = ""
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.session: SerialSession | None = None
        self.dropped = 0

    def start(self) -> None:
        import tty  # POSIX only: imported here so that the package imports everywhere

        master, slave = os.openpty()
        try:
            tty.setraw(slave)
            os.set_blocking(master, False)
            self.path = os.ttyname(slave)
            if self.link is not None:
                self._make_link(self.link)
        except BaseException:
            os.close(master)
            os.close(slave)
            raise
        self.master, self.slave = master, slave
        extra = {"interface": self.interface} if self._session_class is SerialSession else {}
        self.session = self._session_class(self.bus, self._write, gap=self.gap, pace_bytes=self.pace_bytes,
                                           **extra)
        self._thread = threading.Thread(target=self._loop, name="opentmcl-pty", daemon=True)
        self._thread.start()

    def _make_link(self, link: Path) -> None:
        if link.is_symlink():
            link.unlink()
        elif link.exists():
            raise FileExistsError(f"{link} exists and is not a symbolic link; not replacing it")
        link.symlink_to(self.path)

    def _write(self, data: bytes) -> None:
        view = memoryview(data)
        while view and self.master is not None:
            try:
                n = os.write(self.master, view)
            except BlockingIOError:
                self.dropped += len(view)  # nobody reads the port: drop, never block
                return
            except OSError:
                return
            view = view[n:]

    def _loop(self) -> None:
        while not self._stop.is_set():
            master, session = self.master, self.session  # set by start() before the thread runs
            if master is None or session is None:
                return
            try:
                ready, _, _ = select.select([master], [], [], POLL)
            except (OSError, ValueError):
                return
            if not ready:
                continue
            try:
                data = os.read(master, 4096)
            except BlockingIOError:
                continue
            except OSError as exc:
                if exc.errno == errno.EIO:  # no slave open (not with our own handle)
                    time.sleep(POLL)
                    continue
                return
            if data:
                session.receive(data)

    def stop(self) -> None:
        self._stop.set()
        if self.session is not None:
            self.session.closed = True  # a read being handled ends at its next frame (server/stream.py)
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        if self.session is not None:
            self.session.close()
        if self.link is not None and self.link.is_symlink():
            try:
                if os.readlink(self.link) == self.path:
                    self.link.unlink()
            except OSError:
                pass
        for fd in (self.master, self.slave):
            if fd is not None:
                try:
                    os.close(fd)
                except OSError:
                    pass
        self.master = self.slave = None
