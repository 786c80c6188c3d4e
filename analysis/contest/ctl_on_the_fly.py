"""CTL formulas decided on the fly from the net: no graph first, only the markings the
formula's answer needs.

The formula and the net make a dependency graph (Liu and Smolka, *Simple linear-time
algorithms for minimal fixed points*, ICALP 1998): a *configuration* is a marking and a
subformula, a *hyperedge* from it a set of configurations that together make it true,
and the formula holds in M0 where (M0, φ) is 1 in the graph's least assignment. The
encoding (Dalsgaard, Enevoldsen, Fogh, Jensen, Jepsen, Kaufmann, Larsen, Nielsen, Olesen,
Schmidt, Srba, *A distributed fixed-point algorithm for extended dependency graphs*,
Fundamenta Informaticae 161, 2018), for a marking M with successors M1 ... Mk:

* an atom: 1 or 0 at once, read from M;
* ``a and b``: one edge {(M, a), (M, b)}; ``a or b``: two, {(M, a)} and {(M, b)};
* ``E X a``: an edge {(Mi, a)} per successor; ``A X a``: one edge {(M1, a) ... (Mk, a)}
  (empty where M is dead: true, as the contest reads CTL);
* ``E(a U b)``: {(M, b)}, and {(M, a), (Mi, E(a U b))} per successor; ``A(a U b)``:
  {(M, b)}, and where M is not dead {(M, a), (M1, A(a U b)) ... (Mk, A(a U b))};
  ``F`` is ``true U``;
* ``not a``: a *negation edge* to (M, a), read once (M, a) is final; ``E G a`` is
  ``not A F not a`` and ``A G a`` is ``not E F not a`` (a dead marking ends its path:
  ``E G a`` holds there where ``a`` does, as :class:`~.answers.Graph` reads it).

The search (the local algorithm with *certain zero*): hyperedges wait on a stack, each
on one target not yet known, explored when first waited on; a configuration is 1 when
one edge has every target 1, and certainly 0 when every edge has a target certainly 0,
and its waiting edges are taken up again then. It stops as soon as (M0, φ) is known. A
negation edge is read when no other edge waits, the one whose target has the fewest
negations inside first: every configuration that target depends on is then final, and
one still unknown is 0. With nothing left to read, an unknown (M0, φ) is 0.

Markings are tuples of token counts, found by firing the net (any net, bounded or not:
the search is limited by the markings it may hold, not by the net's size).
"""
from __future__ import annotations

import heapq
import time
from typing import Callable

import numpy as np

from mcl2pnml.core import queries as q
from mcl2pnml.core.bounds import MAX_STATES
from mcl2pnml.core.memory import default_memory
from mcl2pnml.core.net import Net
from mcl2pnml.core.structure import Structure, structure

from mcl2pnml.analysis.contest.ltl_on_the_fly import FLY_SECONDS, Unnamed, path_formula
from mcl2pnml.analysis.statespace.firing import Firing

#: Bytes a marking takes here (its key, its slot in the index, its successors' list)
#: besides 8 a place; a configuration (its slots in the tables); a hyperedge besides 8 a
#: target (its tuple, its slots, its place on the stack and in a waiting list).
MARKING_BYTES = 200
CONFIGURATION_BYTES = 300
EDGE_BYTES = 150
#: Edges read between two looks at the clock.
_TICK = 4096

# the kinds of a node of the formula (one per distinct subformula)
_STATE, _NOT, _AND, _OR, _EX, _AX, _EU, _AU = range(8)


class _Node:
    """A subformula: its kind, its children's node numbers, its evaluator (a state
    formula) and the negations nested in it (a negation edge's order)."""

    __slots__ = ("kind", "args", "holds", "depth")

    def __init__(self, kind: int, args: tuple[int, ...] = (), holds=None, depth: int = 0):
        self.kind, self.args, self.holds, self.depth = kind, args, holds, depth


