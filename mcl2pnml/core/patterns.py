"""Properties of a net's runs: the specification patterns and scopes, over markings.

A mission engineer states what must (never) happen in a mission: "the marker
is never released unless the cross was found", "after an abort, no primitive
stays enabled". Such a statement is one of the property specification
patterns catalogued by Dwyer, Avrunin and Corbett ("Patterns in property
specifications for finite-state verification", ICSE 1999): a *pattern*
(absence, universality, existence, bounded existence, precedence, response)
applied within a *scope* (globally, before R, after Q, between Q and R,
after Q until R).

This module is the typed form every stage shares, and nothing else: the
language compiles a mission's ``property`` declarations to it (its atoms,
"KeepDepth is enabled", "the call Survey-1 ended ABORTED", become
predicates on the places of the compiled net), :mod:`mcl2pnml.analysis.checking.on_graph`
checks it on the state space, and :mod:`mcl2pnml.io.mccquery` writes it in
the Model Checking Contest's property language. So a predicate here is
over a net's places only (token counts compared with constants), the one
kind of atom every Petri-net tool reads.

Semantics. A run is a maximal firing sequence from the initial marking,
seen as the sequence of markings it passes through: a finite run ends in a
dead marking (a mission's proper end is one), an infinite run loops. The
patterns and scopes mean what Dwyer et al.'s LTL mappings say, read over
these sequences, with a finite run taken as it is (no stuttering of its last
marking is assumed: "eventually" must happen within it). A property holds
when it holds on every run.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Callable

from mcl2pnml.core.errors import Location


# -- predicates on markings ---------------------------------------------------------------

@dataclass(frozen=True)
class Tokens:
    """The sum of the tokens in ``places`` is at least ``at_least``.

    "A place is marked" is ``Tokens((p,), 1)``; "all of them empty" is
    ``Not(Tokens(places, 1))``. Sums compared from below only, as the
    contest's ``integer-le`` writes them.
    """

    places: tuple[str, ...]
    at_least: int = 1


@dataclass(frozen=True)
class Not:
    arg: "Predicate"


@dataclass(frozen=True)
class And:
    args: tuple["Predicate", ...]


@dataclass(frozen=True)
class Or:
    args: tuple["Predicate", ...]


@dataclass(frozen=True)
class Const:
    """True or false in every marking (an empty conjunction, a scope never closed)."""

    value: bool


Predicate = Tokens | Not | And | Or | Const


def evaluate(predicate: Predicate, atom) -> bool:
    """Whether ``predicate`` holds, each of its ``Tokens`` comparisons answered by
    ``atom(tokens)``: a marking's sums (:func:`holds`), or a table of the atoms' truths (the
    on-the-fly checker's letters)."""
    if isinstance(predicate, Tokens):
        return atom(predicate)
    if isinstance(predicate, Not):
        return not evaluate(predicate.arg, atom)
    # loops rather than all()/any() over a generator: the same operands asked, in the same
    # order, stopping at the same one, without a generator frame per operand (a property of
    # thousands of operands is evaluated in every marking)
    if isinstance(predicate, And):
        for a in predicate.args:
            if not evaluate(a, atom):
                return False
        return True
    if isinstance(predicate, Or):
        for a in predicate.args:
            if evaluate(a, atom):
                return True
        return False
    return predicate.value


def holds(predicate: Predicate, marking) -> bool:
    """Whether ``predicate`` holds in ``marking`` (a mapping: place id -> tokens)."""
    return evaluate(predicate, lambda t: sum(marking.get(p, 0) for p in t.places) >= t.at_least)


def atoms_of(predicate: Predicate) -> tuple[Tokens, ...]:
    """The ``Tokens`` comparisons a predicate is made of, each once, in the order met."""
    # walked with a stack of what is left, left to right: a recursion through nested
    # generators cost several calls per operand, and the analysis asks this of every property
    met: dict[Tokens, None] = {}
    left = [predicate]
    while left:
        p = left.pop()
        if isinstance(p, Tokens):
            met[p] = None
        elif isinstance(p, Not):
            left.append(p.arg)
        elif isinstance(p, (And, Or)):
            left.extend(reversed(p.args))
    return tuple(met)


def places_of(predicate: Predicate) -> frozenset[str]:
    """Every place a predicate reads."""
    return frozenset(p for t in atoms_of(predicate) for p in t.places)


# -- patterns and scopes (Dwyer, Avrunin and Corbett) --------------------------------------

class Pattern(enum.Enum):
    """What must happen, or not, inside the scope."""

    ABSENCE = "absence"
    """P never holds inside the scope ("never P")."""
    UNIVERSALITY = "universality"
    """P holds in every marking inside the scope ("always P")."""
    EXISTENCE = "existence"
    """P holds in some marking inside the scope ("eventually P")."""
    BOUNDED_EXISTENCE = "bounded existence"
    """P becomes true at most ``bound`` times inside the scope (a becoming
    true is a marking where P holds after one where it did not, or the
    scope's first marking where it holds)."""
    PRECEDENCE = "precedence"
    """S precedes P: inside the scope, P holds only after S has held
    ("P only after S"; S need not happen if P never does)."""
    RESPONSE = "response"
    """S responds to P: inside the scope, every marking where P holds is
    followed (there or later, inside the scope) by one where S holds."""


class ScopeKind(enum.Enum):
    """The part of a run a pattern speaks about."""

    GLOBALLY = "globally"
    """The whole run."""
    BEFORE = "before"
    """From the start up to (not including) the first marking where R holds.

    A run where R never holds has no such interval, so the property holds on
    it by default, as Dwyer et al.'s mappings say (``<>R -> ...``): "never P
    before R" speaks of what precedes R, and a run without R has nothing to
    precede."""
    AFTER = "after"
    """From the first marking where Q holds to the end of the run."""
    BETWEEN = "between"
    """From each marking where Q holds (R not) to the next where R holds;
    an interval that R never closes does not count."""
    AFTER_UNTIL = "after until"
    """As between, but an interval R never closes counts, to the end of the run."""


@dataclass(frozen=True)
class Scope:
    kind: ScopeKind = ScopeKind.GLOBALLY
    q: Predicate | None = None      # opens the scope: after, between, after-until
    r: Predicate | None = None      # closes it: before, between, after-until


@dataclass(frozen=True)
class Property:
    """One property of a net's runs: a pattern in a scope, named, where it was written.

    ``p`` is the pattern's predicate (for precedence and response, the one
    that needs S: "P only after S", "P leads to S"); ``s`` the second one
    of precedence and response; ``bound`` the "at most" of bounded existence.
    ``text`` is the property as its author wrote it, for reports.
    """

    name: str
    pattern: Pattern
    p: Predicate
    s: Predicate | None = None
    bound: int | None = None
    scope: Scope = field(default_factory=Scope)
    text: str = ""
    location: Location | None = None


# -- reading them ---------------------------------------------------------------------------

class Grouping(enum.Enum):
    """Where a printed conjunction or disjunction puts its parentheses."""

    OPERANDS = "operands"
    """Around each compound operand, never around the whole: ``a >= 1 and (b >= 1 or
    c >= 1)``; no reader has to know which of ``and`` and ``or`` binds tighter."""
    WHOLE = "whole"
    """Around the whole, never around an operand: ``(a >= 1 and (b >= 1 or c >= 1))``,
    as verifydtapn's query grammar wants every boolean connective bracketed."""


@dataclass(frozen=True)
class PredicateSyntax:
    """What differs between the texts a predicate is printed in (:func:`describe`).

    The default is the reports' syntax, with the net's own place ids;
    :mod:`mcl2pnml.io.tapn` prints verifydtapn's, with the names its file
    gives the places.
    """

    #: a place's name in the text, from its id
    name: Callable[[str], str] = str
    #: where a conjunction or disjunction has its parentheses
    grouping: Grouping = Grouping.OPERANDS
    #: an empty sum (0 >= k) written as its truth (``true``/``false``) rather than as ``0``
    empty_sum_as_truth: bool = False


#: The reports' syntax: place ids as the net has them, compound operands parenthesised.
REPORTS = PredicateSyntax()


def describe(predicate: Predicate, syntax: PredicateSyntax = REPORTS) -> str:
    """A predicate as a place formula: ``KeepDepth.ON >= 1 and not (mission.OK >= 1)``,
    in the reports' syntax, or in the one ``syntax`` says (verifydtapn's)."""
    if isinstance(predicate, Tokens):
        if syntax.empty_sum_as_truth and not predicate.places:
            return _truth(predicate.at_least <= 0)
        total = " + ".join(syntax.name(p) for p in predicate.places) or "0"
        return f"{total} >= {predicate.at_least}"
    if isinstance(predicate, Not):
        return f"not ({describe(predicate.arg, syntax)})"
    if isinstance(predicate, (And, Or)):
        if not predicate.args:
            return _truth(isinstance(predicate, And))
        word = " and " if isinstance(predicate, And) else " or "
        if syntax.grouping is Grouping.WHOLE:
            return "(" + word.join(describe(a, syntax) for a in predicate.args) + ")"
        return word.join(describe(a, syntax) if isinstance(a, (Tokens, Const))
                         else f"({describe(a, syntax)})" for a in predicate.args)
    if isinstance(predicate, Const):
        return _truth(predicate.value)
    raise TypeError(f"not a predicate: {predicate!r}")


def _truth(value: bool) -> str:
    return "true" if value else "false"
