"""Code-health limits of issue 12 ("Done when": no function in src/ above cyclomatic complexity 20).

Measured with radon's cyclomatic complexity (the same numbers `radon cc -s -n D src` prints).
"""

from pathlib import Path

from radon.complexity import cc_visit

SRC = Path(__file__).resolve().parents[1] / "src" / "opentmcl"
LIMIT = 20


def _blocks():
    for path in sorted(SRC.rglob("*.py")):
        for block in cc_visit(path.read_text(encoding="utf-8")):   # functions and methods, flat
            if not hasattr(block, "methods"):                       # skip the class totals
                yield path.relative_to(SRC.parent), block


def test_no_function_above_complexity_20():
    """Issue 12: "no function in `src/` has cyclomatic complexity above 20"."""
    too_complex = sorted({f"{path}:{b.lineno} {b.fullname} ({b.complexity})"
                         for path, b in _blocks() if b.complexity > LIMIT})
    assert not too_complex, "split these functions:\n" + "\n".join(too_complex)


def test_every_file_is_maintainability_rank_a_or_b():
    """Issue 33, "Rooms with one job each": "Every file at radon maintainability rank A or B" (the
    numbers `radon mi -s src` prints). Rank C (an index below 10) is a file to split."""
    from radon.metrics import mi_rank, mi_visit

    ranks = {path.relative_to(SRC.parent): mi_visit(path.read_text(encoding="utf-8"), True)
             for path in sorted(SRC.rglob("*.py"))}
    low = sorted(f"{path} {mi_rank(index)} ({index:.1f})" for path, index in ranks.items()
                 if mi_rank(index) not in "AB")
    assert not low, "split these files:\n" + "\n".join(low)
