"""The loops in C (``_native.c``, built when mcl2pnml is installed), behind
:class:`~mcl2pnml.analysis.statespace.loops.interface.Loops`.

This module is the one place that knows the C functions' positional
signatures: it unpacks the interface's values into them. Importing it raises
ImportError where the extension was not built (a machine without a C
compiler): :mod:`mcl2pnml.analysis.statespace.loops.backends` then takes the
plain-Python reference.

The C functions never allocate the arrays: a step that finds the queue or the
table too small for the next marking's successors stops before that marking
(``QUEUE_FULL``, ``TABLE_FULL``), and the functions here grow the array,
numpy's like every other, so that the memory budget sees every byte, and go on.
"""
from __future__ import annotations

import numpy as np

from mcl2pnml.analysis.statespace.loops import _native as c
from mcl2pnml.analysis.statespace.loops.interface import (Buchi, Code, CounterNet, CounterSearch,
                                                          Index, KeyIndex, LtlCode, Observer,
                                                          ProductSearch, SafeNet, SafeSearch,
                                                          StateProgram, STUBBORN_KEYS, Stubborn)

name = "c"

#: A new table's size, as a power of two: 4,096 slots, grown as the loops ask.
FIRST_BITS = 12

_NONE32 = np.zeros(0, dtype=np.int32)


def _contiguous(*arrays: np.ndarray) -> list[np.ndarray]:
    return [np.ascontiguousarray(a) for a in arrays]


def _firing(net: SafeNet) -> list[np.ndarray]:
    """The ten masks and indices of the C loops' ``Masks``, in their order."""
    return _contiguous(net.need, net.keep, net.give, net.needed.ptr, net.needed.items,
                       net.touched.ptr, net.touched.items, *_key(net.key))


def _key(key: KeyIndex) -> list[np.ndarray]:
    return _contiguous(key.by_place.ptr, key.by_place.items, key.free)


def _enabling(net: SafeNet) -> list[np.ndarray]:
    """What testing a transition takes: its needs, the words needed, the key index."""
    return _contiguous(net.need, net.needed.ptr, net.needed.items, *_key(net.key))


# -- a safe net --------------------------------------------------------------------------------

def _new_queue(words: int, max_states: int, room: int) -> np.ndarray:
    """The queue of markings, as long as it may ever need to be (``max_states`` and one
    marking's successors), allocated and never written: the kernel maps a page in only
    when a marking is stored there, so it costs what it holds and never grows by copying
    (``max_states`` comes from the memory budget, so the length is within it)."""
    shape = (max_states + room + 1, words) if words > 1 else (max_states + room + 1,)
    return np.empty(shape, dtype=np.uint64)


def _grown(a: np.ndarray, count: int, size: int) -> np.ndarray:
    grown = np.empty((size, *a.shape[1:]), dtype=a.dtype)
    grown[:count] = a[:count]
    return grown


def _grown_queue(queue: np.ndarray, count: int, room: int) -> np.ndarray:
    size = len(queue)
    while size < count + room:
        size *= 2
    return _grown(queue, count, size)


def _table_bits(count: int, bits: int = FIRST_BITS) -> int:
    """The bits of a table that holds ``count`` rows at most 70% full."""
    while 10 * count > 7 << bits:
        bits += 1
    return bits


def _rehash(rows: np.ndarray, count: int, bits: int, by_value: bool) -> np.ndarray:
    """A table of the first ``count`` rows: the markings themselves (``by_value``, one
    word), or a fingerprint and a position each; 0 is a free slot."""
    table = np.zeros(1 << bits, dtype=np.uint64)
    c.rehash(np.ascontiguousarray(rows), count, table, bits, by_value)
    return table