def _evaluator(s: Structure, firing: Firing, f) -> Callable[[np.ndarray], bool]:
    """A state formula as a function of a marking (:class:`Unnamed` for a name the net
    lacks)."""
    place, transition = s.place_index, s.transition_index

    def total(e):
        if isinstance(e, q.IntConst):
            return [], e.value
        missing = [p for p in e.places if p not in place]
        if missing:
            raise Unnamed(missing[0])
        return [place[p] for p in e.places], 0

    if isinstance(f, q.BoolConst):
        return lambda m, v=f.value: v
    if isinstance(f, q.IntLe):
        (left, a), (right, b) = total(f.left), total(f.right)
        bound = b - a
        left, right = np.array(left, dtype=np.int64), np.array(right, dtype=np.int64)
        return lambda m: int(m[left].sum()) - int(m[right].sum()) <= bound
    if isinstance(f, q.Fireable):
        missing = [t for t in f.transitions if t not in transition]
        if missing:
            raise Unnamed(missing[0])
        ts = [transition[t] for t in f.transitions]
        return lambda m: any(firing.enabled(m, j) for j in ts)
    if isinstance(f, q.Deadlock):
        return lambda m: not len(firing.enabled_all(m))
    if isinstance(f, q.Neg):
        inner = _evaluator(s, firing, f.arg)
        return lambda m: not inner(m)
    parts = [_evaluator(s, firing, a) for a in f.args]
    if isinstance(f, q.Conj):
        return lambda m: all(p(m) for p in parts)
    return lambda m: any(p(m) for p in parts)


class _Formula:
    """The subformulas of a CTL formula as numbered nodes, ``E G`` and ``A G`` rewritten
    through negations, ``F`` as ``true U``."""

    def __init__(self, s: Structure, firing: Firing):
        self.s, self.firing = s, firing
        self.nodes: list[_Node] = []
        self._number: dict = {}

    def node(self, f) -> int:
        got = self._number.get(f)
        if got is None:
            got = self._number[f] = self._build(f)
        return got

    def _add(self, kind: int, args: tuple[int, ...] = (), holds=None) -> int:
        depth = max((self.nodes[a].depth for a in args), default=0) + (kind == _NOT)
        self.nodes.append(_Node(kind, args, holds, depth))
        return len(self.nodes) - 1

    def _build(self, f) -> int:
        if q.is_state(f):
            return self._add(_STATE, holds=_evaluator(self.s, self.firing, f))
        if isinstance(f, q.Neg):
            return self._add(_NOT, (self.node(f.arg),))
        if isinstance(f, (q.Conj, q.Disj)):
            return self._add(_AND if isinstance(f, q.Conj) else _OR,
                             tuple(self.node(a) for a in f.args))
        if not isinstance(f, (q.AllPaths, q.ExistsPath)):
            raise NotCTL
        exists, inner = isinstance(f, q.ExistsPath), f.arg
        if q.is_closed(inner):
            return self.node(inner)                 # a quantifier over a state formula
        if isinstance(inner, q.Next):
            return self._add(_EX if exists else _AX, (self.node(inner.arg),))
        if isinstance(inner, q.Finally):
            return self.node(type(f)(q.Until(q.BoolConst(True), inner.arg)))
        if isinstance(inner, q.Globally):
            # E G a = not A F not a; A G a = not E F not a
            dual = q.AllPaths if exists else q.ExistsPath
            return self._add(_NOT, (self.node(dual(q.Finally(q.Neg(inner.arg)))),))
        if isinstance(inner, q.Until):
            return self._add(_EU if exists else _AU,
                             (self.node(inner.before), self.node(inner.reach)))
        raise NotCTL


class NotCTL(Exception):
    """A formula CTL does not decide (LTL under a quantifier, a temporal operator outside
    one): the dependency graph does not encode it, nor does the graph's labelling
    (:class:`~mcl2pnml.analysis.contest.answers.Graph`) label it."""


