"""The loops of :mod:`mcl2pnml.analysis.statespace.compiled` in C (``analysis/statespace/loops/_native.c``), with the
signatures of :mod:`mcl2pnml.analysis.statespace.loops.numba_safe`, so that either runs the same explorer.

The C module is built when mcl2pnml is installed (an optional extension: a
machine without a C compiler installs without it, and :func:`available`
says so). It never allocates the arrays: a step that finds the queue or
the table too small for the next marking's successors stops before that
marking, and the functions here grow the array, numpy's like every other,
and go on; so the two modules take and return the same values.
"""
from __future__ import annotations

import numpy as np

from mcl2pnml.analysis.statespace.loops import _native as c

GOING, NOT_SAFE, LIMIT = c.GOING, c.NOT_SAFE, c.LIMIT


def slot_of_word(m, bits: int) -> int:
    return c.slot_of_word(int(m), bits)


def slot_of_words(row: np.ndarray, bits: int) -> int:
    return c.slot_of_words(np.ascontiguousarray(row, dtype=np.uint64), bits)


def _contiguous(*arrays: np.ndarray) -> list[np.ndarray]:
    return [np.ascontiguousarray(a) for a in arrays]


def new_queue(words: int, max_states: int, room: int) -> np.ndarray:
    """The queue of markings, as long as it may ever need to be (``max_states`` and one
    marking's successors), allocated and never written: the kernel maps a page in only
    when a marking is stored there, so it costs what it holds and never grows by copying
    (``max_states`` comes from the memory budget, so the length is within it)."""
    shape = (max_states + room + 1, words) if words > 1 else (max_states + room + 1,)
    return np.empty(shape, dtype=np.uint64)


def _grown_queue(queue: np.ndarray, count: int, room: int) -> np.ndarray:
    size = len(queue)
    while size < count + room:
        size *= 2
    grown = np.empty((size, *queue.shape[1:]), dtype=queue.dtype)
    grown[:count] = queue[:count]
    return grown


def permute_rows(rows: np.ndarray, order: np.ndarray) -> np.ndarray:
    """``rows[order]``, in place (``rows`` must own its data)."""
    c.permute_rows(rows, np.ascontiguousarray(order, dtype=np.int64))
    return rows


def start_table(m0: np.ndarray, bits: int) -> np.ndarray:
    """The table of :func:`step_words` holding ``m0`` alone (unlike the numba loops': each
    slot is a fingerprint and a position, 0 free)."""
    table = np.zeros(1 << bits, dtype=np.uint64)
    c.rehash(np.ascontiguousarray(m0, dtype=np.uint64).reshape(1, -1), 1, table, bits, False)
    return table


def _grown_table(queue: np.ndarray, count: int, room: int, bits: int,
                 by_value: bool) -> tuple[np.ndarray, int]:
    while 10 * (count + room) > 7 << bits:
        bits += 1
    table = np.zeros(1 << bits, dtype=np.uint64)
    c.rehash(queue, count, table, bits, by_value)
    return table, bits


def step_one_word(need, keep, give, key_ptr, key_t, free_t, queue, count, head, table, bits,
                  zero_seen, max_states, budget):
    """:func:`mcl2pnml.analysis.statespace.loops.numba_safe.step_one_word`, in C."""
    masks = _contiguous(need, keep, give, key_ptr, key_t, free_t)
    room = len(need)
    while True:
        count, head, zero_seen, code = c.step_one_word(*masks, queue, count, head, table, bits,
                                                       zero_seen, max_states, budget)
        if code == c.QUEUE_FULL:
            queue = _grown_queue(queue, count, room)
        elif code == c.TABLE_FULL:
            table, bits = _grown_table(queue, count, room, bits, True)
        else:
            return queue, count, head, table, bits, zero_seen, code


