"""The reachability graph of a safe net, explored one marking at a time in compiled code.

One of the two safe-net explorers behind :func:`mcl2pnml.analysis.statespace.explore.explore`,
for the same nets as :mod:`mcl2pnml.analysis.statespace.packed` (1-safe, unit weights):
markings are rows of bits packed into 64-bit words
(:mod:`mcl2pnml.analysis.statespace.packedmarkings`), and firing a transition is three bit
operations (``need`` covered, ``keep`` the rest, ``give`` the outputs). Here
the loop is the textbook one, a queue of markings and a hash set, compiled
to machine code by numba, so each (marking, transition) pair costs a few
nanoseconds instead of the fixed cost of a numpy call per breadth-first
level: small and deep state spaces (a compiled mission runs its tasks one
after another) gain most.

* The queue is the array of markings found, in the order found; the set is
  an open-addressing table with linear probing, at most 70% full. With one
  word the table holds the markings themselves (0 marks an empty slot, and
  the empty marking is remembered apart); with several it holds indices into
  the queue, and a probe compares the words, so no two markings are ever
  merged.
* The compiled loop runs in slices of :data:`SLICE` expansions, handing
  back to Python in between: the caller's progress report is called, and
  Ctrl-C is honoured, at least every few tenths of a second.
* The result is a :class:`~mcl2pnml.analysis.statespace.packedmarkings.PackedStateSpace`, the same
  value the numpy explorer returns, so terminal markings, reachability by
  unfiring and the edge list come from the same code whichever explorer ran.

Markings take 8 bytes a word in the queue (up to twice that, as it grows by
doubling) plus 11 to 23 bytes a word in the table; with one word the queue
is then sorted in place to become the state space's keys.
"""
from __future__ import annotations

import importlib.util
from typing import Sequence

import numpy as np

from mcl2pnml.core.net import NetBuilder
from mcl2pnml.core.structure import Structure, structure

from mcl2pnml.analysis.statespace.packedmarkings import (Firing, KeyCollision, NotSafe, PackedStateSpace,
                                     key_index, marking_row, masks, place_weights, touched,
                                     word_count)
# bound under this module's own name, so that the keys of this explorer alone
# can be replaced (the key-collision tests do)
from mcl2pnml.analysis.statespace.packedmarkings import keys_of as _keys

#: How many markings one call of the compiled loop expands before it hands back to Python.
SLICE = 1 << 19


def footprint(s: Structure) -> int:
    """Bytes a marking costs at most: the queue (doubling), the table, the final sort."""
    return 24 * word_count(s) + 48


def available() -> bool:
    """Whether numba is installed, so that this explorer can run (numba is not imported)."""
    return importlib.util.find_spec("numba") is not None


_ran = False   # whether the compiled loops have run in this process, so are loaded


def loaded() -> bool:
    """Whether the compiled loops have been loaded in this process (by a run or :func:`warm_up`)."""
    return _ran


def mark_loaded() -> None:
    """Record that compiled code (this explorer's or the counter one's) has run here."""
    global _ran
    _ran = True


def warm_up() -> None:
    """Load the compiled loops now (importing numba, reading or filling its cache).

    What the first exploration would otherwise pay: most of a second in a
    fresh process, much more the first time ever, when numba compiles them.
    """
    for places in (1, 65):   # one word, then two
        b = NetBuilder("warm-up")
        for p in range(places):
            b.place(f"p{p}", 1 if p == 0 else 0)
        b.transition("t")
        b.arc("p0", "t")
        b.arc("t", f"p{places - 1}")
        s = structure(b.build())
        explore_compiled(s, s.initial_vector(), 10, RuntimeError("warm-up"))


def native_available() -> bool:
    """Whether the loops in C were built when mcl2pnml was installed (they need a C compiler)."""
    try:
        from mcl2pnml.analysis.statespace.loops import native_safe as _native_loops  # noqa: F401
    except ImportError:
        return False
    return True


def explore_native(s: Structure, m0: Sequence[int], max_states: int, limit_error,
                   progress=None) -> PackedStateSpace:
    """:func:`explore_compiled` with the loops in C (:mod:`mcl2pnml.analysis.statespace.loops.native_safe`)."""
    from mcl2pnml.analysis.statespace.loops import native_safe as kernels
    return _explore(kernels, s, m0, max_states, limit_error, progress)


