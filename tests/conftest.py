"""Shared fixtures: the official PNML grammar where it is, a validator every PNML test uses,
graphviz, headless Chromium, and the engine under test; what tests import lives in helpers.py."""
from __future__ import annotations

import sys

import pytest

pytest.register_assert_rewrite("helpers")  # its assertions explain their failures, as a test's do

from helpers import ENGINES, ROOT, Engine  # noqa: E402  (after the rewrite hook)

sys.path.insert(0, str(ROOT))  # examples/ and paper_repro/ are not installed


@pytest.fixture(scope="session")
def grammar_dir() -> Path:
    """The official grammar, for the tests that need AFNOR's files themselves; skipped
    where they are not (a clone without ../shared), since they are not ours to ship."""
    from mcl2pnml.io.pnml.grammar import ENV, find_grammar

    found = find_grammar()
    if found is None:
        pytest.skip(f"the official PNML grammar is not here (no {ENV}, no shared/pnml-grammar "
                    f"beside or above) or is set aside ({ENV}=none); our own schema is applied "
                    "without it")
    return found


@pytest.fixture(scope="session")
def assert_valid():
    """Validate PNML bytes against our schema, the official grammar where it is, and the
    reader's rules."""
    from mcl2pnml.io.pnml.grammar import validate_bytes

    def check(data: bytes, name: str = "<written>") -> None:
        verdict = validate_bytes(data, name)
        assert verdict.valid, "\n".join(str(e) for e in verdict.errors)

    return check


@pytest.fixture(scope="session")
def dot() -> str:
    """graphviz's dot; its absence is a failure that says how to get it."""
    import shutil

    path = shutil.which("dot")
    if path is None:
        pytest.fail("graphviz 'dot' is needed to lay out and draw nets: `make setup` "
                    "installs it with apt-get (or: apt-get install graphviz)")
    return path


#: Chromium as the tests run it: headless, offline, as root in a container.
CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update",
                  "--disable-sync"]


@pytest.fixture(scope="session")
def browser():
    """Headless Chromium, one per test process (each test opens its own pages in their
    own contexts); its absence is a failure that says how to get it."""
    import shutil

    executable = shutil.which("chromium") or shutil.which("chromium-browser")
    if executable is None:
        pytest.fail("Chromium is needed to test the token game page: `make setup` installs "
                    "it with apt-get (or: apt-get install chromium)")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.fail("Playwright is needed to drive Chromium: `make setup` installs the test "
                    "dependencies (pip install -e '.[test]')")
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=executable, headless=True, args=CHROMIUM_FLAGS)
        yield b
        b.close()


@pytest.fixture(params=[Engine(name) for name in ENGINES], ids=ENGINES)
def engine(request) -> Engine:
    """Each engine in turn, for the checks that hold of either one alone."""
    return request.param


#: Modules whose tests wait the longest on other processes (the tutorial's hundred commands
#: and its peers, the autopilot's flights, the Dask clusters): collected first, whole, so
#: that the workers start them first and the run does not end waiting for one of them
#: alone; every other module, and the order within each, is kept.
FIRST = ("test_tutorial.py", "test_ardusub.py", "test_campaign.py")


def pytest_collection_modifyitems(config, items):
    items.sort(key=lambda item: item.path.name not in FIRST)    # stable
