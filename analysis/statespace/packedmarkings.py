"""Markings of a safe net packed into 64-bit words, and the state space they make.

For a 1-safe net with unit weights (every net this project compiles), a
marking is a row of bits, one per place, packed into 64-bit words, and
firing a transition is three bit operations (``need`` covered, ``keep`` the
rest, ``give`` the outputs). This module owns what the two safe-net
explorers share, :mod:`mcl2pnml.analysis.statespace.packed` (numpy, a frontier at a time)
and :mod:`mcl2pnml.analysis.statespace.compiled` (the loops, a marking at a time): the masks of
the transitions, built from the core's pre-sets, •t and post-sets
(:class:`~mcl2pnml.core.structure.Structure`); the 64-bit key of a marking
(the marking itself up to 64 places, a hash of its words beyond); and
:class:`PackedStateSpace`, the value both return.

A :class:`PackedStateSpace` keeps only the markings, packed (8 bytes each up
to 64 places), sorted by key, decoded when asked for. Edges are not stored.
What the analysis asks of them is answered by firing again, a whole array at
a time: a marking is terminal when no transition is enabled in it; the
markings that can reach a set are found backwards, by *unfiring* each
transition on the frontier (for a safe net the marking before a firing is
determined by the one after) and keeping the results that are reachable
markings and really fire into it: in the loops in C where they were built
(:func:`mcl2pnml.analysis.statespace.loops.backends.c_loops`) a marking at a
time, each predecessor found in a hash table of the markings, else in numpy
a frontier at a time. The explicit edge list (``src``,
``trans``, ``dst``) is built only if someone asks for it. Transitions are
grouped by the words their places lie in, so that testing them costs a few
operations per group, not per transition.
"""
from __future__ import annotations

from functools import cached_property
from typing import NamedTuple, Sequence

import numpy as np

from mcl2pnml.core.structure import Structure

from mcl2pnml.analysis.statespace.general import DecodedMarkings, EdgesOnDemand, StateSpace
from mcl2pnml.analysis.statespace.loops.backends import c_loops
from mcl2pnml.analysis.statespace.loops.interface import KeyIndex, Loops, Rows, SafeNet


