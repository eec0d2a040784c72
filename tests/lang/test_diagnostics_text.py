"""The summary and "more" lines of lang/diagnostics.py (`opentmcl asm` prints them, docs/assumptions.md
(Assembler, Diagnostics): "at most 50 errors and 50 warnings are kept ... shown as "... and N more
errors"", the run "ends with `opentmcl asm: error: N errors, M warnings`"): singular at 1, plural
from 2 and at 0."""
from __future__ import annotations

from opentmcl.lang.diagnostics import MAX_REPORTED, more_line, summary


def test_more_line_singular_and_plural():
    assert MAX_REPORTED == 50
    assert more_line(1, "error") == "... and 1 more error (only the first 50 are listed)"
    assert more_line(2, "error") == "... and 2 more errors (only the first 50 are listed)"
    assert more_line(3, "warning") == "... and 3 more warnings (only the first 50 are listed)"


def test_summary_counts():
    assert summary(0, 0) == "no errors"
    assert summary(1, 0) == "1 error"
    assert summary(2, 0) == "2 errors"
    assert summary(0, 1) == "1 warning"
    assert summary(1, 2) == "1 error, 2 warnings"
    assert summary(2, 1) == "2 errors, 1 warning"
