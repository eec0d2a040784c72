"""Signalling a TMCL status code from deep inside a command handler."""
from __future__ import annotations


class TmclStatus(Exception):
    """Raised by handlers to answer with a non-100 status (manual 3.2.1)."""

    def __init__(self, status: int) -> None:
        super().__init__(status)
        self.status = status
