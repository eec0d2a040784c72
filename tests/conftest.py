"""Shared test configuration."""
import os

import pytest
from hypothesis import settings

settings.register_profile("ci", max_examples=60, deadline=None, derandomize=True)  # reproducible CI
settings.register_profile("long", max_examples=5000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture(scope="session")
def sdist(tmp_path_factory):
    """The sdist built from a snapshot of the tracked files, with a developer's untracked leftovers
    added (tests/distribution.py), once a session."""
    from tests.distribution import Built, build, snapshot, with_leftovers

    base = tmp_path_factory.mktemp("sdist")
    tree = with_leftovers(snapshot(base / "tree"))
    return Built(tree, build(tree, base / "dist", "sdist"))


@pytest.fixture(scope="session")
def wheel(sdist, tmp_path_factory):
    """The wheel built from the unpacked sdist (as pip builds one), for this Python."""
    import tarfile

    from tests.distribution import Built, build

    base = tmp_path_factory.mktemp("wheel")
    with tarfile.open(sdist.path) as archive:
        archive.extractall(base, filter="data")
    (tree,) = [p for p in base.iterdir() if p.is_dir()]
    return Built(tree, build(tree, base / "dist", "wheel"))


@pytest.fixture(scope="session")
def browser():
    """Headless Chromium through Playwright, once per test process (tests/browser.py)."""
    from tests.browser import chromium_context

    yield from chromium_context()