class _Search:
    """One formula's dependency graph, searched from (M0, φ) (the module's algorithm)."""

    def __init__(self, s: Structure, f, limit: int, memory: int, deadline: float):
        self.firing = Firing(s)
        formula = _Formula(s, self.firing)
        self.root_node = formula.node(f)
        self.nodes = formula.nodes
        self.m0 = np.array(s.initial_vector(), dtype=np.int64)
        self.limit, self.deadline = limit, deadline
        self.memory = memory                 # bytes it may still take
        self.marking_bytes = MARKING_BYTES + 8 * len(s.places)
        self.marking_number: dict[bytes, int] = {}
        self.markings: list[bytes] = []     # each marking's token counts, as int64 bytes
        self.next: list[list[int] | None] = []
        self.config: dict[tuple[int, int], int] = {}
        self.at: list[tuple[int, int]] = []          # each configuration's (marking, node)
        self.value: list[bool | None] = []
        self.explored: list[bool] = []
        self.live: list[int] = []            # edges not yet dead, per configuration
        self.waiting: list[list[int]] = []   # edges waiting on it, per configuration
        self.edge_source: list[int] = []
        self.edge_targets: list[tuple[int, ...]] = []
        self.stack: list[int] = []           # edges to read
        self.negations: list[tuple[int, int]] = []   # (depth of its target, configuration)
        self.negated: dict[int, int] = {}    # a negation's configuration -> its target's
        self.negating: dict[int, list[int]] = {}   # a target -> the negations of it

    # -- markings and configurations ----------------------------------------------------

    def marking(self, m: np.ndarray) -> int:
        key = m.tobytes()
        got = self.marking_number.get(key)
        if got is None:
            self.memory -= self.marking_bytes
            if len(self.markings) >= self.limit or self.memory < 0:
                raise _Limit
            got = self.marking_number[key] = len(self.markings)
            self.markings.append(key)
            self.next.append(None)
        return got

    def tokens(self, i: int) -> np.ndarray:
        return np.frombuffer(self.markings[i], dtype=np.int64)

    def successors(self, i: int) -> list[int]:
        got = self.next[i]
        if got is None:
            seen: set[int] = set()
            got = []
            for row in self.firing.successors(self.tokens(i)):
                j = self.marking(row)
                if j not in seen:
                    seen.add(j)
                    got.append(j)
            self.next[i] = got
        return got

    def configuration(self, i: int, node: int) -> int:
        key = (i, node)
        got = self.config.get(key)
        if got is None:
            self.memory -= CONFIGURATION_BYTES
            if self.memory < 0:
                raise _Limit
            got = self.config[key] = len(self.value)
            self.at.append(key)
            self.value.append(None)
            self.explored.append(False)
            self.live.append(0)
            self.waiting.append([])
        return got

    # -- the algorithm ------------------------------------------------------------------

    def run(self) -> bool | None:
        """The formula's value in M0, or None past the limit or the time."""
        try:
            root = self.configuration(self.marking(self.m0), self.root_node)
            self.explore(root)
            return self.settle(root)
        except _Limit:
            return None

    def settle(self, root: int) -> bool:
        ticks = 0
        value, stack = self.value, self.stack
        while value[root] is None:
            if stack:
                self.read(stack.pop())
                ticks += 1
                if ticks % _TICK == 0 and time.monotonic() > self.deadline:
                    raise _Limit
                continue
            if not self.negations:
                return False         # nothing left to read: the least assignment's 0
            # no edge waits to be read: the negation whose target has the fewest negations
            # inside is final (what it depends on is), an unknown target 0
            _, c = heapq.heappop(self.negations)
            if value[c] is None:
                target = self.negated[c]
                if value[target] is None:
                    self.assign(target, False)
                self.assign(c, not value[target])
        return value[root]

    def assign(self, c: int, v: bool) -> None:
        self.value[c] = v
        waiting = self.waiting[c]
        if waiting:
            self.stack.extend(waiting)
            self.waiting[c] = []
        # a 1, or a certain 0, is final: the negations of it need not wait for the rest
        for n in self.negating.pop(c, ()):
            if self.value[n] is None:
                self.assign(n, not v)

    def read(self, e: int) -> None:
        c = self.edge_source[e]
        value = self.value
        if value[c] is not None:
            return
        unknown = -1
        for u in self.edge_targets[e]:
            v = value[u]
            if v is True:
                continue
            if v is False:         # a target certainly 0: the edge is dead
                self.live[c] -= 1
                if self.live[c] == 0:
                    self.assign(c, False)
                return
            if unknown < 0:
                unknown = u
        if unknown < 0:
            self.assign(c, True)
            return
        self.waiting[unknown].append(e)
        if not self.explored[unknown]:
            self.explore(unknown)

    def edge(self, c: int, targets: tuple[int, ...]) -> None:
        self.memory -= EDGE_BYTES + 8 * len(targets)
        if self.memory < 0:
            raise _Limit
        self.edge_source.append(c)
        self.edge_targets.append(targets)
        self.live[c] += 1
        self.stack.append(len(self.edge_source) - 1)

    def explore(self, c: int) -> None:
        """Give configuration c its value (an atom), its negation edge, or its edges; one
        with no edge at all is 0."""
        self.explored[c] = True
        i, n = self.at[c]
        node = self.nodes[n]
        kind, args = node.kind, node.args
        if kind == _STATE:
            self.assign(c, node.holds(self.tokens(i)))
            return
        if kind == _NOT:
            target = self.configuration(i, args[0])
            self.negated[c] = target
            if self.value[target] is not None:
                self.assign(c, not self.value[target])
                return
            heapq.heappush(self.negations, (self.nodes[args[0]].depth, c))
            self.negating.setdefault(target, []).append(c)
            if not self.explored[target]:
                self.explore(target)
            return
        # the edges are read last pushed first: what M itself may settle is pushed last
        if kind == _AND:
            self.edge(c, tuple(self.configuration(i, a) for a in args))
        elif kind == _OR:
            for a in reversed(args):
                self.edge(c, (self.configuration(i, a),))
        elif kind == _EX:
            for j in reversed(self.successors(i)):
                self.edge(c, (self.configuration(j, args[0]),))
        elif kind == _AX:
            self.edge(c, tuple(self.configuration(j, args[0]) for j in self.successors(i)))
        else:                       # E(a U b), A(a U b)
            before, reach = args
            nxt = self.successors(i)
            if kind == _EU:
                a = self.configuration(i, before)
                for j in reversed(nxt):
                    self.edge(c, (a, self.configuration(j, n)))
            elif nxt:
                self.edge(c, (self.configuration(i, before),
                              *(self.configuration(j, n) for j in nxt)))
            self.edge(c, (self.configuration(i, reach),))
        if self.live[c] == 0:
            self.assign(c, False)


