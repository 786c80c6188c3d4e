"""The reachability graph of a bounded net, counters packed into words, in compiled code.

The explorer for nets that are not safe (weights, places with several
tokens) but bounded: a marking is a row of 64-bit words holding one
counter a place, each as wide as the place needs, and the loop is the
textbook queue and hash set of :mod:`mcl2pnml.analysis.statespace.compiled`, in C where
it was built at install (:mod:`mcl2pnml.analysis.statespace.loops.native_counters`), else
compiled by numba (:mod:`mcl2pnml.analysis.statespace.loops.numba_counters`).

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
"""
from __future__ import annotations

from functools import cached_property
from typing import Sequence

import numpy as np

from mcl2pnml.core.structure import Structure

from mcl2pnml.analysis.statespace.general import DecodedMarkings, EdgesOnDemand, StateSpace
from mcl2pnml.analysis.statespace.packedmarkings import distinct

#: How many markings one call of the compiled loop expands before it hands back to Python.
SLICE = 1 << 18

#: The widest counter: a place past 2^32 tokens is taken for unbounded.
MAX_BITS = 32

#: Invariant bounds are looked for on nets up to this many places (Farkas
#: can need exponentially many rows; past its limit the widths are grown).
INVARIANT_PLACES = 2_000
INVARIANT_ROWS = 20_000


class NotBounded(Exception):
    """The net may be unbounded: the caller explores with Karp-Miller coverability."""


def available() -> bool:
    from mcl2pnml.analysis.statespace.compiled import available as numba_installed
    return native_loops() is not None or numba_installed()


def native_loops():
    """The loops in C where they were built (:mod:`mcl2pnml.analysis.statespace.loops.native_counters`), else None."""
    try:
        from mcl2pnml.analysis.statespace.loops import native_counters as _native_counter_loops
    except ImportError:
        return None
    return _native_counter_loops


def kernels():
    """The loops: in C where they were built, else numba's (imported only now: 0.5 s)."""
    native = native_loops()
    if native is not None:
        return native
    from mcl2pnml.analysis.statespace.loops import numba_counters as _counter_loops
    return _counter_loops


def footprint(s: Structure) -> int:
    """Bytes a marking costs at most while exploring: queue and parents (doubling), table."""
    return 16 * _words_estimate(s) + 64


def _words_estimate(s: Structure) -> int:
    return max(1, -(-len(s.places) * 8 // 64))


def invariant_bounds(s: Structure, m0: Sequence[int]) -> list[int | None]:
    """Per place, the bound a semi-positive P-invariant proves (None: none does)."""
    from mcl2pnml.analysis.structure.invariants import AnalysisLimit, minimal_semipositive_p_invariants  # sympy
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


def _tables(s: Structure, layout: Layout) -> tuple:
    """The transitions' needs and changes as compressed rows of fields (see the kernels)."""
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
        return (ptr, np.array([layout.word[p] for p in places], dtype=np.int64),
                np.array([layout.shift[p] for p in places], dtype=np.uint64),
                np.array([layout.mask(p) for p in places], dtype=np.uint64),
                np.array([w for _, w in flat], dtype=value_type), places)

    n = rows(need, np.uint64)[:5]
    d = rows(change, np.int64)
    growing = np.array([bool(c) and all(w > 0 for _, w in c) for c in change], dtype=np.bool_)
    return n, d, growing


def _initial_widths(s: Structure, m0: Sequence[int]) -> list[int]:
    widths = []
    for p, bound in enumerate(invariant_bounds(s, m0)):
        if bound is None:
            bound = 2 * m0[p] + 1
        widths.append(max(1, int(bound).bit_length()))
    return widths


def explore_counters(s: Structure, m0: Sequence[int], max_states: int, limit_error,
                     progress=None) -> "CounterStateSpace":
    """Breadth-first from ``m0``; raises :class:`NotBounded` when the net may be unbounded."""
    k = kernels()
    layout = Layout(_initial_widths(s, m0))
    queue = layout.pack(np.array([m0], dtype=np.int64))
    parent = np.full(queue.shape[0], -1, dtype=np.int64)
    bits = 12
    count, head, dead = 1, 0, 0
    table = k.rehash(queue, 1, bits)
    while True:
        n, d, growing = _tables(s, layout)
        while True:
            queue, parent, count, head, table, bits, dead, code, info = k.step(
                *n, *d[:5], d[5], growing, queue, parent, count, head, table, bits, dead,
                max_states, SLICE)
            if progress and code == k.GOING:
                progress(count, count - head)
            if code != k.GOING or head == count:
                break
        if code == k.GOING:
            return CounterStateSpace(s, queue[:count], table, bits, layout, k)
        if code == k.LIMIT:
            limit_error.explored, limit_error.deadlocks = count, dead
            raise limit_error
        if (code == k.GROWING or layout.widths[info] >= MAX_BITS
                or _covers_an_ancestor(s, layout, queue, parent, head)):
            raise NotBounded
        # widen the place that overflowed, re-pack what was found, go on
        counts = layout.unpack(queue[:count])
        widths = list(layout.widths)
        widths[info] = min(MAX_BITS, 2 * widths[info])
        layout = Layout(widths)
        queue = layout.pack(counts)
        del counts
        table = k.rehash(queue, count, bits)


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

    def __init__(self, structure: Structure, rows: np.ndarray, table: np.ndarray, bits: int,
                 layout: Layout, loops=None):
        self.structure = structure
        self.rows, self.table, self.bits, self.layout = rows, table, bits, layout
        # the loops that built the table ask it again: its slots are theirs
        self.loops = loops or kernels()
        self.coverability = False
        self._need, self._change, _ = _tables(structure, layout)

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
        return self.loops.out_degree(self.rows, self.states, *self._need)

    @cached_property
    def terminal(self) -> list[int]:  # type: ignore[override]
        return np.flatnonzero(self.out_degree == 0).tolist()

    @cached_property
    def _edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.loops.edges(self.rows, self.states, self.table, self.bits, *self._need,
                       *self._change[:5], int(self.out_degree.sum()))

    def can_reach(self, targets: Sequence[int]) -> list[bool]:
        """For every node, whether one of ``targets`` is reachable from it (by unfiring)."""
        k = self.loops
        frontier = distinct(np.sort(np.asarray(list(targets), dtype=np.int64)))
        seen = np.zeros(self.states, dtype=np.bool_)
        seen[frontier] = True
        table, bits = k.sparse_index(self.rows, self.states)
        return k.backward(self.rows, self.states, table, bits, *self._need,
                          *self._change[:5], seen, frontier).tolist()
