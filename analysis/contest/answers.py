"""The Model Checking Contest's questions answered on a net's reachability graph.

Any bounded P/T net, any formula of :mod:`mcl2pnml.core.queries`: its
reachable markings explored (:func:`mcl2pnml.analysis.statespace.explore.explore`), its edges
held as compressed rows, then each question decided on the graph, exactly,
by searches in C (``analysis/statespace/loops/_native.c``; the same in Python,
``analysis/statespace/loops/python.py``, where C was not built):

* state atoms, for every marking at once (numpy columns of token counts);
* CTL by the classic labelling (Clarke, Emerson and Sistla, 1986): ``EX``
  by the successors, ``EU`` backwards from its goal, ``EG`` as the states
  that reach, inside the formula's states, a cycle of them or a dead marking
  (Tarjan's strongly connected components); the other operators from these
  three. The reachability examinations are CTL's ``EF`` and ``AG``;
* LTL (the contest's ``A φ``): the generalised Büchi automaton of ``not φ``
  by Gerth, Peled, Vardi and Wolper's tableau (1995; ``buchi.py``), its product
  with the graph searched on the fly by Couvreur's emptiness check (1999), which
  numbers only the product states it meets and stops at the first cycle
  meeting every acceptance set;
* the upper bounds: the largest token sum over the markings.

The generic examinations are :mod:`.generic`'s, on this module's graph and portfolio.

Where the state space is larger than a first, small exploration, cheaper techniques
come first, each answer handed out as soon as one settles it (:func:`answers_as_found`;
docs/query.md): the markings found as witnesses and the graph explored so far read
three-valued (:class:`PartialGraph`), the state equation
(:mod:`mcl2pnml.analysis.structure.state_equation`), formulas simplified by it and the
P-invariants, the questions the structural reductions keep, on the net reduced for each
(:mod:`mcl2pnml.analysis.structure.reductions`), the path formulas searched on the fly
from the net under stubborn sets
(:mod:`mcl2pnml.analysis.contest.ltl_on_the_fly`), random walks and the runs of walkers
that close (each run a one-path :class:`RunGraph`), then explorations in larger stages.

Where the graph cannot be built (past the limits, or an unbounded net), the
reachability questions of a 1-safe net are searched on the fly by the
property checker's engine (:mod:`mcl2pnml.analysis.checking.on_the_fly`), stopping at
the first witness. With ``stubborn``, those questions go to that engine first, under
stubborn sets.

Dead markings, as the contest's 2021 consensus answers read them (every one
of its 2,223 verdicts on the 19 models in ``../shared/external-nets/mcc-queries``
agrees, tests/analysis/test_mcc.py): in CTL a path is maximal, so a dead marking has
no next marking (``EX`` false, ``AX`` true there) and ends its path (``EG φ``
holds there where ``φ`` does); in LTL a finite path is extended by repeating
its dead marking. The two differ only on ``X`` at a dead marking: a formula of
both kinds with an ``X`` is decided both ways, and left unanswered, with the
reason, where they disagree.

What is not answered is said with its reason, never guessed: a formula that
is neither CTL nor LTL, a question past the limits that nothing else settles,
an LTL product past the memory budget.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from functools import cached_property
from typing import Iterator, Sequence

import numpy as np

from mcl2pnml.core import queries as q
from mcl2pnml.core.bounds import MAX_STATES
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.memory import default_memory, size_text
from mcl2pnml.core.net import Net
from mcl2pnml.core.structure import structure

from mcl2pnml.analysis.contest.buchi import NotLTL, negation_normal_form, tableau
from mcl2pnml.analysis.contest.ctl_on_the_fly import NotCTL, settled_by_ctl_on_the_fly
from mcl2pnml.analysis.contest.ltl_on_the_fly import FLY_SECONDS, settled_by_ltl_on_the_fly
from mcl2pnml.analysis.contest.reachability_queries import (BEST_FIRST_SECONDS,
                                                            GUIDED_SECONDS, WALK_SECONDS,
                                                            ListedMarkings, Truths,
                                                            reach_on_the_fly, reachability,
                                                            settled_by_best_first,
                                                            settled_by_equation_witness,
                                                            settled_by_found,
                                                            settled_by_guided_search,
                                                            settled_by_state_equation,
                                                            settled_by_walks,
                                                            settled_without_exploring,
                                                            simplified_by_structure)
from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore
from mcl2pnml.analysis.statespace.loops.backends import chosen
from mcl2pnml.analysis.statespace.partial import partial_space
from mcl2pnml.analysis.statespace.rows import compressed_rows
from mcl2pnml.analysis.statespace.walks import runs
from mcl2pnml.analysis.structure.reductions import Keep, reduced

_loops = chosen()         # the graph searches in C, else the same in Python


@dataclass(frozen=True)
class Answer:
    """One question's answer: True/False, a bound, or None with the reason."""

    id: str
    value: bool | int | None
    technique: str
    reason: str = ""

    def line(self) -> str:
        """The contest's answer line (``FORMULA id TRUE TECHNIQUES ...``), or a line
        saying why there is none."""
        if self.value is None:
            return f"FORMULA {self.id} CANNOT_COMPUTE ({self.reason})"
        shown = self.value if isinstance(self.value, int) and not isinstance(self.value, bool) \
            else ("TRUE" if self.value else "FALSE")
        return f"FORMULA {self.id} {shown} TECHNIQUES {self.technique}"


