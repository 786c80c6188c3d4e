"""The contest's formulas simplified by what the net's structure proves of their states, as
verifypn simplifies them (Bønneland, Dyhr, Jensen, Johannsen, Srba, "Simplification of CTL
formulae for efficient model checking of Petri nets", 2018).

A state subformula that no reachable marking satisfies (the state equation proves it
unreachable) is false in every marking a run meets, and one whose negation none satisfies
is true there: either is replaced by its value. The values are then carried up through
the connectives and the temporal operators, by rules that hold in the contest's CTL
reading (a maximal path may end at a dead marking) and in its LTL reading (a dead marking
repeats) alike: ``F c``, ``G c`` and a quantifier over ``c`` are ``c``; ``a U true`` is
true, ``a U false`` false, ``false U b`` is ``b`` and ``true U b`` is ``F b``. ``X`` keeps
its argument's value only in one reading (a dead marking has no next marking in CTL), so
it is left as it is, but in a formula read in LTL alone (``X c`` is ``c`` there), and in
``A X true`` (true) and ``E X false`` (false), which hold in both: no next marking, or
one, satisfies false, and every one satisfies true. Read in LTL alone, an ``X`` before a
formula both purely eventual and purely universal (``F G φ``, ``G F φ``: Etessami and
Holzmann 2000) is dropped, and ``F X φ`` is ``F φ`` where that is one (``F X φ = X F φ``):
a formula left without ``X`` is searched under stubborn sets. A formula that becomes a constant is answered; one that becomes
simpler (``E F φ`` out of a CTL formula) goes on to the other techniques as that.
"""
from __future__ import annotations

import time
from typing import Callable

from mcl2pnml.core import queries as q

#: A state formula's value in every reachable marking, where it is proven (None: not).
Decide = Callable[[object], "bool | None"]


def simplified(f, decide: Decide, linear: bool = False):
    """``f`` with each state subformula ``decide`` settles replaced by its value, and the
    values carried up (the module's rules). ``linear``: ``f`` is read in LTL alone (the
    contest's LTL, not CTL too), where every marking has a next one: ``X c`` is ``c``."""
    def go(g):
        return simplified(g, decide, linear)

    if q.is_state(f):
        value = decide(f)
        if value is not None:
            return q.BoolConst(value)
        if isinstance(f, (q.Neg, q.Conj, q.Disj)):
            return _fold(f, [go(a) for a in q.children(f)])
        return f
    if isinstance(f, (q.Neg, q.Conj, q.Disj)):
        return _fold(f, [go(a) for a in q.children(f)])
    if isinstance(f, (q.Finally, q.Globally)):
        arg = go(f.arg)
        if isinstance(arg, q.BoolConst):
            return arg
        while linear and isinstance(arg, q.Next) and _absolute(type(f)(arg.arg)):
            arg = arg.arg                 # F X φ = X F φ, and X drops before F φ here
        return type(f)(arg)
    if isinstance(f, q.Until):
        before, reach = go(f.before), go(f.reach)
        if isinstance(reach, q.BoolConst):
            return reach
        if isinstance(before, q.BoolConst):
            return q.Finally(reach) if before.value else reach
        return q.Until(before, reach)
    if isinstance(f, (q.AllPaths, q.ExistsPath)):
        arg = go(f.arg)
        if (isinstance(arg, q.Next) and isinstance(arg.arg, q.BoolConst)
                and arg.arg.value is isinstance(f, q.AllPaths)):
            return arg.arg      # A X true, E X false: a dead marking has no next one to differ
        return arg if isinstance(arg, q.BoolConst) or q.is_closed(arg) else type(f)(arg)
    if isinstance(f, q.Next):
        arg = go(f.arg)
        return arg if linear and (isinstance(arg, q.BoolConst) or _absolute(arg)) \
            else q.Next(arg)
    return f


