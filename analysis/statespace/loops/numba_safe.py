"""The loops of :mod:`mcl2pnml.analysis.statespace.compiled`, compiled by numba (imported only when used).

Plain Python on numpy arrays of 64-bit words, which numba compiles once
into its cache on disk (beside this file, or in the user's cache directory
when this one is not writable). Each ``step_*`` function expands up to
``budget`` markings from the head of the queue and returns what the next
call needs, with a code: :data:`GOING` (more to do, or done when the head
has caught up with the queue), :data:`NOT_SAFE` (a firing would put a
second token in a place) or :data:`LIMIT` (``max_states`` markings found).

Markings are sets of places as bits; a transition is enabled when its
``need`` bits (consumed and read places) are all set, and firing it keeps
the ``keep`` bits and sets the ``give`` bits. The set of markings found is
an open-addressing table with linear probing, grown at 70% full; slots
come from Fibonacci hashing (the top bits of the product with 2^64 over
the golden ratio).
"""
import numba
import numpy as np

GOING, NOT_SAFE, LIMIT = 0, 1, 2

GOLDEN = np.uint64(0x9E3779B97F4A7C15)

_jit = numba.njit(cache=True, nogil=True)

# The index of a word's lowest set bit: multiplied by a de Bruijn constant, the
# lowest bit alone (x & -x) puts a distinct pattern in the top six bits.
DEBRUIJN = np.uint64(0x03F79D71B4CB0A89)
LOWEST = np.zeros(64, dtype=np.int64)
for _b in range(64):
    LOWEST[((0x03F79D71B4CB0A89 << _b) & 0xFFFFFFFFFFFFFFFF) >> 58] = _b
del _b


@_jit
def candidates(row, key_ptr, key_t, free_t, out):
    """The transitions worth testing on marking ``row``, into ``out``; how many.

    Each transition is keyed on one place it cannot do without (see
    :func:`mcl2pnml.analysis.statespace.packedmarkings.key_index`): only those keyed on a marked
    place can be enabled, so a marking of forty tokens tests some forty
    transitions, not every one of the net's hundreds. Transitions that test
    nothing (``free_t``) are always candidates.
    """
    n = 0
    for t in free_t:
        out[n] = t
        n += 1
    for w in range(row.shape[0]):
        x = row[w]
        while x != 0:
            low = x & (~x + np.uint64(1))
            x ^= low
            p = w * 64 + LOWEST[(low * DEBRUIJN) >> np.uint64(58)]
            for k in range(key_ptr[p], key_ptr[p + 1]):
                out[n] = key_t[k]
                n += 1
    return n


@_jit
def slot_of_word(m, bits):
    return np.int64((m * GOLDEN) >> np.uint64(64 - bits))


@_jit
def slot_of_words(row, bits):
    h = np.uint64(0)
    for w in range(row.shape[0]):
        h = (h ^ row[w]) * GOLDEN
        h ^= h >> np.uint64(29)
    return np.int64((h * GOLDEN) >> np.uint64(64 - bits))


@_jit
def find(queue, table, bits, row):
    """Position of ``row`` among the rows of ``queue`` that ``table`` holds, or -1 and
    the free slot where it would go (linear probing; the words are compared, so
    two markings are never merged)."""
    words = queue.shape[1]
    mask = (1 << bits) - 1
    i = slot_of_words(row, bits)
    while table[i] >= 0:
        j = table[i]
        same = True
        for w in range(words):
            if queue[j, w] != row[w]:
                same = False
                break
        if same:
            return j, i
        i = (i + 1) & mask
    return -1, i


@_jit
def rehash(queue, count, bits):
    """A new table of positions for the first ``count`` rows (after growth or re-packing)."""
    mask = (1 << bits) - 1
    table = np.full(1 << bits, -1, dtype=np.int64)
    for q in range(count):
        i = slot_of_words(queue[q], bits)
        while table[i] >= 0:
            i = (i + 1) & mask
        table[i] = q
    return table


@_jit
def sparse_index(queue, count):
    """A table of positions at most 35% full, and its bits, for searching backwards.

    There a predecessor is looked for at every edge, and each probe is a
    cache miss: half as full as while exploring, probes are fewer (on
    RwMutex-PT-r0020w0010, 21 million edges: 1.7 s instead of 2.2 s).
    """
    bits = 12
    while 20 * count > 7 << bits:
        bits += 1
    return rehash(queue, count, bits), bits


def new_queue(words, max_states, room):
    """The first queue of markings (grown by doubling in the loops)."""
    return np.empty((1024, words) if words > 1 else 1024, dtype=np.uint64)


