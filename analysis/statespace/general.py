"""The general explorer: the reachability graph, or the Karp-Miller coverability graph.

From a net's initial marking, :func:`explore_general` builds

* the **reachability graph** when the net is bounded (every reachable
  marking once, an edge per firing), or
* a **coverability graph** (Karp and Miller 1969; Murata 1989, section V-A)
  when it is not: a marking that strictly covers one of its ancestors gets
  the token count ``omega`` (written ``w``) in the places that grew, and the
  set of nodes covers every reachable marking.

Markings are tuples of counts and edges flat integer arrays (source,
transition, target); the acceleration follows the first-discovery path. It
takes every net, where the safe-net explorers (:mod:`mcl2pnml.analysis.statespace.packed`,
:mod:`mcl2pnml.analysis.statespace.compiled`) take only 1-safe nets with unit weights.

Transitions are explored untimed: a timed transition (the task's time-out
``t03``) may fire in any order with the others, which is what equations.md
asks for the coverability analysis ("any order of firing").

Owns :class:`StateSpace`, the value every explorer returns (the safe-net
ones a subclass of it): terminal markings, reachability of a set, shortest
firing sequences for counterexamples, and :meth:`StateSpace.graph`, the
graph as networkx on demand.
"""
from __future__ import annotations

import math
from array import array
from collections import deque
from dataclasses import dataclass, field
from functools import cached_property
from itertools import compress
from operator import itemgetter
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np

from mcl2pnml.core.structure import Structure
from mcl2pnml.analysis.structure.invariants import (INVARIANT_PLACES, INVARIANT_ROWS, AnalysisLimit,
                                                    minimal_semipositive_p_invariants)

if TYPE_CHECKING:
    import networkx as nx

OMEGA = math.inf
"""The token count of a place that the coverability graph found unbounded."""

Progress = Callable[[int, int], None]
"""Called now and then during a long exploration with (states, frontier)."""


PROGRESS_EVERY = 100_000
"""Markings between two progress reports (the safe-net explorers report once a
breadth-first level or a compiled slice)."""


class DecodedMarkings(Sequence):
    """The markings of a state space kept packed, decoded one node at a time.

    A packed state space (safe nets' bits, bounded nets' counters) keeps its
    markings in arrays; this sequence gives each as the tuple of counts every
    :class:`StateSpace` shows, without unpacking them all at once.
    """

    def __init__(self, space: "StateSpace"):
        self.space = space

    def __len__(self) -> int:
        return self.space.states

    def __getitem__(self, node):
        if isinstance(node, slice):
            return [self[i] for i in range(*node.indices(len(self)))]
        return self.decode(node + len(self) if node < 0 else node)

    def decode(self, node: int) -> tuple[int, ...]:
        raise NotImplementedError


class EdgesOnDemand:
    """A packed state space's edge list, built when first asked for (its ``_edges``).

    The packed explorers keep markings, not edges: most analyses never need
    them, and they would cost more than the markings.
    """

    @property
    def src(self):
        return self._edges[0]

    @property
    def trans(self):
        return self._edges[1]

    @property
    def dst(self):
        return self._edges[2]


