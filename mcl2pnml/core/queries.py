"""The Model Checking Contest's questions about a P/T net, as typed values.

The contest (https://mcc.lip6.fr) asks each model the same kinds of
questions, each file one *examination* of 16 formulas: reachability,
CTL and LTL formulas over *cardinality* atoms (token counts compared) or
*fireability* atoms (is this transition enabled), and the upper bound of
sets of places. Its property language (an XML, the one
:mod:`mcl2pnml.io.mccquery` writes and reads) is this module's syntax tree,
and nothing else: :mod:`mcl2pnml.analysis.contest.answers` answers it on a net's state space.

A formula is evaluated at the initial marking, over the net's maximal firing
sequences; how a dead marking ends one (CTL and LTL read it differently) is
:mod:`mcl2pnml.analysis.contest.answers`'s to say.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

from mcl2pnml.core.errors import Location
from mcl2pnml.core.temporal import (AllPaths, Conj, Disj, ExistsPath, Finally,  # noqa: F401
                                    Globally, Neg, Until)


# -- integers and atoms -----------------------------------------------------------------------

@dataclass(frozen=True)
class IntConst:
    value: int


@dataclass(frozen=True)
class TokensCount:
    """The sum of the tokens in ``places``."""

    places: tuple[str, ...]


IntExpr = IntConst | TokensCount


@dataclass(frozen=True)
class IntLe:
    """``left <= right``: the contest's one comparison (its ``integer-le``)."""

    left: IntExpr
    right: IntExpr


@dataclass(frozen=True)
class Fireable:
    """One of ``transitions`` is enabled (the contest's ``is-fireable``)."""

    transitions: tuple[str, ...]


@dataclass(frozen=True)
class Deadlock:
    """No transition is enabled."""


@dataclass(frozen=True)
class BoolConst:
    value: bool


# -- connectives, temporal operators, path quantifiers ---------------------------------------
#
# Those of a property's temporal form (:mod:`mcl2pnml.core.temporal`), the same tree, and
# the next-marking operator, which the contest's language has and the patterns do not use.

@dataclass(frozen=True)
class Next:
    arg: "Formula"


Formula = (IntLe | Fireable | Deadlock | BoolConst | Neg | Conj | Disj | Next | Until | Globally
           | Finally | AllPaths | ExistsPath)
ATOMS = (IntLe, Fireable, Deadlock, BoolConst)


@dataclass(frozen=True)
class PlaceBound:
    """The contest's UpperBounds question: the largest number of tokens ``places`` hold
    together in a reachable marking."""

    places: tuple[str, ...]


@dataclass(frozen=True)
class Query:
    """One formula of a file: its id, what it asks, where it was written."""

    id: str
    asks: Formula | PlaceBound
    location: Location | None = None


def children(f: Formula) -> tuple[Formula, ...]:
    """The formulas directly under ``f`` (none under an atom)."""
    if isinstance(f, (Conj, Disj)):
        return f.args
    if isinstance(f, Until):
        return (f.before, f.reach)
    if isinstance(f, ATOMS):
        return ()
    return (f.arg,)


def named(f: "Formula | PlaceBound") -> Iterator[tuple[str, str]]:
    """``("place", id)`` for each place ``f`` counts and ``("transition", id)`` for each
    transition whose fireability it asks, in the formula's order, repeats included."""
    if isinstance(f, (PlaceBound, TokensCount)):
        yield from (("place", p) for p in f.places)
    elif isinstance(f, Fireable):
        yield from (("transition", t) for t in f.transitions)
    elif isinstance(f, IntLe):
        yield from named(f.left)
        yield from named(f.right)
    elif not isinstance(f, IntConst):
        for g in children(f):
            yield from named(g)


def seen(f: "Formula | PlaceBound") -> tuple[frozenset[str], frozenset[str]]:
    """The places ``f`` counts and the transitions whose fireability it asks
    (:func:`named`, as two sets)."""
    names = list(named(f))
    return (frozenset(n for kind, n in names if kind == "place"),
            frozenset(n for kind, n in names if kind == "transition"))


def contains(f: Formula, kind: type) -> bool:
    """Whether an operator of ``kind`` occurs in ``f``."""
    return isinstance(f, kind) or any(contains(g, kind) for g in children(f))


def unnegated(f: Formula) -> tuple[bool, Formula]:
    """``(negated, g)``: ``f`` is ``g`` under an odd number of negations (``negated``) or
    an even one; ``g`` is not a negation."""
    negated = False
    while isinstance(f, Neg):
        negated, f = not negated, f.arg
    return negated, f


def path_quantified(f: Formula) -> tuple[bool, Formula] | None:
    """``(negated, g)``: ``f`` is ``g``, ``A ψ`` or ``E ψ`` with ψ free of path quantifiers
    (one run decides ψ), under ``negated``; None for any other formula."""
    negated, g = unnegated(f)
    if isinstance(g, (AllPaths, ExistsPath)) and not contains(g.arg, (AllPaths, ExistsPath)):
        return negated, g
    return None


def is_state(f: Formula) -> bool:
    """Whether ``f`` is a state formula without temporal operators (a marking decides it)."""
    return isinstance(f, (*ATOMS, Neg, Conj, Disj)) and all(map(is_state, children(f)))


def is_closed(f: Formula) -> bool:
    """Whether every temporal operator of ``f`` is under a path quantifier of ``f``: a
    marking decides it (a state formula of CTL*), so a quantifier over it is it."""
    if isinstance(f, (AllPaths, ExistsPath)):
        return True
    return isinstance(f, (*ATOMS, Neg, Conj, Disj)) and all(map(is_closed, children(f)))


def is_ctl(f: Formula) -> bool:
    """Whether ``f`` is a CTL formula: each temporal operator right under a quantifier."""
    if isinstance(f, (*ATOMS, Neg, Conj, Disj)):
        return all(map(is_ctl, children(f)))
    if isinstance(f, (AllPaths, ExistsPath)):
        inner = f.arg
        if isinstance(inner, (Next, Globally, Finally, Until)):
            return all(map(is_ctl, children(inner)))
        return is_closed(inner) and is_ctl(inner)      # A over a state formula: itself
    return False


def is_ltl(f: Formula) -> bool:
    """Whether ``f`` is ``A φ`` with ``φ`` free of path quantifiers (the contest's LTL)."""
    return isinstance(f, AllPaths) and not any(contains(g, (AllPaths, ExistsPath))
                                               for g in children(f))
