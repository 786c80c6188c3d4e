"""Temporal formulas over place predicates: a property's LTL and CTL forms.

A property (:mod:`mcl2pnml.core.patterns`) is checked here by an observer
of the marking sequence (:mod:`mcl2pnml.analysis.checking.on_graph`); other model checkers
are given it as a temporal formula, in the Model Checking Contest's
language (:mod:`mcl2pnml.io.mccquery`). This module is the formula: a small
typed syntax (state predicates, the path operators next-free LTL needs,
CTL's path quantifiers), and the translation of each pattern in each scope,
after Dwyer, Avrunin and Corbett's catalogue of mappings ("Patterns in
property specifications for finite-state verification", ICSE 1999).

The mappings are built from one piece per pattern, *the pattern on the
stretch from here up to (not including) the first R* (:func:`_segment`),
placed in its scope:

========================  ===============================================
globally                  the segment with R = false: the whole run
before R                  ``<>R -> segment``
after Q                   ``[]!Q | (!Q U (Q & segment))``: from the first Q
between Q and R           ``[]((Q & !R & <>R) -> segment)``
after Q until R           ``[]((Q & !R) -> segment)``
========================  ===============================================

and the segments, with ``a W b`` (weak until) written ``(a U b) | []a``
since the contest's language has the strong one only:

========================  ===============================================
absence                   ``!P W R``
universality              ``P W R``
existence                 ``!R U (P & !R)``
bounded existence (K)     ``!(!R U (P & !R & (!R U (!P & !R & (!R U ...)))))``:
                          no P, then not-P, then P ... (K + 1 times P)
                          before R (the catalogue's alternating weak
                          untils say the same, with far larger automata)
precedence (P after S)    ``!P W (S | R)``
response (P leads to S)   ``(P -> (!R U (S & !R))) W R``
========================  ===============================================

Two departures from the catalogue's text, both to mean what
:class:`~mcl2pnml.core.patterns.ScopeKind` says: *after Q* is anchored
at the first Q (the catalogue's ``<>(Q & ...)`` for bounded existence
would let a later Q choose a shorter suffix), and a weak until stands where
the catalogue writes a strong one under ``<>R`` (the same there).

The formulas read runs as :mod:`mcl2pnml.core.patterns` does; the
contest's tools extend a finite run by repeating its dead marking forever,
and for these formulas, which have no next operator, that is the same
reading (a finite run satisfies one exactly when its stuttered extension
does). The tests check each formula against the observer on every run of
random nets, and against verifypn and LoLA on the exported queries.
"""
from __future__ import annotations

from dataclasses import dataclass

from mcl2pnml.core.patterns import (And, Const, Not, Or, Pattern, Predicate, Property,
                                      ScopeKind, describe, holds)


# -- the syntax ------------------------------------------------------------------------------

@dataclass(frozen=True)
class State:
    """A predicate on the current marking."""

    predicate: Predicate


@dataclass(frozen=True)
class Neg:
    arg: "Formula"


@dataclass(frozen=True)
class Conj:
    args: tuple["Formula", ...]


@dataclass(frozen=True)
class Disj:
    args: tuple["Formula", ...]


@dataclass(frozen=True)
class Until:
    """``before U reach``: reach holds some time, before it holds until then (strong)."""

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
    """CTL's A, or the LTL formula's "on every run" at its top."""

    arg: "Formula"


@dataclass(frozen=True)
class ExistsPath:
    """CTL's E."""

    arg: "Formula"


Formula = State | Neg | Conj | Disj | Until | Globally | Finally | AllPaths | ExistsPath

TRUE, FALSE = State(Const(True)), State(Const(False))


# -- building, with the trivial cases folded (the formulas stay readable) --------------------

def neg(f: Formula) -> Formula:
    if isinstance(f, State) and isinstance(f.predicate, Const):
        return FALSE if f.predicate.value else TRUE
    if isinstance(f, Neg):
        return f.arg
    if isinstance(f, State) and isinstance(f.predicate, Not):
        return State(f.predicate.arg)
    return Neg(f)


def conj(*fs: Formula) -> Formula:
    if FALSE in fs:
        return FALSE
    fs = tuple(g for f in fs for g in (f.args if isinstance(f, Conj) else (f,)) if g != TRUE)
    return TRUE if not fs else fs[0] if len(fs) == 1 else Conj(fs)