def step_words(need, keep, give, need_ptr, need_word, touch_ptr, touch_word, key_ptr, key_t,
               free_t, queue, count, head, table, bits, max_states, budget):
    """:func:`mcl2pnml.analysis.statespace.loops.numba_safe.step_words`, in C."""
    masks = _contiguous(need, keep, give, need_ptr, need_word, touch_ptr, touch_word, key_ptr,
                        key_t, free_t)
    room = len(need)
    while True:
        count, head, code = c.step_words(*masks, queue, count, head, table, bits, max_states,
                                         budget)
        if code == c.QUEUE_FULL:
            queue = _grown_queue(queue, count, room)
        elif code == c.TABLE_FULL:
            table, bits = _grown_table(queue, count, room, bits, False)
        else:
            return queue, count, head, table, bits, code


def out_degree(packed, need, need_ptr, need_word, key_ptr, key_t, free_t) -> np.ndarray:
    """:func:`mcl2pnml.analysis.statespace.loops.numba_safe.out_degree`, in C."""
    degree = np.zeros(len(packed), dtype=np.int32)
    c.out_degree(*_contiguous(packed, need, need_ptr, need_word, key_ptr, key_t, free_t), degree,
                 False)
    return degree


def live(packed, need, need_ptr, need_word, key_ptr, key_t, free_t) -> np.ndarray:
    """:func:`mcl2pnml.analysis.statespace.loops.numba_safe.live`, in C."""
    alive = np.zeros(len(packed), dtype=np.int32)
    c.out_degree(*_contiguous(packed, need, need_ptr, need_word, key_ptr, key_t, free_t), alive,
                 True)
    return alive


def edges(packed, need, keep, give, ids, order, need_ptr, need_word, key_ptr, key_t, free_t
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every edge of the explored markings (sorted rows; node ``i`` is row ``order[i]``,
    ``order`` its own inverse) as int32 columns source, transition (``ids`` of the
    firing's row), target, in node order and by transition within a node."""
    packed = np.ascontiguousarray(packed)
    index = _contiguous(need_ptr, need_word, key_ptr, key_t, free_t)
    total = int(out_degree(packed, need, *index).sum())
    table, bits = paired_index(packed, len(packed), by_value=False)
    src, trans, dst = (np.empty(total, dtype=np.int32) for _ in range(3))
    order = np.ascontiguousarray(order, dtype=np.int64)
    c.packed_edges(packed, table, bits, *_contiguous(need, keep, give), *index,
                   np.ascontiguousarray(ids, dtype=np.int64), order, order, src, dst, trans)
    return src, trans, dst


def paired_index(queue: np.ndarray, count: int, by_value: bool = True
                 ) -> tuple[np.ndarray, int]:
    """The backward search's table of the first ``count`` rows: entries as in
    :func:`start_table`, at most 70% full: the fingerprints make a search for a
    predecessor that is not there cheap, so a table twice as full costs no
    time and half the memory. Rows of one word are keyed by their value unless
    ``by_value`` is false (:func:`edges` probes every width alike)."""
    bits = 12
    while 10 * count > 7 << bits:
        bits += 1
    table = np.zeros(1 << bits, dtype=np.uint64)
    rows = np.ascontiguousarray(queue[:count])
    if by_value and rows.ndim == 2 and rows.shape[1] == 1:
        c.rehash(rows, count, table, bits, True)   # one word: the markings themselves
    else:
        c.paired_index(rows, table, bits)
    return table, bits


def backward(packed, pairs, bits, need, take, give, touch_ptr, touch_word, key_ptr, key_t, free_t,
             seen, frontier) -> np.ndarray:
    """:func:`mcl2pnml.analysis.statespace.loops.numba_safe.backward`, in C."""
    frontier = np.ascontiguousarray(frontier, dtype=np.int64)
    if packed.ndim == 2 and packed.shape[1] == 1:
        # a table of the markings themselves (:func:`paired_index`): its slots are the nodes
        c.backward_one_word(*_contiguous(packed, pairs), bits,
                            *_contiguous(need, take, give, key_ptr, key_t, free_t), seen, frontier)
        return seen
    c.backward(*_contiguous(packed, pairs), bits,
               *_contiguous(need, take, give, touch_ptr, touch_word, key_ptr, key_t, free_t),
               seen, frontier)
    return seen
