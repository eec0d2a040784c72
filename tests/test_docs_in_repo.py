"""A newcomer reads the design in the repository (issue 12 item 1, docs/architecture.md).

docs/architecture.md: "Source docstrings cite the sections of this page as `docs/architecture.md
"Section"`; the behaviour itself is specified by the manuals". The README's layout block names the
packages of the layer contract (`[tool.importlinter]` in pyproject, docs/architecture.md "Layers").
"""
from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUTSIDE = re.compile(r"DESIGN\.md|FACTS\.md|\bshared/")
"""Files a clone does not contain: the design notes and facts kept next to the repository."""


def test_no_source_file_cites_a_file_outside_the_repository():
    """Code, profile data and include files cite the manuals or docs/*.md, never the design notes,
    the facts file or the shared directory beside the repository (the OUTSIDE pattern)."""
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
             for path in sorted((ROOT / "src" / "opentmcl").rglob("*")) if path.is_file() and path.suffix != ".pyc"
             for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1)
             if OUTSIDE.search(line)]
    assert found == []


NOT_IN_A_CLONE = re.compile(r"DESIGN\.md|FACTS\.md|\bshared/(?!manuals)")
"""The notes beside the repository; shared/manuals is allowed: the manuals are the specification."""
SOURCE_CITATION = re.compile(r'docs/sources\.md\s+"([^"]+)"')
"""How docs and tests cite a section of docs/sources.md (its first line says so)."""


def _docs_tests_bench_readme() -> list[Path]:
    files = [ROOT / "README.md"]
    for folder in ("docs", "tests", "bench"):
        files += [p for p in sorted((ROOT / folder).rglob("*")) if p.suffix in (".md", ".py")]
    return files


def test_docs_tests_and_bench_cite_sources_in_the_repository():
    """Issue 12 item 1: a newcomer can follow every citation. docs/, tests/, bench/ and README.md
    name docs/sources.md and docs/architecture.md, never the design notes or the facts file kept
    beside the repository."""
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}" for path in _docs_tests_bench_readme()
             for n, line in enumerate(path.read_text().splitlines(), 1) if NOT_IN_A_CLONE.search(line)]
    assert found == []


def test_every_sources_citation_names_a_section_of_docs_sources():
    """docs/sources.md: "Docstrings and docs cite a section of this page as `docs/sources.md
    "Section"`" - each cited section exists, and the README's docs table links the page."""
    sections = {line[3:].strip() for line in (ROOT / "docs" / "sources.md").read_text().splitlines()
                if line.startswith("## ")}
    cited = {(str(path.relative_to(ROOT)), " ".join(name.split())) for path in _docs_tests_bench_readme()
             for name in SOURCE_CITATION.findall(path.read_text())}
    assert len(cited) > 10
    assert sorted(c for c in cited if c[1] not in sections | {"Section"}) == []
    assert "| [docs/sources.md](docs/sources.md) |" in (ROOT / "README.md").read_text()


def _layout_block() -> str:
    readme = (ROOT / "README.md").read_text()
    section = readme.split("\n## Layout\n", 1)[1]
    return section.split("```\n", 2)[1]


def test_the_readme_layout_names_every_package_of_the_layer_contract():
    """Every package of the "layers point downwards" contract is a line of the README layout,
    in the contract's order (top first)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    (contract,) = [c for c in config["contracts"] if c["type"] == "layers"]
    packages = [p.strip().removeprefix("opentmcl.") for layer in contract["layers"] for p in layer.split("|")]
    named = [word for line in _layout_block().splitlines() if line and not line[0].isspace()
             for word in re.split(r",\s*", line.split("  ")[0].strip())]
    assert sorted(named) == sorted(packages)
    order = {p: i for i, layer in enumerate(contract["layers"]) for p in
             (q.strip().removeprefix("opentmcl.") for q in layer.split("|"))}
    ranks = [order[w] for w in named]
    assert ranks == sorted(ranks)
