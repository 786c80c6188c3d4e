"""The exploration loops' one interface: what every backend takes and gives back, typed.

The loops that explore markings and search the graphs they make exist once
per backend: in C (:mod:`mcl2pnml.analysis.statespace.loops.c`, built at
install from ``_native.c``) and in plain Python
(:mod:`mcl2pnml.analysis.statespace.loops.python`, the reference, which
serves where C was not built). Both implement :class:`Loops` on the values
defined here, so that a caller names a net's tables and a search's state
once, as a value, instead of some twenty positional arguments; the C
signatures are known to the C backend's wrapper alone.

The algorithms are those of the explicit-state textbook (a breadth-first
queue of markings and a hash set of them; Clarke, Grumberg and Peled,
*Model Checking*, ch. 4): a safe net's markings are rows of bits packed into
64-bit words (:mod:`mcl2pnml.analysis.statespace.packedmarkings`), a bounded
net's are counters packed into words
(:mod:`mcl2pnml.analysis.statespace.counters`). The state of a search is
returned, never changed in place as far as the caller sees: each step gives
a new :class:`SafeSearch` (or :class:`CounterSearch`, :class:`ProductSearch`)
whose arrays the backend may have grown, with a :class:`Code` saying why
it stopped.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Protocol

import numpy as np


class Code(enum.IntEnum):
    """Why a step of a search handed back (the values the C loops return)."""

    GOING = 0
    """Its budget of expansions is spent, or the queue is exhausted (head == count)."""
    NOT_SAFE = 1
    """A firing would put a second token in a place: the net is not safe."""
    LIMIT = 2
    """``max_states`` markings are found and another one was met."""
    OVERFLOW = 5
    """A counter would not fit its field; ``info`` is the place (counters only)."""
    GROWING = 6
    """A transition that only adds tokens is enabled: the net is unbounded (counters only)."""
    FOUND_BAD = 7
    """The observer rejected a prefix: ``found`` is the row (products only)."""
    FOUND_DEAD = 8
    """A dead marking with an obligation open: ``found`` is the row (products only)."""


# -- a safe net's tables ---------------------------------------------------------------------

@dataclass(frozen=True)
class Rows:
    """Sets of integers as compressed rows: row i is ``items[ptr[i]:ptr[i + 1]]``."""

    ptr: np.ndarray
    items: np.ndarray

    def of(self, i: int) -> np.ndarray:
        return self.items[self.ptr[i]:self.ptr[i + 1]]

    @classmethod
    def of_sets(cls, rows) -> "Rows":
        """Sets (or lists) of integers, each row sorted."""
        rows = [sorted(r) for r in rows]
        ptr = np.zeros(len(rows) + 1, dtype=np.int64)
        np.cumsum([len(r) for r in rows], out=ptr[1:])
        return cls(ptr, np.array([x for r in rows for x in r], dtype=np.int64))


@dataclass(frozen=True)
class KeyIndex:
    """Each transition keyed on one place it cannot do without
    (:func:`~mcl2pnml.analysis.statespace.packedmarkings.key_index`): a marking tries only
    the transitions keyed on its marked places (``by_place``), and those testing nothing
    (``free``), in that order: ``free`` first, then place by place upwards."""

    by_place: Rows
    free: np.ndarray


@dataclass(frozen=True)
class SafeNet:
    """A safe net's transitions as masks of 64-bit words, one row a transition.

    A transition is enabled when every ``need`` bit is set (consumed and read places);
    firing it keeps the ``keep`` bits and sets the ``give`` ones. ``needed`` and
    ``touched`` are the words each transition tests and changes
    (:func:`~mcl2pnml.analysis.statespace.packedmarkings.touched`); ``key`` which
    transitions a marking tries.
    """

    need: np.ndarray       # (transitions, words) uint64
    keep: np.ndarray       # the complement of the places a transition consumes
    give: np.ndarray
    needed: Rows
    touched: Rows
    key: KeyIndex

    @property
    def take(self) -> np.ndarray:
        return ~self.keep

    @property
    def words(self) -> int:
        return self.need.shape[1]

    @property
    def transitions(self) -> int:
        return self.need.shape[0]


@dataclass(frozen=True)
class SafeSearch:
    """A safe net's breadth-first search between two steps.

    ``queue`` holds the markings found in the order found (its first ``count`` rows;
    ``head`` is the next to expand); ``table`` is the backend's set of them (opaque to
    the caller; ``bits``: its size as a power of two); ``zero_seen`` whether the empty
    marking was found (the C loop on one word keeps it apart).
    """

    queue: np.ndarray
    count: int
    head: int
    table: object
    bits: int
    zero_seen: bool = False
    code: Code = Code.GOING

    def found(self) -> np.ndarray:
        return self.queue[:self.count]


# -- a bounded net's tables ------------------------------------------------------------------

@dataclass(frozen=True)
class Fields:
    """Per transition, counters of the marking as compressed rows of fields: row t's fields
    are ``ptr[t]`` to ``ptr[t + 1]``, each at ``word``, ``shift`` bits up, ``mask`` wide,
    with a ``value`` (tokens needed, or the signed change) and, for changes, its ``place``."""

    ptr: np.ndarray
    word: np.ndarray
    shift: np.ndarray
    mask: np.ndarray
    value: np.ndarray
    place: np.ndarray | None = None


@dataclass(frozen=True)
class CounterNet:
    """A bounded net's transitions on packed counters: what each needs, what it changes,
    and whether it only adds tokens (``growing``: enabled, it proves the net unbounded)."""

    need: Fields
    change: Fields
    growing: np.ndarray    # bool, per transition

    @property
    def transitions(self) -> int:
        return len(self.need.ptr) - 1


@dataclass(frozen=True)
class Index:
    """The backend's lookup table of a set of rows (opaque to callers), and its size."""

    table: object
    bits: int