class UnknownName(Mcl2PnmlError):
    """A query names a place or a transition the net does not have."""


def check_names(net: Net, queries: Sequence[q.Query]) -> None:
    """Refuse the first query that names a place or a transition ``net`` lacks, at its
    location (:class:`UnknownName`): before any answer, whatever the net's size (else a
    small net's graph refused it and a large one's techniques left it unanswered, blaming
    their limits). :func:`answers_as_found` asks it first."""
    for x in queries:
        for kind, name in q.named(x.asks):
            known = net.place_index if kind == "place" else net.transition_index
            if name not in known:
                raise UnknownName(f"no {kind} '{name}' in the net", x.location)


class Graph:
    """The reachability graph of a bounded net, as the checker reads it: its edges in
    compressed rows (successors with a dead marking's self-loop, the temporal operators'
    graph; the firings alone; predecessors), searched by the loops in C."""

    def __init__(self, space):
        self.space = space
        s = space.structure
        self.structure = s
        self.n = n = space.states
        # as the explorer gave them (int32 where it can: a copy in int64 was most of the
        # memory of a graph of tens of millions of edges); the rows in int64 for the loops
        src, dst = np.asarray(space.src), np.asarray(space.dst)
        self.trans = np.asarray(space.trans)
        self.src, self.dst = src, dst
        self.dead = np.ones(n, dtype=bool)
        self.dead[src] = False
        self.real = compressed_rows(src, dst, n)
        self.place_index = {p: i for i, p in enumerate(s.places)}
        self.transition_index = {t: i for i, t in enumerate(s.transitions)}
        self._tokens: dict[int, np.ndarray] = {}
        self._firings: tuple[np.ndarray, np.ndarray] | None = None
        self._loops: np.ndarray | None = None

    @cached_property
    def succ(self) -> tuple[np.ndarray, np.ndarray]:
        """The temporal operators' graph: the firings, and a dead marking repeats for ever."""
        loops = np.flatnonzero(self.dead)
        return compressed_rows(np.concatenate([self.src, loops]),
                               np.concatenate([self.dst, loops]), self.n)

    @cached_property
    def pred(self) -> tuple[np.ndarray, np.ndarray]:
        """The temporal operators' graph backwards."""
        loops = np.flatnonzero(self.dead)
        return compressed_rows(np.concatenate([self.dst, loops]),
                               np.concatenate([self.src, loops]), self.n)

    # -- atoms ---------------------------------------------------------------------------------

    def tokens(self, places: Sequence[str], where) -> np.ndarray:
        total = np.zeros(self.n, dtype=np.int64)
        for p in places:
            i = self.place_index.get(p)
            if i is None:
                raise UnknownName(f"no place '{p}' in the net", where)
            column = self._tokens.get(i)
            if column is None:
                # kept in the narrowest integer type the counts fit: a column a place
                # named, of tens of millions of markings, adds up
                column = np.asarray(self.space.tokens(i))
                column = self._tokens[i] = column.astype(
                    np.min_scalar_type(int(column.max(initial=0))))
            total += column
        return total

    def enabled(self, transitions: Sequence[str], where) -> np.ndarray:
        out = np.zeros(self.n, dtype=bool)
        if self._firings is None:          # the edges grouped by transition, once
            self._firings = compressed_rows(self.trans, self.src, len(self.transition_index))
        ptr, sources = self._firings
        for t in transitions:
            j = self.transition_index.get(t)
            if j is None:
                raise UnknownName(f"no transition '{t}' in the net", where)
            # enabled exactly where it fires: the graph's edges are its firings
            out[sources[ptr[j]:ptr[j + 1]]] = True
        return out

    def integer(self, e, where) -> np.ndarray:
        if isinstance(e, q.IntConst):
            return np.full(self.n, e.value, dtype=np.int64)
        return self.tokens(e.places, where)

    # -- CTL -----------------------------------------------------------------------------------

    def ex(self, sat: np.ndarray) -> np.ndarray:
        """EX sat: a firing leads to ``sat`` (none from a dead marking)."""
        out = np.zeros(self.n, dtype=bool)
        out[self.src[sat[self.dst]]] = True
        return out

    def eu(self, before: np.ndarray, reach: np.ndarray) -> np.ndarray:
        """E(before U reach): backwards from ``reach`` through ``before``."""
        out = reach.astype(np.uint8)
        _loops.back_reach(*self.pred, before.astype(np.uint8), out)
        return out.view(bool)

    def eg(self, sat: np.ndarray) -> np.ndarray:
        """EG sat: the states that reach, through ``sat``, a cycle inside ``sat`` (a dead
        marking's self-loop is one)."""
        return self.eu(sat, self._cycles_in(sat))

    def _cycles_in(self, sat: np.ndarray) -> np.ndarray:
        """The states on a cycle inside ``sat``: in a strongly connected component of
        ``sat`` with more than one state, or with an edge to themselves."""
        if not sat.any():
            return np.zeros(self.n, dtype=bool)
        keep = sat.astype(np.uint8)
        label = np.empty(self.n, dtype=np.int64)
        count = _loops.scc(*self.succ, keep, label)
        ptr, idx = self.succ
        inside = label >= 0
        size = np.bincount(label[inside], minlength=count)
        looped = size > 1
        if self._loops is None:             # the markings with an edge to themselves
            tail = np.repeat(np.arange(self.n), np.diff(ptr))
            self._loops = np.unique(tail[tail == idx])
        loops = self._loops[inside[self._loops]]
        looped[label[loops]] = True
        return inside & looped[np.where(inside, label, 0)]

    def check(self, f, where) -> np.ndarray:
        """The states where CTL formula ``f`` holds."""
        if isinstance(f, q.BoolConst):
            return np.full(self.n, f.value)
        if isinstance(f, q.IntLe):
            return self.integer(f.left, where) <= self.integer(f.right, where)
        if isinstance(f, q.Fireable):
            return self.enabled(f.transitions, where)
        if isinstance(f, q.Deadlock):
            return self.dead.copy()
        if isinstance(f, q.Neg):
            return ~self.check(f.arg, where)
        if isinstance(f, q.Conj):
            out = np.ones(self.n, dtype=bool)
            for a in f.args:
                out &= self.check(a, where)
            return out
        if isinstance(f, q.Disj):
            out = np.zeros(self.n, dtype=bool)
            for a in f.args:
                out |= self.check(a, where)
            return out
        if isinstance(f, (q.AllPaths, q.ExistsPath)):
            return self._quantified(f, where)
        raise NotCTL("a temporal operator outside a path quantifier")

    def _quantified(self, f, where) -> np.ndarray:
        inner, exists = f.arg, isinstance(f, q.ExistsPath)
        if q.is_closed(inner):
            return self.check(inner, where)        # a quantifier over a state formula
        true = np.ones(self.n, dtype=bool)
        if isinstance(inner, q.Next):
            sat = self.check(inner.arg, where)
            return self.ex(sat) if exists else ~self.ex(~sat)
        if isinstance(inner, q.Finally):
            sat = self.check(inner.arg, where)
            return self.eu(true, sat) if exists else ~self.eg(~sat)
        if isinstance(inner, q.Globally):
            sat = self.check(inner.arg, where)
            return self.eg(sat) if exists else ~self.eu(true, ~sat)
        if isinstance(inner, q.Until):
            a, b = self.check(inner.before, where), self.check(inner.reach, where)
            if exists:
                return self.eu(a, b)
            # A(a U b) = not E(not b U (not a and not b)) and not EG not b
            return ~self.eu(~b, ~a & ~b) & ~self.eg(~b)
        raise NotCTL("a path formula that is not CTL (LTL under a path quantifier)")