def start_table(m0, bits):
    """The table of :func:`step_words` holding ``m0`` alone (positions, -1 free)."""
    table = np.full(1 << bits, -1, dtype=np.int64)
    table[slot_of_words(m0, bits)] = 0
    return table


@_jit
def paired_index(queue, count):
    """A table of positions at most 70% full, each slot holding a marking's first word too.

    A probe then reads one cache line, the slot, and goes to the marking
    itself only when the first words agree (with one word, never). Slots are
    twice as wide as :func:`sparse_index`'s, so the table is filled twice as
    much: the same memory, and no slower on 2^20 one-word markings.
    """
    bits = 12
    while 10 * count > 7 << bits:
        bits += 1
    mask = (1 << bits) - 1
    pairs = np.zeros((1 << bits, 2), dtype=np.int64)   # (first word, position + 1); 0: free
    for q in range(count):
        i = slot_of_words(queue[q], bits)
        while pairs[i, 1] != 0:
            i = (i + 1) & mask
        pairs[i, 0] = np.int64(queue[q, 0])
        pairs[i, 1] = q + 1
    return pairs, bits


@_jit
def find_paired(queue, pairs, bits, row):
    """Position of ``row`` among the rows of ``queue`` indexed by :func:`paired_index`, or -1."""
    mask = (1 << bits) - 1
    first = np.int64(row[0])
    i = slot_of_words(row, bits)
    while pairs[i, 1] != 0:
        if pairs[i, 0] == first:
            j = pairs[i, 1] - 1
            same = True
            for w in range(1, row.shape[0]):
                if queue[j, w] != row[w]:
                    same = False
                    break
            if same:
                return j
        i = (i + 1) & mask
    return -1


@_jit
def step_one_word(need, keep, give, key_ptr, key_t, free_t, queue, count, head, table, bits,
                  zero_seen, max_states, budget):
    """Markings of one word: the table holds the markings themselves (0: a free slot).

    The empty marking, which cannot be told from a free slot, is
    remembered apart, in ``zero_seen``.
    """
    mask = (1 << bits) - 1
    stop = head + budget
    cand = np.empty(need.shape[0], dtype=np.int64)
    row = np.empty(1, dtype=np.uint64)
    while head < count and head < stop:
        m = queue[head]
        row[0] = m
        for c in range(candidates(row, key_ptr, key_t, free_t, cand)):
            t = cand[c]
            if m & need[t] != need[t]:
                continue
            rest = m & keep[t]
            if rest & give[t]:
                return queue, count, head, table, bits, zero_seen, NOT_SAFE
            new = rest | give[t]
            if new == 0:
                if zero_seen:
                    continue
                zero_seen = True
            else:
                i = slot_of_word(new, bits)
                while table[i] != 0 and table[i] != new:
                    i = (i + 1) & mask
                if table[i] == new:
                    continue
                table[i] = new
            if count >= max_states:
                return queue, count, head, table, bits, zero_seen, LIMIT
            if count == len(queue):
                grown = np.empty(2 * count, dtype=np.uint64)
                grown[:count] = queue[:count]
                queue = grown
            queue[count] = new
            count += 1
            if 10 * count > 7 * len(table):
                bits += 1
                mask = (1 << bits) - 1
                table = np.zeros(1 << bits, dtype=np.uint64)
                for q in range(count):
                    v = queue[q]
                    if v != 0:
                        i = slot_of_word(v, bits)
                        while table[i] != 0:
                            i = (i + 1) & mask
                        table[i] = v
        head += 1
    return queue, count, head, table, bits, zero_seen, GOING


@_jit
def enables(rows, q, t, need, need_ptr, need_word):
    """Whether marking ``rows[q]`` (of several words) enables t, tested on the words t needs."""
    for k in range(need_ptr[t], need_ptr[t + 1]):
        w = need_word[k]
        if rows[q, w] & need[t, w] != need[t, w]:
            return False
    return True


