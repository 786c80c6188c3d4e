"""The Model Checking Contest's questions about a P/T net, as typed values.

The contest (https://mcc.lip6.fr) asks each model the same kinds of
questions, each file one *examination* of 16 formulas: reachability,
CTL and LTL formulas over *cardinality* atoms (token counts compared) or
*fireability* atoms (is this transition enabled), and the upper bound of
sets of places. Its property language (an XML, the one
:mod:`mcl2pnml.io.mccquery` writes and reads) is this module's syntax tree,
and nothing else: :mod:`analysis.mcc` answers it on a net's state space.

A formula is evaluated at the initial marking, over the net's maximal firing
sequences; how a dead marking ends one (CTL and LTL read it differently) is
:mod:`analysis.mcc`'s to say.
"""
from __future__ import annotations

from dataclasses import dataclass

from mcl2pnml.core.errors import Location


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

@dataclass(frozen=True)
class Not:
    arg: "Formula"


@dataclass(frozen=True)
class And:
    args: tuple["Formula", ...]


@dataclass(frozen=True)
class Or:
    args: tuple["Formula", ...]


@dataclass(frozen=True)
class Next:
    arg: "Formula"


@dataclass(frozen=True)
class Until:
    before: "Formula"
    reach: "Formula"


@dataclass(frozen=True)
class Globally:
    arg: "Formula"


@dataclass(frozen=True)
class Finally:
    arg: "Formula"


@dataclass(frozen=True)
class AllPaths:
    arg: "Formula"


@dataclass(frozen=True)
class ExistsPath:
    arg: "Formula"


Formula = (IntLe | Fireable | Deadlock | BoolConst | Not | And | Or | Next | Until | Globally
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


def is_state(f: Formula) -> bool:
    """Whether ``f`` is a state formula without temporal operators (a marking decides it)."""
    if isinstance(f, ATOMS):
        return True
    if isinstance(f, Not):
        return is_state(f.arg)
    if isinstance(f, (And, Or)):
        return all(is_state(a) for a in f.args)
    return False


def is_ctl(f: Formula) -> bool:
    """Whether ``f`` is a CTL formula: each temporal operator right under a quantifier."""
    if isinstance(f, ATOMS):
        return True
    if isinstance(f, Not):
        return is_ctl(f.arg)
    if isinstance(f, (And, Or)):
        return all(is_ctl(a) for a in f.args)
    if isinstance(f, (AllPaths, ExistsPath)):
        inner = f.arg
        if isinstance(inner, (Next, Globally, Finally)):
            return is_ctl(inner.arg)
        if isinstance(inner, Until):
            return is_ctl(inner.before) and is_ctl(inner.reach)
        return is_state(inner) or is_ctl(inner) and isinstance(inner, (AllPaths, ExistsPath))
    return False


def is_ltl(f: Formula) -> bool:
    """Whether ``f`` is ``A φ`` with ``φ`` free of path quantifiers (the contest's LTL)."""
    def free(g: Formula) -> bool:
        if isinstance(g, ATOMS):
            return True
        if isinstance(g, (AllPaths, ExistsPath)):
            return False
        if isinstance(g, (Not, Next, Globally, Finally)):
            return free(g.arg)
        if isinstance(g, (And, Or)):
            return all(free(a) for a in g.args)
        if isinstance(g, Until):
            return free(g.before) and free(g.reach)
        return False
    return isinstance(f, AllPaths) and free(f.arg)
