"""Shared fixtures: the official PNML grammar where it is, a validator every PNML test uses,
graphviz, and the engine under test; what tests import lives in helpers.py."""
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


@pytest.fixture(params=[Engine(name) for name in ENGINES], ids=ENGINES)
def engine(request) -> Engine:
    """Each engine in turn, for the checks that hold of either one alone."""
    return request.param
