"""The reachability graph of a safe net, explored one marking at a time by the loops.

One of the two safe-net explorers behind :func:`mcl2pnml.analysis.statespace.explore.explore`,
for the same nets as :mod:`mcl2pnml.analysis.statespace.packed` (1-safe, unit weights):
markings are rows of bits packed into 64-bit words
(:mod:`mcl2pnml.analysis.statespace.packedmarkings`), and firing a transition is three bit
operations (``need`` covered, ``keep`` the rest, ``give`` the outputs). Here
the loop is the textbook one, a queue of markings and a hash set, run by a
backend of :class:`~mcl2pnml.analysis.statespace.loops.interface.Loops`: in C
(built at install; a few nanoseconds a (marking, transition) pair instead of
the fixed cost of a numpy call per breadth-first level: small and deep state
spaces, as a compiled mission's, gain most), or the plain-Python reference.

* The queue is the array of markings found, in the order found; the set is
  an open-addressing table with linear probing, at most 70% full. With one
  word the C table holds the markings themselves (0 marks an empty slot, and
  the empty marking is remembered apart); with several it holds fingerprints
  and positions in the queue, and a probe compares the words, so no two
  markings are ever merged.
* The loop runs in slices of :data:`SLICE` expansions, handing back to
  Python in between: the caller's progress report is called, and Ctrl-C is
  honoured, at least every few tenths of a second.
* The result is a :class:`~mcl2pnml.analysis.statespace.packedmarkings.PackedStateSpace`, the same
  value the numpy explorer returns, so terminal markings, reachability by
  unfiring and the edge list come from the same code whichever explorer ran.

Markings take 8 bytes a word in the queue (allocated at its longest but
mapped in by the kernel only as it fills) plus 11 to 23 bytes a word in the
table; with one word the queue is then sorted in place to become the state
space's keys.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from mcl2pnml.core.structure import Structure

from mcl2pnml.analysis.statespace.general import FoundMarkings
from mcl2pnml.analysis.statespace.loops.backends import c_loops
from mcl2pnml.analysis.statespace.loops.interface import Code, Loops, SafeNet, SafeSearch
from mcl2pnml.analysis.statespace.packedmarkings import (Firing, KeyCollision, NotSafe,
                                                         PackedStateSpace, marking_row, masks,
                                                         place_weights, safe_net, word_count)
# bound under this module's own name, so that the keys of this explorer alone
# can be replaced (the key-collision tests do)
from mcl2pnml.analysis.statespace.packedmarkings import keys_of as _keys

#: How many markings one step of the loops expands before it hands back to Python.
SLICE = 1 << 19


def footprint(s: Structure) -> int:
    """Bytes a marking costs at most: the queue (doubling in the Python loops), the table,
    the final sort."""
    return 24 * word_count(s) + 48


def native_available() -> bool:
    """Whether the loops in C were built when mcl2pnml was installed (they need a C compiler)."""
    return c_loops() is not None


def explore_native(s: Structure, m0: Sequence[int], max_states: int, limit_error,
                   progress=None, loops: Loops | None = None) -> PackedStateSpace:
    """Breadth-first from ``m0`` by ``loops`` (default: the loops in C); raises
    :class:`NotSafe` at a second token in a place."""
    return _explore(loops or c_loops(), s, m0, max_states, limit_error, progress)


def _explore(loops: Loops, s: Structure, m0: Sequence[int], max_states: int, limit_error,
             progress) -> PackedStateSpace:
    words = word_count(s)
    need, take, give = masks(s, words)
    start = marking_row(m0, words)
    net = safe_net(need, take, give, place_weights(start))
    rows = _owned(_drive(loops, net, loops.safe_search(net, start[0], max_states), max_states,
                         limit_error, progress))
    if words == 1:
        rows.sort()   # in place: the markings are their own keys
        keys = rows if rows.base is None or 4 * rows.base.size < 5 * rows.size else rows.copy()
        packed = keys.reshape(-1, 1)
    else:
        keys = _keys(rows)
        order = np.argsort(keys)
        keys = keys[order]
        if len(keys) > 1 and np.any(keys[1:] == keys[:-1]):
            raise KeyCollision   # distinct markings, one key: the exact explorer takes over
        packed = loops.permute_rows(rows, order)   # in place where it can: no second copy
        del rows, order
    return PackedStateSpace(s, packed, keys, _keys(start)[0], Firing.by(need, need, take, give),
                            loops)


def _owned(rows: np.ndarray) -> np.ndarray:
    """The found markings, the queue's spare rows given back where the queue can shrink in
    place (it is allocated at its longest: most of it may be spare)."""
    queue = rows.base
    if queue is None or not queue.flags.owndata or queue.base is not None:
        return rows
    count = len(rows)
    del rows   # no view may outlive the resize
    queue.resize((count, *queue.shape[1:]), refcheck=False)
    return queue


def _drive(loops: Loops, net: SafeNet, search: SafeSearch, max_states: int, limit_error,
           progress) -> np.ndarray:
    """Step the search a slice at a time until the queue is exhausted; the markings found."""
    while True:
        search = loops.safe_step(net, search, max_states, SLICE)
        if search.code == Code.NOT_SAFE:
            raise NotSafe
        if search.code == Code.LIMIT:
            limit_error.explored = search.count
            limit_error.deadlocks = _dead(search.queue[:search.head], net.need)
            places = range(64 * net.need.reshape(len(net.need), -1).shape[1])   # a bit each
            limit_error.found = FoundMarkings(search.queue[:search.count],
                                              [p // 64 for p in places],
                                              [p % 64 for p in places], [1] * len(places),
                                              search.head)
            raise limit_error
        if progress:
            progress(search.count, search.count - search.head)
        if search.head == search.count:
            return search.found()


def _dead(rows: np.ndarray, need: np.ndarray) -> int:
    """How many of ``rows`` (markings, or one word each) enable no transition.

    A transition at a time, on the words its inputs are in, over the rows that no
    transition tried so far enables: most markings enable one of the first few, so the
    rows left shrink at once (testing every transition on every word of every row was a
    third of a second for a limit of 20,000 markings)."""
    if not len(rows):   # stopped before any marking was explored (a limit of one or two)
        return 0
    rows = rows.reshape(len(rows), -1)
    need = need.reshape(len(need), -1)
    inputs = [[(w, t[w]) for w in np.flatnonzero(t)] for t in np.unique(need, axis=0)]
    dead = 0
    for start in range(0, len(rows), 1 << 16):   # a bounded copy of the queue at a time
        left = rows[start:start + (1 << 16)]
        for words in inputs:
            enabled = np.ones(len(left), dtype=bool)
            for w, mask in words:
                enabled &= (left[:, w] & mask) == mask
            left = left[~enabled]
            if not len(left):
                break
        dead += len(left)
    return dead
