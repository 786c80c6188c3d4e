"""docs/ARCHITECTURE.md stays a true, short map: under 2,500 words, and every file,
test and module it names exists (a renamed module breaks this test, not the reader)."""
from __future__ import annotations

import importlib
import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "ARCHITECTURE.md"
TEXT = DOC.read_text(encoding="utf-8")
ROOTS = ("tests/", "mcl2pnml/", "analysis/", "docs/", "bench/", "templates/", "paper_repro/")


def _quoted() -> list[str]:
    return re.findall(r"`([^`\s]+)`", TEXT)


def test_the_map_is_short():
    words = len(TEXT.split())
    assert words < 2500, f"docs/ARCHITECTURE.md has {words:,} words"


@pytest.mark.parametrize("path", sorted({q.split("::")[0] for q in _quoted()
                                         if q.startswith(ROOTS) and "*" not in q
                                         and "NAME" not in q}))
def test_every_file_it_names_exists(path: str):
    assert (ROOT / path).exists(), f"docs/ARCHITECTURE.md names {path}, which is not there"


def _resolves(dotted: str) -> bool:
    """A module of the package, or an attribute of one."""
    module, attribute = dotted, None
    while module:
        try:
            if importlib.util.find_spec(module) is not None:
                break
        except ModuleNotFoundError:
            pass
        module, _, last = module.rpartition(".")
        attribute = last if attribute is None else f"{last}.{attribute}"
    if not module:
        return False
    found = importlib.import_module(module)
    for name in (attribute.split(".") if attribute else ()):
        if not hasattr(found, name):
            return False
        found = getattr(found, name)
    return True


#: A dotted name the map writes short, and the package it is short for.
SHORT = {**{head: "mcl2pnml." for head in ("core", "language", "io", "runtime", "view",
                                          "certify", "commands", "pipeline", "analysis")},
         **{head: "mcl2pnml.analysis." for head in ("statespace", "checking", "structure",
                                                    "timed", "contest", "report")}}


def _dotted() -> set[str]:
    out = set()
    for q in _quoted():
        q = q.split("(")[0].rstrip(",.:;")
        head = q.split(".")[0]
        if re.fullmatch(r"mcl2pnml(\.\w+)+", q) and not q.endswith(".py"):
            out.add(q)
        elif head in SHORT and re.fullmatch(r"\w+(\.\w+)+", q) and not q.endswith(".py"):
            out.add(SHORT[head] + q)
    return out


@pytest.mark.parametrize("dotted", sorted(_dotted()))
def test_every_module_it_names_exists(dotted: str):
    assert _resolves(dotted), f"docs/ARCHITECTURE.md names {dotted}, which is not there"
