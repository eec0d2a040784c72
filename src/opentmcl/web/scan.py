"""Module scan (docs/dashboard.md "Module scan"): which addresses on the dashboard's link answer
command 136 type 0, the firmware version string (TMCM-6212 manual 3.6.36, PD86-1180 4.6.39).

Bounded: addresses 1..255 (GP66 "Serial address 1...255", TMCM-6212 manual 5.1), one request per
address with its own time-out, one scan at a time, cancellable between two requests. On a serial
link the scan can also try baud rates (GP65's table, the rates a PC supports); other links (TCP,
the server's bus, an in-process module) have no baud rate, and a CAN link reaches only the module
of its CAN ID (manual 3.1), so there the scan tries only the connection's own address.
A module that answers every address byte (a USB link, docs/endpoints.md) is listed once, at its
own address: after each version answer GGP 66 (manual 3.6.8) is asked at the same address, and a
reply carrying another module address (GP66) means the answer was not that address's own.

The scan gives the link up to a stop after each address (web/link.py): each address is one turn
on the link, and a baud-rate scan, which holds the link throughout, lends it back at the link's
own rate to a stop waiting. So a stop waits at most for one address: its time-out per address,
which is why that is at most `TIMEOUT_MAX` (a module with the longest telegram pause, GP75 = 255
ms, still answers at 9600 baud well within it).
"""
from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from functools import partial

from ..host import Client, TmclError, VersionReply
from ..host.errors import TmclConnectionError, TmclTimeout
from ..modules.profile import ModuleProfile
from ..protocol.opcodes import GET_FIRMWARE_VERSION, Op
from .link import link_gate
from .service import DashboardError

SERIAL_ADDRESS = 66
_GGP = int(Op.GGP)  # a plain int, which `Client.request` keeps ready to send
ADDRESSES = range(1, 256)
# GP65 "RS485 baud rate" 0..11 (TMCM-6212 manual 5.1) without the rows "Not supported by PCs".
BAUD_RATES = (9600, 14400, 19200, 28800, 38400, 57600, 115200)
TIMEOUT_MIN, TIMEOUT_MAX, TIMEOUT_DEFAULT = 0.01, 0.5, 0.1


def link_kind(client: Client) -> str:
    """"serial" when the link's baud rate can be changed, "can", or "fixed" (TCP, bus, in-process)."""
    transport = client.transport
    if transport.frame_format == "can":
        return "can"
    return "serial" if hasattr(transport, "baud") else "fixed"


def check_request(first: int, last: int, timeout: float, bauds: Sequence[int], kind: str) -> None:
    """The scan's bounds; DashboardError with a one-line message when one is outside."""
    if not (ADDRESSES.start <= first <= last < ADDRESSES.stop):
        raise DashboardError(f"addresses must be within 1..255 with first <= last, got {first}..{last}")
    if not TIMEOUT_MIN <= timeout <= TIMEOUT_MAX:
        raise DashboardError(f"time-out per address must be {TIMEOUT_MIN}..{TIMEOUT_MAX} s, got {timeout:g}")
    bad = [b for b in bauds if b not in BAUD_RATES]
    if bad:
        raise DashboardError(f"baud rate {bad[0]} is not one of {', '.join(map(str, BAUD_RATES))}")
    twice = [b for i, b in enumerate(bauds) if b in bauds[:i]]
    if twice:
        raise DashboardError(f"baud rate {twice[0]} is given twice")
    if bauds and kind != "serial":
        raise DashboardError("this link has no baud rate to change (only a serial link has): "
                             "scan the addresses alone")


def _profile_name(version: str) -> str:
    from ..host.module import profile_for_version

    try:
        profile: ModuleProfile = profile_for_version(version)
    except TmclError:
        return ""
    return profile.name


