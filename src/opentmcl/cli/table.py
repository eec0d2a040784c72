"""Text tables that fit the terminal: columns beyond its width wrap into further blocks, each
repeating the leading key columns (time), so `demo` fits an 80-column terminal (docs/cli.md)."""
from __future__ import annotations

import shutil
from collections.abc import Sequence

GAP = 2


def width() -> int:
    """Columns to fill: one less than the terminal's ($COLUMNS, else the terminal's, else 80), so a
    full line never makes a terminal wrap."""
    return max(40, shutil.get_terminal_size(fallback=(80, 24)).columns - 1)


def fit(header: Sequence[str], rows: Sequence[Sequence[str]], columns: int, keep: int = 1) -> list[str]:
    """Lines of an aligned table no wider than `columns`: the first `keep` columns in every block,
    the others packed left to right; blocks are separated by an empty line."""
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(header)]
    blocks: list[list[int]] = []
    used = sum(widths[:keep]) + GAP * max(0, keep - 1)
    for i in range(keep, len(header)):
        if not blocks or used + GAP + widths[i] > columns:
            blocks.append([])
            used = sum(widths[:keep]) + GAP * max(0, keep - 1)
        blocks[-1].append(i)
        used += GAP + widths[i]
    lines: list[str] = []
    for n, block in enumerate(blocks or [[]]):
        cols = list(range(keep)) + block
        if n:
            lines.append("")
        head = (" " * GAP).join(header[i].rjust(widths[i]) for i in cols)
        lines += [head, "-" * len(head)]
        lines += [(" " * GAP).join(r[i].rjust(widths[i]) for i in cols) for r in rows]
    return lines
