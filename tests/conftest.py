"""Shared fixtures: the official PNML grammar and a validator every PNML test uses,
graphviz, and the engine under test; what tests import lives in helpers.py."""
from __future__ import annotations

import sys

import pytest

pytest.register_assert_rewrite("helpers")  # its assertions explain their failures, as a test's do

from helpers import ENGINES, ROOT, Engine  # noqa: E402  (after the rewrite hook)

sys.path.insert(0, str(ROOT))  # examples/ and paper_repro/ are not installed


@pytest.fixture(scope="session")
def grammar_dir() -> Path:
    """The official grammar; its absence is a failure that says what is missing."""
    from mcl2pnml.core.errors import Mcl2PnmlError
    from mcl2pnml.io.pnml.grammar import find_grammar

    try:
        return find_grammar()
    except Mcl2PnmlError as e:
        pytest.fail(f"the official PNML grammar is needed to judge our PNML: {e}")


@pytest.fixture(scope="session")
def assert_valid(grammar_dir):
    """Validate PNML bytes against the official grammar and the reader's rules."""
    from mcl2pnml.io.pnml.grammar import validate_bytes

    def check(data: bytes, name: str = "<written>") -> None:
        verdict = validate_bytes(data, name, grammar_dir)
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


@pytest.fixture(params=[Engine(name) for name in ENGINES], ids=ENGINES)
def engine(request) -> Engine:
    """Each engine in turn, for the checks that hold of either one alone."""
    return request.param
