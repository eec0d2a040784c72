"""The served modules' EEPROM files, written outside the bus lock (docs/endpoints.md "Real time").

A store (STAP, STGP, SCO, SGP to bank 0, the 133 that ends a download; by a host or a TMCL
program) writes the module's EEPROM file atomically, with an fsync that takes milliseconds. Under
the bus lock, a host that pipelines stores, or a program that stores in a loop, held every other
request behind those writes, stops too (an MST waited 0.9-1.9 s beside a host pipelining STGP).
While a server runs, a store therefore only marks the image changed; `EepromWriter`'s thread
takes a copy under the lock (no encoding, no disk: 0.2 ms for the largest image) and encodes and
writes it outside, at most once every `WRITE_EVERY` seconds; `Server.stop` writes what is left (`vm.close`). A process killed with
SIGKILL loses the stores of at most the last `WRITE_EVERY` seconds and the write under way; the
file is the old one or a new one, never torn (atomicfile.py).
"""
from __future__ import annotations

import logging
import threading
import time

log = logging.getLogger("opentmcl.server")

WRITE_EVERY = 0.1
"""Seconds between two writes of the EEPROM files (stores in between are written together)."""
LOG_EVERY = 10.0
"""Seconds between two log lines about a file that cannot be written."""


class EepromWriter:
    """The thread that writes the file-backed EEPROMs of a bus's modules when they change."""

    def __init__(self, bus, every: float = WRITE_EVERY) -> None:
        self.bus = bus
        self.every = every
        self.eeproms: list = [e for e in (getattr(vm, "eeprom", None) for vm in bus.modules)
                              if getattr(e, "path", None) is not None and callable(getattr(e, "snapshot", None))]
        self._changed = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._logged = -LOG_EVERY
        self.failures = 0
        """Writes that failed (the image stays marked changed and is written again later)."""

    def start(self) -> None:
        if not self.eeproms:
            return
        for eeprom in self.eeproms:
            eeprom.on_change = self._changed.set
        self._thread = threading.Thread(target=self._run, name="opentmcl-eeprom", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while True:
            self._changed.wait()
            if self._stop.is_set():
                return
            self._changed.clear()
            self.write_now()
            self._stop.wait(self.every)

    def write_now(self) -> None:
        """Write every changed image: the copies under the bus lock, the files outside it."""
        with self.bus.lock:
            snaps = [(e, e.snapshot()) for e in self.eeproms if not e.deferred]
        for eeprom, snap in snaps:
            if snap is None:
                continue
            try:
                eeprom.write(snap)
            except OSError as exc:
                self.failures += 1
                self._changed.set()  # try again after WRITE_EVERY
                now = time.monotonic()
                if now - self._logged >= LOG_EVERY:
                    self._logged = now
                    log.warning("cannot write EEPROM file %s: %s (tried again)", eeprom.path, exc.strerror or exc)

    def stop(self) -> None:
        """End the thread; the caller writes what is left (`vm.close`)."""
        self._stop.set()
        self._changed.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        for eeprom in self.eeproms:
            eeprom.on_change = None
