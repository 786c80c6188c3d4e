"""The loops of :mod:`mcl2pnml.analysis.statespace.counters`, compiled by numba (imported only when used).

Markings are rows of 64-bit words holding one unsigned counter a place,
each counter a field of ``bits`` bits that never straddles two words. A
transition is two lists of fields (compressed rows: ``*_ptr[t]`` to
``*_ptr[t + 1]``): what it needs (word, shift, mask, tokens) and what it
changes (word, shift, mask, signed change, place). The queue of markings
and the open-addressing hash set of positions in it are those of
:mod:`mcl2pnml.analysis.statespace.loops.numba_safe` (its probe and re-hash, ``find`` and ``rehash``): the
queue is the array of markings in the order found, so node ``n`` of the
state space is row ``n`` and node 0 the initial marking.

Each ``step`` expands up to ``budget`` markings and returns a code:
:data:`GOING`, :data:`LIMIT` (``max_states`` markings), :data:`OVERFLOW`
(a counter would not fit its field; ``info`` is the place: the caller
checks the ancestors, ``parent`` of each marking, then widens the place,
re-packs and calls again from the same head) or :data:`GROWING`
(a transition whose firing only adds tokens is enabled, so the marking
after it strictly covers the one before: the net is unbounded, Karp and
Miller 1969).
"""
import numba
import numpy as np

from mcl2pnml.analysis.statespace.loops.numba_safe import find as _find, rehash, sparse_index  # noqa: F401

GOING, LIMIT, OVERFLOW, GROWING = 0, 1, 2, 3

_jit = numba.njit(cache=True, nogil=True)


@_jit
def _enabled(row, t, n_ptr, n_word, n_shift, n_mask, n_val):
    for k in range(n_ptr[t], n_ptr[t + 1]):
        if (row[n_word[k]] >> n_shift[k]) & n_mask[k] < n_val[k]:
            return False
    return True


@_jit
def step(n_ptr, n_word, n_shift, n_mask, n_val, d_ptr, d_word, d_shift, d_mask, d_val,
         d_place, growing, queue, parent, count, head, table, bits, dead, max_states, budget):
    words = queue.shape[1]
    new = np.empty(words, dtype=np.uint64)
    stop = head + budget
    while head < count and head < stop:
        fired = False
        for t in range(n_ptr.shape[0] - 1):
            if not _enabled(queue[head], t, n_ptr, n_word, n_shift, n_mask, n_val):
                continue
            fired = True
            if growing[t]:
                return queue, parent, count, head, table, bits, dead, GROWING, t
            for w in range(words):
                new[w] = queue[head, w]
            for k in range(d_ptr[t], d_ptr[t + 1]):
                field = np.int64((new[d_word[k]] >> d_shift[k]) & d_mask[k]) + d_val[k]
                if field > np.int64(d_mask[k]):
                    return queue, parent, count, head, table, bits, dead, OVERFLOW, d_place[k]
                new[d_word[k]] = ((new[d_word[k]] & ~(d_mask[k] << d_shift[k]))
                                  | (np.uint64(field) << d_shift[k]))
            j, i = _find(queue, table, bits, new)
            if j >= 0:
                continue
            if count >= max_states:
                return queue, parent, count, head, table, bits, dead, LIMIT, 0
            if count == queue.shape[0]:
                grown = np.empty((2 * count, words), dtype=np.uint64)
                grown[:count] = queue[:count]
                queue = grown
                longer = np.empty(2 * count, dtype=np.int64)
                longer[:count] = parent[:count]
                parent = longer
            queue[count] = new
            parent[count] = head
            table[i] = count
            count += 1
            if 10 * count > 7 * len(table):
                bits += 1
                table = rehash(queue, count, bits)
        if not fired:
            dead += 1
        head += 1
    return queue, parent, count, head, table, bits, dead, GOING, 0


@_jit
def out_degree(queue, count, n_ptr, n_word, n_shift, n_mask, n_val):
    degree = np.zeros(count, dtype=np.int32)
    for q in range(count):
        for t in range(n_ptr.shape[0] - 1):
            if _enabled(queue[q], t, n_ptr, n_word, n_shift, n_mask, n_val):
                degree[q] += 1
    return degree


@_jit
def _fire_into(row, out, t, d_ptr, d_word, d_shift, d_mask, d_val, sign):
    """``out`` = ``row`` changed by ``sign`` times t's change; False if a counter leaves its field."""
    for w in range(row.shape[0]):
        out[w] = row[w]
    for k in range(d_ptr[t], d_ptr[t + 1]):
        field = np.int64((out[d_word[k]] >> d_shift[k]) & d_mask[k]) + sign * d_val[k]
        if field < 0 or field > np.int64(d_mask[k]):
            return False
        out[d_word[k]] = ((out[d_word[k]] & ~(d_mask[k] << d_shift[k]))
                          | (np.uint64(field) << d_shift[k]))
    return True


@_jit
def edges(queue, count, table, bits, n_ptr, n_word, n_shift, n_mask, n_val,
          d_ptr, d_word, d_shift, d_mask, d_val, total):
    """Every firing (source, transition, target), ``total`` of them, in node order."""
    src = np.empty(total, dtype=np.int32)
    trans = np.empty(total, dtype=np.int32)
    dst = np.empty(total, dtype=np.int32)
    new = np.empty(queue.shape[1], dtype=np.uint64)
    e = 0
    for q in range(count):
        for t in range(n_ptr.shape[0] - 1):
            if _enabled(queue[q], t, n_ptr, n_word, n_shift, n_mask, n_val):
                _fire_into(queue[q], new, t, d_ptr, d_word, d_shift, d_mask, d_val, 1)
                src[e], trans[e], dst[e] = q, t, _find(queue, table, bits, new)[0]
                e += 1
    return src, trans, dst


@_jit
def backward(queue, count, table, bits, n_ptr, n_word, n_shift, n_mask, n_val,
             d_ptr, d_word, d_shift, d_mask, d_val, seen, frontier):
    """Mark in ``seen`` every node that reaches one of ``frontier`` (already seen).

    Unfiring: the only marking t can come from is the one after minus t's
    change; it is a predecessor when it is reachable and enables t.
    """
    # first in, first out, as :func:`mcl2pnml.analysis.statespace.loops.numba_safe.backward` does
    todo = np.empty(count, dtype=np.int64)
    top = 0
    for n in frontier:
        todo[top] = n
        top += 1
    before = np.empty(queue.shape[1], dtype=np.uint64)
    head = 0
    while head < top:
        after = queue[todo[head]]
        head += 1
        for t in range(n_ptr.shape[0] - 1):
            if not _fire_into(after, before, t, d_ptr, d_word, d_shift, d_mask, d_val, -1):
                continue
            if not _enabled(before, t, n_ptr, n_word, n_shift, n_mask, n_val):
                continue
            j = _find(queue, table, bits, before)[0]
            if j >= 0 and not seen[j]:
                seen[j] = True
                todo[top] = j
                top += 1
    return seen