def explore_compiled(s: Structure, m0: Sequence[int], max_states: int, limit_error,
                     progress=None) -> PackedStateSpace:
    """Breadth-first from ``m0``; raises :class:`NotSafe` at a second token in a place."""
    global _ran
    from mcl2pnml.analysis.statespace.loops import numba_safe as kernels  # imports numba: 0.3 s, so only now
    space = _explore(kernels, s, m0, max_states, limit_error, progress)
    _ran = True
    return space


def _explore(kernels, s: Structure, m0: Sequence[int], max_states: int, limit_error,
             progress) -> PackedStateSpace:
    words = word_count(s)
    need, take, give = masks(s, words)
    start = marking_row(m0, words)
    if words == 1:
        rows = _owned(_run_one_word(kernels, need[:, 0], ~take[:, 0], give[:, 0], start[0, 0],
                                    max_states, limit_error, progress))
        rows.sort()   # in place: the markings are their own keys
        keys = rows if rows.base is None or 4 * rows.base.size < 5 * rows.size else rows.copy()
        packed = keys.reshape(-1, 1)
    else:
        rows = _owned(_run_words(kernels, need, ~take, give, start[0], max_states, limit_error,
                                 progress))
        keys = _keys(rows)
        order = np.argsort(keys)
        keys = keys[order]
        if len(keys) > 1 and np.any(keys[1:] == keys[:-1]):
            raise KeyCollision   # distinct markings, one key: the exact explorer takes over
        if hasattr(kernels, "permute_rows") and rows.flags.owndata:
            packed = kernels.permute_rows(rows, order)   # no second copy of the markings
        else:
            packed = rows[order]
        del rows, order
    return PackedStateSpace(s, packed, keys, _keys(start)[0], Firing.by(need, need, take, give))


def _owned(rows: np.ndarray) -> np.ndarray:
    """The found markings, the queue's spare rows given back where the queue can shrink in
    place (it doubles as it grows: up to half of it is spare)."""
    queue = rows.base
    if queue is None or not queue.flags.owndata or queue.base is not None:
        return rows
    count = len(rows)
    del rows   # no view may outlive the resize
    queue.resize((count, *queue.shape[1:]), refcheck=False)
    return queue


def _drive(kernels, step, masks: tuple, state: tuple, max_states: int, limit_error,
           progress) -> np.ndarray:
    """Call the compiled ``step`` a slice at a time until the queue is exhausted.

    ``state`` is what the loop carries from one slice to the next (the queue,
    its length, its head, the table...); the markings found are returned.
    """
    while True:
        *state, code = step(*masks, *state, max_states, SLICE)
        queue, count, head = state[:3]
        if code == kernels.NOT_SAFE:
            raise NotSafe
        if code == kernels.LIMIT:
            limit_error.explored = count
            limit_error.deadlocks = _dead(queue[:head], masks[0])
            raise limit_error
        if progress:
            progress(count, count - head)
        if head == count:
            return queue[:count]


def _dead(rows: np.ndarray, need: np.ndarray) -> int:
    """How many of ``rows`` (markings, or one word each) enable no transition."""
    if not len(rows):   # stopped before any marking was explored (a limit of one or two)
        return 0
    rows = rows.reshape(len(rows), -1)
    need = need.reshape(len(need), -1)
    dead = 0
    for start in range(0, len(rows), 1 << 12):
        part = rows[start:start + (1 << 12), None, :]
        dead += int((~np.all(part & need == need, axis=2)).all(axis=1).sum())
    return dead


def _run_one_word(kernels, need, keep, give, m0, max_states, limit_error,
                  progress) -> np.ndarray:
    bits = 12
    queue = kernels.new_queue(1, max_states, len(need))
    queue[0] = m0
    table = np.zeros(1 << bits, dtype=np.uint64)
    table[kernels.slot_of_word(m0, bits)] = m0   # an empty marking stays out, as 0 is "free"
    return _drive(kernels, kernels.step_one_word,
                  (need, keep, give, *key_index(need, place_weights(np.array([m0], dtype=np.uint64)))),
                  (queue, 1, 0, table, bits, m0 == 0), max_states, limit_error, progress)


def _run_words(kernels, need, keep, give, m0, max_states, limit_error,
               progress) -> np.ndarray:
    bits = 12
    queue = kernels.new_queue(len(m0), max_states, len(need))
    queue[0] = m0
    table = kernels.start_table(m0, bits)
    return _drive(kernels, kernels.step_words,
                  (need, keep, give, *touched(need), *touched(need, ~keep, give),
                   *key_index(need, place_weights(m0.reshape(1, -1)))),
                  (queue, 1, 0, table, bits),
                  max_states, limit_error, progress)
