"""The reachability graph of a safe net, explored a whole frontier at a time (numpy).

For a 1-safe net with unit weights (every net this project compiles), a
marking is a row of bits, one per place, packed into 64-bit words, and
firing a transition is three bit operations. Instead of one marking at a
time, this explorer applies each transition to the whole breadth-first
frontier at once, in numpy, and keeps only the markings: sorted, packed
(8 bytes each up to 64 places), decoded when asked for.

Edges are not stored. What the analysis asks of them is answered by firing
again, a whole array at a time: a marking is terminal when no transition is
enabled in it; the markings that can reach a set are found backwards, by
*unfiring* each transition on the frontier (for a safe net the marking
before a firing is determined by the one after) and keeping the results
that are reachable markings and really fire into it. The explicit edge list
(``src``, ``trans``, ``dst``) is built only if someone asks for it.

So a million markings take a couple of seconds and about 60 bytes each at
the peak, where markings as tuples and edges as integer triples take ten
times that.
"""
from __future__ import annotations

from functools import cached_property
from typing import Sequence

import numpy as np

from .matrix import Structure
from .statespace import StateSpace


def _masks(s: Structure, words: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per transition: the places it needs (consumed or read), consumes, and marks."""
    need = np.zeros((len(s.transitions), words), dtype=np.uint64)
    take = np.zeros_like(need)
    give = np.zeros_like(need)
    for t, (pre, read, post) in enumerate(zip(s.pre, s.read, s.post)):
        for p in pre:
            take[t, p // 64] |= np.uint64(1 << (p % 64))
        for p in read:
            need[t, p // 64] |= np.uint64(1 << (p % 64))
        for p in post:
            give[t, p // 64] |= np.uint64(1 << (p % 64))
    need |= take
    return need, take, give


def _keys(rows: np.ndarray) -> np.ndarray:
    """Rows of words as sortable scalars: the word itself, or raw bytes for several words."""
    if rows.shape[1] == 1:
        return rows[:, 0]
    # big-endian words compare, byte by byte, like the integers they form
    return np.ascontiguousarray(rows.byteswap()).view(
        np.dtype((np.void, 8 * rows.shape[1]))).ravel()


def _all(rows: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Which rows contain every bit of ``mask``."""
    if rows.shape[1] == 1:
        return (rows[:, 0] & mask[0]) == mask[0]
    return np.all((rows & mask) == mask, axis=1)


class NotSafe(Exception):
    """A firing would put a second token in a place: the caller explores another way."""


def explore_packed(s: Structure, m0: Sequence[int], max_states: int, limit_error,
                   progress=None) -> "PackedStateSpace":
    """Breadth-first, a frontier at a time; raises :class:`NotSafe` at a second token."""
    words = max(1, (len(s.places) + 63) // 64)
    need, take, give = _masks(s, words)
    start = np.zeros((1, words), dtype=np.uint64)
    for p, k in enumerate(m0):
        if k:
            start[0, p // 64] |= np.uint64(1 << (p % 64))
    seen_keys = _keys(start).copy()
    rows = [start]              # kept only when a key is not the row itself
    frontier = start
    while len(frontier):
        if words == 1:
            fresh = _level_one_word(frontier[:, 0], seen_keys, need[:, 0], take[:, 0],
                                    give[:, 0])
            frontier = fresh.reshape(-1, 1)
        else:
            fresh, frontier = _level_rows(frontier, seen_keys, need, take, give)
        if not len(fresh):
            break
        if len(seen_keys) + len(fresh) > max_states:
            raise limit_error
        seen_keys = np.concatenate([seen_keys, fresh])
        seen_keys.sort(kind="stable")   # in place: two sorted runs, merged
        if words > 1:
            rows.append(frontier)
        if progress:
            progress(len(seen_keys), len(frontier))
    if words == 1:
        packed = seen_keys.reshape(-1, 1)
    else:
        packed = np.concatenate(rows)
        packed = packed[np.argsort(_keys(packed), kind="stable")]
    return PackedStateSpace(s, packed, _keys(start)[0], need, take, give)


def _unseen(keys: np.ndarray, seen: np.ndarray) -> np.ndarray:
    """The sorted, distinct ``keys`` (sorted already) that are not in ``seen`` (sorted)."""
    if len(keys) > 1:
        keys = keys[np.concatenate(([True], keys[1:] != keys[:-1]))]
    at = np.searchsorted(seen, keys)
    old = np.zeros(len(keys), dtype=bool)
    inside = at < len(seen)
    old[inside] = seen[at[inside]] == keys[inside]
    return keys[~old]


#: How many (marking, transition) pairs one vectorized step handles at most:
#: frontiers are cut in chunks so that memory stays bounded.
PAIRS = 1 << 21


def _chunks(n: int, transitions: int):
    step = max(1, PAIRS // max(1, transitions))
    for start in range(0, n, step):
        yield slice(start, min(n, start + step))


def _fire(rows: np.ndarray, need, take, give) -> np.ndarray:
    """Every successor of ``rows`` (one or several words), all transitions at once."""
    out = []
    one_word = rows.ndim == 1
    for part in _chunks(len(rows), len(need)):
        f = rows[part]
        if one_word:
            enabled = (f[:, None] & need[None, :]) == need[None, :]
        else:
            enabled = np.all((f[:, None, :] & need[None]) == need[None], axis=2)
        r, t = np.nonzero(enabled)
        if not len(r):
            continue
        rest = f[r] & ~take[t]
        if np.any(rest & give[t]):
            raise NotSafe
        out.append(rest | give[t])
    if not out:
        return rows[:0]
    return np.concatenate(out)


def _level_one_word(frontier, seen, need, take, give) -> np.ndarray:
    """The next breadth-first level, for markings of one word: sorted, new, distinct."""
    succ = _fire(frontier, need, take, give)
    succ.sort()
    return _unseen(succ, seen)


def _level_rows(frontier, seen, need, take, give) -> tuple[np.ndarray, np.ndarray]:
    """The next level for markings of several words: (new keys, new rows), sorted."""
    cand = _fire(frontier, need, take, give)
    if not len(cand):
        return np.zeros(0, dtype=seen.dtype), frontier[:0]
    keys = _keys(cand)
    order = np.argsort(keys, kind="stable")
    keys, cand = keys[order], cand[order]
    first = np.ones(len(keys), dtype=bool)
    first[1:] = keys[1:] != keys[:-1]
    keys, cand = keys[first], cand[first]
    at = np.searchsorted(seen, keys)
    old = np.zeros(len(keys), dtype=bool)
    inside = at < len(seen)
    old[inside] = seen[at[inside]] == keys[inside]
    return keys[~old], cand[~old]


class PackedMarkings(Sequence):
    """The markings by node, decoded one at a time into tuples of 0/1."""

    def __init__(self, space: "PackedStateSpace"):
        self.space = space

    def __len__(self) -> int:
        return self.space.states

    def __getitem__(self, node):
        if isinstance(node, slice):
            return [self[i] for i in range(*node.indices(len(self)))]
        if node < 0:
            node += len(self)
        row = self.space.packed[self.space.position(node)]
        return tuple(int(row[p // 64] >> np.uint64(p % 64)) & 1
                     for p in range(len(self.space.structure.places)))


class PackedStateSpace(StateSpace):
    """A reachability graph kept as its sorted, packed markings (see the module's documentation).

    Node 0 is the initial marking, as in every :class:`StateSpace`; the
    others are numbered in the sorted order of the markings.
    """

    def __init__(self, structure: Structure, packed: np.ndarray, start_key,
                 need: np.ndarray, take: np.ndarray, give: np.ndarray):
        self.structure = structure
        self.packed = packed          # (markings, words) uint64, sorted
        self.keys = _keys(packed)     # the same memory when one word is enough
        self.need, self.take, self.give = need, take, give
        self.coverability = False
        self.start = int(np.searchsorted(self.keys, start_key))

    # -- node numbers: sorted positions with the initial marking swapped to 0 --------

    def position(self, node):
        """Sorted position of a node (or an array of them): 0 and ``start`` trade places."""
        if isinstance(node, np.ndarray):
            return np.where(node == 0, self.start, np.where(node == self.start, 0, node))
        return self.start if node == 0 else (0 if node == self.start else node)

    node_of = position   # swapping is its own inverse

    @property
    def states(self) -> int:
        return len(self.packed)

    @cached_property
    def bound(self) -> float:
        return 1 if np.any(self.packed) else 0

    @cached_property
    def markings(self) -> PackedMarkings:  # type: ignore[override]
        return PackedMarkings(self)

    def _lookup(self, rows: np.ndarray) -> np.ndarray:
        """Sorted positions of ``rows`` (-1 for rows that are not reachable markings)."""
        keys = _keys(rows)
        at = np.searchsorted(self.keys, keys)
        inside = at < len(self.keys)
        found = np.zeros(len(keys), dtype=bool)
        found[inside] = self.keys[at[inside]] == keys[inside]
        return np.where(found, at, -1)

    # -- successors, counted or listed -----------------------------------------------

    @cached_property
    def out_degree(self) -> np.ndarray:  # type: ignore[override]
        degree = np.zeros(self.states, dtype=np.int32)
        for t in range(len(self.need)):
            degree += _all(self.packed, self.need[t])
        return degree[self.position(np.arange(self.states))]

    @cached_property
    def terminal(self) -> list[int]:  # type: ignore[override]
        return sorted(np.nonzero(self.out_degree == 0)[0].tolist())

    @cached_property
    def _edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The explicit edge list, in node order, built only when asked for."""
        src, trans, dst = [], [], []
        for t in range(len(self.need)):
            ok = np.nonzero(_all(self.packed, self.need[t]))[0]
            if not len(ok):
                continue
            after = self._lookup((self.packed[ok] & ~self.take[t]) | self.give[t])
            src.append(self.node_of(ok))
            dst.append(self.node_of(after))
            trans.append(np.full(len(ok), t))
        if not src:
            empty = np.zeros(0, dtype=np.int32)
            return empty, empty, empty
        src_, trans_, dst_ = (np.concatenate(x).astype(np.int32) for x in (src, trans, dst))
        order = np.lexsort((trans_, src_))
        return src_[order], trans_[order], dst_[order]

    @property
    def src(self):  # type: ignore[override]
        return self._edges[0]

    @property
    def trans(self):  # type: ignore[override]
        return self._edges[1]

    @property
    def dst(self):  # type: ignore[override]
        return self._edges[2]

    # -- reachability, backwards, by unfiring ------------------------------------------

    def can_reach(self, targets: Sequence[int]) -> list[bool]:
        """For every node, whether one of ``targets`` is reachable from it."""
        seen = np.zeros(self.states, dtype=bool)       # by sorted position
        frontier = _distinct(np.sort(self.position(np.asarray(list(targets), dtype=np.int64))))
        seen[frontier] = True
        while len(frontier):
            nxt = self._predecessors(frontier)
            nxt.sort()
            nxt = _distinct(nxt)
            frontier = nxt[~seen[nxt]]
            seen[frontier] = True
        return seen[self.position(np.arange(self.states))].tolist()

    def _predecessors(self, frontier: np.ndarray) -> np.ndarray:
        """Positions of the markings one firing before those at ``frontier``: unfire all."""
        one_word = self.packed.shape[1] == 1
        need, take, give = ((m[:, 0] for m in (self.need, self.take, self.give)) if one_word
                            else (self.need, self.take, self.give))
        after_all = self.keys[frontier] if one_word else self.packed[frontier]
        found = []
        for part in _chunks(len(after_all), len(need)):
            after = after_all[part]
            if one_word:
                marked = (after[:, None] & give[None, :]) == give[None, :]
            else:
                marked = np.all((after[:, None, :] & give[None]) == give[None], axis=2)
            r, t = np.nonzero(marked)
            later = after[r]
            before = (later & ~give[t]) | take[t]    # the only marking t could come from
            if one_word:
                ok = ((before & need[t]) == need[t]) & (((before & ~take[t]) | give[t]) == later)
            else:
                ok = (np.all((before & need[t]) == need[t], axis=1)
                      & np.all(((before & ~take[t]) | give[t]) == later, axis=1))
            if ok.any():
                at = self._lookup(before[ok].reshape(-1, 1) if one_word else before[ok])
                found.append(at[at >= 0])
        return np.concatenate(found) if found else np.zeros(0, dtype=np.int64)


def _distinct(sorted_values: np.ndarray) -> np.ndarray:
    if len(sorted_values) < 2:
        return sorted_values
    return sorted_values[np.concatenate(([True], sorted_values[1:] != sorted_values[:-1]))]