@dataclass(frozen=True)
class CounterSearch:
    """A bounded net's breadth-first search between two steps: the queue (rows of words
    in the order found), each row's ``parent``, its set of rows (``index``), the dead
    markings met, and why it stopped (``info``: the place that overflowed, or the
    growing transition)."""

    queue: np.ndarray
    parent: np.ndarray
    count: int
    head: int
    index: Index
    dead: int = 0
    code: Code = Code.GOING
    info: int = 0


# -- a property's product, on the fly --------------------------------------------------------

@dataclass(frozen=True)
class Observer:
    """A property's observer as tables (:mod:`mcl2pnml.analysis.checking.on_the_fly`): its
    atoms (a place mask and the least number of tokens among them), the letter of each
    truth of the atoms, ``move[state * 16 + letter]``, which states are ``pending`` (an
    obligation open) and which is ``bad`` (-1: none)."""

    atoms: np.ndarray      # (atoms, words) uint64
    least: np.ndarray
    letters: np.ndarray
    move: np.ndarray
    pending: np.ndarray    # uint8 per state
    bad: int


@dataclass(frozen=True)
class Stubborn:
    """What stubborn sets are grown from (Valmari's method; Clarke, Grumberg and Peled, ch.
    10): per transition the places it consumes (``pre``) and needs; per place the
    transitions consuming, needing and marking it; per transition whether the observer
    sees it (``visible``). ``on``: whether the search reduces at all."""

    pre: Rows
    needs: Rows
    takers: Rows
    needers: Rows
    makers: Rows
    visible: np.ndarray    # uint8 per transition
    on: bool


@dataclass(frozen=True)
class ProductSearch:
    """A product's breadth-first search: rows of the marking's words and the observer's
    state, each row's parent, the transition into it (``via``) and its ``depth``; the
    row of a violation ``found`` (-1: none yet)."""

    queue: np.ndarray
    count: int
    head: int
    index: Index
    parent: np.ndarray
    via: np.ndarray
    depth: np.ndarray
    found: int = -1
    code: Code = Code.GOING


# -- an LTL formula's product with a bounded net, on the fly ----------------------------------

class Op(enum.IntEnum):
    """An instruction of a :class:`StateProgram`: each pushes or combines truths."""

    LINEAR = 0
    """Push whether linear constraint ``arg`` holds (a weighted token sum at most a bound)."""
    ENABLED = 1
    """Push whether transition ``arg`` is enabled."""
    DEAD = 2
    """Push whether no transition is enabled."""
    CONST = 3
    """Push ``arg`` (0 or 1)."""
    NOT = 4
    """Negate the top."""
    AND = 5
    """Replace the top ``arg`` truths by their conjunction."""
    OR = 6
    """Replace the top ``arg`` truths by their disjunction."""


@dataclass(frozen=True)
class StateProgram:
    """State formulas compiled for a marking of counters: atom ``i`` is the postfix program
    ``ops[atom_ptr[i]:atom_ptr[i + 1]]`` of ``(Op, arg)`` rows; linear constraint ``c`` is
    ``sum(coef * tokens) <= bound[c]`` over its fields ``lin_ptr[c]:lin_ptr[c + 1]`` (each a
    place's word, shift and mask, and its coefficient)."""

    ops: np.ndarray          # (instructions, 2) int64
    atom_ptr: np.ndarray
    lin_ptr: np.ndarray
    lin_word: np.ndarray
    lin_shift: np.ndarray    # uint64
    lin_mask: np.ndarray     # uint64
    lin_coef: np.ndarray
    bound: np.ndarray


@dataclass(frozen=True)
class Buchi:
    """A generalised Büchi automaton on the atoms of a :class:`StateProgram`: node ``a``'s
    successors ``succ[ptr[a]:ptr[a + 1]]``, the atoms it requires (a bit each, all of
    which must hold in the marking it reads), the acceptance sets it is in (a bit each;
    ``all`` of them met by a cycle accepts) and the initial nodes."""

    ptr: np.ndarray
    succ: np.ndarray
    required: np.ndarray     # uint64 per node
    accepting: np.ndarray    # uint64 per node
    all: int
    initial: np.ndarray