class _Limit(Exception):
    """The search reached its markings' limit or its time."""


def ctl_on_the_fly(net: Net, f, max_states: int = MAX_STATES, seconds: float = FLY_SECONDS,
                   max_memory: int | None = None) -> bool | None:
    """Whether CTL formula ``f`` holds in M0, searched on the fly (the module's algorithm),
    or None where the search met ``max_states`` markings, the memory budget (what its
    markings, configurations and edges take, counted as they come), or ``seconds``.
    :class:`NotCTL` for a formula the encoding lacks, :class:`Unnamed`
    for a name the net lacks."""
    s = structure(net)
    budget = max_memory if max_memory is not None else default_memory()
    return _Search(s, f, max_states, budget, time.monotonic() + seconds).run()


def settled_by_ctl_on_the_fly(net: Net, queries, seconds: float = FLY_SECONDS,
                              max_states: int = MAX_STATES,
                              max_memory: int | None = None) -> dict[str, tuple[bool, str]]:
    """The CTL formulas one search on the fly each decides, within ``seconds`` each. A
    formula the LTL search reads (:func:`~.ltl_on_the_fly.path_formula`: ``A G φ``,
    ``E F φ``, ``A F φ`` ...) is left to it: it searched the same runs, under stubborn
    sets, just before. One that is LTL too and has an ``X`` (``A X φ``, φ a state formula:
    the only such shape) is read both ways only where M0 is not dead: the two readings
    differ at a dead marking's next one, and only M0's is asked."""
    settled: dict[str, tuple[bool, str]] = {}
    s = structure(net)
    m0 = s.initial_vector()
    m0_dead = not any(s.enabled(m0, j) for j in range(len(s.transitions)))
    for x in queries:
        f = x.asks
        if (isinstance(f, q.PlaceBound) or not q.is_ctl(f) or path_formula(f) is not None
                or (q.is_ltl(f) and q.contains(f, q.Next) and m0_dead)):
            continue
        try:
            holds = ctl_on_the_fly(net, f, max_states, seconds, max_memory)
        except (Unnamed, NotCTL):
            continue
        if holds is not None:
            settled[x.id] = (holds, "EXPLICIT CTL ON_THE_FLY")
    return settled
