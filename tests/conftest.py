"""Shared fixtures: the official PNML grammar and a validator every PNML test uses."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data"
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