@_jit
def step_words(need, keep, give, need_ptr, need_word, touch_ptr, touch_word, key_ptr, key_t,
               free_t, queue, count, head, table, bits, max_states, budget):
    """Markings of several words: the table holds positions in the queue (-1: free).

    A probe compares the words themselves, so two markings are never merged.
    A transition is tested on the words it needs only
    (``need_word[need_ptr[t]:need_ptr[t + 1]]``) and fired on those it
    touches (``touch_*``, :func:`mcl2pnml.analysis.statespace.packedmarkings.touched`): on a net
    of a thousand places, one to four words of sixteen.
    """
    words = need.shape[1]
    new = np.empty(words, dtype=np.uint64)
    cand = np.empty(need.shape[0], dtype=np.int64)
    stop = head + budget
    while head < count and head < stop:
        for c in range(candidates(queue[head], key_ptr, key_t, free_t, cand)):
            t = cand[c]
            if not enables(queue, head, t, need, need_ptr, need_word):
                continue
            for w in range(words):
                new[w] = queue[head, w]
            for k in range(touch_ptr[t], touch_ptr[t + 1]):
                w = touch_word[k]
                rest = new[w] & keep[t, w]
                if rest & give[t, w]:
                    return queue, count, head, table, bits, NOT_SAFE
                new[w] = rest | give[t, w]
            j, i = find(queue, table, bits, new)
            if j >= 0:
                continue
            if count >= max_states:
                return queue, count, head, table, bits, LIMIT
            if count == queue.shape[0]:
                grown = np.empty((2 * count, words), dtype=np.uint64)
                grown[:count] = queue[:count]
                queue = grown
            queue[count] = new
            table[i] = count
            count += 1
            if 10 * count > 7 * len(table):
                bits += 1
                table = rehash(queue, count, bits)
        head += 1
    return queue, count, head, table, bits, GOING


# -- the explored state space, asked again (PackedStateSpace) ---------------------------

@_jit
def out_degree(packed, need, need_ptr, need_word, key_ptr, key_t, free_t):
    """Per sorted position, how many transitions the marking enables (on the words needed)."""
    degree = np.zeros(packed.shape[0], dtype=np.int32)
    cand = np.empty(need.shape[0], dtype=np.int64)
    for q in range(packed.shape[0]):
        for c in range(candidates(packed[q], key_ptr, key_t, free_t, cand)):
            if enables(packed, q, cand[c], need, need_ptr, need_word):
                degree[q] += 1
    return degree


@_jit
def live(packed, need, need_ptr, need_word, key_ptr, key_t, free_t):
    """Per sorted position, 1 if the marking enables a transition, 0 if it is dead: the
    test stops at the first enabled one, where :func:`out_degree` counts them all."""
    alive = np.zeros(packed.shape[0], dtype=np.int32)
    cand = np.empty(need.shape[0], dtype=np.int64)
    for q in range(packed.shape[0]):
        for c in range(candidates(packed[q], key_ptr, key_t, free_t, cand)):
            if enables(packed, q, cand[c], need, need_ptr, need_word):
                alive[q] = 1
                break
    return alive


@_jit
def backward(packed, pairs, bits, need, take, give, touch_ptr, touch_word, key_ptr, key_t, free_t,
             seen, frontier):
    """Mark in ``seen`` every sorted position that reaches one of ``frontier`` (already seen).

    Unfiring: in a safe net the only marking t can come from is the one after
    without t's outputs and with its inputs; it is a predecessor when it is a
    reachable marking (found in ``pairs``, :func:`paired_index` of ``packed``),
    enables t and really fires into the one after. Only transitions keyed on
    a place marked after (on their outputs, :func:`candidates`) are tried.
    """
    words = packed.shape[1]
    # first in, first out: the next marking to unfire was queued long ago, so the
    # processor overlaps its lookups (last in, first out chains every cache miss
    # to the one before: half as fast)
    todo = np.empty(packed.shape[0], dtype=np.int64)
    top = 0
    for n in frontier:
        todo[top] = n
        top += 1
    before = np.empty(words, dtype=np.uint64)
    cand = np.empty(need.shape[0], dtype=np.int64)
    head = 0
    while head < top:
        a = todo[head]
        head += 1
        for w in range(words):
            before[w] = packed[a, w]
        for c in range(candidates(packed[a], key_ptr, key_t, free_t, cand)):
            t = cand[c]
            ok = True
            for k in range(touch_ptr[t], touch_ptr[t + 1]):
                w = touch_word[k]
                after = packed[a, w]
                if after & give[t, w] != give[t, w]:
                    ok = False
                    break
                b = (after & ~give[t, w]) | take[t, w]
                if (b & need[t, w] != need[t, w]
                        or (b & ~take[t, w]) | give[t, w] != after):
                    ok = False
                    break
                before[w] = b
            if ok:
                j = find_paired(packed, pairs, bits, before)
                if j >= 0 and not seen[j]:
                    seen[j] = True
                    todo[top] = j
                    top += 1
            for k in range(touch_ptr[t], touch_ptr[t + 1]):   # back to the marking after
                w = touch_word[k]
                before[w] = packed[a, w]
    return seen
