"""Shared fixtures: the official PNML grammar beside the checkout, a validator every PNML test uses,
graphviz, headless Chromium, the engine under test, and the examples compiled once; what
tests import lives in helpers.py."""
from __future__ import annotations

import functools
import sys
from pathlib import Path

import pytest

pytest.register_assert_rewrite("helpers")  # its assertions explain their failures, as a test's do

from helpers import (ENGINES, NO_GRAMMAR, ROOT, Engine,  # noqa: E402  (after the rewrite hook)
                     official_grammar_dir)

from mcl2pnml import pipeline  # noqa: E402
from mcl2pnml.core.net import Net  # noqa: E402

sys.path.insert(0, str(ROOT))  # examples/ and paper_repro/ are not installed


@pytest.fixture(scope="session")
def grammar_dir() -> Path:
    """The official grammar at ../shared/pnml-grammar, for the tests that need AFNOR's files
    themselves; skipped where it is not (a clone without ../shared), saying so."""
    found = official_grammar_dir()
    if found is None:
        pytest.skip(NO_GRAMMAR)
    return found


@pytest.fixture(scope="session")
def assert_valid():
    """Validate PNML bytes against our schema, the official grammar where it is, and the
    reader's rules."""
    from mcl2pnml.io.pnml.grammar import validate_bytes

    def check(data: bytes, name: str = "<written>") -> None:
        verdict = validate_bytes(data, name, official_grammar_dir())
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


@pytest.fixture(scope="session")
def browser():
    """Headless Chromium, one per test process (each test opens its own pages in their
    own contexts); its absence is a failure that says how to get it."""
    from screens import CHROMIUM_FLAGS, chromium   # (as docs/show_sauce_*.png are shot)

    executable = chromium()
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


class Tab:
    """One page of the browser that the tests opening page files one at a time navigate
    afresh (each opening a new document: its script, its DOM, its timers): a new page
    costs Chromium a window of its own, its renderer and its omnibox's WebUI, about a
    core-second, where a navigation costs a fifth of that. A page closed (a test that
    broke it) is replaced at the next opening."""

    def __init__(self, browser):
        self.browser = browser
        self.current = None

    def page(self, viewport: dict):
        if self.current is None or self.current.is_closed():
            self.current = self.browser.new_page(viewport=viewport)
        else:
            self.current.set_viewport_size(viewport)
        return self.current

    def leave(self) -> None:
        """The page emptied (nothing of the last test's page runs on) for the next test;
        closed if it does not answer, to be replaced."""
        page = self.current
        if page is None or page.is_closed():
            return
        try:
            page.goto("about:blank", timeout=30_000)
            page.mouse.up()                 # a drag a failed test left pressed
            page.mouse.move(0, 0)           # where a new page has it: nothing hovered
        except Exception:   # noqa: BLE001  (a page that broke: the next test gets a new one)
            page.close()


@pytest.fixture(scope="session")
def tab(browser) -> Tab:
    """The page the tests share, one test at a time (see :class:`Tab`)."""
    return Tab(browser)


class CompiledExamples:
    """``examples/NAME.mcl`` checked, compiled and written as PNML at most once per test
    process, for the tests that need an example's net rather than the compiling itself.

    Nets and checked programs are immutable, so every test may share them; the PNML
    files are the ones ``mcl2pnml compile NAME.mcl -o NAME.pnml`` writes (laid out by
    dot), in a folder of the session's, and are only to be read.
    """

    def __init__(self, folder: Path):
        self.folder = folder

    @staticmethod
    def mission(name: str) -> Path:
        """The example's source, by its stem (``sauce``) or file name."""
        path = ROOT / "examples" / Path(name).with_suffix(".mcl").name
        assert path.is_file(), f"no example {path}"
        return path

    # cached on the instance, which lives as long as the session: the point of the class
    @functools.cache   # noqa: B019
    def checked(self, name: str):
        """The example as ``pipeline.check_file`` returns it."""
        return pipeline.check_file(self.mission(name))

    @functools.cache   # noqa: B019
    def net(self, name: str) -> Net:
        """The example's net, as ``pipeline.compile_file`` returns it."""
        return pipeline.compile_file(self.mission(name), checked=self.checked(name))

    @functools.cache   # noqa: B019
    def pnml(self, name: str) -> Path:
        """The example's net as ``mcl2pnml compile`` writes it (not to be written to)."""
        return pipeline.save_pnml(self.net(name), self.folder / f"{self.mission(name).stem}.pnml")


@pytest.fixture(scope="session")
def examples(tmp_path_factory) -> CompiledExamples:
    """Every example compiled once per test process (each xdist worker has its own)."""
    return CompiledExamples(tmp_path_factory.mktemp("examples"))


@pytest.fixture(params=[Engine(name) for name in ENGINES], ids=ENGINES)
def engine(request) -> Engine:
    """Each engine in turn, for the checks that hold of either one alone."""
    return request.param


#: Modules whose tests wait the longest on other processes (the tutorial's hundred commands
#: and its peers, the autopilot's flights, the Dask clusters, the runs stopped by signals):
#: collected first, whole, so that the workers start them first and the run does not end
#: waiting for one of them alone; every other module, and the order within each, is kept.
FIRST = ("test_tutorial.py", "test_ardusub.py", "test_campaign.py", "test_endings.py")


def pytest_collection_modifyitems(config, items):
    items.sort(key=lambda item: item.path.name not in FIRST)    # stable
