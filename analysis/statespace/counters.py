"""The reachability graph of a bounded net, counters packed into words, in compiled code.

The explorer for nets that are not safe (weights, places with several
tokens) but bounded: a marking is a row of 64-bit words holding one
counter a place, each as wide as the place needs, and the loop is the
textbook queue and hash set of :mod:`mcl2pnml.analysis.statespace.compiled`, run by a
backend of :class:`~mcl2pnml.analysis.statespace.loops.interface.Loops`: in C where
it was built at install, else the plain-Python reference
(:func:`mcl2pnml.analysis.statespace.loops.backends.chosen`).

* **Widths.** A place covered by a semi-positive P-invariant y is bounded
  by y.M0 / y(p) (Murata 1989, section VII; the invariants are the minimal
  ones of Martinez and Silva 1982, :mod:`mcl2pnml.analysis.structure.invariants`), and gets
  just the bits that bound needs: such a counter never overflows. Any other
  place starts with room for twice its initial tokens; when a firing would
  overflow it, the place is widened, every marking found is re-packed and
  the exploration goes on from where it stopped.
* **Unbounded nets** are handed over (:class:`NotBounded`, which
  :func:`mcl2pnml.analysis.statespace.explore.explore` answers with the Karp-Miller explorer)
  as soon as a transition that only adds tokens is enabled, or when a
  counter overflows in a marking that strictly covers one of its ancestors
  (either proves the net unbounded: Karp and Miller 1969), or outgrows
  :data:`MAX_BITS` bits.
* The result is a :class:`CounterStateSpace`: node n is the n-th marking
  found (node 0 the initial one); edges are not stored but fired again when
  asked for, and reachability of a set is computed backwards by unfiring, as
  :class:`~mcl2pnml.analysis.statespace.packedmarkings.PackedStateSpace` does for safe nets.

Memory: 8 bytes a word a marking in the queue (twice that while it grows by
doubling) and 11 to 23 bytes a marking in the table (:func:`footprint`).
A transition is two lists of fields (:class:`~mcl2pnml.analysis.statespace.loops.interface.CounterNet`):
what it needs (word, shift, mask, tokens) and what it changes (word, shift,
mask, signed change, place); each field lies within one word.
"""
from __future__ import annotations

from functools import cached_property
from typing import Sequence

import numpy as np

from mcl2pnml.core.structure import Structure

from mcl2pnml.analysis.statespace.general import (DecodedMarkings, EdgesOnDemand, FoundMarkings,
                                                StateSpace)
from mcl2pnml.analysis.statespace.loops.backends import chosen
from mcl2pnml.analysis.statespace.loops.interface import Code, CounterNet, Fields, Index, Loops
from mcl2pnml.analysis.statespace.packedmarkings import distinct
# invariant bounds are looked for on nets up to INVARIANT_PLACES places (Farkas can need
# exponentially many rows; past INVARIANT_ROWS the widths are grown)
from mcl2pnml.analysis.structure.invariants import (INVARIANT_PLACES, INVARIANT_ROWS,
                                                    AnalysisLimit,
                                                    minimal_semipositive_p_invariants)

#: How many markings one step of the loops expands before it hands back to Python.
SLICE = 1 << 18

#: The widest counter: a place past 2^32 tokens is taken for unbounded.
MAX_BITS = 32

class NotBounded(Exception):
    """The net may be unbounded: the caller explores with Karp-Miller coverability."""


def footprint(s: Structure) -> int:
    """Bytes a marking costs at most while exploring: queue and parents (doubling), table."""
    return 16 * _words_estimate(s) + 64