def masks(s: Structure, words: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per transition: the places it needs (•t: consumed or read), consumes, and marks."""
    return masks_of(s.transition_inputs, words), masks_of(s.pre, words), masks_of(s.post, words)


def masks_of(place_sets, words: int) -> np.ndarray:
    """One row of ``words`` 64-bit words per set of place indices."""
    bits = [sum(1 << p for p in places) for places in place_sets]
    return np.array([[(b >> (64 * w)) & 0xFFFF_FFFF_FFFF_FFFF for w in range(words)]
                     for b in bits], dtype=np.uint64).reshape(len(bits), words)


def touched(*masks: np.ndarray) -> Rows:
    """The words each transition's masks have bits in, as compressed rows.

    So that the loops test and fire a transition on those words only.
    """
    rows, words = np.nonzero(np.bitwise_or.reduce(masks) != 0)
    ptr = np.zeros(len(masks[0]) + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=len(masks[0])), out=ptr[1:])
    return Rows(ptr, words.astype(np.int64))


def key_index(test: np.ndarray, weight: np.ndarray) -> KeyIndex:
    """Each transition keyed on one place of its ``test`` mask, as compressed rows by place.

    ``test`` is ``(transitions, words)``: what must be marked for the
    transition to be worth trying (its needed places when firing, its
    outputs when unfiring). A marking then tries only the transitions keyed
    on its marked places (:class:`~mcl2pnml.analysis.statespace.loops.interface.KeyIndex`), so
    the key is the place of the mask least often marked: ``weight`` says how
    often each place is (:func:`place_weights`), the lowest-numbered place
    winning a tie. Place p's transitions are ``by_place.of(p)``; ``free`` are
    those that test nothing.
    """
    words = len(weight) // 64
    test = np.ascontiguousarray(test.reshape(len(test), words))
    place = np.full(len(test), -1, dtype=np.int64)
    for first in range(0, len(test), 4096):   # a few MB of bits at a time
        bits = np.unpackbits(test[first:first + 4096].view(np.uint8), axis=1,
                             bitorder="little").astype(bool)
        scored = np.where(bits, weight, np.inf)
        best = np.argmin(scored, axis=1)
        place[first:first + 4096] = np.where(bits.any(axis=1), best, -1)
    keyed = np.nonzero(place >= 0)[0]
    order = keyed[np.argsort(place[keyed], kind="stable")]
    ptr = np.zeros(words * 64 + 1, dtype=np.int64)
    np.cumsum(np.bincount(place[keyed], minlength=words * 64), out=ptr[1:])
    return KeyIndex(Rows(ptr, order.astype(np.int64)),
                    np.nonzero(place < 0)[0].astype(np.int64))


def safe_net(need: np.ndarray, take: np.ndarray, give: np.ndarray,
             weight: np.ndarray) -> SafeNet:
    """The loops' tables of a safe net's masks (:func:`masks`), each transition keyed on
    its needed place least often marked by ``weight`` (:func:`place_weights`)."""
    need, take, give = (np.ascontiguousarray(a) for a in (need, take, give))
    return SafeNet(need, np.ascontiguousarray(~take), give, touched(need),
                   touched(need, take, give), key_index(need, weight))


def place_weights(rows: np.ndarray, sample: int = 1 << 12) -> np.ndarray:
    """How often each place is marked in ``rows`` (markings, one row of words each),
    counted on an even sample of at most ``sample`` of them: the weights of
    :func:`key_index`. With the initial marking alone, its marked places weigh
    1 and the others 0: places marked at the start (mutexes, idle states)
    stay marked in most markings."""
    rows = rows.reshape(len(rows), -1)
    step = max(1, len(rows) // sample)
    bits = np.unpackbits(np.ascontiguousarray(rows[::step]).view(np.uint8), axis=1,
                         bitorder="little")
    return bits.sum(axis=0, dtype=np.float64)


def word_count(s: Structure) -> int:
    """64-bit words per marking of ``s``: one per 64 places, at least one."""
    return max(1, (len(s.places) + 63) // 64)


def marking_row(m0: Sequence[int], words: int) -> np.ndarray:
    """A marking of 0/1 counts as one row of ``words`` words (shape ``(1, words)``)."""
    return masks_of([[p for p, k in enumerate(m0) if k]], words)


class Firing(NamedTuple):
    """The transitions' masks in an order where those that test the same words are adjacent.

    ``groups`` lists, for each run of transitions (a slice of the arrays),
    the words its ``test`` masks have bits in: a transition's places are
    few and numbered close together, so most test one word, and testing a
    group is a few operations on a slice instead of one per word and
    transition.
    """

    test: np.ndarray       # what must be marked: needed places (firing), or given ones (unfiring)
    need: np.ndarray
    keep: np.ndarray       # the complement of the places a transition consumes
    take: np.ndarray
    give: np.ndarray
    ids: np.ndarray        # the transition (its index in the net) of each row
    groups: tuple[tuple[int, int, tuple[int, ...]], ...]

    @classmethod
    def by(cls, test: np.ndarray, need: np.ndarray, take: np.ndarray,
           give: np.ndarray) -> "Firing":
        # the words a mask has bits in, as a number (bit w: word w), to sort by
        signature = (test != 0).astype(np.int64) @ (np.int64(1) << np.arange(test.shape[1]))
        pick = np.argsort(signature, kind="stable")
        signature = signature[pick]
        cuts = [0, *(np.flatnonzero(signature[1:] != signature[:-1]) + 1).tolist(), len(test)]
        groups = [(a, b, tuple(w for w in range(test.shape[1]) if signature[a] >> w & 1))
                  for a, b in zip(cuts, cuts[1:]) if b > a]
        return cls(test[pick], need[pick], ~take[pick], take[pick], give[pick], pick,
                   tuple(groups))

    def tested(self, rows: np.ndarray) -> np.ndarray:
        """(rows, transitions) table: whether each row has every bit of each test mask."""
        out = np.empty((len(rows), len(self.test)), dtype=bool)
        for a, b, words in self.groups:
            if not words:
                out[:, a:b] = True
                continue
            m = self.test[a:b, words[0]]
            np.equal(rows[:, words[0], None] & m, m, out=out[:, a:b])
            for w in words[1:]:
                m = self.test[a:b, w]
                out[:, a:b] &= (rows[:, w, None] & m) == m
        return out


#: The two odd multipliers of MurmurHash3's 64-bit finaliser (``fmix64``).
_MIX1, _MIX2 = np.uint64(0xFF51AFD7ED558CCD), np.uint64(0xC4CEB9FE1A85EC53)
_SHIFT = np.uint64(33)


def keys_of(rows: np.ndarray) -> np.ndarray:
    """Rows of words as sortable 64-bit keys: the word itself, or a hash of several.

    A hash sorts and searches as fast as a single word does, where raw bytes
    (numpy's void type) compare byte by byte, ten times slower. Two markings
    may then share a key; each explorer makes sure none ever do in one state
    space (or raises :class:`KeyCollision`), so that a key still names one
    marking exactly.

    Each word is folded in, then the whole mixed by a full avalanche step
    (MurmurHash3's finaliser, a bijection in which every bit of the input
    moves about half the bits of the output). A weaker step, one multiply and
    one shift, let two markings that differ in the top bits of two words share
    a key: two of the 4,773 markings of a small mission did.
    """
    if rows.shape[1] == 1:
        return rows[:, 0]
    h = rows[:, 0].copy()
    with np.errstate(over="ignore"):
        for w in range(rows.shape[1]):
            if w:
                h ^= rows[:, w]
            h ^= h >> _SHIFT
            h *= _MIX1
            h ^= h >> _SHIFT
            h *= _MIX2
            h ^= h >> _SHIFT
    return h


def search(sorted_keys: np.ndarray, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where ``keys`` sort in ``sorted_keys`` (distinct), and whether each is there."""
    at = np.searchsorted(sorted_keys, keys)
    found = np.zeros(len(keys), dtype=bool)
    inside = at < len(sorted_keys)
    found[inside] = sorted_keys[at[inside]] == keys[inside]
    return at, found


class KeyCollision(Exception):
    """Two reachable markings of several words share a key (once in 2^64 pairs)."""


def _covers(rows: np.ndarray, masks: np.ndarray) -> np.ndarray:
    """Whether rows contain every bit of masks (word axis last; the others broadcast).

    A loop over the few words rather than ``np.all(..., axis=-1)``: numpy
    reduces a short last axis several times slower than it ANDs whole arrays.
    """
    out = (rows[..., 0] & masks[..., 0]) == masks[..., 0]
    for w in range(1, rows.shape[-1]):
        out &= (rows[..., w] & masks[..., w]) == masks[..., w]
    return out


def same(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row by row equality of two arrays of words (word axis last)."""
    out = a[..., 0] == b[..., 0]
    for w in range(1, a.shape[-1]):
        out &= a[..., w] == b[..., w]
    return out


class NotSafe(Exception):
    """A firing would put a second token in a place: the caller explores another way."""


#: How many (marking, transition) pairs one vectorized step handles at most:
#: frontiers are cut in chunks so that memory stays bounded.
PAIRS = 1 << 21


def chunks(n: int, transitions: int):
    step = max(1, PAIRS // max(1, transitions))
    for start in range(0, n, step):
        yield slice(start, min(n, start + step))


class PackedMarkings(DecodedMarkings):
    """The markings by node, decoded one at a time into tuples of 0/1."""

    def decode(self, node: int) -> tuple[int, ...]:
        # the row's bytes unpacked at once, least significant bit first (place p is bit
        # p % 64 of word p // 64): a shift per place cost ten times more, and the
        # contract's checks decode every marking several times
        row = np.ascontiguousarray(self.space.packed[self.space.position(node)], dtype="<u8")
        bits = np.unpackbits(row.view(np.uint8), bitorder="little")
        return tuple(bits[:len(self.space.structure.places)].tolist())

    def __iter__(self):
        """Every marking in node order, unpacked a chunk of rows at a time (the same tuples
        as :meth:`decode`, without a numpy call per marking)."""
        space, places = self.space, len(self.space.structure.places)
        for part in chunks(space.states, max(1, places // 8)):
            rows = space.packed[space.position(np.arange(part.start, part.stop))]
            bits = np.unpackbits(np.ascontiguousarray(rows, dtype="<u8").view(np.uint8),
                                 axis=1, bitorder="little")
            yield from map(tuple, bits[:, :places].tolist())


class PackedStateSpace(EdgesOnDemand, StateSpace):
    """A reachability graph kept as its sorted, packed markings (see the module's documentation).

    Node 0 is the initial marking, as in every :class:`StateSpace`; the
    others are numbered in the sorted order of their keys.
    """

    def __init__(self, structure: Structure, packed: np.ndarray, keys: np.ndarray, start_key,
                 firing: Firing, loops: Loops | None = None):
        self.structure = structure
        self.loops = loops            # the loops that explored it, which answer for it too
        self.packed = packed          # (markings, words) uint64, in the order of their keys
        self.keys = keys              # sorted, distinct; the same memory when one word is enough
        self.firing = firing
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

    def tokens(self, place: int) -> np.ndarray:  # type: ignore[override]
        word = self.packed[self.position(np.arange(self.states)), place // 64]
        return ((word >> np.uint64(place % 64)) & np.uint64(1)).astype(np.float64)

    def _lookup(self, rows: np.ndarray) -> np.ndarray:
        """Sorted positions of ``rows`` (-1 for rows that are not reachable markings)."""
        at, found = search(self.keys, keys_of(rows))
        if rows.shape[1] > 1:
            # a key names one reachable marking; another marking may share it
            hit = np.flatnonzero(found)
            found[hit] = same(rows[hit], self.packed[at[hit]])
        return np.where(found, at, -1)

    # -- successors, counted or listed -----------------------------------------------

    def _enabled(self):
        """(sorted positions, rows of :attr:`firing`) of every enabled pair, a chunk at a time."""
        for part in chunks(self.states, len(self.firing.test)):
            r, j = np.nonzero(self.firing.tested(self.packed[part]))
            yield r + part.start, j

    def _kernels(self) -> Loops | None:
        """The loops that explored it; else the loops in C when they were built; else None:
        numpy's whole arrays, faster than the plain-Python loops."""
        return self.loops or c_loops()

    @cached_property
    def out_degree(self) -> np.ndarray:  # type: ignore[override]
        kernels = self._kernels()
        if kernels is not None:
            degree = kernels.out_degree(self.packed, self._net)
        else:
            degree = np.zeros(self.states, dtype=np.int32)
            for r, _ in self._enabled():
                degree += np.bincount(r, minlength=self.states).astype(np.int32)
        return degree[self.position(np.arange(self.states))]

    @cached_property
    def terminal(self) -> list[int]:  # type: ignore[override]
        if "out_degree" not in self.__dict__:
            kernels = self._kernels()
            if kernels is not None:
                # whether each marking enables anything: the first enabled transition says
                alive = kernels.live(self.packed, self._net)
                return sorted(self.node_of(np.nonzero(alive == 0)[0]).tolist())
        return sorted(np.nonzero(self.out_degree == 0)[0].tolist())

    @cached_property
    def _edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The explicit edge list, in node order, built only when asked for."""
        f = self.firing
        kernels = self._kernels()
        if kernels is not None:
            # already in node order (position and node_of are one permutation)
            return kernels.edges(self.packed, self._net, f.ids,
                                 self.position(np.arange(self.states)))
        src, trans, dst = [], [], []
        for r, j in self._enabled():
            after = self._lookup((self.packed[r] & f.keep[j]) | f.give[j])
            src.append(self.node_of(r))
            dst.append(self.node_of(after))
            trans.append(f.ids[j])
        if not src:
            empty = np.zeros(0, dtype=np.int32)
            return empty, empty, empty
        src_, trans_, dst_ = (np.concatenate(x).astype(np.int32) for x in (src, trans, dst))
        order = np.lexsort((trans_, src_))
        return src_[order], trans_[order], dst_[order]

    # -- reachability, backwards, by unfiring ------------------------------------------

    def can_reach(self, targets: Sequence[int]) -> list[bool]:
        """For every node, whether one of ``targets`` is reachable from it.

        In the loops (a breadth-first search, unfiring one marking at a
        time, each predecessor found in a hash table of the markings) where
        they were built in C; otherwise in numpy, a frontier at a time
        (:meth:`_can_reach_numpy`). Both give the same answer.
        """
        kernels = self._kernels()
        if kernels is None:
            return self._can_reach_numpy(targets)
        return self._reaching(kernels, targets)[self.position(np.arange(self.states))].tolist()

    def always_can_reach(self, targets: Sequence[int]) -> bool:
        kernels = self._kernels()
        if kernels is None:
            return all(self._can_reach_numpy(targets))
        return bool(self._reaching(kernels, targets).all())

    def _reaching(self, kernels: Loops, targets: Sequence[int]) -> np.ndarray:
        """By sorted position, whether the marking reaches one of ``targets`` (the loops)."""
        seen = np.zeros(self.states, dtype=np.bool_)
        # distinct(sort), not np.unique, which imports numpy.ma (7 ms of start-up)
        frontier = distinct(np.sort(self.position(np.asarray(list(targets), dtype=np.int64))))
        seen[frontier] = True
        # unfiring tries the transitions keyed on a place they mark
        unfire = key_index(self.firing.give, self._weights)
        return kernels.backward(self.packed, self._net, unfire, seen, frontier)

    @cached_property
    def _net(self) -> SafeNet:
        """The loops' tables of the firing's masks, built once for every question."""
        f = self.firing
        return safe_net(f.need, f.take, f.give, self._weights)

    @cached_property
    def _weights(self) -> np.ndarray:
        """How often each place is marked here, on a sample (:func:`place_weights`)."""
        return place_weights(self.packed)

    def _can_reach_numpy(self, targets: Sequence[int]) -> list[bool]:
        """:meth:`can_reach` in numpy: a breadth-first frontier unfired at once."""
        seen = np.zeros(self.states, dtype=bool)       # by sorted position
        frontier = distinct(np.sort(self.position(np.asarray(list(targets), dtype=np.int64))))
        seen[frontier] = True
        while len(frontier):
            nxt = self._predecessors(frontier)
            nxt.sort()
            nxt = distinct(nxt)
            frontier = nxt[~seen[nxt]]
            seen[frontier] = True
        return seen[self.position(np.arange(self.states))].tolist()

    @cached_property
    def _unfiring(self) -> Firing:
        """The transitions grouped by the places they mark: what unfiring tests first."""
        f = self.firing
        return Firing.by(f.give, f.need, f.take, f.give)

    def _predecessors(self, frontier: np.ndarray) -> np.ndarray:
        """Positions of the markings one firing before those at ``frontier``: unfire all."""
        u = self._unfiring
        after_all = self.packed[frontier]
        found = []
        for part in chunks(len(after_all), len(u.test)):
            after = after_all[part]
            r, t = np.nonzero(u.tested(after))
            later = after[r]
            before = (later & ~u.give[t]) | u.take[t]    # the only marking t could come from
            ok = _covers(before, u.need[t]) & same((before & u.keep[t]) | u.give[t], later)
            if ok.any():
                at = self._lookup(before[ok])
                found.append(at[at >= 0])
        return np.concatenate(found) if found else np.zeros(0, dtype=np.int64)


def distinct(sorted_values: np.ndarray) -> np.ndarray:
    """The distinct values of a sorted array, in order."""
    if len(sorted_values) < 2:
        return sorted_values
    return sorted_values[np.concatenate(([True], sorted_values[1:] != sorted_values[:-1]))]
