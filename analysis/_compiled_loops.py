"""The loops of :mod:`analysis.compiledspace`, compiled by numba (imported only when used).

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
def step_one_word(need, keep, give, queue, count, head, table, bits, zero_seen,
                  max_states, budget):
    """Markings of one word: the table holds the markings themselves (0: a free slot).

    The empty marking, which cannot be told from a free slot, is
    remembered apart, in ``zero_seen``.
    """
    mask = (1 << bits) - 1
    stop = head + budget
    while head < count and head < stop:
        m = queue[head]
        for t in range(need.shape[0]):
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
def step_words(need, keep, give, queue, count, head, table, bits, max_states, budget):
    """Markings of several words: the table holds positions in the queue (-1: free).

    A probe compares the words themselves, so two markings are never merged.
    """
    words = need.shape[1]
    mask = (1 << bits) - 1
    new = np.empty(words, dtype=np.uint64)
    stop = head + budget
    while head < count and head < stop:
        for t in range(need.shape[0]):
            enabled = True
            for w in range(words):
                if queue[head, w] & need[t, w] != need[t, w]:
                    enabled = False
                    break
            if not enabled:
                continue
            for w in range(words):
                rest = queue[head, w] & keep[t, w]
                if rest & give[t, w]:
                    return queue, count, head, table, bits, NOT_SAFE
                new[w] = rest | give[t, w]
            i = slot_of_words(new, bits)
            seen = False
            while table[i] >= 0:
                j = table[i]
                seen = True
                for w in range(words):
                    if queue[j, w] != new[w]:
                        seen = False
                        break
                if seen:
                    break
                i = (i + 1) & mask
            if seen:
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
                mask = (1 << bits) - 1
                table = np.full(1 << bits, -1, dtype=np.int64)
                for q in range(count):
                    i = slot_of_words(queue[q], bits)
                    while table[i] >= 0:
                        i = (i + 1) & mask
                    table[i] = q
        head += 1
    return queue, count, head, table, bits, GOING