@dataclass(eq=False)
class StateSpace:
    """The explored graph: node 0 is the initial marking."""

    structure: Structure
    markings: list[tuple]                 # node -> token counts (OMEGA where unbounded)
    src: array = field(repr=False)        # edge k goes src[k] --trans[k]--> dst[k]
    trans: array = field(repr=False)
    dst: array = field(repr=False)
    coverability: bool = False            # True if acceleration was needed (unbounded)

    # -- basic facts -------------------------------------------------------------

    @property
    def states(self) -> int:
        return len(self.markings)

    @property
    def bounded(self) -> bool:
        return not self.coverability

    @cached_property
    def bound(self) -> float:
        """The largest token count of any place in any node (OMEGA if unbounded)."""
        return max((max(m) for m in self.markings if m), default=0)

    @property
    def safe(self) -> bool:
        return self.bounded and self.bound <= 1

    @cached_property
    def out_degree(self) -> array:
        deg = array("i", bytes(4 * self.states))
        for s in self.src:
            deg[s] += 1
        return deg

    @cached_property
    def terminal(self) -> list[int]:
        """Nodes where no transition is enabled (dead markings)."""
        return [n for n, d in enumerate(self.out_degree) if d == 0]

    def tokens(self, place: int) -> np.ndarray:
        """The tokens of place ``place`` (its index) in every node, in node order: a
        property reads a few places of every marking, not every place."""
        return np.array([m[place] for m in self.markings], dtype=np.float64)

    def marking(self, node: int) -> dict[str, float]:
        places = self.structure.places
        return {places[i]: n for i, n in enumerate(self.markings[node]) if n}

    def format(self, node: int) -> list[str]:
        """Sorted place names, ``P*2`` for counts above one, ``P*w`` for omega."""
        out = []
        for p, n in sorted(self.marking(node).items()):
            out.append(p if n == 1 else f"{p}*{'w' if n == OMEGA else int(n)}")
        return out

    # -- graph questions -----------------------------------------------------------

    def _reverse(self) -> list[list[int]]:
        rev: list[list[int]] = [[] for _ in range(self.states)]
        for s, d in zip(self.src, self.dst):
            rev[d].append(s)
        return rev

    def can_reach(self, targets: Sequence[int]) -> list[bool]:
        """For every node, whether some node of ``targets`` is reachable from it."""
        rev = self._reverse()
        seen = [False] * self.states
        queue = deque(targets)
        for t in targets:
            seen[t] = True
        while queue:
            n = queue.popleft()
            for m in rev[n]:
                if not seen[m]:
                    seen[m] = True
                    queue.append(m)
        return seen

    def always_can_reach(self, targets: Sequence[int]) -> bool:
        return all(self.can_reach(targets))

    @property
    def home_initial(self) -> bool:
        """Whether the initial marking can be reached again from every marking."""
        return self.always_can_reach([0])

    def path_to(self, node: int) -> list[str]:
        """Transition names of a shortest firing sequence from M0 to ``node``."""
        parent: dict[int, tuple[int, int]] = {0: (-1, -1)}
        adj: list[list[tuple[int, int]]] = [[] for _ in range(self.states)]
        for s, t, d in zip(self.src, self.trans, self.dst):
            adj[s].append((t, d))
        queue = deque([0])
        while queue and node not in parent:
            n = queue.popleft()
            for t, d in adj[n]:
                if d not in parent:
                    parent[d] = (n, t)
                    queue.append(d)
        path = []
        while node in parent and parent[node][0] >= 0:
            node, t = parent[node]
            path.append(self.structure.transitions[t])
        return path[::-1]

    def graph(self) -> nx.MultiDiGraph:
        """The graph as networkx: nodes carry ``marking``, edges ``transition``."""
        import networkx as nx   # a quarter of a second to import: only for whoever asks
        g = nx.MultiDiGraph()
        for n in range(self.states):
            g.add_node(n, marking=self.marking(n))
        names = self.structure.transitions
        for s, t, d in zip(self.src, self.trans, self.dst):
            g.add_edge(s, d, transition=names[t])
        return g


class FoundMarkings:
    """The markings an exploration found before a limit stopped it: each one reachable,
    not all the reachable ones (a breadth-first prefix). A witness among them is a
    witness in the net; an absence proves nothing.

    Rows of 64-bit words, as the packed explorers keep them: place ``p``'s count is the
    field of row word ``word[p]`` at bit ``shift[p]`` under ``mask[p]`` (a bit a place
    for the safe explorers, a counter for the bounded ones). The search was breadth first:
    the first ``expanded`` rows had every successor found (each one among the rows), the
    rest are the open frontier (:mod:`mcl2pnml.analysis.statespace.partial`)."""

    def __init__(self, rows: np.ndarray, word: Sequence[int], shift: Sequence[int],
                 mask: Sequence[int], expanded: int = 0):
        self.rows = rows.reshape(len(rows), -1)
        self.word, self.shift, self.mask = list(word), list(shift), list(mask)
        self.expanded = expanded

    @property
    def states(self) -> int:
        return len(self.rows)

    def tokens(self, place: int) -> np.ndarray:
        """Place ``place``'s count in each found marking."""
        field = (self.rows[:, self.word[place]] >> np.uint64(self.shift[place])) \
            & np.uint64(self.mask[place])
        return field.astype(np.int64)


def footprint(s: Structure) -> int:
    """Bytes a marking costs at most: its tuple of counts, its entry in the index and
    the parent list, its edges (a few a marking), the reverse lists built to answer
    reachability, and the filter's two numbers. A tuple past the C library's
    threshold for mapping memory of its own (128 KB, 16,384 places) is counted
    twice: the list and the tuple each firing makes and drops are then taken
    from the heap between the markings kept, and stay resident (a ring of
    100,000 places held 1.6 MB a marking)."""
    tuple_bytes = 8 * len(s.places)
    if tuple_bytes >= 128 << 10:
        tuple_bytes *= 2
    return tuple_bytes + 220 + 24 * min(len(s.transitions), 8)