# -- LTL: the negation's Büchi automaton (buchi.py), in product with the graph ------------------

class TooLarge(Exception):
    """A product past the limits: the question is left unanswered, with this reason."""


def ltl_holds(graph: "Graph", f: q.AllPaths, where, max_states: int = 1 << 31,
              max_memory: int | None = None, within: np.ndarray | None = None) -> bool:
    """``A φ``: no path of the graph (a dead marking repeated for ever) satisfies ``not φ``:
    the product with the negation's automaton, searched on the fly from its initial states
    (Couvreur's check, in C), has no reachable cycle meeting every acceptance set. Only
    the product states the search meets are numbered; it stops at the first such cycle.
    ``within``: the markings the paths may visit (every one where None)."""
    atoms: list[np.ndarray] = []

    def atom(g, negate: bool) -> int:     # each maximal state subformula, a column of truths
        sat = graph.check(g, where)
        atoms.append(~sat if negate else sat)
        return len(atoms) - 1

    literals, accepting, initial, edges = tableau(negation_normal_form(f.arg, True, atom))
    if any(not acc for acc in accepting):
        return True                     # a set no node is in: no run of not-φ is accepted
    if len(accepting) > 64:
        raise TooLarge(f"the automaton of the negation has {len(accepting)} acceptance sets "
                       "(the search holds 64)")
    n, k = graph.n, len(literals)
    need = n * k * 5                    # the numbering (4 bytes) and the labels (1 byte)
    budget = default_memory() if max_memory is None else max_memory
    if need > budget or n * k >= 2 ** 31:
        raise TooLarge(f"the product of {n:,} markings and the {k} nodes of the negation's "
                       f"automaton needs {size_text(need)}, past the limit of "
                       f"{size_text(budget)}")
    label = np.ones((k, n), dtype=bool)
    for j, lits in enumerate(literals):
        for a in lits:
            label[j] &= atoms[a]
        if within is not None:
            label[j] &= within
    start = np.array([j for j in sorted(initial) if label[j][0]], dtype=np.int64)
    if not len(start):
        return True
    a_src = np.array([e[0] for e in edges], dtype=np.int64)
    a_dst = np.array([e[1] for e in edges], dtype=np.int64)
    acc = np.zeros(k, dtype=np.uint64)
    for bit, members in enumerate(accepting):
        acc[sorted(members)] |= np.uint64(1 << bit)
    found, states = _loops.ltl_product(
        *graph.succ, *compressed_rows(a_src, a_dst, k), label.view(np.uint8).ravel(), acc,
        (1 << len(accepting)) - 1, start, np.zeros(n * k, dtype=np.int32),
        min(max_states, 2 ** 31 - 2))
    if found < 0:
        raise TooLarge(f"the product is past its limit of {max_states:,} states")
    return not found


