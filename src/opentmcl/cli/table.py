"""Text tables that fit the terminal: columns beyond its width wrap into further blocks, each
repeating the leading key columns (time), so `demo` fits an 80-column terminal (docs/cli.md)."""
from __future__ import annotations

import shutil
from collections.abc import Sequence

COLUMN_GAP = 2  # spaces between two columns


def width() -> int:
    """Columns to fill: one less than the terminal's ($COLUMNS, else the terminal's, else 80), so a
    full line never makes a terminal wrap."""
    return max(40, shutil.get_terminal_size(fallback=(80, 24)).columns - 1)


def fit(header: Sequence[str], rows: Sequence[Sequence[str]], columns: int, keep: int = 1,
        group: int = 1) -> list[str]:
    """Lines of an aligned table no wider than `columns`: the first `keep` columns in every block,
    the others packed left to right in groups of `group` that stay together (an axis's position and
    velocity); blocks are separated by an empty line. A group wider than `columns` alone gets a
    block of its own."""
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(header)]
    base = sum(widths[:keep]) + COLUMN_GAP * max(0, keep - 1)
    blocks: list[list[int]] = []
    used = base
    for start in range(keep, len(header), group):
        members = list(range(start, min(start + group, len(header))))
        need = sum(COLUMN_GAP + widths[i] for i in members)
        if not blocks or used + need > columns:
            blocks.append([])
            used = base
        blocks[-1] += members
        used += need
    lines: list[str] = []
    for n, block in enumerate(blocks or [[]]):
        cols = list(range(keep)) + block
        if n:
            lines.append("")
        head = (" " * COLUMN_GAP).join(header[i].rjust(widths[i]) for i in cols)
        lines += [head, "-" * len(head)]
        lines += [(" " * COLUMN_GAP).join(r[i].rjust(widths[i]) for i in cols) for r in rows]
    return lines
