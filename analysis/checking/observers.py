"""The observers of the property patterns: what a marking sequence owes, read one
marking at a time, and the verdicts of a check.

Shared by the two ways a property is checked: :mod:`mcl2pnml.analysis.checking.on_graph` (the
reference: every reachable marking first, then the product in Python) and
:mod:`mcl2pnml.analysis.checking.on_the_fly` (the product searched on the fly in C). The observer
and its states are explained in :mod:`mcl2pnml.analysis.checking.on_graph`' docstring.
:class:`Watcher` reads them along one run, for the runs of a mission with a
vehicle (the exact odds' chain and the campaigns' runs, in :mod:`mcl2pnml`).
"""
from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Callable, Sequence

from mcl2pnml.core.patterns import Const, Pattern, Predicate, Property, ScopeKind, evaluate


class Status(enum.Enum):
    HOLDS = "holds"
    FAILS = "fails"
    UNKNOWN = "unknown"


class Shape(enum.Enum):
    """What a counterexample is."""

    PREFIX = "prefix"   # a finite prefix that already violates (any continuation does)
    FINITE = "finite"   # a whole finite run, ending in a dead marking
    LASSO = "lasso"     # an infinite run: the prefix, then the cycle from ``loop`` forever


Marked = tuple[tuple[str, int], ...]


@dataclass(frozen=True)
class Verdict:
    """The answer for one property.

    For ``FAILS``: ``transitions`` the firing sequence from M0 (transition ids),
    ``markings`` the markings it passes through (``len(transitions) + 1``, M0
    first, each as its marked places); for a lasso, ``loop`` is the index in
    ``markings`` where the cycle starts (the last marking equals it).
    ``states`` is the number of product states explored (or, for ``UNKNOWN``,
    the markings counted when the limit was met); ``reason`` says why unknown.
    """

    property: Property
    status: Status
    transitions: tuple[str, ...] = ()
    markings: tuple[Marked, ...] = ()
    shape: Shape | None = None
    loop: int | None = None
    states: int = 0
    reason: str | None = None


# -- the observer ------------------------------------------------------------------------------

OUT, IN, DONE = 0, 1, 2
BAD = ("BAD",)


@dataclass(frozen=True)
class _Obs:
    scope: int
    seen: bool = False
    owed: bool = False
    count: int = 0
    last: bool = False
    broken: bool = False


def initial(kind: ScopeKind) -> _Obs:
    return _Obs(IN if kind in (ScopeKind.GLOBALLY, ScopeKind.BEFORE) else OUT)


def step(prop: Property, obs, p: bool, s: bool, q: bool, r: bool):
    """The observer's state after reading one marking where P, S, Q, R are as given."""
    if obs is BAD:
        return BAD
    kind, pattern = prop.scope.kind, prop.pattern
    # scope transitions first: R closes (its marking outside), Q opens (its marking inside)
    if obs.scope == IN and r and kind in (ScopeKind.BEFORE, ScopeKind.BETWEEN,
                                          ScopeKind.AFTER_UNTIL):
        if obs.broken or (pattern is Pattern.EXISTENCE and not obs.seen) or obs.owed:
            return BAD
        obs = _Obs(DONE if kind is ScopeKind.BEFORE else OUT)
    if kind in (ScopeKind.AFTER, ScopeKind.BETWEEN, ScopeKind.AFTER_UNTIL) and q and not (
            r and kind is not ScopeKind.AFTER):
        if obs.scope == OUT:
            obs = _Obs(IN)
        elif obs.scope == IN and kind is not ScopeKind.AFTER:
            # a nested interval: existence and precedence are needed afresh in it
            if pattern in (Pattern.EXISTENCE, Pattern.PRECEDENCE):
                obs = _Obs(IN, seen=False, broken=obs.broken)
    if obs.scope != IN:
        return obs
    violated = False
    if pattern is Pattern.ABSENCE:
        violated = p
    elif pattern is Pattern.UNIVERSALITY:
        violated = not p
    elif pattern is Pattern.EXISTENCE:
        obs = _Obs(IN, seen=obs.seen or p, broken=obs.broken)
    elif pattern is Pattern.BOUNDED_EXISTENCE:
        count = obs.count + (1 if p and not obs.last else 0)
        violated = count > (prop.bound or 0)
        obs = _Obs(IN, count=min(count, (prop.bound or 0) + 1), last=p, broken=obs.broken)
    elif pattern is Pattern.PRECEDENCE:
        seen = obs.seen or s
        violated = p and not seen
        obs = _Obs(IN, seen=seen, broken=obs.broken)
    elif pattern is Pattern.RESPONSE:
        obs = _Obs(IN, owed=(obs.owed or p) and not s, broken=obs.broken)
    if violated:
        if kind in (ScopeKind.BETWEEN, ScopeKind.BEFORE):
            # counts only if R closes this interval: remembered until then
            return _Obs(IN, obs.seen, obs.owed, obs.count, obs.last, broken=True)
        return BAD
    return obs