# -- the questions --------------------------------------------------------------------------------


#: The markings explored before the state equation is asked: a state space this small is
#: built in a fraction of a second, and answers every question exactly (the equation's
#: solver alone takes most of a second to import).
FIRST_STATES = 100_000


def _space(net: Net, max_states: int, max_memory: int | None):
    """The reachability graph, or None with the reason, and the limit that stopped the
    exploration, or None (its ``found``: the markings met before it)."""
    try:
        space = explore(net, max_states=max_states, max_memory=max_memory)
    except ExplorationLimit as e:
        return None, f"the state space is past its limit: {e.message}", e
    if getattr(space, "coverability", False):
        return None, "the net is unbounded: its coverability graph does not decide these", None
    return space, "", None


def _stages(max_states: int) -> list[int]:
    """The limits of the explorations after the first: ten times larger each, up to
    ``max_states``. Each one stopped at its limit hands its markings over as witnesses
    before the next starts, so a run cut short keeps them; all of them cost about a
    tenth more than the last alone."""
    limits, limit = [], FIRST_STATES
    while limit < max_states:
        limit = min(max_states, 10 * limit)
        limits.append(limit)
    return limits


def answer(net: Net, queries: Sequence[q.Query], *, max_states: int = MAX_STATES,
           max_memory: int | None = None, stubborn: bool = False,
           safe: bool = False) -> list[Answer]:
    """Each query's answer, in the queries' order (:func:`answers_as_found`)."""
    got = {a.id: a for a in answers_as_found(net, queries, max_states=max_states,
                                             max_memory=max_memory, stubborn=stubborn,
                                             safe=safe)}
    return [got[x.id] for x in queries]


