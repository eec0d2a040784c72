"""Issue 33, "Rooms with one job each": "Every file at radon maintainability rank A or B" - here for
the files of opentmcl.lang (the same numbers `radon mi -s src/opentmcl/lang` prints)."""

from pathlib import Path

from radon.metrics import mi_rank, mi_visit

import opentmcl.lang

LANG = Path(opentmcl.lang.__file__).resolve().parent


def test_every_lang_file_is_rank_a_or_b():
    """Rank C (an index below 10) is a file to split."""
    ranks = {path.name: mi_visit(path.read_text(encoding="utf-8"), True) for path in sorted(LANG.glob("*.py"))}
    assert "assembler.py" in ranks
    low = sorted(f"{name} {mi_rank(index)} ({index:.1f})" for name, index in ranks.items() if mi_rank(index) not in "AB")
    assert not low, "split these files:\n" + "\n".join(low)