class Scanner:
    """One scan at a time on `client`'s link; `status()` is what the page polls."""

    def __init__(self, client: Client, served: Callable[[], Sequence[int]]) -> None:
        self.client = client
        self.served = served        # the addresses the dashboard serves (their pages exist)
        self.kind = link_kind(client)
        self.gate = link_gate(client)
        self._lock = threading.Lock()
        self._cancel = threading.Event()
        self._thread: threading.Thread | None = None
        self._status: dict[str, object] = self._fresh(0, [])

    def _fresh(self, total: int, bauds: Sequence[int]) -> dict[str, object]:
        return {"running": False, "done": 0, "total": total, "found": [], "cancelled": False, "error": "",
                "any_address": False,
                "bauds": list(bauds), "link": self.kind, "baud": getattr(self.client.transport, "baud", None)}

    def status(self) -> dict[str, object]:
        with self._lock:
            out = dict(self._status)
            out["found"] = [dict(f, served=f["address"] in self.served()) for f in self._status["found"]]  # type: ignore[attr-defined]
        return out

    def start(self, first: int, last: int, timeout: float = TIMEOUT_DEFAULT, bauds: Sequence[int] = ()) -> None:
        check_request(first, last, timeout, bauds, self.kind)
        with self._lock:
            if self._thread is not None and self._thread.is_alive():
                raise DashboardError("a scan is already running: cancel it or wait for it to end")
            if self.kind == "can":
                first = last = self.client.address
            addresses = range(first, last + 1)
            self._status = self._fresh(len(addresses) * max(1, len(bauds)), bauds)
            self._status["running"] = True
            self._cancel.clear()
            self._thread = threading.Thread(target=self._run, args=(addresses, timeout, list(bauds)),
                                            name="dashboard-scan", daemon=True)
            self._thread.start()

    def cancel(self) -> None:
        self._cancel.set()

    def join(self, timeout: float = 5.0) -> None:
        thread = self._thread
        if thread is not None:
            thread.join(timeout)

    def _run(self, addresses: range, timeout: float, bauds: list[int]) -> None:
        try:
            if bauds:
                self._scan_bauds(addresses, timeout, bauds)
            else:
                self._scan(addresses, timeout, None)
        except TmclError as exc:  # the link is gone
            self._set(error=str(exc))
        finally:
            self._set(running=False, cancelled=self._cancel.is_set())

    def _scan_bauds(self, addresses: range, timeout: float, bauds: list[int]) -> None:
        """Each baud rate in turn, with the link held so the dashboard's own polling does not
        talk at a rate its module does not listen at; the link's rate comes back afterwards, and
        in between for a stop that waits (`_lend`)."""
        transport = self.client.transport
        original = transport.baud  # type: ignore[attr-defined]
        with self.gate:
            try:
                for baud in bauds:
                    if self._cancel.is_set():
                        break
                    self._set_baud(baud)
                    self._scan(addresses, timeout, baud, partial(self._lend, original, baud))
            finally:
                self._set_baud(original)

    def _set_baud(self, baud: int) -> None:
        self.client.transport.baud = baud  # type: ignore[attr-defined]
        self.client.transport.reset_input()

    def _lend(self, original: int, baud: int) -> None:
        """A stop waits: the link back at its own rate for it, then on with the scan at `baud`."""
        if self.gate.stops_waiting:
            self._set_baud(original)
            self.gate.yield_to_stops()
            self._set_baud(baud)

    def _scan(self, addresses: range, timeout: float, baud: int | None,
              between: Callable[[], None] = lambda: None) -> None:
        for address in addresses:
            between()
            if self._cancel.is_set():
                return
            with self.gate:  # one turn per address: a stop goes before the next one
                if self._cancel.is_set():  # cancelled (STOP ALL) while waiting for the turn
                    return
                version = self._ask(address, timeout)
                foreign = version is not None and self._answers_for_another(address, timeout)
            with self._lock:
                self._status["done"] = int(self._status["done"]) + 1  # type: ignore[call-overload]
                if version is None:
                    continue
                if foreign:  # a module that answers any address byte (USB)
                    self._status["any_address"] = True
                    continue
                self._status["found"].append(  # type: ignore[attr-defined]
                    {"address": address, "baud": baud, "version": version, "module": _profile_name(version)})

    def _ask(self, address: int, timeout: float) -> str | None:
        try:
            reply = self.client.request(GET_FIRMWARE_VERSION, 0, 0, 0, address=address, timeout=timeout)
        except TmclTimeout:
            return None
        except TmclConnectionError:
            raise
        except TmclError:
            return None  # a garbled or refused answer: no module of ours there
        return reply.text if isinstance(reply, VersionReply) else None

    def _answers_for_another(self, address: int, timeout: float) -> bool:
        """GGP 66, 0 at `address` answered by a frame of another module address (which the client
        counts as a stray reply) or with another value than `address`."""
        strays = self.client.stray_replies
        try:
            value = self.client.reply(_GGP, SERIAL_ADDRESS, 0, address=address, timeout=timeout).value
        except TmclConnectionError:
            raise
        except TmclError:
            return self.client.stray_replies > strays
        return value != address

    def _set(self, **values: object) -> None:
        with self._lock:
            self._status.update(values)