# long: one generator walks the portfolio in its order, each answer handed out as soon as
# it is settled; split up, the order (the point of it) would be spread over functions
def answers_as_found(net: Net, queries: Sequence[q.Query], *, max_states: int = MAX_STATES,
                     max_memory: int | None = None, stubborn: bool = False,
                     safe: bool = False) -> Iterator[Answer]:
    """Each query's answer once, as soon as a technique settles it (the module's
    documentation): what the cheap techniques settle comes out before a long exploration
    starts, as the contest's tools print it, and a run cut short keeps it.

    A state space of up to :data:`FIRST_STATES` markings is built first, and answers
    everything; past it, the markings it found are witnesses (:func:`settled_by_found`),
    then what the state equation proves unreachable is answered
    (:func:`settled_by_state_equation`: ``E F φ`` false, ``A G φ`` true), then what the
    formulas simplify to (:func:`simplified_by_structure`: a constant, or what the
    initial marking decides on every path; the rest goes on simplified), then what the
    initial marking and the P-invariants settle
    (:func:`~mcl2pnml.analysis.contest.reachability_queries.settled_without_exploring`),
    then the questions the reductions keep (reachability, bounds, CTL and LTL without
    ``X``) on the nets reduced for them (:func:`settled_by_reduction`, again before each
    larger exploration), then the
    formulas one search on the fly decides (LTL under stubborn sets, then CTL's
    dependency graph), then what random walks meet (:func:`settled_by_walks`, witnesses
    as found markings are) and what the runs of walkers that close show
    (:func:`settled_by_runs`), then the state equation's solutions fired
    (:func:`settled_by_equation_witness`), then the witnesses a best-first search by the
    formula's distance meets (:func:`settled_by_guided_search`), then the upper bounds a
    best-first search reaches (:func:`settled_by_best_first`), then the state space is
    explored to limits ten times larger each up to ``max_states`` (:func:`_stages`), the
    markings of each one stopped witnesses again, and walks, runs and the guided searches
    twice as long as the last after each (their own seed each: new walks). With
    ``stubborn``, the reachability questions (``E F φ``, ``A G φ``) of a 1-safe net are
    searched on the fly under partial-order reduction (:func:`reach_on_the_fly`) before
    any graph. Past the graph's limits, the reachability questions are searched on the
    fly, each stopping at its first witness; the rest is unanswered, with the reason. A
    query naming a place or transition the net lacks is refused before any answer
    (:func:`check_names`)."""
    check_names(net, queries)
    done: set[str] = set()

    def settle(settled: dict) -> Iterator[Answer]:
        for k, (value, technique) in settled.items():
            if k not in done:
                done.add(k)
                yield Answer(k, value, technique)

    asked = {x.id: x for x in queries}     # as simplified, once they are

    def left() -> list[q.Query]:
        return [asked[x.id] for x in queries if x.id not in done]

    # a small state space first: built at once, it answers everything exactly; past its
    # limit, the markings it found are witnesses
    space, why, stopped = (None, "", None) if stubborn else \
        _space(net, min(max_states, FIRST_STATES), max_memory)
    if stopped is not None and stopped.found is not None:
        yield from settle(settled_by_found(net, left(), stopped.found))
        yield from settle(settled_by_partial_graph(net, left(), stopped.found, max_memory))
    limited = stubborn or stopped is not None
    del stopped
    if space is None:
        # then the cheap proofs, as the contest's tools order them: what the state equation
        # proves unreachable, and what the invariants bound, need no marking explored
        # (seconds, where exploring may not end)
        yield from settle(settled_by_state_equation(net, left()))
        decided, rewritten = simplified_by_structure(net, left())
        yield from settle(decided)
        asked.update(rewritten)
        yield from settle(settled_without_exploring(net, left()))
        # then the questions the reductions keep, on the nets reduced for them, where
        # those are small enough to explore whole
        reductions: dict = {}
        yield from settle(settled_by_reduction(net, left(), min(max_states, FIRST_STATES),
                                               max_memory, reductions))
        # then the path formulas one search each decides on the fly, under stubborn sets
        yield from settle(settled_by_ltl_on_the_fly(net, left(), max_states=max_states,
                                                    max_memory=max_memory))
        yield from settle(settled_by_ctl_on_the_fly(net, left(), max_states=max_states,
                                                    max_memory=max_memory))
        # then witnesses deep in the net, where the first exploration stayed near M0; more
        # walks, twice as long each time, after each larger exploration stopped
        yield from settle(settled_by_walks(net, left()))
        yield from settle(settled_by_runs(net, left()))
        yield from settle(settled_by_equation_witness(net, left()))
        yield from settle(settled_by_guided_search(net, left(), max_states=max_states,
                                                   max_memory=max_memory))
        yield from settle(settled_by_best_first(net, left(), max_states=max_states,
                                                max_memory=max_memory))
        if stubborn:
            yield from settle(reach_on_the_fly(net, left(), max_states, max_memory, True,
                                               safe))
        if not left():
            return
        first = [min(max_states, FIRST_STATES)] if stubborn else []   # none explored yet
        for k, limit in enumerate((first + _stages(max_states)) if limited else [], 1):
            yield from settle(settled_by_reduction(net, left(), limit, max_memory, reductions,
                                                   REDUCED_NETS_SECONDS * 2 ** k))
            if not left():
                return
            space, why, stopped = _space(net, limit, max_memory)
            if stopped is not None and stopped.found is not None:
                yield from settle(settled_by_found(net, left(), stopped.found))
                yield from settle(settled_by_partial_graph(net, left(), stopped.found,
                                                           max_memory))
            # a memory budget, not the count, stopped it: a larger limit would not pass it
            ended = stopped is None or stopped.explored is None or stopped.explored < limit
            del stopped
            if ended or not left():
                break
            yield from settle(settled_by_ltl_on_the_fly(net, left(), FLY_SECONDS * 2 ** k,
                                                        max_states, max_memory))
            yield from settle(settled_by_ctl_on_the_fly(net, left(), FLY_SECONDS * 2 ** k,
                                                        max_states, max_memory))
            yield from settle(settled_by_walks(net, left(), WALK_SECONDS * 2 ** k, seed=k))
            yield from settle(settled_by_runs(net, left(), WALK_SECONDS * 2 ** k, seed=k))
            yield from settle(settled_by_guided_search(net, left(), GUIDED_SECONDS * 2 ** k,
                                                       max_states, max_memory))
            yield from settle(settled_by_best_first(net, left(), BEST_FIRST_SECONDS * 2 ** k,
                                                    max_states, max_memory))
        if not left():
            return
    if space is None:
        if not stubborn:
            yield from settle(reach_on_the_fly(net, left(), max_states, max_memory))
        for x in left():
            yield Answer(x.id, None, "", why)
        return
    graph = Graph(space)
    for x in left():
        if isinstance(x.asks, q.PlaceBound):
            yield Answer(x.id, int(graph.tokens(x.asks.places, x.location).max()),
                         "EXPLICIT STATE_SPACE")
        else:
            yield _decide(graph, x, max_memory)


