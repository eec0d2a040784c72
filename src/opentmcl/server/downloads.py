"""Program downloads on a served bus: each belongs to the link that opened it (docs/endpoints.md
"Several hosts").

TMCM-6212 manual 3.6.36, 132 "Enter download mode": "All following commands (except control
commands) are not executed but stored in the TMCL memory"; 133 "End the download mode". The
manuals know one host per module. A served module has several links (each TCP client, the pty,
CAN, the served dashboard), so a download belongs to the link whose 132 the module accepted
(status 100). Until it ends, the requests of every other link to that module are executed as in
direct mode and never stored (`VirtualModule.handle(direct=True)`): a poll gets the true value
and a stop stops at once. The owner's requests are stored as the manual says.

The download is released when its link's 133 is answered, when its link closes (the module stays
in download mode with no owner: any link's requests are stored, as for one host), or, once its link
has been silent for `SILENT` seconds, when another link's 132 asks for the module. Nothing here
runs unless a 132 passes or a download is open (`ModuleBus` looks at `owners` first).
"""
from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

from ..protocol.opcodes import ENTER_DOWNLOAD_MODE, EXIT_DOWNLOAD_MODE
from ..protocol.status import Status

log = logging.getLogger("opentmcl.server")

SILENT = 5.0
"""Seconds of silence after which a link's download may be taken over by another link's 132."""

_OPENED = (int(Status.OK), ENTER_DOWNLOAD_MODE)
_REFUSED = (int(Status.NOT_AVAILABLE), ENTER_DOWNLOAD_MODE)

Handle = Callable[[object, bytes, str], bytes]
"""`ModuleBus`'s call of one module: (module, frame, interface) -> reply."""


@dataclass
class Owner:
    """The link a module's download belongs to, and when that link was last heard."""

    link: object
    heard: float


def _status(reply: bytes) -> tuple[int, int]:
    """(status, command) of a 9-byte reply (manual 3.2), else (0, 0)."""
    return (reply[2], reply[3]) if len(reply) == 9 else (0, 0)


def _in_download(vm) -> bool:
    return getattr(vm, "download_mode", False) is True


def _name(vm) -> str:
    return f"{getattr(getattr(vm, 'profile', None), 'name', type(vm).__name__)} at address " \
           f"{getattr(vm, 'address', '?')}"


class Downloads:
    """Which link each module's open download belongs to; the bus asks under its lock."""

    def __init__(self, clock: Callable[[], float]) -> None:
        self.clock = clock
        self.owners: dict[int, Owner] = {}
        """id(module) -> the owner of its open download; empty while none is open."""

    def exchange(self, vm, frame: bytes, interface: str, link: object, handle: Handle) -> bytes:
        """`vm`'s reply to `frame` from `link`: through `handle` for the owner of its download and
        when none is open; as a direct-mode request (never stored) for any other link."""
        owner = self.owners.get(id(vm))
        if owner is not None and not _in_download(vm):  # ended otherwise (power-up, 137)
            del self.owners[id(vm)]
            owner = None
        if owner is None or owner.link is link:
            return self._own(vm, frame, interface, link, handle)
        self.heard(link)
        reply = vm.handle(frame, interface=interface, direct=True)
        if _status(reply) == _REFUSED and self.clock() - owner.heard >= SILENT:
            return self._take_over(vm, frame, interface, link, handle, owner)
        return reply

    def _own(self, vm, frame: bytes, interface: str, link: object, handle: Handle) -> bytes:
        """A request handled as the module handles it: stored in its download if one is open."""
        self.heard(link)
        was = _in_download(vm)
        reply = handle(vm, frame, interface)
        if len(frame) == 9:
            self.answered(vm, frame[1], reply, link, was)
        return reply

    def _take_over(self, vm, frame: bytes, interface: str, link: object, handle: Handle, owner: Owner) -> bytes:
        """Another link's 132 (refused as long as `owner` talks) once `owner` has been silent for
        `SILENT` s: handled as the module handles it; if it opens no download, `owner` keeps its own."""
        silent = self.clock() - owner.heard
        del self.owners[id(vm)]
        reply = self._own(vm, frame, interface, link, handle)
        if id(vm) in self.owners:
            log.warning("%s: a link silent for %.0f s lost its program download to another link's 132",
                        _name(vm), silent)
        elif _in_download(vm):
            self.owners[id(vm)] = owner
        return reply

    def answered(self, vm, command: int, reply: bytes, link: object, was: bool) -> None:
        """Note the download `link` opened (132 accepted) or ended (its 133)."""
        if command == ENTER_DOWNLOAD_MODE and _in_download(vm) and (
                _status(reply) == _OPENED or (not reply and not was)):  # no reply: GP255 = 1
            self.owners[id(vm)] = Owner(link, self.clock())
        elif command == EXIT_DOWNLOAD_MODE:
            owner = self.owners.get(id(vm))
            if owner is not None and owner.link is link:
                del self.owners[id(vm)]

    def heard(self, link: object) -> None:
        """`link` sent a request: the downloads it owns are not silent."""
        if self.owners:
            now = self.clock()
            for owner in self.owners.values():
                if owner.link is link:
                    owner.heard = now

    def forget(self, link: object, modules) -> None:
        """`link` closed: its downloads have no owner from now on (the modules stay in download
        mode, manual 3.6.36, until a 133 from any link)."""
        for vm in modules:
            owner = self.owners.get(id(vm))
            if owner is not None and owner.link is link:
                del self.owners[id(vm)]
                if _in_download(vm):
                    log.info("%s: the link that opened its download closed; the module stays in "
                             "download mode until a 133", _name(vm))