def disj(*fs: Formula) -> Formula:
    if TRUE in fs:
        return TRUE
    fs = tuple(g for f in fs for g in (f.args if isinstance(f, Disj) else (f,)) if g != FALSE)
    return FALSE if not fs else fs[0] if len(fs) == 1 else Disj(fs)


def implies(a: Formula, b: Formula) -> Formula:
    return disj(neg(a), b)


def until(a: Formula, b: Formula) -> Formula:
    if b in (TRUE, FALSE):
        return b
    return finally_(b) if a == TRUE else b if a == FALSE else Until(a, b)


def weak_until(a: Formula, b: Formula) -> Formula:
    """``a W b``: ``(a U b) | []a`` (the contest's language has no weak until)."""
    return disj(until(a, b), globally(a))


def globally(a: Formula) -> Formula:
    return a if a in (TRUE, FALSE) else Globally(a)


def finally_(a: Formula) -> Formula:
    return a if a in (TRUE, FALSE) else Finally(a)


def state(p: Predicate | None) -> Formula:
    return FALSE if p is None else State(p)


# -- the patterns (the module's tables) -------------------------------------------------------

def _segment(prop: Property, r: Formula) -> Formula:
    """The pattern on the stretch from here up to (not including) the first ``r``."""
    p, s, nr = state(prop.p), state(prop.s), neg(r)
    pattern = prop.pattern
    if pattern is Pattern.ABSENCE:
        return weak_until(neg(p), r)
    if pattern is Pattern.UNIVERSALITY:
        return weak_until(p, r)
    if pattern is Pattern.EXISTENCE:
        return until(nr, conj(p, nr))
    if pattern is Pattern.BOUNDED_EXISTENCE:
        # not K + 1 times: no P, later a not-P, later a P ... (2K + 1 markings, P last)
        # before R; the catalogue's alternating weak untils mean the same, but their
        # Buechi automata grow so fast that LoLA takes 85 s on K = 2
        f = conj(p, nr)
        for _ in range(prop.bound or 0):
            f = conj(p, nr, until(nr, conj(neg(p), nr, until(nr, f))))
        return neg(until(nr, f))
    if pattern is Pattern.PRECEDENCE:
        return weak_until(neg(p), disj(s, r))
    if pattern is Pattern.RESPONSE:
        return weak_until(implies(p, until(nr, conj(s, nr))), r)
    raise ValueError(pattern)


def ltl(prop: Property) -> Formula:
    """The property as an LTL formula, ``A`` at its top: on every run, the formula."""
    kind, q, r = prop.scope.kind, state(prop.scope.q), state(prop.scope.r)
    if kind is ScopeKind.GLOBALLY:
        f = _segment(prop, FALSE)
    elif kind is ScopeKind.BEFORE:
        f = implies(finally_(r), _segment(prop, r))
    elif kind is ScopeKind.AFTER:
        f = disj(globally(neg(q)), until(neg(q), conj(q, _segment(prop, FALSE))))
    elif kind is ScopeKind.BETWEEN:
        f = globally(implies(conj(q, neg(r), finally_(r)), _segment(prop, r)))
    else:
        f = globally(implies(conj(q, neg(r)), _segment(prop, r)))
    # folded to a constant: said as "always" it, the shape every tool reads
    return AllPaths(Globally(f) if f in (TRUE, FALSE) else f)


def reachability(prop: Property) -> Formula | None:
    """``AG phi`` when the property is an invariant (absence or universality, globally):
    the contest's reachability category, which every tool answers fastest. None otherwise."""
    if prop.scope.kind is not ScopeKind.GLOBALLY:
        return None
    # Globally unfolded: a reachability query is AG of a state formula, even a constant one
    if prop.pattern is Pattern.ABSENCE:
        return AllPaths(Globally(neg(state(prop.p))))
    if prop.pattern is Pattern.UNIVERSALITY:
        return AllPaths(Globally(state(prop.p)))
    return None