def safe_search(net: SafeNet, m0: np.ndarray, max_states: int) -> SafeSearch:
    """The search holding ``m0`` alone. On one word the table holds the markings
    themselves (0: free; the empty marking is remembered apart, ``zero_seen``)."""
    words = net.words
    queue = _new_queue(words, max_states, net.transitions)
    queue[0] = m0 if words > 1 else m0[0]
    if words == 1:
        table = np.zeros(1 << FIRST_BITS, dtype=np.uint64)
        table[c.slot_of_word(int(m0[0]), FIRST_BITS)] = m0[0]
        return SafeSearch(queue, 1, 0, table, FIRST_BITS, bool(m0[0] == 0))
    return SafeSearch(queue, 1, 0, _rehash(queue, 1, FIRST_BITS, False), FIRST_BITS)


def safe_step(net: SafeNet, search: SafeSearch, max_states: int, budget: int) -> SafeSearch:
    """Up to ``budget`` expansions from the head; the arrays grown as the loop asks."""
    queue, count, head = search.queue, search.count, search.head
    table, bits, zero = search.table, search.bits, search.zero_seen
    one = queue.ndim == 1
    if one:
        masks = _contiguous(net.need[:, 0], net.keep[:, 0], net.give[:, 0], *_key(net.key))
    else:
        masks = _firing(net)
    while True:
        if one:
            count, head, zero, code = c.step_one_word(*masks, queue, count, head, table, bits,
                                                      zero, max_states, budget)
        else:
            count, head, code = c.step_words(*masks, queue, count, head, table, bits,
                                             max_states, budget)
        if code == c.QUEUE_FULL:
            queue = _grown_queue(queue, count, net.transitions)
        elif code == c.TABLE_FULL:
            bits = _table_bits(count + net.transitions, bits)
            table = _rehash(queue, count, bits, one)
        else:
            return SafeSearch(queue, count, head, table, bits, zero, Code(code))


def permute_rows(rows: np.ndarray, order: np.ndarray) -> np.ndarray:
    """``rows[order]``, in place when ``rows`` owns its data (no second copy)."""
    if not rows.flags.owndata:
        return rows[order]
    c.permute_rows(rows, np.ascontiguousarray(order, dtype=np.int64))
    return rows


def out_degree(rows: np.ndarray, net: SafeNet) -> np.ndarray:
    degree = np.zeros(len(rows), dtype=np.int32)
    c.out_degree(np.ascontiguousarray(rows), *_enabling(net), degree, False)
    return degree


def live(rows: np.ndarray, net: SafeNet) -> np.ndarray:
    alive = np.zeros(len(rows), dtype=np.int32)
    c.out_degree(np.ascontiguousarray(rows), *_enabling(net), alive, True)
    return alive


def _paired_index(rows: np.ndarray, by_value: bool = True) -> tuple[np.ndarray, int]:
    """The backward search's table of ``rows``, at most 70% full: the fingerprints make a
    search for a predecessor that is not there cheap, so a table twice as full costs no
    time and half the memory. Rows of one word are keyed by their value unless
    ``by_value`` is false (:func:`edges` probes every width alike)."""
    bits = _table_bits(len(rows))
    table = np.zeros(1 << bits, dtype=np.uint64)
    if by_value and rows.shape[1] == 1:
        c.rehash(rows, len(rows), table, bits, True)   # one word: the markings themselves
    else:
        c.paired_index(rows, table, bits)
    return table, bits