def _pure(f, eventual: bool) -> bool:
    """Whether ``f`` is purely eventual (``eventual``: a run that satisfies it still does
    with any steps put before it) or purely universal (every suffix of a run that
    satisfies it does), by Etessami and Holzmann's rules (2000): ``F φ`` is eventual and
    ``G φ`` universal whatever φ; ``G``, ``X``, and, or keep eventual (``F``, ``X``, and,
    or keep universal); a negation swaps the two."""
    own, keeps = (q.Finally, q.Globally) if eventual else (q.Globally, q.Finally)
    if isinstance(f, (own, q.BoolConst)):
        return True
    if isinstance(f, (keeps, q.Next)):
        return _pure(f.arg, eventual)
    if isinstance(f, q.Neg):
        return _pure(f.arg, not eventual)
    return isinstance(f, (q.Conj, q.Disj)) and all(_pure(a, eventual) for a in f.args)


def _absolute(f) -> bool:
    """Both: on infinite runs ``X f`` is ``f`` (the suffix keeps it, the step before
    does not lose it): ``F G φ``, ``G F φ`` and the like."""
    return _pure(f, True) and _pure(f, False)


def _fold(f, args: list):
    """A connective over simplified arguments, its constants folded."""
    if isinstance(f, q.Neg):
        [a] = args
        return q.BoolConst(not a.value) if isinstance(a, q.BoolConst) else q.Neg(a)
    absorbing = isinstance(f, q.Disj)          # or: true absorbs; and: false absorbs
    if any(isinstance(a, q.BoolConst) and a.value is absorbing for a in args):
        return q.BoolConst(absorbing)
    kept = [a for a in args if not isinstance(a, q.BoolConst)]
    if not kept:
        return q.BoolConst(not absorbing)
    return kept[0] if len(kept) == 1 else type(f)(tuple(kept))


class ByStructure:
    """:data:`Decide` by the P-invariants' bounds, then the state equation, within
    ``seconds`` for all the questions of a command; each state formula asked once."""

    def __init__(self, s, seconds: float, bounds, unreachable):
        self.s, self.bounds, self.unreachable = s, bounds, unreachable
        self.end = time.monotonic() + seconds
        self.known: dict = {}
        #: the techniques that decided something (the answer's TECHNIQUES words)
        self.used: set[str] = set()

    def __call__(self, phi) -> bool | None:
        if isinstance(phi, q.BoolConst):
            return phi.value
        if phi in self.known:
            return self.known[phi]
        value = None
        try:
            value = self.bounds(phi)
            if value is not None:
                self.used.add("STRUCTURAL P_INVARIANTS")
            for candidate, meaning in ((phi, False), (q.Neg(phi), True)):
                left = self.end - time.monotonic()
                if value is None and left > 0 and self.unreachable(self.s, candidate, left):
                    value = meaning
                    self.used.add("STATE_EQUATION")
        except KeyError:            # a name the net does not have: said by the graph's path
            value = None
        self.known[phi] = value
        return value


def at_start(f, holds_initially) -> bool | None:
    """``f``'s value in the initial marking where that marking alone decides it on every
    path from it (None elsewhere): ``F φ`` true where φ holds there, ``G φ`` false where
    it does not, ``a U b`` true where ``b`` holds and false where neither does; a
    quantifier over a path formula so decided has its value (E and A alike: every path
    starts there); connectives three-valued. ``holds_initially`` decides a state formula
    in the initial marking. ``X`` needs the next marking: left open."""
    def go(g):
        if q.is_state(g):
            return holds_initially(g)
        if isinstance(g, q.Neg):
            v = go(g.arg)
            return None if v is None else not v
        if isinstance(g, (q.Conj, q.Disj)):
            values = [go(a) for a in g.args]
            absorbing = isinstance(g, q.Disj)
            if absorbing in values:
                return absorbing
            return None if None in values else not absorbing
        if isinstance(g, (q.AllPaths, q.ExistsPath)):
            return go(g.arg)
        if isinstance(g, q.Finally):
            return True if go(g.arg) is True else None
        if isinstance(g, q.Globally):
            return False if go(g.arg) is False else None
        if isinstance(g, q.Until):
            reach = go(g.reach)
            if reach is True:
                return True
            if reach is False and go(g.before) is False:
                return False
            return None
        return None                 # X
    return go(f)