def _decide(graph: Graph, x: q.Query, max_memory: int | None = None) -> Answer:
    """A formula's answer: by CTL's labelling, by LTL's automaton, or by both where the
    formula is both (``A F p``). The two semantics differ only on ``X`` at a dead marking
    (CTL: no next marking; LTL: the dead marking repeated): where a formula of both
    kinds has an ``X`` and the answers differ, none is given."""
    f = x.asks
    ctl, ltl = q.is_ctl(f), q.is_ltl(f)
    if not ctl and not ltl:
        return Answer(x.id, None, "", "neither CTL nor LTL (a path formula under a "
                                      "quantifier mixes them)")
    by_ctl = bool(graph.check(f, x.location)[0]) if ctl else None
    try:
        by_ltl = ltl_holds(graph, f, x.location, max_memory=max_memory) \
            if ltl and (not ctl or q.contains(f, q.Next)) else None
    except TooLarge as e:
        return Answer(x.id, None, "", str(e))
    if by_ctl is not None and by_ltl is not None and by_ctl != by_ltl:
        return Answer(x.id, None, "", "CTL and LTL semantics differ here (X of a dead "
                                      "marking): the contest's category decides, which the "
                                      "file does not say")
    return Answer(x.id, by_ctl if by_ctl is not None else by_ltl,
                  f"EXPLICIT {'CTL' if by_ctl is not None else 'LTL'}")


# -- past the limit: the part of the graph explored, three-valued ---------------------------------

class PartialGraph(Graph):
    """The graph an exploration built before its limit
    (:class:`~mcl2pnml.analysis.statespace.partial.PartialStateSpace`), read three-valued:
    each formula gets the states where it surely holds and those where it may, whatever
    the ``open`` frontier markings do (Bruns and Godefroid, *Model checking partial state
    spaces with 3-valued temporal logics*, CAV 1999). An open marking has no known
    successor: it may go anywhere, so it is neither dead nor surely anything past its
    own atoms. The atoms are exact in every found marking: token sums from the markings,
    a transition enabled by its needs, dead by the out-degree."""

    def __init__(self, space):
        super().__init__(space)
        self.open = space.open
        self.dead &= ~self.open           # no edge out of an open marking: not dead for that

    @cached_property
    def _open_truths(self) -> Truths:
        """The open markings' atoms, evaluated from their counts (they have no edges)."""
        return Truths(self.structure, self.space.open_markings())

    def enabled(self, transitions: Sequence[str], where) -> np.ndarray:
        out = super().enabled(transitions, where)   # the expanded markings, by their edges
        at = np.flatnonzero(self.open)
        if len(at):
            for t in transitions:
                out[at[self._open_truths.enabled(self.transition_index[t])]] = True
        return out

    def check3(self, f, where) -> tuple[np.ndarray, np.ndarray]:
        """``(surely, maybe)``: the states where CTL formula ``f`` holds whatever the open
        markings do, and those where it holds for some future of theirs."""
        if q.is_state(f):
            sat = self.check(f, where)
            return sat, sat
        if isinstance(f, q.Neg):
            surely, maybe = self.check3(f.arg, where)
            return ~maybe, ~surely
        if isinstance(f, (q.Conj, q.Disj)):
            parts = [self.check3(a, where) for a in f.args]
            join = np.logical_and if isinstance(f, q.Conj) else np.logical_or
            return (join.reduce([p[0] for p in parts]), join.reduce([p[1] for p in parts]))
        if isinstance(f, (q.AllPaths, q.ExistsPath)):
            return self._quantified3(f, where)
        raise NotCTL("a temporal operator outside a path quantifier")

    def _quantified3(self, f, where) -> tuple[np.ndarray, np.ndarray]:
        inner, exists = f.arg, isinstance(f, q.ExistsPath)
        if q.is_closed(inner):
            return self.check3(inner, where)
        o = self.open

        def neg(p):
            return ~p[1], ~p[0]

        def ex(p):          # an open marking may have a successor in anything
            return self.ex(p[0]), self.ex(p[1]) | o

        def eu(a, b):       # ... and may go on to b from there
            return self.eu(a[0], b[0]), self.eu(a[1], b[1] | (a[1] & o))

        def eg(a):          # ... or stay in a for ever
            return self.eg(a[0] & ~o), self.eu(a[1], self._cycles_in(a[1]) | (a[1] & o))

        true = np.ones(self.n, dtype=bool)
        if isinstance(inner, q.Next):
            a = self.check3(inner.arg, where)
            return ex(a) if exists else neg(ex(neg(a)))
        if isinstance(inner, q.Finally):
            b = self.check3(inner.arg, where)
            return eu((true, true), b) if exists else neg(eg(neg(b)))
        if isinstance(inner, q.Globally):
            a = self.check3(inner.arg, where)
            return eg(a) if exists else neg(eu((true, true), neg(a)))
        if isinstance(inner, q.Until):
            a, b = self.check3(inner.before, where), self.check3(inner.reach, where)
            if exists:
                return eu(a, b)
            # A(a U b) = not E(not b U (not a and not b)) and not EG not b
            not_a, not_b = neg(a), neg(b)
            one = neg(eu(not_b, (not_a[0] & not_b[0], not_a[1] & not_b[1])))
            two = neg(eg(not_b))
            return one[0] & two[0], one[1] & two[1]
        raise NotCTL("a path formula that is not CTL (LTL under a path quantifier)")