#: How many enabled keys a marking's stubborn sets are grown from, the smallest set kept
#: (C's ``KEYS``): each growth may look at every transition, and a marking of a wide net
#: enables thousands.
STUBBORN_KEYS = 16


class LtlCode(enum.IntEnum):
    """How an LTL product search on the fly ended."""

    HOLDS = 0
    """Every reachable cycle of the product was met, none accepting: the formula holds."""
    ACCEPTING = 1
    """An accepting cycle: a run of the net violates the formula."""
    LIMIT = 2
    """``max_states`` product states were met first."""
    TIME = 3
    """Its seconds were spent first."""
    OVERFLOW = 4
    """A counter would not fit its field: ``info`` is the place (widen it, search again)."""
    GROWING = 5
    """A transition that only adds tokens is enabled: the net is unbounded."""


# -- what every backend implements -----------------------------------------------------------

class Loops(Protocol):
    """The loops, one backend's: a safe net's exploration and the questions asked of the
    markings found, a bounded net's, a property's product, and the graph searches of
    :mod:`mcl2pnml.analysis.contest.answers` (their arguments as compressed rows, as
    scipy's)."""

    name: str

    # a safe net: explore, then ask the found markings (rows) again
    def safe_search(self, net: SafeNet, m0: np.ndarray, max_states: int) -> SafeSearch: ...

    def safe_step(self, net: SafeNet, search: SafeSearch, max_states: int,
                  budget: int) -> SafeSearch: ...

    def permute_rows(self, rows: np.ndarray, order: np.ndarray) -> np.ndarray: ...

    def out_degree(self, rows: np.ndarray, net: SafeNet) -> np.ndarray: ...

    def live(self, rows: np.ndarray, net: SafeNet) -> np.ndarray: ...

    def edges(self, rows: np.ndarray, net: SafeNet, ids: np.ndarray, order: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...

    def backward(self, rows: np.ndarray, net: SafeNet, unfire: KeyIndex, seen: np.ndarray,
                 frontier: np.ndarray) -> np.ndarray: ...

    # a bounded net, counters packed into words
    def counter_search(self, queue: np.ndarray, parent: np.ndarray, count: int, head: int,
                       dead: int = 0) -> CounterSearch: ...

    def counter_step(self, net: CounterNet, search: CounterSearch, max_states: int,
                     budget: int) -> CounterSearch: ...

    def counter_out_degree(self, rows: np.ndarray, net: CounterNet) -> np.ndarray: ...

    def counter_edges(self, rows: np.ndarray, index: Index, net: CounterNet, total: int
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The first ``total`` firings ``(source, transition, target)`` in node order:
        every firing of the rows whose out-degrees sum to ``total``."""

    def counter_backward(self, rows: np.ndarray, net: CounterNet, seen: np.ndarray,
                         frontier: np.ndarray) -> np.ndarray: ...

    # a property's product with a safe net, on the fly
    def product_search(self, start: np.ndarray, capacity: int) -> ProductSearch: ...

    def product_step(self, net: SafeNet, observer: Observer, stubborn: Stubborn,
                     search: ProductSearch, max_states: int, budget: int) -> ProductSearch: ...

    def product_edges(self, net: SafeNet, observer: Observer, search: ProductSearch,
                      first: int, room: int
                      ) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]: ...

    # graph searches on compressed rows
    def scc(self, indptr: np.ndarray, indices: np.ndarray, keep: np.ndarray,
            label: np.ndarray) -> int: ...

    def back_reach(self, indptr: np.ndarray, indices: np.ndarray, through: np.ndarray,
                   out: np.ndarray) -> None: ...

    def scatter_by_source(self, src: np.ndarray, values: np.ndarray, cursor: np.ndarray,
                          out: np.ndarray) -> None: ...

    def ltl_search(self, net: CounterNet, program: StateProgram, buchi: Buchi,
                   stubborn: Stubborn, m0: np.ndarray, max_states: int, seconds: float
                   ) -> tuple[LtlCode, int, int]:
        """The product of the net from ``m0`` (one row of counters) and ``buchi`` searched
        on the fly, depth first, for a cycle meeting every acceptance set (Couvreur's
        check); a dead marking repeats. With ``stubborn.on``, a marking fires only the
        enabled members of a stubborn set with no visible member, unless one of the
        product states that gives is on the search's stack (then it fires everything:
        every cycle closes on the stack, so no cycle is reduced throughout). ``(code,
        product states met, info)``."""

    def ltl_product(self, indptr, indices, a_ptr, a_succ, label, acc, all_sets: int,
                    initial, num, max_states: int) -> tuple[int, int]: ...
