"""The contest's questions without the reachability graph
(:func:`mcl2pnml.analysis.contest.answers.answers_as_found` asks here past its first
exploration, or with ``--stubborn``; docs/query.md has the order).

* Among markings known to be reachable (the initial one, those a stopped exploration
  found, those random walks meet): ``E F φ`` true and ``A G φ`` false where one of them
  satisfies φ (for ``A G``: violates it), an upper bound one of them reaches where a
  proof allows no more (:class:`Truths` evaluates φ on all of them at once).
* By the state equation (:mod:`mcl2pnml.analysis.structure.state_equation`): ``E F φ``
  false and ``A G not φ`` true where no solution of ``M = M0 + C x`` satisfies φ; the
  upper bound of a place sum.
* By the bounds of the semi-positive P-invariants (Murata 1989, section VII).
* CTL and LTL formulas simplified by what those prove of their state subformulas
  (:mod:`mcl2pnml.analysis.contest.simplify`).
* On the fly: on a 1-safe net, ``A G φ`` is the universality of φ and ``E F φ`` the
  failure of the universality of not φ, for the property checker's engine
  (:mod:`mcl2pnml.analysis.checking.on_the_fly`), which searches breadth first in C and
  stops at the first marking that decides; under stubborn sets when asked, on a net
  proven safe.
"""
from __future__ import annotations

import heapq
import itertools
import time
from collections import Counter
from typing import Callable, Sequence

import numpy as np

from mcl2pnml.core import patterns as pr
from mcl2pnml.core import queries as q
from mcl2pnml.core.bounds import MAX_STATES
from mcl2pnml.core.memory import default_memory
from mcl2pnml.core.net import Net
from mcl2pnml.core.structure import structure

from mcl2pnml.analysis.checking import on_the_fly as onthefly
from mcl2pnml.analysis.checking.observers import Status
from mcl2pnml.analysis.contest.simplify import ByStructure, at_start, simplified
from mcl2pnml.analysis.statespace.firing import Firing
from mcl2pnml.analysis.statespace.walks import random_walks
from mcl2pnml.analysis.structure import state_equation
from mcl2pnml.analysis.structure.state_machine import free_tokens
from mcl2pnml.analysis.structure.invariants import (INVARIANT_PLACES, INVARIANT_ROWS, AnalysisLimit,
                                                    minimal_semipositive_p_invariants)

#: A question settled here: its value (True/False, a bound) and what decided it, as the
#: contest's TECHNIQUES words.
Settled = tuple[bool | int, str]


# -- among markings known to be reachable: the initial one, or those an exploration found ----------

class ListedMarkings:
    """Markings given as rows of counts, a column per place (the initial marking): what
    :class:`~mcl2pnml.analysis.statespace.general.FoundMarkings` offers, for a few."""

    def __init__(self, rows):
        self.rows = np.asarray(rows, dtype=np.int64).reshape(len(rows), -1)

    @property
    def states(self) -> int:
        return len(self.rows)

    def tokens(self, place: int) -> np.ndarray:
        return self.rows[:, place]


#: A deadlock atom is evaluated on a set of markings only up to this many markings times
#: transitions (every transition tried on every marking).
DEADLOCK_WORK = 50_000_000


class Truths:
    """State formulas evaluated on every marking of a set at once (``markings``: anything
    with ``states`` and ``tokens(place)``), a column of counts per place kept for the
    next formula."""

    def __init__(self, s, markings):
        self.s, self.markings, self.n = s, markings, markings.states
        self._columns: dict[int, np.ndarray] = {}

    def tokens(self, places) -> np.ndarray:
        total = np.zeros(self.n, dtype=np.int64)
        for p in places:
            i = self.s.place_index[p]          # KeyError: a name the net does not have
            if i not in self._columns:
                self._columns[i] = np.asarray(self.markings.tokens(i), dtype=np.int64)
            total += self._columns[i]
        return total

    def enabled(self, j: int) -> np.ndarray:
        need: Counter = Counter(self.s.pre[j])
        need.update(self.s.read[j])
        on = np.ones(self.n, dtype=bool)
        for i, w in need.items():
            on &= self.tokens([self.s.places[i]]) >= w
        return on

    def of(self, f) -> np.ndarray:
        """φ's truth in each marking. Raises KeyError at a name the net does not have,
        LookupError at a deadlock atom past :data:`DEADLOCK_WORK`."""
        s = self.s
        if isinstance(f, q.BoolConst):
            return np.full(self.n, f.value)
        if isinstance(f, q.IntLe):
            left, right = (e.value if isinstance(e, q.IntConst) else self.tokens(e.places)
                           for e in (f.left, f.right))
            return np.broadcast_to(np.asarray(left <= right), (self.n,)).copy()
        if isinstance(f, q.Fireable):
            out = np.zeros(self.n, dtype=bool)
            for t in f.transitions:
                out |= self.enabled(s.transition_index[t])
            return out
        if isinstance(f, q.Deadlock):
            if self.n * len(s.transitions) > DEADLOCK_WORK:
                raise LookupError
            live = np.zeros(self.n, dtype=bool)
            for j in range(len(s.transitions)):
                live |= self.enabled(j)
            return ~live
        if isinstance(f, q.Neg):
            return ~self.of(f.arg)
        if isinstance(f, (q.Conj, q.Disj)):
            parts = [self.of(a) for a in f.args]
            return np.logical_and.reduce(parts) if isinstance(f, q.Conj) \
                else np.logical_or.reduce(parts)
        raise LookupError(f"not a state formula: {type(f).__name__}")