def _decide_partial(graph: PartialGraph, x: q.Query, max_memory: int | None) -> bool | None:
    """A formula's answer on a partial graph where its open markings cannot change it,
    else None: CTL three-valued at M0; LTL false where a lasso (or a path to a dead
    marking) of expanded markings violates it (its product kept off the open ones). A
    formula of both kinds with an ``X`` needs both answers, and the same."""
    f = x.asks
    ctl, ltl = q.is_ctl(f), q.is_ltl(f)
    by_ctl = by_ltl = None
    if ctl:
        surely, maybe = graph.check3(f, x.location)
        by_ctl = True if surely[0] else (False if not maybe[0] else None)
    if ltl and (not ctl or q.contains(f, q.Next)):
        try:
            if not ltl_holds(graph, f, x.location, max_memory=max_memory,
                             within=~graph.open):
                by_ltl = False
        except TooLarge:
            pass
    if ctl and ltl and q.contains(f, q.Next):
        return by_ctl if by_ctl is not None and by_ctl == by_ltl else None
    return by_ctl if ctl else by_ltl


#: The largest partial graph labelled, in edges: its labelling costs about what the whole
#: graph's would (a tenth of a second an operator a million markings), and past about ten
#: million edges that is more than the explorations and walks it would delay.
PARTIAL_EDGES = 10_000_000

#: The seconds one partial graph's formulas may take, the smallest first: one formula
#: started is finished.
PARTIAL_SECONDS = 10.0


def settled_by_partial_graph(net: Net, queries: Sequence[q.Query], found,
                             max_memory: int | None = None,
                             seconds: float = PARTIAL_SECONDS) -> dict[str, tuple[bool, str]]:
    """The CTL and LTL formulas the graph of ``found`` (an exploration stopped at its
    limit) decides whatever its open markings do (:class:`PartialGraph`), of up to
    :data:`PARTIAL_EDGES` edges, within about ``seconds``."""
    asked = sorted((x for x in queries if not isinstance(x.asks, q.PlaceBound)
                    and (q.is_ctl(x.asks) or q.is_ltl(x.asks))),
                   key=lambda x: len(repr(x.asks)))
    if not asked or found is None:
        return {}
    space = partial_space(structure(net), found, max_memory, PARTIAL_EDGES)
    if space is None:
        return {}
    graph = PartialGraph(space)
    settled: dict[str, tuple[bool, str]] = {}
    deadline = time.monotonic() + seconds
    for x in asked:
        if time.monotonic() > deadline:
            break
        try:
            value = _decide_partial(graph, x, max_memory)
        except (UnknownName, NotCTL, NotLTL):
            continue
        if value is not None:
            kind = "CTL" if q.is_ctl(x.asks) else "LTL"
            settled[x.id] = (value, f"EXPLICIT {kind} PARTIAL_STATE_SPACE")
    return settled


# -- on a smaller net: the structural reductions ----------------------------------------------

#: Seconds the reduced nets of one step may take, explorations included; one started is
#: finished (it is bounded by its limit).
REDUCED_NETS_SECONDS = 10.0


def reducible(x: q.Query) -> Keep | None:
    """What a reduced net must keep to answer ``x`` as the net does
    (:class:`~mcl2pnml.analysis.structure.reductions.Keep`): the reachable markings for an
    upper bound or ``E F φ`` / ``A G φ``; the paths, up to stuttering, for CTL and LTL
    without ``X``; None for a formula with ``X`` or ``deadlock``, which no reduction
    keeps."""
    if isinstance(x.asks, q.PlaceBound):
        return Keep.REACHABLE
    if q.contains(x.asks, q.Deadlock) or q.contains(x.asks, q.Next):
        return None
    if reachability(x.asks) is not None:
        return Keep.REACHABLE
    return Keep.PATHS if q.is_ctl(x.asks) or q.is_ltl(x.asks) else None


