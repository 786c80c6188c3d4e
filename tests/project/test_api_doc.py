"""docs/api.md stays true: every example of its ```python blocks runs, in order, as one
session from the repository's root, and so does every example of the facade's docstrings
(mcl2pnml.pipeline, re-exported by mcl2pnml)."""
from __future__ import annotations

import doctest
import re

import mcl2pnml
from mcl2pnml import pipeline

from helpers import ROOT

DOC = ROOT / "docs" / "api.md"
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
FENCE = re.compile(r"^```python\n(.*?)^```", re.M | re.S)


def run(tests) -> tuple[int, str]:
    """How many examples ``tests`` tried, and the report of those that failed ("" when
    none did)."""
    said: list[str] = []
    runner = doctest.DocTestRunner(verbose=False, optionflags=FLAGS)   # not pytest's -v
    for test in tests:
        runner.run(test, out=said.append, clear_globs=False)
    return runner.tries, "".join(said) if runner.failures else ""


def test_every_example_of_the_api_page_runs(monkeypatch):
    monkeypatch.chdir(ROOT)
    text = DOC.read_text(encoding="utf-8")
    parser, session = doctest.DocTestParser(), {}
    tests = [parser.get_doctest(m.group(1), session, "docs/api.md", str(DOC),
                                text[:m.start()].count("\n") + 1) for m in FENCE.finditer(text)]
    for test in tests:   # one session: each block goes on from the one before
        test.globs = session
    tried, failed = run(tests)
    assert not failed, failed
    assert tried > 25


def test_every_example_of_the_facade_runs(monkeypatch):
    monkeypatch.chdir(ROOT)
    tests = doctest.DocTestFinder().find(pipeline) + doctest.DocTestFinder().find(mcl2pnml)
    tried, failed = run(tests)
    assert not failed, failed
    documented = {t.name.rpartition(".")[2] for t in tests if t.examples}
    assert {"check_file", "compile_file", "compile_source", "analyze", "certify_file",
            "run_mission", "exact_odds", "timed_ends", "check_properties"} <= documented