def _witnessed(s, queries: Sequence[q.Query], markings, bound_of, technique: str,
               seen: str) -> dict[str, Settled]:
    """The questions a reachable marking among ``markings`` settles: ``E F φ`` true and
    ``A G φ`` false where one satisfies φ (for ``A G``: violates it), as ``technique``;
    an upper bound where the largest found is the bound that ``bound_of`` proves (its
    technique after ``seen``, the words for the witness)."""
    settled: dict[str, Settled] = {}
    if not markings.states:
        return settled
    truths = Truths(s, markings)
    for x in queries:
        try:
            if isinstance(x.asks, q.PlaceBound):
                most = int(truths.tokens(x.asks.places).max())
                bound, how = bound_of(x.asks.places, most)
                if bound == most:
                    settled[x.id] = (most, f"{seen} {how}")
                continue
            r = reachability(x.asks)
            if r is None:
                continue
            exists, phi = r
            if (truths.of(phi) == exists).any():
                settled[x.id] = (exists, technique)
        except (KeyError, LookupError):     # a name the net lacks: said by the graph's path
            continue
    return settled


class _Bounds:
    """Upper bounds of place sums over the reachable markings: the P-invariants' (found
    once, if ever asked), then the state equation's (:func:`state_equation.upper_bound`)
    where those do not close the question, within :data:`STATE_EQUATION_SECONDS` for a
    command."""

    def __init__(self, s):
        self.s = s
        self._invariants: list = []
        self._end: float | None = None
        self._by_equation: dict[tuple, int | None] = {}

    def invariant(self, places) -> int | None:
        if not self._invariants:
            self._invariants.append(_invariant_bounds(self.s))
        return self._invariants[0](places)

    def __call__(self, places, reached: int) -> tuple[int | None, str]:
        """The least bound proven, with its technique; ``reached`` is a sum known to be
        reached: a bound that meets it needs nothing further."""
        bound = self.invariant(places)
        if bound is not None and bound <= reached:
            return bound, "STRUCTURAL P_INVARIANTS"
        if self._end is None:
            self._end = time.monotonic() + STATE_EQUATION_SECONDS
        key = tuple(sorted(places))
        left = self._end - time.monotonic()
        if key not in self._by_equation and left > 0:
            self._by_equation[key] = state_equation.upper_bound(self.s, places, left)
        by_equation = self._by_equation.get(key)
        if by_equation is not None and (bound is None or by_equation < bound):
            return by_equation, "STATE_EQUATION"
        return bound, "STRUCTURAL P_INVARIANTS"


def settled_without_exploring(net: Net, queries: Sequence[q.Query]) -> dict[str, Settled]:
    """The questions decided without a reachable marking beyond the initial one, by id:

    * ``E F φ`` where φ holds initially (true), ``A G φ`` where it does not (false);
    * with the bounds of the semi-positive P-invariants (Murata 1989, section VII: a
      place set whose invariant weights are all at least 1 never holds more than the
      invariant's initial value): a state formula true or false in every marking those
      bounds allow decides both ``E F`` and ``A G`` of it; an upper bound the initial
      marking already reaches is the bound;
    * on a strongly connected state machine, every upper bound: all the tokens in the
      sum's places (:func:`~mcl2pnml.analysis.structure.state_machine.free_tokens`).
    """
    s = structure(net)
    bounds = _Bounds(s)
    found = _witnessed(s, queries, ListedMarkings([s.initial_vector()]), bounds,
                       "INITIAL_STATE", "INITIAL_STATE")
    tokens = free_tokens(s)
    for x in queries:
        if x.id in found:
            continue
        if isinstance(x.asks, q.PlaceBound):
            named = x.asks.places
            if tokens is not None and named and all(p in s.place_index for p in named):
                found[x.id] = (tokens * max(Counter(named).values()),
                               "STRUCTURAL STATE_MACHINE")
            continue
        r = reachability(x.asks)
        if r is None:
            continue
        try:
            always = _three_valued(r[1], s, bounds.invariant)
        except KeyError:            # a name the net does not have: said by the graph's path
            continue
        if always is not None:
            found[x.id] = (always, "STRUCTURAL P_INVARIANTS")
    return found