def settled_by_reduction(net: Net, queries: Sequence[q.Query], max_states: int,
                         max_memory: int | None, cache: dict,
                         seconds: float = REDUCED_NETS_SECONDS) -> dict[str, tuple]:
    """The :func:`reducible` questions answered on the net reduced for what they see
    and ask, where the rules made it smaller: its whole state space, of up to
    ``max_states`` markings, decides them exactly (``STRUCTURAL_REDUCTION EXPLICIT
    STATE_SPACE``, ``... CTL``, ``... LTL``); past it, its markings found are witnesses
    (``E F φ`` true, ``A G φ`` false, a bound the invariants prove reached). Questions
    that see the same places and transitions and keep the same share one reduced net;
    ``cache`` keeps them (and those that did not shrink, as None) across calls, so a
    later, larger limit does not reduce again."""
    groups: dict[tuple, list[q.Query]] = {}
    for x in queries:
        keep = reducible(x)
        if keep is not None:
            groups.setdefault((*q.seen(x.asks), keep), []).append(x)
    settled: dict[str, tuple] = {}
    deadline = time.monotonic() + seconds
    for key, xs in sorted(groups.items(), key=lambda kv: len(kv[0][0]) + len(kv[0][1])):
        if time.monotonic() > deadline:
            break
        if key not in cache:
            places, transitions, keep = key
            r = reduced(net, places, transitions, keep=keep)
            cache[key] = r.net if r.smaller else None
        small = cache[key]
        if small is None:
            continue
        space, _, stopped = _space(small, max_states, max_memory)
        if space is None:
            if stopped is not None and stopped.found is not None:
                for k, (value, technique) in settled_by_found(small, xs,
                                                              stopped.found).items():
                    settled[k] = (value, f"STRUCTURAL_REDUCTION {technique}")
            continue
        graph = Graph(space)
        for x in xs:
            if isinstance(x.asks, q.PlaceBound):
                value, technique = int(graph.tokens(x.asks.places, x.location).max()), ""
            else:
                found = _decide(graph, x, max_memory)
                value, technique = found.value, found.technique
            if key[2] is Keep.REACHABLE:    # what the graph shows: the markings reached
                technique = "EXPLICIT STATE_SPACE"
            if value is not None:
                settled[x.id] = (value, f"STRUCTURAL_REDUCTION {technique}")
    return settled


# -- one run at a time: the lassos and maximal runs of random walkers ----------------------------

class RunGraph(Graph):
    """One run of the net as a graph (:func:`~mcl2pnml.analysis.statespace.walks.runs`):
    its markings in a line, the last one's successor the marking it returns to (a lasso),
    or none (a dead marking: a maximal run, the dead marking repeated in LTL's reading).
    Its one path from the first node is the run. Whether a transition is enabled is read
    from the markings (the graph's edges are not every firing); a node without a
    successor is dead in the net too (the walker found nothing to fire)."""

    def __init__(self, s, markings: np.ndarray, back: int | None):
        n = len(markings)
        src = np.arange(n - 1 if back is None else n, dtype=np.int64)
        dst = np.append(np.arange(1, n, dtype=np.int64), [] if back is None else [back])
        space = _Run(s, markings, src, dst.astype(np.int64))
        super().__init__(space)
        self._truths = Truths(s, ListedMarkings(markings))

    def enabled(self, transitions: Sequence[str], where) -> np.ndarray:
        out = np.zeros(self.n, dtype=bool)
        for t in transitions:
            j = self.transition_index.get(t)
            if j is None:
                raise UnknownName(f"no transition '{t}' in the net", where)
            out |= self._truths.enabled(j)
        return out


@dataclass
class _Run:
    """What :class:`Graph` reads of a state space, for one run."""

    structure: object
    markings: np.ndarray
    src: np.ndarray
    dst: np.ndarray

    @property
    def states(self) -> int:
        return len(self.markings)

    @property
    def trans(self) -> np.ndarray:
        return np.zeros(len(self.src), dtype=np.int64)

    def tokens(self, place: int) -> np.ndarray:
        return self.markings[:, place]


def _on_one_run(f) -> tuple[bool, object, bool] | None:
    """``(universal, ψ, negated)`` for ``A ψ`` or ``E ψ`` under negations, ψ free of path
    quantifiers (a run decides ψ); None for any other formula."""
    shaped = q.path_quantified(f)
    if shaped is None or q.is_state(shaped[1].arg):
        return None
    negated, g = shaped
    return isinstance(g, q.AllPaths), g, negated


def settled_by_runs(net: Net, queries: Sequence[q.Query], seconds: float = WALK_SECONDS,
                    seed: int = 0) -> dict[str, tuple[bool, str]]:
    """The path formulas a run of a random walker settles: ``A ψ`` is false where a run
    (a lasso, or a maximal run to a dead marking) violates ψ, ``E ψ`` true where one
    satisfies it; each run decided on its own graph (:class:`RunGraph`) as the whole
    graph is decided (:func:`_decide`: CTL's and LTL's readings must agree). Within
    ``seconds``; a run proves nothing by what it does not show."""
    shaped = [(x, r) for x in queries if (r := _on_one_run(x.asks)) is not None]
    settled: dict[str, tuple[bool, str]] = {}
    if not shaped:
        return settled
    s = structure(net)
    for markings, back in runs(s, seconds, seed=seed):
        graph = RunGraph(s, markings, back)
        for x, (universal, quantified, negated) in shaped:
            if x.id in settled:
                continue
            try:
                value = _decide(graph, q.Query(x.id, quantified, x.location)).value
            except (UnknownName, KeyError, LookupError):
                continue
            if value is not None and value is not universal:   # A false, or E true
                settled[x.id] = (value is not negated, "RANDOM_WALK")
        if len(settled) == len(shaped):
            break
    return settled
