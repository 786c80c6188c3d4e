"""The reachability graph of a safe net, explored a whole frontier at a time (numpy).

One of the two safe-net explorers behind :func:`mcl2pnml.analysis.statespace.explore.explore`
(markings packed into bits, :mod:`mcl2pnml.analysis.statespace.packedmarkings`). Instead of one
marking at a time, this explorer applies each transition to the whole
breadth-first frontier at once, in numpy, and keeps only the markings,
sorted by their 64-bit keys; with several words a key is a hash, and two
markings that share one are noticed (:class:`KeyCollision`: the exact
explorer takes over). It returns a
:class:`~mcl2pnml.analysis.statespace.packedmarkings.PackedStateSpace`.

So a million markings take a couple of seconds and about 60 bytes each at
the peak, where markings as tuples and edges as integer triples take ten
times that.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from mcl2pnml.core.structure import Structure

from mcl2pnml.analysis.statespace.packedmarkings import (Firing, KeyCollision, NotSafe, PackedStateSpace, chunks,
                                     distinct, marking_row, masks, same, search, word_count)
# bound under this module's own name, so that the keys of this explorer alone
# can be replaced (the key-collision tests do)
from mcl2pnml.analysis.statespace.packedmarkings import keys_of as _keys


def footprint(s: Structure) -> int:
    """Bytes a marking costs at most: the sorted markings and their keys, merged
    into a copy a level at a time, and the frontier fired in chunks."""
    return 32 * word_count(s) + 64


def explore_packed(s: Structure, m0: Sequence[int], max_states: int, limit_error,
                   progress=None) -> "PackedStateSpace":
    """Breadth-first, a frontier at a time; raises :class:`NotSafe` at a second token."""
    words = word_count(s)
    need, take, give = masks(s, words)
    firing = Firing.by(need, need, take, give)
    start = marking_row(m0, words)
    seen_keys = _keys(start).copy()
    if words == 1:
        frontier = start
        while len(frontier):
            fresh = _level_one_word(frontier, seen_keys, firing)
            if not len(fresh):
                break
            if len(seen_keys) + len(fresh) > max_states:
                raise limit_error
            seen_keys = _merge(seen_keys, fresh)
            frontier = fresh.reshape(-1, 1)
            if progress:
                progress(len(seen_keys), len(frontier))
        packed = seen_keys.reshape(-1, 1)
    else:
        # the rows in the order found (a buffer that doubles), and for every
        # sorted key the index of its row there
        found = np.zeros((1024, words), dtype=np.uint64)
        found[0] = start[0]
        count = 1
        seen_order = np.zeros(1, dtype=np.int64)
        frontier = start
        while len(frontier):
            keys, frontier = _level_rows(frontier, seen_keys, seen_order, found, firing)
            if not len(keys):
                break
            if count + len(keys) > max_states:
                raise limit_error
            if count + len(keys) > len(found):
                grown = np.zeros((2 * (count + len(keys)), words), dtype=np.uint64)
                grown[:count] = found[:count]
                found = grown
            found[count:count + len(keys)] = frontier
            at = np.searchsorted(seen_keys, keys)
            seen_keys = _merge(seen_keys, keys, at)
            seen_order = _merge(seen_order, np.arange(count, count + len(keys)), at)
            count += len(keys)
            if progress:
                progress(count, len(frontier))
        packed = found[seen_order]
    return PackedStateSpace(s, packed, seen_keys, _keys(start)[0], firing)


def _unseen(keys: np.ndarray, seen: np.ndarray) -> np.ndarray:
    """The sorted, distinct ``keys`` (sorted already) that are not in ``seen`` (sorted)."""
    keys = distinct(keys)
    _, old = search(seen, keys)
    return keys[~old]


def _fire(rows: np.ndarray, firing: Firing) -> np.ndarray:
    """Every successor of ``rows`` (markings of one or several words), all transitions at once."""
    out = []
    for part in chunks(len(rows), len(firing.test)):
        f = rows[part]
        r, t = np.nonzero(firing.tested(f))
        if not len(r):
            continue
        succ = f[r]
        succ &= firing.keep[t]
        given = firing.give[t]
        if np.any(succ & given):
            raise NotSafe
        succ |= given
        out.append(succ)
    if not out:
        return rows[:0]
    return np.concatenate(out) if len(out) > 1 else out[0]


def _level_one_word(frontier, seen, firing: Firing) -> np.ndarray:
    """The next breadth-first level, for markings of one word: sorted, new, distinct keys."""
    succ = _fire(frontier, firing).ravel()
    succ.sort()
    return _unseen(succ, seen)


def _level_rows(frontier, seen, seen_order, found, firing: Firing):
    """The next level for markings of several words: (new keys, new rows), sorted by key."""
    cand = _fire(frontier, firing)
    if not len(cand):
        return np.zeros(0, dtype=np.uint64), frontier[:0]
    keys = _keys(cand)
    order = np.argsort(keys)
    keys, cand = keys[order], cand[order]
    again = keys[1:] == keys[:-1]
    if again.any():
        _check_distinct(cand[1:][again], cand[:-1][again])
        first = np.concatenate(([True], ~again))
        keys, cand = keys[first], cand[first]
    at, old = search(seen, keys)
    if old.any():
        _check_distinct(cand[old], found[seen_order[at[old]]])
        return keys[~old], cand[~old]
    return keys, cand


def _merge(seen: np.ndarray, fresh: np.ndarray, at: np.ndarray | None = None) -> np.ndarray:
    """``fresh`` inserted into ``seen`` before positions ``at`` (where it sorts), in linear time."""
    if at is None:
        at = np.searchsorted(seen, fresh)
    out = np.empty(len(seen) + len(fresh), dtype=seen.dtype)
    slots = at + np.arange(len(fresh))
    rest = np.ones(len(out), dtype=bool)
    rest[slots] = False
    out[slots] = fresh
    out[rest] = seen
    return out


def _check_distinct(a: np.ndarray, b: np.ndarray) -> None:
    """Rows ``a`` and ``b`` have equal keys, pairwise: they must be the same markings."""
    if len(a) and not np.all(same(a, b)):
        raise KeyCollision