def settled_by_found(net: Net, queries: Sequence[q.Query], found) -> dict[str, Settled]:
    """The questions a witness among ``found`` settles, by id (``found``: the markings an
    exploration met before its limit, each reachable: ``ExplorationLimit.found``):

    * ``E F φ`` true, ``A G φ`` false, where a found marking satisfies φ (for ``A G``:
      violates it); a witness proves it, its absence nothing;
    * the upper bound of a place sum, where the largest found is the bound that the
      P-invariants prove (:func:`_invariant_bounds`).

    φ is evaluated on every found marking at once (:class:`Truths`)."""
    s = structure(net)
    return _witnessed(s, queries, found, _Bounds(s), "EXPLICIT", "EXPLICIT")


#: Seconds the state equation may take over all the questions of one command.
STATE_EQUATION_SECONDS = 10.0


def settled_by_state_equation(net: Net, queries: Sequence[q.Query],
                              seconds: float = STATE_EQUATION_SECONDS) -> dict[str, Settled]:
    """The reachability questions the state equation settles, by id: ``E F φ`` is false
    and ``A G φ`` true where it proves φ (for ``A G``: not φ) unreachable, within
    ``seconds`` over all of them. It proves only unreachability: the other answers are
    left to the other techniques."""
    s = structure(net)
    bounds = _Bounds(s)
    found: dict[str, Settled] = {}
    end = time.monotonic() + seconds
    for x in queries:
        left = end - time.monotonic()
        if left <= 0:
            break
        r = reachability(x.asks)        # None for an upper bound, as for CTL and LTL
        if r is None:
            continue
        exists, phi = r
        try:
            if state_equation.unreachable(s, phi if exists else q.Neg(phi), left,
                                          lambda p: bounds.invariant((s.places[p],))):
                found[x.id] = (not exists, "STATE_EQUATION")
        except KeyError:            # a name the net does not have: said by the graph's path
            continue
    return found


def simplified_by_structure(net: Net, queries: Sequence[q.Query],
                            seconds: float = STATE_EQUATION_SECONDS
                            ) -> tuple[dict[str, Settled], dict[str, q.Query]]:
    """The questions other than ``E F φ`` and ``A G φ`` (those are the state equation's
    own) with each state subformula the P-invariants or the state equation decide
    replaced by its value (:mod:`mcl2pnml.analysis.contest.simplify`): those that become
    a constant, or that the initial marking decides on every path (:func:`at_start`),
    answered, by id; those that become simpler, rewritten, by id."""
    s = structure(net)
    bounds = _Bounds(s)
    decide = ByStructure(s, seconds, lambda phi: _three_valued(phi, s, bounds.invariant),
                         state_equation.unreachable)
    initially = Truths(s, ListedMarkings([s.initial_vector()]))
    settled: dict[str, Settled] = {}
    rewritten: dict[str, q.Query] = {}
    for x in queries:
        if isinstance(x.asks, q.PlaceBound) or reachability(x.asks) is not None:
            continue
        decide.used.clear()
        f = simplified(x.asks, decide, q.is_ltl(x.asks) and not q.is_ctl(x.asks))
        if isinstance(f, q.BoolConst):
            settled[x.id] = (f.value, " ".join(sorted(decide.used)))
            continue
        try:
            start = at_start(f, lambda phi: bool(initially.of(phi)[0]))
        except (KeyError, LookupError):  # a name the net lacks: said by the graph's path
            start = None
        if start is not None:
            settled[x.id] = (start, " ".join(sorted({*decide.used, "INITIAL_STATE"})))
        elif f != x.asks:
            rewritten[x.id] = q.Query(x.id, f, x.location)
    return settled, rewritten


#: Seconds the semi-positive P-invariants may take for the bounds of one command: they
#: come before the explorations, which must not wait on them.
INVARIANT_SECONDS = 2.0