def edges(rows: np.ndarray, net: SafeNet, ids: np.ndarray, order: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rows = np.ascontiguousarray(rows)
    total = int(out_degree(rows, net).sum())
    table, bits = _paired_index(rows, by_value=False)
    src, trans, dst = (np.empty(total, dtype=np.int32) for _ in range(3))
    order = np.ascontiguousarray(order, dtype=np.int64)
    index = _contiguous(net.needed.ptr, net.needed.items, *_key(net.key))
    c.packed_edges(rows, table, bits, *_contiguous(net.need, net.keep, net.give), *index,
                   np.ascontiguousarray(ids, dtype=np.int64), order, order, src, dst, trans)
    return src, trans, dst


def backward(rows: np.ndarray, net: SafeNet, unfire: KeyIndex, seen: np.ndarray,
             frontier: np.ndarray) -> np.ndarray:
    rows = np.ascontiguousarray(rows)
    frontier = np.ascontiguousarray(frontier, dtype=np.int64)
    # a hash table of positions: a probe or two a predecessor, where a binary
    # search on the keys costs some twenty cache misses (4.5 s, not 1.7)
    table, bits = _paired_index(rows)
    masks = _contiguous(net.need, net.take, net.give)
    if rows.shape[1] == 1:
        # a table of the markings themselves: its slots are the nodes
        c.backward_one_word(rows, table, bits, *masks, *_key(unfire), seen, frontier)
    else:
        c.backward(rows, table, bits, *masks, *_contiguous(net.touched.ptr, net.touched.items),
                   *_key(unfire), seen, frontier)
    return seen


# -- a bounded net -----------------------------------------------------------------------------

def _fields(net: CounterNet) -> list[np.ndarray]:
    n, d = net.need, net.change
    return _contiguous(n.ptr, n.word, n.shift, n.mask, n.value,
                       d.ptr, d.word, d.shift, d.mask, d.value)


def counter_search(queue: np.ndarray, parent: np.ndarray, count: int, head: int,
                   dead: int = 0) -> CounterSearch:
    bits = _table_bits(count)
    return CounterSearch(queue, parent, count, head, Index(_rehash(queue, count, bits, False),
                                                           bits), dead)


def counter_step(net: CounterNet, search: CounterSearch, max_states: int,
                 budget: int) -> CounterSearch:
    fields = _fields(net)
    place = np.ascontiguousarray(net.change.place)
    growing = np.ascontiguousarray(net.growing, dtype=np.bool_)
    queue, parent, count, head = search.queue, search.parent, search.count, search.head
    table, bits, dead = search.index.table, search.index.bits, search.dead
    while True:
        count, head, dead, code, info = c.counter_step(*fields, place, growing, queue, parent,
                                                       count, head, table, bits, dead,
                                                       max_states, budget)
        if code == c.QUEUE_FULL:
            queue = _grown_queue(queue, count, net.transitions)
            parent = _grown(parent, count, len(queue))
        elif code == c.TABLE_FULL:
            bits = _table_bits(count + net.transitions, bits)
            table = _rehash(queue, count, bits, False)
        else:
            return CounterSearch(queue, parent, count, head, Index(table, bits), dead,
                                 Code(code), info)


def counter_out_degree(rows: np.ndarray, net: CounterNet) -> np.ndarray:
    degree = np.zeros(len(rows), dtype=np.int32)
    c.counter_out_degree(np.ascontiguousarray(rows), *_fields(net)[:5], degree)
    return degree


def counter_edges(rows: np.ndarray, index: Index, net: CounterNet, total: int
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    src, trans, dst = (np.empty(total, dtype=np.int32) for _ in range(3))
    c.counter_walk(np.ascontiguousarray(rows), index.table, index.bits, *_fields(net), 1,
                   np.zeros(0, dtype=np.bool_), np.zeros(0, dtype=np.int64), src, trans, dst)
    return src, trans, dst


def counter_backward(rows: np.ndarray, net: CounterNet, seen: np.ndarray,
                     frontier: np.ndarray) -> np.ndarray:
    rows = np.ascontiguousarray(rows)
    bits = _table_bits(len(rows))
    c.counter_walk(rows, _rehash(rows, len(rows), bits, False), bits, *_fields(net), -1, seen,
                   np.ascontiguousarray(frontier, dtype=np.int64), _NONE32, _NONE32, _NONE32)
    return seen


# -- a property's product ----------------------------------------------------------------------

def _observer(o: Observer) -> list[np.ndarray]:
    return _contiguous(o.atoms, o.least, o.letters, o.move, o.pending)


def _stubborn(st: Stubborn) -> list[np.ndarray]:
    return _contiguous(*(a for r in (st.pre, st.needs, st.takers, st.needers, st.makers)
                         for a in (r.ptr, r.items)), st.visible)


def product_search(start: np.ndarray, capacity: int) -> ProductSearch:
    queue = np.empty((capacity, len(start)), dtype=np.uint64)
    queue[0] = start
    parent, via, depth = (np.empty(capacity, dtype=np.int64) for _ in range(3))
    parent[0], via[0], depth[0] = -1, -1, 0
    table = _rehash(queue, 1, FIRST_BITS, False)
    return ProductSearch(queue, 1, 0, Index(table, FIRST_BITS), parent, via, depth)


def product_step(net: SafeNet, observer: Observer, stubborn: Stubborn, search: ProductSearch,
                 max_states: int, budget: int) -> ProductSearch:
    masks, seen_by, reducing = _firing(net), _observer(observer), _stubborn(stubborn)
    queue, count, head, found = search.queue, search.count, search.head, search.found
    table, bits = search.index.table, search.index.bits
    parent, via, depth = search.parent, search.via, search.depth
    while True:
        count, head, code, found = c.product_step(
            *masks, *seen_by, observer.bad, queue, count, head, table, bits, parent, via,
            depth, found, max_states, budget, *reducing, stubborn.on)
        if code == c.QUEUE_FULL:
            size = 2 * len(queue)
            queue, parent, via, depth = (_grown(a, count, size)
                                         for a in (queue, parent, via, depth))
        elif code == c.TABLE_FULL:
            bits = _table_bits(count + net.transitions + 1, bits)
            table = _rehash(queue, count, bits, False)
        else:
            return ProductSearch(queue, count, head, Index(table, bits), parent, via, depth,
                                 found, Code(code))


def product_edges(net: SafeNet, observer: Observer, search: ProductSearch, first: int,
                  room: int) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    src, dst, trans = (np.empty(room, dtype=np.int64) for _ in range(3))
    following, n = c.product_edges(*_firing(net), *_observer(observer), search.queue,
                                   search.count, search.index.table, search.index.bits, first,
                                   src, dst, trans)
    return following, src[:n], dst[:n], trans[:n]


# -- graph searches ----------------------------------------------------------------------------

scc = c.scc
back_reach = c.back_reach
scatter_by_source = c.scatter_by_source
ltl_product = c.ltl_product


# -- an LTL formula's product with a bounded net, on the fly ------------------------------------

def ltl_search(net: CounterNet, program: StateProgram, buchi: Buchi, stubborn: Stubborn,
               m0: np.ndarray, max_states: int, seconds: float) -> tuple[LtlCode, int, int]:
    n, d = net.need, net.change
    m0 = np.ascontiguousarray(m0, dtype=np.uint64).ravel()
    capacity = max(1, max_states)
    bits = _table_bits(capacity)
    # np.empty and np.zeros take pages only as the search writes them
    rows = np.empty((capacity, len(m0) + 1), dtype=np.uint64)
    table = np.zeros(1 << bits, dtype=np.uint64)
    code, states, info = c.ltl_search(
        *_contiguous(n.ptr, n.word, n.shift, n.mask, n.value, n.place,
                     d.ptr, d.word, d.shift, d.mask, d.value, d.place, net.growing,
                     program.ops, program.atom_ptr, program.lin_ptr, program.lin_word,
                     program.lin_shift, program.lin_mask, program.lin_coef, program.bound,
                     buchi.ptr, buchi.succ, buchi.required, buchi.accepting),
        buchi.all, np.ascontiguousarray(buchi.initial), *_stubborn(stubborn), int(stubborn.on),
        m0, rows, table, bits, max_states, float(seconds), STUBBORN_KEYS)
    return LtlCode(code), states, info