def _words_estimate(s: Structure) -> int:
    return max(1, -(-len(s.places) * 8 // 64))


def invariant_bounds(s: Structure, m0: Sequence[int]) -> list[int | None]:
    """Per place, the bound a semi-positive P-invariant proves (None: none does)."""
    bounds: list[int | None] = [None] * len(s.places)
    if len(s.places) > INVARIANT_PLACES:
        return bounds
    try:
        invariants = minimal_semipositive_p_invariants(s, INVARIANT_ROWS)
    except AnalysisLimit:
        return bounds
    index = s.place_index
    for y in invariants:
        value = sum(c * m0[index[p]] for p, c in y.items())
        for p, c in y.items():
            i = index[p]
            b = value // c
            bounds[i] = b if bounds[i] is None else min(bounds[i], b)
    return bounds


class Layout:
    """Where each place's counter lies: word, shift and width, no field across two words."""

    def __init__(self, widths: Sequence[int]):
        self.widths = list(widths)
        self.word, self.shift = [], []
        w, used = 0, 0
        for b in self.widths:
            if used + b > 64:
                w, used = w + 1, 0
            self.word.append(w)
            self.shift.append(used)
            used += b
        self.words = w + 1

    def mask(self, p: int) -> int:
        return (1 << self.widths[p]) - 1

    def pack(self, counts: np.ndarray) -> np.ndarray:
        """(markings, places) counts as (markings, words) rows."""
        rows = np.zeros((len(counts), self.words), dtype=np.uint64)
        for p in range(len(self.widths)):
            rows[:, self.word[p]] |= counts[:, p].astype(np.uint64) << np.uint64(self.shift[p])
        return rows

    def unpack(self, rows: np.ndarray) -> np.ndarray:
        counts = np.empty((len(rows), len(self.widths)), dtype=np.int64)
        for p in range(len(self.widths)):
            counts[:, p] = ((rows[:, self.word[p]] >> np.uint64(self.shift[p]))
                            & np.uint64(self.mask(p))).astype(np.int64)
        return counts


def counter_net(s: Structure, layout: Layout) -> CounterNet:
    """The transitions' needs and changes as compressed rows of fields, for the loops."""
    need, change = [], []
    for pre, read, col in zip(s.pre, s.read, s.incidence):
        needs = dict(read)
        for p, w in pre.items():
            needs[p] = max(needs.get(p, 0), w)
        need.append(sorted(needs.items()))
        change.append(sorted(col.items()))

    def rows(per_t, value_type):
        ptr = np.zeros(len(per_t) + 1, dtype=np.int64)
        ptr[1:] = np.cumsum([len(x) for x in per_t])
        flat = [pw for x in per_t for pw in x]
        places = np.array([p for p, _ in flat], dtype=np.int64)
        return Fields(ptr, np.array([layout.word[p] for p in places], dtype=np.int64),
                      np.array([layout.shift[p] for p in places], dtype=np.uint64),
                      np.array([layout.mask(p) for p in places], dtype=np.uint64),
                      np.array([w for _, w in flat], dtype=value_type), places)

    growing = np.array([bool(c) and all(w > 0 for _, w in c) for c in change], dtype=np.bool_)
    return CounterNet(rows(need, np.uint64), rows(change, np.int64), growing)


def initial_widths(s: Structure, m0: Sequence[int]) -> list[int]:
    """Each place's counter width: what its P-invariant bound needs, else room for twice
    its initial tokens (widened where a firing overflows it)."""
    widths = []
    for p, bound in enumerate(invariant_bounds(s, m0)):
        if bound is None:
            bound = 2 * m0[p] + 1
        widths.append(max(1, int(bound).bit_length()))
    return widths


def explore_counters(s: Structure, m0: Sequence[int], max_states: int, limit_error,
                     progress=None, loops: Loops | None = None) -> "CounterStateSpace":
    """Breadth-first from ``m0`` by ``loops`` (default: C where built, else the Python
    reference); raises :class:`NotBounded` when the net may be unbounded."""
    loops = loops or chosen()
    layout = Layout(initial_widths(s, m0))
    queue = layout.pack(np.array([m0], dtype=np.int64))
    search = loops.counter_search(queue, np.full(1, -1, dtype=np.int64), 1, 0)
    while True:
        net = counter_net(s, layout)
        while True:
            search = loops.counter_step(net, search, max_states, SLICE)
            if progress and search.code == Code.GOING:
                progress(search.count, search.count - search.head)
            if search.code != Code.GOING or search.head == search.count:
                break
        queue, count, info = search.queue, search.count, search.info
        if search.code == Code.GOING:
            return CounterStateSpace(s, queue[:count], search.index, layout, loops)
        if search.code == Code.LIMIT:
            limit_error.explored, limit_error.deadlocks = count, search.dead
            limit_error.found = FoundMarkings(
                queue[:count], layout.word, layout.shift,
                [layout.mask(p) for p in range(len(layout.widths))], search.head)
            raise limit_error
        if (search.code == Code.GROWING or layout.widths[info] >= MAX_BITS
                or _covers_an_ancestor(s, layout, queue, search.parent, search.head)):
            raise NotBounded
        # widen the place that overflowed, re-pack what was found, go on
        counts = layout.unpack(queue[:count])
        widths = list(layout.widths)
        widths[info] = min(MAX_BITS, 2 * widths[info])
        layout = Layout(widths)
        search = loops.counter_search(layout.pack(counts), search.parent, count, search.head,
                                      search.dead)
        del counts


def _covers_an_ancestor(s: Structure, layout: Layout, queue: np.ndarray, parent: np.ndarray,
                        head: int) -> bool:
    """Whether a successor of ``head`` strictly covers ``head`` or one of its ancestors.

    Such a pair proves the net unbounded (Karp and Miller 1969); asked only
    when a counter overflows, so the walk up the first-discovery path is rare.
    """
    chain = [head]
    while parent[chain[-1]] >= 0:
        chain.append(int(parent[chain[-1]]))
    ancestors = layout.unpack(queue[np.array(chain)])
    m = ancestors[0]
    for pre, read, col in zip(s.pre, s.read, s.incidence):
        if all(m[p] >= w for p, w in pre.items()) and all(m[p] >= w for p, w in read.items()):
            after = m.copy()
            for p, w in col.items():
                after[p] += w
            covered = np.all(after >= ancestors, axis=1) & np.any(after > ancestors, axis=1)
            if covered.any():
                return True
    return False


class CounterMarkings(DecodedMarkings):
    """The markings by node, decoded one at a time into tuples of counts."""

    def decode(self, node: int) -> tuple[int, ...]:
        row = self.space.rows[node:node + 1]
        return tuple(int(x) for x in self.space.layout.unpack(row)[0])


class CounterStateSpace(EdgesOnDemand, StateSpace):
    """A reachability graph kept as its packed markings in the order found (see the module)."""

    def __init__(self, structure: Structure, rows: np.ndarray, index: Index, layout: Layout,
                 loops: Loops):
        self.structure = structure
        self.rows, self.index, self.layout = rows, index, layout
        # the loops that built the index ask it again: its slots are theirs
        self.loops = loops
        self.coverability = False
        self._net = counter_net(structure, layout)

    @property
    def states(self) -> int:
        return len(self.rows)

    @cached_property
    def markings(self) -> CounterMarkings:  # type: ignore[override]
        return CounterMarkings(self)

    def tokens(self, place: int) -> np.ndarray:  # type: ignore[override]
        lay = self.layout
        field = (self.rows[:, lay.word[place]] >> np.uint64(lay.shift[place])) \
            & np.uint64(lay.mask(place))
        return field.astype(np.float64)

    @cached_property
    def bound(self) -> float:
        # a place at a time: unpacking every marking into a row of counts
        # would cost 8 bytes a place a marking
        lay, top = self.layout, 0
        for p in range(len(lay.widths)):
            field = (self.rows[:, lay.word[p]] >> np.uint64(lay.shift[p])) & np.uint64(lay.mask(p))
            top = max(top, int(field.max(initial=0)))
        return top

    @cached_property
    def out_degree(self) -> np.ndarray:  # type: ignore[override]
        return self.loops.counter_out_degree(self.rows, self._net)

    @cached_property
    def terminal(self) -> list[int]:  # type: ignore[override]
        return np.flatnonzero(self.out_degree == 0).tolist()

    @cached_property
    def _edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.loops.counter_edges(self.rows, self.index, self._net,
                                        int(self.out_degree.sum()))

    def can_reach(self, targets: Sequence[int]) -> list[bool]:
        """For every node, whether one of ``targets`` is reachable from it (by unfiring)."""
        frontier = distinct(np.sort(np.asarray(list(targets), dtype=np.int64)))
        seen = np.zeros(self.states, dtype=np.bool_)
        seen[frontier] = True
        return self.loops.counter_backward(self.rows, self._net, seen, frontier).tolist()