def _invariant_bounds(s):
    """A function bounding a sum of places by the P-invariants (None: not bounded)."""
    invariants = []
    if len(s.places) <= INVARIANT_PLACES:
        try:
            invariants = minimal_semipositive_p_invariants(s, INVARIANT_ROWS,
                                                           INVARIANT_SECONDS)
        except AnalysisLimit:
            pass
    m0 = dict(zip(s.places, s.initial_vector()))
    values = [sum(c * m0[p] for p, c in y.items()) for y in invariants]

    def one(p: str) -> int | None:
        found = [v // y[p] for y, v in zip(invariants, values) if p in y]
        return min(found) if found else None

    def bound(places) -> int | None:
        if any(p not in m0 for p in places):
            raise KeyError
        counts = Counter(places)
        # sum(P) <= y M = y M0 for an invariant y that weighs each place of P at least as
        # often as P names it; or the sum of the places' own bounds
        found = [v for y, v in zip(invariants, values)
                 if all(y.get(p, 0) >= c for p, c in counts.items())]
        singles = [one(p) for p in counts]
        if None not in singles:
            found.append(sum(b * c for b, c in zip(singles, counts.values())))
        return min(found) if found else None

    return bound


def _three_valued(phi, s, bound_of) -> bool | None:
    """φ's truth in every marking the invariants' bounds allow (``bound_of``): True,
    False, or None where the bounds leave it open."""
    def total(e):
        if isinstance(e, q.IntConst):
            return e.value, e.value
        if any(p not in s.place_index for p in e.places):
            raise KeyError
        return 0, bound_of(e.places)            # (at least, at most: None unbounded)

    def go(f):
        if isinstance(f, q.BoolConst):
            return f.value
        if isinstance(f, q.Neg):
            v = go(f.arg)
            return None if v is None else not v
        if isinstance(f, (q.Conj, q.Disj)):
            vs = [go(a) for a in f.args]
            stop = isinstance(f, q.Disj)       # or: one true settles; and: one false
            if stop in vs:
                return stop
            return None if None in vs else not stop
        if isinstance(f, q.IntLe):
            (llo, lhi), (rlo, rhi) = total(f.left), total(f.right)
            if lhi is not None and lhi <= rlo:
                return True
            if rhi is not None and llo > rhi:
                return False
            return None
        if isinstance(f, q.Fireable):
            if any(t not in s.transition_index for t in f.transitions):
                raise KeyError
            # dead when some place it needs is bounded below its weight
            dead = all(any((b := bound_of([s.places[i]])) is not None and b < w
                           for i, w in (*s.pre[j].items(), *s.read[j].items()))
                       for j in (s.transition_index[t] for t in f.transitions))
            return False if dead else None
        return None

    return go(phi)


# -- random walks ---------------------------------------------------------------------------------

#: Seconds the random walks may take over all the questions of one command.
WALK_SECONDS = 5.0


def settled_by_walks(net: Net, queries: Sequence[q.Query], seconds: float = WALK_SECONDS,
                     seed: int = 0) -> dict[str, Settled]:
    """The questions a marking met by random walks settles (:func:`random_walks`: each
    reachable), as a found marking settles them (:func:`settled_by_found`): ``E F φ``
    true, ``A G φ`` false, an upper bound the walks reach. Within ``seconds``, from
    ``seed`` (another seed, other walks); a walk proves nothing by what it does not
    meet."""
    s = structure(net)
    asked = [x for x in queries
             if isinstance(x.asks, q.PlaceBound) or reachability(x.asks) is not None]
    settled: dict[str, Settled] = {}
    bounds = _Bounds(s)
    for batch in random_walks(s, seconds, seed=seed):
        left = [x for x in asked if x.id not in settled]
        if not left:
            break
        settled.update(_witnessed(s, left, ListedMarkings(batch), bounds,
                                  "RANDOM_WALK", "RANDOM_WALK"))
    return settled


#: Seconds the best-first searches for upper bounds may take over the questions of one
#: command, at first; after each stopped exploration, twice as long as the last.
BEST_FIRST_SECONDS = 10.0
#: Bytes a marking takes in a best-first search besides 8 a place (its key, its slot in
#: the set of those seen and in the heap).
BEST_FIRST_BYTES = 200


def settled_by_best_first(net: Net, queries: Sequence[q.Query],
                          seconds: float = BEST_FIRST_SECONDS, max_states: int = MAX_STATES,
                          max_memory: int | None = None) -> dict[str, Settled]:
    """The upper bounds a best-first search reaches: from M0, the marking with the most
    tokens in the bound's places is fired next, until one holds the bound that a proof
    allows (:class:`_Bounds`), within ``seconds`` over the questions and ``max_states``
    markings (or the memory budget's share) each. Every marking met is reachable (it was
    fired to), so one that holds the proven bound settles it; the search proves nothing by
    what it does not meet. A bound that has no proof is not searched for."""
    s = structure(net)
    asked = [x for x in queries if isinstance(x.asks, q.PlaceBound)
             and all(p in s.place_index for p in x.asks.places)]
    settled: dict[str, Settled] = {}
    if not asked:
        return settled
    budget = max_memory if max_memory is not None else default_memory()
    limit = max(1, min(max_states, budget // (BEST_FIRST_BYTES + 8 * len(s.places))))
    bounds, firing = _Bounds(s), Firing(s)
    m0 = np.array(s.initial_vector(), dtype=np.int64)
    end = time.monotonic() + seconds
    for n, x in enumerate(asked):
        counts = Counter(s.place_index[p] for p in x.asks.places)
        places = np.array(list(counts), dtype=np.int64)
        weights = np.array(list(counts.values()), dtype=np.int64)
        bound, how = bounds(x.asks.places, int(m0[places] @ weights))
        left = end - time.monotonic()
        if bound is None or left <= 0:
            continue
        if _best_first(firing, m0, places, weights, _distances(s, places), bound, limit,
                       time.monotonic() + left / (len(asked) - n)):
            settled[x.id] = (bound, f"EXPLICIT BEST_FIRST {how}")
    return settled


def _distances(s, places: np.ndarray) -> np.ndarray:
    """Each place's distance to ``places``: the fewest firings that move a token from it
    into one of them, by the arcs alone (a breadth-first search backwards through the
    transitions); a place from which no token gets there, one more than the farthest."""
    far = len(s.places)
    dist = np.full(far, far, dtype=np.int64)
    frontier = sorted(set(places.tolist()))
    dist[frontier] = 0
    feeding = [[] for _ in s.places]              # place -> the places a firing feeds it from
    for pre, post in zip(s.pre, s.post):
        for p in post:
            feeding[p].extend(pre)
    d = 0
    while frontier:
        d += 1
        nxt = []
        for p in frontier:
            for r in feeding[p]:
                if dist[r] == far:
                    dist[r] = d
                    nxt.append(r)
        frontier = nxt
    dist[dist == far] = d + 1
    return dist


def _best_first(firing: Firing, m0: np.ndarray, places: np.ndarray, weights: np.ndarray,
                distance: np.ndarray, bound: int, limit: int, deadline: float) -> bool:
    """Whether a marking with ``weights`` tokens in ``places`` summing to ``bound`` is met,
    the fullest marking fired first, and among equally full ones the one whose tokens lie
    nearest ``places`` (``distance``, a place's), within ``limit`` markings and the
    deadline: :func:`_nearest_first`, the distance being the tokens still short of it."""
    def short(rows: np.ndarray) -> np.ndarray:
        return np.maximum(bound - rows[:, places] @ weights, 0)
    return _nearest_first(firing, m0, short, distance, limit, deadline) is not None


def distance(phi, s, firing: Firing | None = None) -> Callable[[np.ndarray], np.ndarray]:
    """How far each marking (a row of counts) is from satisfying the state formula
    ``phi``: 0 exactly where it does, else the tokens that would have to move (verifypn's
    distance heuristic for its best-first search: Jensen, Nielsen, Oestergaard and Srba
    2016). ``a <= b`` is ``a - b`` past 0; a transition enabled, the tokens its input
    places lack; disabled, the fewest tokens that one of them must lose; a conjunction the
    sum, a disjunction the least; a negation is pushed to the atoms. A deadlock is every
    transition disabled. Raises KeyError at a name the net lacks. ``firing``: the net's,
    where the caller has one (its input arcs are read here)."""
    needs = (firing or Firing(s)).need_arrays

    def value(e, rows):
        if isinstance(e, q.IntConst):
            return np.full(len(rows), e.value, dtype=np.int64)
        cols = [s.place_index[p] for p in e.places]
        return rows[:, cols].sum(axis=1)

    def enable(j, rows):              # tokens t_j's input places lack
        places, weights = needs[j]
        if not len(places):
            return np.zeros(len(rows), dtype=np.int64)
        return np.maximum(weights - rows[:, places], 0).sum(axis=1)

    def disable(j, rows):             # the fewest tokens one input place must lose
        places, weights = needs[j]
        if not len(places):
            return np.full(len(rows), BIG, dtype=np.int64)
        return np.maximum(rows[:, places] - weights + 1, 0).min(axis=1)

    def d(f, positive: bool):
        if isinstance(f, q.Neg):
            return d(f.arg, not positive)
        if isinstance(f, q.BoolConst):
            return lambda rows: np.full(len(rows), 0 if f.value is positive else BIG,
                                        dtype=np.int64)
        if isinstance(f, (q.Conj, q.Disj)):
            parts = [d(a, positive) for a in f.args]
            if isinstance(f, q.Conj) is positive:
                return lambda rows: np.minimum(sum(x(rows) for x in parts), BIG)
            return lambda rows: np.min([x(rows) for x in parts], axis=0)
        if isinstance(f, q.IntLe):
            left, right = f.left, f.right
            if positive:
                return lambda rows: np.maximum(value(left, rows) - value(right, rows), 0)
            return lambda rows: np.maximum(value(right, rows) + 1 - value(left, rows), 0)
        if isinstance(f, q.Fireable):
            ts = [s.transition_index[t] for t in f.transitions]
            if positive:
                return lambda rows: np.min([enable(j, rows) for j in ts], axis=0)
            return lambda rows: np.minimum(sum(disable(j, rows) for j in ts), BIG)
        if isinstance(f, q.Deadlock):
            ts = range(len(s.transitions))
            if positive:
                return lambda rows: np.minimum(sum(disable(j, rows) for j in ts), BIG)
            return lambda rows: np.min([enable(j, rows) for j in ts], axis=0)
        raise LookupError(f"no distance to {type(f).__name__}")
    return d(phi, True)


#: A distance no marking reaches: a formula false whatever the tokens do.
BIG = 1 << 40
#: Seconds the guided searches for reachability witnesses may take over the questions of
#: one command, at first.
GUIDED_SECONDS = 5.0


def settled_by_guided_search(net: Net, queries: Sequence[q.Query],
                             seconds: float = GUIDED_SECONDS, max_states: int = MAX_STATES,
                             max_memory: int | None = None) -> dict[str, Settled]:
    """The reachability questions a best-first search settles: for ``E F φ`` (``A G φ``:
    not φ) the marking nearest φ by :func:`distance` is fired next, from M0, until one
    satisfies it (``E F φ`` true, ``A G φ`` false), within ``seconds`` over the questions
    (shared equally) and ``max_states`` markings (or the memory budget's share) each.
    Every marking met was fired to, so it is reachable; the found one is checked by the
    formula's own evaluation (:class:`Truths`) before it is believed; the search proves
    nothing by what it does not meet."""
    s = structure(net)
    firing = Firing(s)
    asked = []
    for x in queries:
        r = reachability(x.asks)
        if r is not None:
            exists, phi = r
            target = phi if exists else q.Neg(phi)
            try:
                asked.append((x, exists, target, distance(target, s, firing)))
            except (KeyError, LookupError):
                continue
    settled: dict[str, Settled] = {}
    if not asked:
        return settled
    budget = max_memory if max_memory is not None else default_memory()
    limit = max(1, min(max_states, budget // (BEST_FIRST_BYTES + 8 * len(s.places))))
    m0 = np.array(s.initial_vector(), dtype=np.int64)
    end = time.monotonic() + seconds
    for n, (x, exists, target, far) in enumerate(asked):
        left = end - time.monotonic()
        if left <= 0:
            break
        near = _distances(s, np.array(sorted(_support(target, s)), dtype=np.int64))
        found = _nearest_first(firing, m0, far, near, limit,
                               time.monotonic() + left / (len(asked) - n))
        if found is not None and Truths(s, ListedMarkings([found.tolist()])).of(target)[0]:
            settled[x.id] = (exists, "EXPLICIT BEST_FIRST")
    return settled


def _support(phi, s) -> set[int]:
    """The places ``phi`` counts, and the input places of the transitions it names."""
    if isinstance(phi, q.TokensCount):
        return {s.place_index[p] for p in phi.places}
    if isinstance(phi, q.IntLe):
        return _support(phi.left, s) | _support(phi.right, s)
    if isinstance(phi, q.Fireable):
        return {p for t in phi.transitions for arcs in (s.pre[s.transition_index[t]],
                                                        s.read[s.transition_index[t]])
                for p in arcs}
    if isinstance(phi, (q.IntConst, q.BoolConst, q.Deadlock)):
        return set()
    return set().union(*(_support(a, s) for a in q.children(phi)))


def _nearest_first(firing: Firing, m0: np.ndarray, far, near: np.ndarray, limit: int,
                   deadline: float) -> np.ndarray | None:
    """A marking at distance 0 (``far``), the nearest fired first; among equally near
    ones, the one whose tokens lie fewest firings from the formula's places (``near``,
    a place's, as for the bounds), then the first met; within ``limit`` markings and the
    deadline. None where none is met."""
    seen = {m0.tobytes()}
    heap = [(int(far(m0[None, :])[0]), int(m0 @ near), 0, m0.tobytes())]
    order = popped = 1
    while heap:
        value, _, _, key = heapq.heappop(heap)
        if value == 0:
            return np.frombuffer(key, dtype=np.int64)
        popped += 1
        if popped % 256 == 0 and time.monotonic() > deadline:
            return None
        rows = firing.successors(np.frombuffer(key, dtype=np.int64))
        if not len(rows):
            continue
        for row, v, h in zip(rows, far(rows).tolist(), (rows @ near).tolist()):
            k = row.tobytes()
            if k not in seen and v < BIG:
                if len(seen) >= limit:
                    return None
                seen.add(k)
                heapq.heappush(heap, (v, h, order, k))
                order += 1
    return None


#: Orders in which a solution of the state equation is fired before it is given up.
FIRING_TRIES = 16
#: Seconds the state equation's solutions may be sought and fired over the questions of
#: one command.
FIRED_SOLUTION_SECONDS = 5.0
#: The markings met while firing one question's solutions that are kept as witnesses for
#: the others (the rest are fired through, not kept).
MET_MARKINGS = 100_000


def settled_by_equation_witness(net: Net, queries: Sequence[q.Query],
                                seconds: float = FIRED_SOLUTION_SECONDS, seed: int = 0
                                ) -> dict[str, Settled]:
    """The reachability questions a solution of the state equation, fired, settles: for
    ``E F φ`` (``A G φ``: not φ) the solution with the fewest firings of each disjunct
    (:func:`state_equation.firing_counts`) is fired from M0, an enabled transition with
    firings left at each step (the first, then in random orders, :data:`FIRING_TRIES`),
    until a marking satisfies φ (``E F φ`` true, ``A G φ`` false). Every marking on the
    way is fired to, so reachable: each is a witness for the other questions too, checked
    after each solution fired. A witness is checked by the formula's own evaluation; a
    solution that cannot be fired proves nothing (LoLA's Sara: Schmidt, Wimmel; it
    refines such a solution, this does not). Within ``seconds`` over the questions."""
    s = structure(net)
    settled: dict[str, Settled] = {}
    firing = Firing(s)
    m0 = np.array(s.initial_vector(), dtype=np.int64)
    rng = np.random.default_rng(seed)
    end = time.monotonic() + seconds
    pending = []
    for x in queries:
        r = reachability(x.asks)
        if r is not None:
            exists, phi = r
            pending.append((x.id, exists, phi if exists else q.Neg(phi)))
    while pending and time.monotonic() < end:
        k, exists, target = pending.pop(0)
        met: list[np.ndarray] = []
        try:
            far = distance(target, s, firing)
            for counts in state_equation.firing_counts(s, target, end - time.monotonic()):
                if _fired(firing, m0, counts, far, rng, end, met) is not None:
                    break
        except (KeyError, LookupError):
            continue
        if not met:
            continue
        # the markings met are witnesses for this question and for the ones still waiting
        truths = Truths(s, ListedMarkings([m.tolist() for m in met]))
        left = []
        for item in [(k, exists, target), *pending]:
            try:
                hit = bool(np.any(truths.of(item[2])))
            except (KeyError, LookupError):
                hit = False
            if hit:
                settled[item[0]] = (item[1], "EXPLICIT STATE_EQUATION")
            elif item[0] != k:
                left.append(item)
        pending = left
    return settled


def _fired(firing: Firing, m0: np.ndarray, counts: np.ndarray, far, rng, deadline: float,
           met: list[np.ndarray]) -> np.ndarray | None:
    """A marking at distance 0 (``far``) met while firing ``counts`` from ``m0``, an
    enabled transition with firings left at each step; None where every order tried
    stops short of one. Each marking fired to is added to ``met``."""
    for attempt in range(FIRING_TRIES):
        if attempt and time.monotonic() > deadline:
            return None
        m, left = m0, counts.copy()
        for step in itertools.count(1):
            if far(m[None, :])[0] == 0:
                return m
            enabled = firing.enabled_all(m)
            ready = enabled[left[enabled] > 0]
            if not len(ready):
                break
            j = int(ready[0] if attempt == 0 else rng.choice(ready))
            m = firing.fire(m, j)
            if len(met) < MET_MARKINGS:
                met.append(m)
            left[j] -= 1
            # a solution may ask millions of firings: the clock bounds it too
            if step % 256 == 0 and time.monotonic() > deadline:
                return None
    return None


# -- on the fly: the property checker's engine ---------------------------------------

def reachability(f) -> tuple[bool, object] | None:
    """``(exists, φ)`` for ``E F φ`` (``exists``) or ``A G φ``, φ a state formula, under
    any negations; None for any other formula."""
    negated, f = q.unnegated(f)
    if isinstance(f, q.ExistsPath) and isinstance(f.arg, q.Finally) and q.is_state(f.arg.arg):
        exists, phi = True, f.arg.arg
    elif isinstance(f, q.AllPaths) and isinstance(f.arg, q.Globally) \
            and q.is_state(f.arg.arg):
        exists, phi = False, f.arg.arg
    else:
        return None
    # not E F φ = A G not φ; not A G φ = E F not φ
    return (not exists, q.Neg(phi)) if negated else (exists, phi)


def safe_predicate(phi, s) -> object | None:
    """A state formula as the property checker's predicate on a 1-safe net (its sums are
    counts of marked places); None where it has none (a deadlock, a place named twice in
    a sum, a name the net does not have)."""
    def sum_of(e):
        if isinstance(e, q.IntConst):
            return e.value
        if len(set(e.places)) != len(e.places) or not set(e.places) <= s.place_index.keys():
            raise LookupError
        return tuple(e.places)

    def at_least(places, v):           # sum(places) >= v
        return pr.Const(True) if v <= 0 else pr.Const(False) if v > len(places) \
            else pr.Tokens(places, v)

    def go(f):
        if isinstance(f, q.BoolConst):
            return pr.Const(f.value)
        if isinstance(f, q.Neg):
            return pr.Not(go(f.arg))
        if isinstance(f, (q.Conj, q.Disj)):
            return (pr.And if isinstance(f, q.Conj) else pr.Or)(tuple(go(a) for a in f.args))
        if isinstance(f, q.Fireable):
            out = []
            for t in f.transitions:
                j = s.transition_index.get(t)
                if j is None:
                    raise LookupError
                need = tuple(s.places[i] for i in sorted(s.transition_inputs[j]))
                out.append(at_least(need, len(need)))
            return pr.Or(tuple(out))
        if isinstance(f, q.IntLe):
            left, right = sum_of(f.left), sum_of(f.right)
            if isinstance(left, int) and isinstance(right, int):
                return pr.Const(left <= right)
            if isinstance(left, int):
                return at_least(right, left)
            if isinstance(right, int):
                return pr.Not(at_least(left, right + 1))
            # sum(P) <= sum(Q) on counts: whenever P holds v tokens, so does Q
            return pr.And(tuple(pr.Or((pr.Not(at_least(left, v)), at_least(right, v)))
                                for v in range(1, len(left) + 1)))
        raise LookupError              # a deadlock: not a sum of marked places

    try:
        return go(phi)
    except LookupError:
        return None


def reach_on_the_fly(net: Net, queries: Sequence[q.Query], max_states: int,
                     max_memory: int | None, stubborn: bool = False,
                     safe: bool = False) -> dict[str, Settled]:
    """The reachability questions the on-the-fly checker (:mod:`mcl2pnml.analysis.checking.on_the_fly`) settles,
    by id: on a net it takes (1-safe as given), each ``A G φ`` is the universality of φ
    and each ``E F φ`` the failure of the universality of not φ, searched breadth first
    in C and stopped at the first marking that decides it. With ``stubborn``, stubborn
    sets keep only the interleavings the atoms can see (a safety property keeps its
    verdict: :mod:`mcl2pnml.analysis.checking.on_the_fly`), on a net proven 1-safe (``safe``, or a P-invariant
    found here). A question past the limits is left to the graph."""
    shaped = [(x, reachability(x.asks)) for x in queries]
    shaped = [(x, r) for x, r in shaped if r is not None]
    if not shaped or not onthefly.available():
        return {}
    s = structure(net)
    props, asked = [], []
    for x, (exists, phi) in shaped:
        pred = safe_predicate(q.Neg(phi) if exists else phi, s)
        if pred is None or len(pr.atoms_of(pred)) > onthefly.ATOMS:
            continue
        props.append(pr.Property(x.id, pr.Pattern.UNIVERSALITY, pred))
        asked.append((x, exists))
    if not props:
        return {}
    try:
        verdicts = onthefly.check_properties_on_the_fly(net, props, max_states, max_memory,
                                                        stubborn, safe)
    except onthefly.NotProvenSafe:
        verdicts = onthefly.check_properties_on_the_fly(net, props, max_states, max_memory)
        stubborn = False
    if verdicts is None:
        return {}
    technique = "EXPLICIT ON_THE_FLY" + (" STUBBORN_SETS" if stubborn else "")
    found = {}
    for (x, exists), v in zip(asked, verdicts):
        if v.status is Status.UNKNOWN:
            continue
        holds = v.status is Status.HOLDS
        found[x.id] = (not holds if exists else holds, technique)
    return found
