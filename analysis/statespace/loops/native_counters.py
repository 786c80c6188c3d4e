"""The loops of :mod:`mcl2pnml.analysis.statespace.counters` in C (``analysis/statespace/loops/_native.c``), with the
signatures of :mod:`mcl2pnml.analysis.statespace.loops.numba_counters`, so that either runs the same explorer.

Built with the safe-net loops (:mod:`mcl2pnml.analysis.statespace.loops.native_safe`, whose table of
fingerprints and positions it shares); like them, the C functions never
allocate the arrays: a step that finds the queue or the table too small for
the next marking's successors stops before that marking, and the functions
here grow the arrays and go on.
"""
from __future__ import annotations

import numpy as np

from mcl2pnml.analysis.statespace.loops import _native as c
from mcl2pnml.analysis.statespace.loops.native_safe import _grown_queue

GOING, LIMIT, OVERFLOW, GROWING = c.GOING, c.LIMIT, c.OVERFLOW, c.GROWING


def rehash(queue: np.ndarray, count: int, bits: int) -> np.ndarray:
    """A table of the first ``count`` rows of ``queue`` (fingerprints and positions, 0 free)."""
    table = np.zeros(1 << bits, dtype=np.uint64)
    c.rehash(np.ascontiguousarray(queue), count, table, bits, False)
    return table


def sparse_index(rows: np.ndarray, count: int) -> tuple[np.ndarray, int]:
    """The backward search's table of ``rows``: :func:`rehash`, at most 70% full."""
    bits = 12
    while 10 * count > 7 << bits:
        bits += 1
    return rehash(rows, count, bits), bits


def step(n_ptr, n_word, n_shift, n_mask, n_val, d_ptr, d_word, d_shift, d_mask, d_val,
         d_place, growing, queue, parent, count, head, table, bits, dead, max_states, budget):
    """:func:`mcl2pnml.analysis.statespace.loops.numba_counters.step`, in C."""
    fields = [np.ascontiguousarray(a) for a in (n_ptr, n_word, n_shift, n_mask, n_val, d_ptr,
                                                 d_word, d_shift, d_mask, d_val, d_place)]
    growing = np.ascontiguousarray(growing, dtype=np.bool_)
    room = len(n_ptr) - 1
    while True:
        count, head, dead, code, info = c.counter_step(*fields, growing, queue, parent, count,
                                                       head, table, bits, dead, max_states,
                                                       budget)
        if code == c.QUEUE_FULL:
            queue = _grown_queue(queue, count, room)
            longer = np.empty(len(queue), dtype=np.int64)
            longer[:count] = parent[:count]
            parent = longer
        elif code == c.TABLE_FULL:
            while 10 * (count + room) > 7 << bits:
                bits += 1
            table = rehash(queue, count, bits)
        else:
            return queue, parent, count, head, table, bits, dead, code, info


def out_degree(queue, count, n_ptr, n_word, n_shift, n_mask, n_val) -> np.ndarray:
    """:func:`mcl2pnml.analysis.statespace.loops.numba_counters.out_degree`, in C."""
    degree = np.zeros(count, dtype=np.int32)
    c.counter_out_degree(np.ascontiguousarray(queue[:count]), n_ptr, n_word, n_shift, n_mask,
                         n_val, degree)
    return degree


_NONE = np.zeros(0, dtype=np.int32)


def edges(queue, count, table, bits, n_ptr, n_word, n_shift, n_mask, n_val,
          d_ptr, d_word, d_shift, d_mask, d_val, total):
    """:func:`mcl2pnml.analysis.statespace.loops.numba_counters.edges`, in C."""
    src, trans, dst = (np.empty(total, dtype=np.int32) for _ in range(3))
    c.counter_walk(np.ascontiguousarray(queue[:count]), table, bits, n_ptr, n_word, n_shift,
                   n_mask, n_val, d_ptr, d_word, d_shift, d_mask, d_val, 1,
                   np.zeros(0, dtype=np.bool_), np.zeros(0, dtype=np.int64), src, trans, dst)
    return src, trans, dst


def backward(queue, count, table, bits, n_ptr, n_word, n_shift, n_mask, n_val,
             d_ptr, d_word, d_shift, d_mask, d_val, seen, frontier):
    """:func:`mcl2pnml.analysis.statespace.loops.numba_counters.backward`, in C."""
    c.counter_walk(np.ascontiguousarray(queue[:count]), table, bits, n_ptr, n_word, n_shift,
                   n_mask, n_val, d_ptr, d_word, d_shift, d_mask, d_val, -1, seen,
                   np.ascontiguousarray(frontier, dtype=np.int64), _NONE, _NONE, _NONE)
    return seen