def ctl(prop: Property) -> Formula | None:
    """The property in CTL where a CTL formula means the same as its LTL one, else None.

    Globally: absence ``AG !P``, universality ``AG P``, existence ``AF P``,
    precedence ``A[!P W S]`` = ``!E[!S U (P & !S)]``, response
    ``AG (P -> AF S)``; after Q: absence ``AG (Q -> AG !P)`` and universality
    ``AG (Q -> AG P)`` (a later Q's suffix is inside the first's). Bounded
    existence, and the other scopes, need the run's past: LTL only.
    """
    kind, pattern = prop.scope.kind, prop.pattern
    p, s = state(prop.p), state(prop.s)
    if kind is ScopeKind.AFTER and pattern in (Pattern.ABSENCE, Pattern.UNIVERSALITY):
        inner = neg(p) if pattern is Pattern.ABSENCE else p
        return AllPaths(Globally(implies(state(prop.scope.q), AllPaths(Globally(inner)))))
    if kind is not ScopeKind.GLOBALLY:
        return None
    # the path operators right under a quantifier are never folded away: a CTL formula
    # is a path quantifier over one of them, whatever its state formulas fold to
    if pattern is Pattern.ABSENCE:
        return AllPaths(Globally(neg(p)))
    if pattern is Pattern.UNIVERSALITY:
        return AllPaths(Globally(p))
    if pattern is Pattern.EXISTENCE:
        return AllPaths(Finally(p))
    if pattern is Pattern.PRECEDENCE:
        return Neg(ExistsPath(Until(neg(s), conj(p, neg(s)))))
    if pattern is Pattern.RESPONSE:
        return AllPaths(Globally(implies(p, AllPaths(Finally(s)))))
    return None


# -- reading them ---------------------------------------------------------------------------

def show(f: Formula) -> str:
    """The formula in the usual notation: ``A [](m.OK >= 1 -> <>(...))``."""
    if isinstance(f, State):
        text = describe(f.predicate)
        return text if isinstance(f.predicate, Const) or " " not in text else f"({text})"
    if isinstance(f, Neg):
        return f"!{show(f.arg)}"
    if isinstance(f, (Conj, Disj)):
        word = " & " if isinstance(f, Conj) else " | "
        return "(" + word.join(show(a) for a in f.args) + ")"
    if isinstance(f, Until):
        return f"({show(f.before)} U {show(f.reach)})"
    if isinstance(f, Globally):
        return f"[]{show(f.arg)}"
    if isinstance(f, Finally):
        return f"<>{show(f.arg)}"
    if isinstance(f, AllPaths):
        return f"A {show(f.arg)}"
    return f"E {show(f.arg)}"


def evaluate(f: Formula, word, loop: int | None = None) -> bool:
    """Whether the run ``word`` (its markings, as mappings place -> tokens) satisfies the
    path formula ``f`` at its start (path quantifiers are read on this run alone): a
    finite run repeats its last marking forever, a lasso returns to ``word[loop]``
    after its last marking. For tests: the LTL formula against the observer."""
    n = len(word)
    back = n - 1 if loop is None else loop   # where the run goes after word[n - 1]

    def succ(i):
        return i + 1 if i + 1 < n else back

    def positions(i):
        """The positions from i on, each once: the prefix, then the cycle."""
        seen, out = set(), []
        while i not in seen:
            seen.add(i)
            out.append(i)
            i = succ(i)
        return out

    memo: dict = {}

    def at(g, i) -> bool:
        key = (id(g), i)
        if key in memo:
            return memo[key]
        if isinstance(g, State):
            v = holds(g.predicate, word[i])
        elif isinstance(g, Neg):
            v = not at(g.arg, i)
        elif isinstance(g, Conj):
            v = all(at(a, i) for a in g.args)
        elif isinstance(g, Disj):
            v = any(at(a, i) for a in g.args)
        elif isinstance(g, (AllPaths, ExistsPath)):
            v = at(g.arg, i)
        elif isinstance(g, Globally):
            v = all(at(g.arg, j) for j in positions(i))
        elif isinstance(g, Finally):
            v = any(at(g.arg, j) for j in positions(i))
        else:   # until: reach somewhere ahead, before everywhere until then
            v = False
            for j in positions(i):
                if at(g.reach, j):
                    v = True
                    break
                if not at(g.before, j):
                    break
        memo[key] = v
        return v

    return at(f, 0)