def pending(prop: Property, obs) -> bool:
    """Whether a run ending here, or staying in such states forever, violates the property."""
    if obs is BAD:
        return True
    if obs.scope != IN or prop.scope.kind in (ScopeKind.BETWEEN, ScopeKind.BEFORE):
        return False   # an interval R never closes does not count
    if prop.pattern is Pattern.EXISTENCE:
        return not obs.seen
    return obs.owed


def truths(prop: Property) -> tuple[Predicate, Predicate, Predicate, Predicate]:
    f = Const(False)
    return (prop.p, prop.s or f, prop.scope.q or f, prop.scope.r or f)


# -- the observer's states numbered, for a product -----------------------------------------

class ObserverTable:
    """The observer's states met, numbered, and its moves, each worked out once: the
    product's states are then pairs of integers (a marking, an observer state), and a
    move one table lookup, whatever the pattern. The product of a state space (the
    reference checker's) or of a zone graph (the timed one) with the observer of ``prop``."""

    def __init__(self, prop: Property):
        self.prop = prop
        self.states: list = []
        self.number: dict = {}
        self.moves: dict[int, int] = {}
        self.pending: list[bool] = []
        self.bad = self.intern(BAD)
        self.start = self.intern(initial(prop.scope.kind))

    def intern(self, obs) -> int:
        """The number of observer state ``obs``, given one if new."""
        k = self.number.get(obs)
        if k is None:
            k = self.number[obs] = len(self.states)
            self.states.append(obs)
            self.pending.append(pending(self.prop, obs))
        return k

    def after(self, k: int, code: int) -> int:
        """The state after reading a marking whose truths are ``code`` (P S Q R as bits)."""
        key = k * 16 + code
        got = self.moves.get(key)
        if got is None:
            got = self.moves[key] = self.intern(step(
                self.prop, self.states[k], bool(code & 8), bool(code & 4), bool(code & 2),
                bool(code & 1)))
        return got


def path_to(parent: dict, node) -> tuple[list, list]:
    """The nodes from the root to ``node`` and the transitions between them, read back
    from a breadth-first search's ``parent`` map (node to ``(parent, transition)``, the
    root to None)."""
    nodes, trans = [node], []
    while parent[node] is not None:
        node, t = parent[node]
        nodes.append(node)
        trans.append(t)
    return nodes[::-1], trans[::-1]


# -- observers along one run ---------------------------------------------------------------

class Watcher:
    """The observers of ``properties`` along one run, read one marking at a time: a
    marking as a list of token counts in the order of ``places`` (an engine's), each
    property's predicates compiled once to functions of it. The runs of a mission with
    a vehicle (the exact odds' chain, a campaign's runs) are judged with it."""

    def __init__(self, properties: Sequence[Property], places: Sequence[str]):
        index = {p: i for i, p in enumerate(places)}
        self.properties = tuple(properties)
        self.truths = [tuple(_compiled(x, index) for x in truths(prop))
                       for prop in self.properties]

    def start(self, marking: Sequence[int]) -> tuple:
        """The observers after reading the initial marking."""
        return self.read(tuple(initial(p.scope.kind) for p in self.properties),
                         marking)

    def read(self, states: tuple, marking: Sequence[int]) -> tuple:
        return tuple(step(prop, obs, *(f(marking) for f in fs))
                     for prop, obs, fs in zip(self.properties, states, self.truths))

    def pending(self, states: tuple) -> tuple[bool, ...]:
        """For each property: does a run that ends here, or stays in such states for
        ever, violate it?"""
        return tuple(pending(p, obs) for p, obs in zip(self.properties, states))


def _compiled(predicate, index: dict[str, int]) -> Callable[[Sequence[int]], bool]:
    def atom(tokens, m) -> bool:
        return sum(m[index[p]] for p in tokens.places) >= tokens.at_least
    return lambda m: evaluate(predicate, lambda t: atom(t, m))
