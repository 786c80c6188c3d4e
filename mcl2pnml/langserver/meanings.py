"""What the words of MCL mean, read from where the project says it: the grammar's keywords
(lark's terminals of :data:`mcl2pnml.language.parser.GRAMMAR`), the task patterns and
control structures (the template library, ``templates/*.pnt``, and the patterns' proofs
for their results: sections 2.3-2.5 of the paper), the primitives of the simulated
vehicle (its table, :mod:`mcl2pnml.runtime.simprims`, through the facade) and the atoms
of a property (:data:`mcl2pnml.language.declared_properties.ATOMS`).

Nothing here is a second copy: a pattern added as a ``.pnt`` file, or a simulated
primitive an installed package adds, is offered and explained as the built-in ones are.
Each fact is read once, when first asked for.
"""
from __future__ import annotations

import re
import threading
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from mcl2pnml import pipeline
from mcl2pnml.core.errors import Mcl2PnmlError, visible
from mcl2pnml.core.payloads import doc_of

#: The grammar's words by where they may be written (:func:`grammar_words` is their
#: union, ``tests/langserver`` holds them to it): those that begin a declaration, a
#: structure statement, what follows an ``if``'s or a ``while``'s condition and an if's
#: block, and a task's time-out; every other word of the grammar is a property's.
DECLARATION_WORDS = ("const", "primitive", "task", "function", "mission", "property")
STATEMENT_WORDS = ("parallel", "monitor", "if", "while")
FOLLOWING_WORDS = ("then", "do", "else")
TASK_WORDS = ("timeout",)
#: Each structure statement's template (section 2.5): the net its keyword compiles to.
STRUCTURE_TEMPLATES = {"parallel": "parallel", "monitor": "monitor", "if": "if-then-else",
                       "while": "while"}
#: A task's results (docs/mcl.md, "Results"), in the order they are told.
RESULTS = ("OK", "FAIL", "ABORTED")
#: What aborts a task: only a monitor stops anything (docs/mcl.md, "Results").
ABORTED = "when the structure above stops it: a monitor whose other part ended first"


def grammar_words() -> frozenset[str]:
    """Every word the grammar writes as a literal: its keywords, reserved or a property's."""
    # lark, 40 ms, and the grammar's analysis, 0.1 s: only for a server's words
    from lark import Lark
    from mcl2pnml.language.parser import GRAMMAR
    terminals = Lark(GRAMMAR, parser="lalr").terminals
    return frozenset(t.pattern.value for t in terminals
                     if t.pattern.type == "str" and re.fullmatch("[a-z]+", t.pattern.value))


@dataclass(frozen=True)
class Pattern:
    """A task pattern: its name, its one-line doc, its template file, its number of
    primitives, and each result's words (its place's doc in the template)."""

    name: str
    doc: str
    source: Path | None
    slots: int
    results: dict[str, str]


@dataclass(frozen=True)
class Simulated:
    """A primitive of the simulated vehicle: its arguments, when it reports achieved and
    when failed, in words."""

    arguments: str
    achieves: str
    fails: str


class Vocabulary:
    """The facts, each read on first use; safe to ask from two threads (the server's
    checks run in one, its answers in another)."""

    def __init__(self) -> None:
        self._lock = threading.RLock()
        self._ends: dict[tuple[str, bool], tuple[tuple[str, ...], bool] | str] = {}

    @cached_property
    def words(self) -> frozenset[str]:
        with self._lock:
            return grammar_words()

    @cached_property
    def property_words(self) -> tuple[str, ...]:
        said = {*DECLARATION_WORDS, *STATEMENT_WORDS, *FOLLOWING_WORDS, *TASK_WORDS}
        return tuple(sorted(self.words - said))

    @cached_property
    def _library(self):
        # lark, 40 ms, and the templates, 30 ms: only for a server's words
        from mcl2pnml.language.library import default_library
        with self._lock:
            return default_library()

    @cached_property
    def patterns(self) -> dict[str, Pattern]:
        # the template kinds, with the library: only for a server's words
        from mcl2pnml.language.template_parser import TemplateKind
        out = {}
        for t in self._library.unique():
            if t.kind is TemplateKind.PATTERN:
                docs = {p.interface: str(doc_of(p.payload) or "").removeprefix("ended: ")
                        for p in t.net.places if p.interface in RESULTS}
                out[t.name] = Pattern(t.name, t.doc, _path(t.source), len(t.primitives),
                                      docs)
        return out

    def structure(self, keyword: str) -> tuple[str, str, Path | None] | None:
        """The template a structure keyword compiles to: its name, doc and file."""
        name = STRUCTURE_TEMPLATES.get(keyword)
        if name is None or name not in self._library.templates:
            return None
        t = self._library.templates[name]
        return t.name, t.doc, _path(t.source)

    def ends(self, pattern: str, timeout: bool) -> tuple[tuple[str, ...], bool] | str:
        """:func:`mcl2pnml.pipeline.pattern_ends`, or why it cannot be told."""
        key = (pattern, timeout)
        with self._lock:
            if key not in self._ends:
                try:
                    self._ends[key] = pipeline.pattern_ends(pattern, timeout)
                except (Mcl2PnmlError, KeyError) as e:
                    self._ends[key] = visible(str(e))
            return self._ends[key]

    @cached_property
    def simulated(self) -> dict[str, Simulated]:
        with self._lock:
            try:
                rows = pipeline.simulated_primitives()
            except Mcl2PnmlError:   # an installed package's primitives that do not load
                rows = []
        return {name: Simulated(args, achieves, fails) for name, args, achieves, fails in rows}

    @cached_property
    def atoms(self) -> dict[str, tuple[str, ...]]:
        # the properties' atoms, with lark: only for a server's words
        from mcl2pnml.language.declared_properties import ATOMS
        return dict(ATOMS)

    @cached_property
    def unbounded(self) -> dict[str, str]:
        """What a task of a built-in pattern with no time-out waits for (the lint's words,
        :data:`mcl2pnml.language.lint.UNBOUNDED`)."""
        # the lint's words, with lark: only for a server's words
        from mcl2pnml.language.lint import UNBOUNDED
        return dict(UNBOUNDED)

    def warm(self) -> None:
        """Read every fact now (the server does it once it has started, before the first
        question that needs them)."""
        for name in self.patterns:
            for timeout in (True, False):
                self.ends(name, timeout)
        self.structure("if")
        _ = self.words, self.simulated, self.atoms, self.unbounded


def _path(source) -> Path | None:
    path = Path(str(source)) if source else None
    return path if path is not None and path.is_file() else None
