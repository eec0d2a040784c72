"""The source distribution and the wheel carry what the README promises (issue 32 items 2 and 3).

Issue 32: "The sdist lacks docs/ and examples/, so the README's relative links are dead on an index
page, and the examples that the docs cite cannot be run from an sdist"; "Placeholder project URLs
(`opentmcl.example.org`) are published in the metadata. Metadata must not point at addresses that
do not exist: give none rather than fake ones." Done when "the built sdist and wheel carry what the
README links to". The sdist is built by `python -m build` from the tracked files (tests/conftest.py).
"""
from __future__ import annotations

import fnmatch
import posixpath
import re

from tests.distribution import LEFTOVERS, PROJECT, Built

LINK = re.compile(r"\]\(([^)\s]+)\)")
"""A Markdown link or image target."""
CITED = re.compile(r"(?<![\w./-])((?:docs|examples|bench|tests|src|\.ci)/[\w.*/-]*[\w*])")
"""A path of the tree cited in prose or a command (`examples/...tmc`, `bench/run.py`)."""
PLACEHOLDER_HOSTS = re.compile(r"\bexample\.(?:org|com|net)\b|\.(?:invalid|example)(?![\w.-])", re.I)
"""Names reserved for documentation (RFC 2606): no real project lives there."""


def tracked(built: Built, folder: str) -> set[str]:
    return {p.relative_to(built.tree).as_posix() for p in (built.tree / folder).rglob("*")
            if p.is_file() and p.relative_to(built.tree).as_posix() not in LEFTOVERS}


def markdown_files(built: Built) -> list[str]:
    return ["README.md"] + sorted(n for n in tracked(built, "docs") if n.endswith(".md"))


def test_the_sdist_carries_docs_and_examples_whole(sdist):
    """Every tracked file of docs/ (pages and their images) and examples/ (the programs the docs
    run, the scenarios, the pytest example) is in the sdist."""
    names = sdist.names()
    for folder in ("docs", "examples"):
        files = tracked(sdist, folder)
        assert len(files) > 10, folder
        assert sorted(files - names) == [], folder


def test_every_relative_link_of_the_readme_and_docs_resolves_inside_the_sdist(sdist):
    """The README's and the docs' Markdown links (pages, images, `../src/...` files), followed from
    the file that holds them, land on a file of the sdist."""
    names = sdist.names()
    dead, seen = [], 0
    for page in markdown_files(sdist):
        for target in LINK.findall((sdist.tree / page).read_text(encoding="utf-8")):
            path = target.split("#", 1)[0]
            if not path or re.match(r"[a-z][a-z0-9+.-]*:", path):   # an anchor of the page, a URL
                continue
            seen += 1
            resolved = posixpath.normpath(posixpath.join(posixpath.dirname(page), path))
            if resolved not in names:
                dead.append(f"{page}: {target}")
    assert seen > 40 and dead == []


def present(path: str, files: set[str]) -> bool:
    """Is `path` (a file, a folder or a glob) among `files`?"""
    return path in files or any(f.startswith(path.rstrip("/") + "/") for f in files) or bool(fnmatch.filter(files, path))


def test_every_path_the_readme_and_docs_cite_is_in_the_sdist(sdist):
    """Paths cited in prose and commands (`opentmcl run examples/...tmc`, `python bench/run.py`,
    `tests/modules/test_pytrinamic_names.py`, `src/opentmcl/modules/data/*.toml`) that are tracked
    files are in the sdist; the others are files a command writes (`first.bin`, bench results)."""
    names, files = sdist.names(), tracked(sdist, ".")
    cited = {p for page in markdown_files(sdist)
             for p in CITED.findall((sdist.tree / page).read_text(encoding="utf-8"))}
    in_tree = {p for p in cited if present(p, files)}
    assert {"bench/run.py", "examples/scenarios/tmcm6212_stage.toml", "tests/test_layers.py", ".ci/run"} <= in_tree
    assert sorted(p for p in in_tree if not present(p, names)) == []


def test_the_sdist_leaves_out_what_a_working_tree_collects(sdist):
    """Bytecode, a compiled file left in place and bench results of the developer's tree
    (tests/distribution.py LEFTOVERS, put into the built tree) stay out; the package is pure Python
    (issue 33: "installs without a compiler"), so no C source travels either."""
    names = sdist.names()
    assert {n for n in LEFTOVERS if (sdist.tree / n).exists()} == set(LEFTOVERS)
    assert sorted(names & set(LEFTOVERS)) == []
    assert [n for n in names if "__pycache__" in n or n.endswith((".pyc", ".so"))] == []
    assert [n for n in names if n.endswith((".c", ".h", ".pyi")) or n == "setup.py"] == []


def test_the_metadata_names_no_placeholder_address(sdist):
    """Item 2: no `Project-URL` or `Home-page` at all while the project has no public address, and
    no documentation-only host name (example.org, ...) anywhere in the metadata, README included."""
    meta = sdist.read("PKG-INFO")
    headers = meta.split("\n\n", 1)[0]
    assert not [line for line in headers.splitlines() if line.startswith(("Project-URL:", "Home-page:"))]
    assert PLACEHOLDER_HOSTS.findall(meta) == []
    assert "urls" not in PROJECT


def test_placeholder_hosts_are_recognised():
    """The pattern of the test above catches the old metadata's addresses and passes real text."""
    assert PLACEHOLDER_HOSTS.findall("Project-URL: Homepage, https://opentmcl.example.org/") == ["example.org"]
    assert PLACEHOLDER_HOSTS.findall("http://host.invalid/ www.example.com a.example:80") == [
        ".invalid", "example.com", ".example"]
    assert PLACEHOLDER_HOSTS.findall("open http://127.0.0.1:8080/ (examples/x.tmc)") == []


def test_the_metadata_claims_the_python_versions_of_pyproject(sdist):
    """Item 1: the published metadata says >= 3.11 and lists the same classifiers; the test extra
    names the starlette whose TestClient uses httpx2 (1.2)."""
    headers = sdist.read("PKG-INFO").split("\n\n", 1)[0].splitlines()
    assert "Requires-Python: >=3.11" in headers
    assert [h.split(": ", 1)[1] for h in headers if h.startswith("Classifier: Programming Language :: Python :: 3.")] == \
        ["Programming Language :: Python :: 3.11", "Programming Language :: Python :: 3.12",
         "Programming Language :: Python :: 3.13"]
    assert 'Requires-Dist: starlette>=1.2; extra == "test"' in headers


def test_the_wheel_is_one_universal_pure_python_wheel(wheel):
    """Issue 33: "the package is pure Python, installs without a compiler, and ships one universal
    wheel": the wheel's tag is py3-none-any and it holds no compiled file."""
    assert wheel.path.name.endswith("-py3-none-any.whl"), wheel.path.name
    assert [n for n in wheel.names() if n.endswith((".so", ".pyd", ".c"))] == []


def test_the_wheel_built_from_the_sdist_carries_the_whole_package(sdist, wheel):
    """Every tracked file of src/opentmcl -- code, py.typed, the module profiles, the include files,
    the dashboard's pages and vendored uPlot and CodeMirror -- is in the wheel built from the sdist."""
    names = wheel.names()
    package = {n.removeprefix("src/") for n in tracked(sdist, "src/opentmcl")}
    assert {"opentmcl/py.typed", "opentmcl/modules/data/tmcm6212.toml"} <= package | names
    assert sorted(package - names) == []
    assert any(n.startswith("opentmcl/web/static/vendor/uplot/") for n in names)
    assert any(n.startswith("opentmcl/web/static/vendor/codemirror/") for n in names)