def explore_general(s: Structure, m0: Sequence[int], max_states: int, limit_error,
                    progress: Progress | None = None) -> StateSpace:
    """Breadth-first reachability, turning into Karp-Miller coverability only where needed.

    Markings are tuples of counts (OMEGA for unbounded). The acceleration of
    Karp and Miller (1969) compares a new marking with every ancestor on its
    first-discovery path; here that walk is taken only when it can find
    something: a marking that strictly covers an ancestor has a larger
    :func:`_weight` (places no semi-positive P-invariant covers: Murata 1989,
    section VII), so each node keeps the smallest weight on its path, and
    a new marking no heavier than that is stored as it is. On a net whose
    places are all covered no walk ever happens (plain reachability); the
    graph is the same as with the walk every time.

    Raises ``limit_error`` past ``max_states`` markings (with ``explored``
    and ``deadlocks`` set on it); calls ``progress`` once every
    :data:`PROGRESS_EVERY` markings.
    """
    every = PROGRESS_EVERY
    need, delta, filed, unfiled = _tables(s)
    places = range(len(s.places))
    free = _uncovered(s)
    weigh = _weigher(free)
    markings: list[tuple] = [tuple(m0)]
    parent: list[int] = [-1]
    lightest: list[int] = [weigh(markings[0])]   # smallest weight on the path
    index = {markings[0]: 0}
    src, trans, dst = array("i"), array("i"), array("i")
    accelerated = False
    head = dead = 0
    while head < len(markings):
        m = markings[head]
        fired = False
        candidates = unfiled + [t for p in compress(places, m) for t in filed[p]]
        candidates.sort()   # in the transitions' order, as testing them all took them
        for t in candidates:
            if all(m[p] >= w for p, w in need[t]):
                fired = True
                m2 = list(m)
                for p, d in delta[t]:
                    m2[p] += d  # OMEGA +- d stays OMEGA
                m2 = tuple(m2)
                if m2 not in index:
                    w2 = weigh(m2)   # weighed once, for the filter and the path's lightest
                    if free is None or w2 > lightest[head]:
                        m2, grew = _accelerate(m2, head, markings, parent)
                        if grew:
                            accelerated, w2 = True, weigh(m2)
                k = index.get(m2)
                if k is None:
                    k = len(markings)
                    if k >= max_states:
                        limit_error.explored, limit_error.deadlocks = k, dead
                        raise limit_error
                    index[m2] = k
                    markings.append(m2)
                    parent.append(head)
                    lightest.append(min(lightest[head], w2))
                    if progress and k % every == 0:
                        progress(k, k - head)
                src.append(head)
                trans.append(t)
                dst.append(k)
        dead += not fired
        head += 1
    return StateSpace(s, markings, src, trans, dst, coverability=accelerated)




def _tables(s: Structure):
    """Each transition's needs and changes, as sorted (place, tokens) pairs, and the
    transitions filed under one place each (``filed``) or with none (``unfiled``).

    A transition is filed under one place it needs a token in, or with those that
    need none: only the transitions filed under a marked place can be enabled, so a
    marking's few marked places name the transitions to test, instead of testing
    every transition on every marking (a ring of 10,000: 10,000 tests a marking).
    """
    need: list[list[tuple[int, int]]] = []
    delta: list[list[tuple[int, int]]] = []
    for j, (pre, read) in enumerate(zip(s.pre, s.read)):
        needs = dict(read)
        for p, w in pre.items():
            needs[p] = max(needs.get(p, 0), w)
        need.append(sorted(needs.items()))
        delta.append(sorted(s.incidence[j].items()))
    filed: list[list[int]] = [[] for _ in s.places]
    unfiled: list[int] = []
    for t, needs in enumerate(need):
        taken = [p for p, w in needs if w > 0]
        (filed[taken[0]] if taken else unfiled).append(t)
    return need, delta, filed, unfiled


def _uncovered(s: Structure) -> "list[int] | None":
    """The places no semi-positive P-invariant covers (None: every place is covered).

    A covered place is bounded, and a weighted sum of covered places is
    constant on every firing path (the invariant), so a marking that
    strictly covers an ancestor exceeds it on uncovered places only.
    """
    if len(s.places) > INVARIANT_PLACES:
        return list(range(len(s.places)))
    try:
        invariants = minimal_semipositive_p_invariants(s, INVARIANT_ROWS)
    except AnalysisLimit:
        return list(range(len(s.places)))
    covered = {s.place_index[p] for y in invariants for p in y}
    free = [p for p in range(len(s.places)) if p not in covered]
    return free or None


def _weigher(free: "list[int] | None") -> Callable[[tuple], int]:
    """What grows when a marking strictly covers an ancestor: its OMEGA places first,
    then its tokens in uncovered places (a lexicographic pair as one exact integer);
    0 for every marking when every place is covered.

    The uncovered places are picked and summed in C (itemgetter, sum), and the
    OMEGA places counted only when the sum says there are some: a loop in Python
    over them took a sixth of exploring a ring of 10,000 places, where none is
    covered for want of the invariants."""
    if free is None:
        return lambda m: 0
    pick = itemgetter(*free) if len(free) > 1 else (lambda m, p=free[0]: (m[p],))

    def weight(m: tuple) -> int:
        held = pick(m)
        tokens = sum(held)   # counts are ints: the sum is OMEGA only if one of them is
        if tokens != OMEGA:
            return int(tokens)
        omegas = held.count(OMEGA)
        return (omegas << 64) + int(sum(x for x in held if x != OMEGA))
    return weight


def _accelerate(m: tuple, node: int, markings: list[tuple], parent: list[int]) -> tuple[tuple, bool]:
    """Karp-Miller: places that grew since an ancestor it covers become OMEGA."""
    total = sum(m)
    grew = False
    while node >= 0:
        a = markings[node]
        # a cheap filter first: covering needs at least as many tokens in all
        if sum(a) <= total and a != m and all(x >= y for x, y in zip(m, a)):
            m = tuple(OMEGA if x > y else x for x, y in zip(m, a))
            total = sum(m)
            grew = True
        node = parent[node]
    return m, grew
