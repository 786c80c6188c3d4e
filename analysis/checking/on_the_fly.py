"""A property checked on the fly: the product of a safe net and the property's observer,
explored in C breadth first, stopping at the first violation.

:mod:`mcl2pnml.analysis.checking.observers` defines the observers (Dwyer et al.'s patterns and
scopes as deterministic automata reading the marking sequence) and the
verdicts. Its reference method explores every reachable marking first and
then each property's product in Python; model checkers search the product
on the fly and stop at a counterexample. This module does the same, in the
loops of the safe-net explorer (:class:`~mcl2pnml.analysis.statespace.loops.interface.Loops`:
in C, ``analysis/statespace/loops/_native.c``; the plain-Python reference
runs the same search in the tests):

* a row of the product is a marking's words and one more, the observer's
  state; the observer's moves are a table worked out before the search (its
  states are few), and it reads a marking through its *atoms*, the
  ``Tokens`` comparisons of the property's predicates, each a popcount of
  the marking and a mask (the net is safe);
* breadth first, so the first violation found is a shortest one of its
  kind: a prefix the observer rejects (``BAD``), or a dead marking with an
  obligation open (a finite run). The search stops there;
* only when the whole product has neither, an infinite run that keeps an
  obligation open for ever (existence, response) is looked for: the arcs
  between the pending rows are listed by the loops, their strongly connected
  components found by scipy, and the lasso entering a cycle earliest,
  around its shortest cycle, is the counterexample.

With ``stubborn``, partial-order reduction (Valmari's stubborn sets; the
conditions C0-C3 of Clarke, Grumberg and Peled's *Model Checking*, ch. 10):
a row fires only the enabled members of a stubborn set that has no visible
transition (one changing a place the property reads), unless one of their
successors is a row met before no deeper than it, when it fires everything
(the cycle proviso in breadth-first form: every cycle has an arc that does
not go deeper, so each cycle has a row that fires everything). That keeps the verdict of a stutter-invariant property, which the
observer is if reading a letter twice is reading it once (checked, letter by
letter, state by state: a property whose observer is not is checked without
reduction). The reduction only holds on a net proven 1-safe (the bits of a
marking would otherwise hide the firing that puts a second token in a
place): the caller says so (``safe``), or a semi-positive P-invariant proves
it here. A counterexample found with it is a real run, but not always a
shortest one.

So a failing safety property costs the markings up to its counterexample,
and a holding one one pass of the product at C speed, where the reference
method pays the whole state space and a Python loop per property.
:func:`check_properties_on_the_fly` answers ``None`` for a net it does not take (not safe,
or the loops in C not built: the plain-Python loops would be slower than the
reference method); the caller then uses the reference method.
"""
from __future__ import annotations

from typing import Iterable

import numpy as np

from mcl2pnml.core.bounds import MAX_CHECK_STATES
from mcl2pnml.core.memory import default_memory, size_text
from mcl2pnml.core.net import Net
from mcl2pnml.core.patterns import Property, Tokens, atoms_of, evaluate
from mcl2pnml.core.structure import Structure, structure

from mcl2pnml.analysis.checking.observers import BAD, Shape, Status, Verdict, initial, pending, step, truths
from mcl2pnml.analysis.statespace.counters import invariant_bounds
from mcl2pnml.analysis.statespace.loops.backends import c_loops
from mcl2pnml.analysis.statespace.loops.interface import (Code, Loops, Observer, ProductSearch,
                                                          Rows, Stubborn)
from mcl2pnml.analysis.statespace.packedmarkings import (marking_row, masks, masks_of,
                                                         place_weights, safe_net, word_count)

#: A property whose predicates compare more than this many token sums is left to the
#: reference method: the table of the observer's letters has 2**ATOMS entries.
ATOMS = 16
#: Expansions per step of the loops, between which they hand back to Python.
SLICE = 1 << 20


class _Refused(Exception):
    """The net or the property is not for this checker: the reference method takes it."""


def available() -> bool:
    """Whether the loops in C were built (they hold the product's search)."""
    return c_loops() is not None


def check_properties_on_the_fly(net: Net, properties: Iterable[Property], max_states: int = MAX_CHECK_STATES,
              max_memory: int | None = None, stubborn: bool = False,
              safe: bool = False, loops: Loops | None = None) -> list[Verdict] | None:
    """Each property's verdict, on the fly; None if the net is not for this checker (not
    1-safe as given, or the loops in C not built), or a property reads too many sums.

    ``max_memory`` (bytes; default: :func:`~mcl2pnml.core.memory.default_memory`) bounds
    each search as ``max_states`` does: past either, the verdict is unknown.
    ``stubborn``: with partial-order reduction, on a net ``safe`` says is proven 1-safe
    (a certificate) or that a P-invariant proves so here; else :class:`NotProvenSafe`.
    ``loops``: the backend that searches (default: the loops in C).
    """
    loops = loops or c_loops()
    if loops is None:
        return None
    s = structure(net)
    m0 = s.initial_vector()
    if any(k > 1 for k in m0) or any(a.weight != 1 for a in net.arcs):
        return None
    if stubborn and not safe and not proven_safe(s):
        raise NotProvenSafe(f"the net '{net.name}' is not proven 1-safe, which the reduction "
                            "needs (a certificate, or a P-invariant)")
    search = _Search(s, loops, stubborn)
    budget = default_memory() if max_memory is None else max_memory
    verdicts = []
    for prop in properties:
        try:
            verdicts.append(search.check(prop, max_states, budget))
        except _Refused:
            return None
    return verdicts


class NotProvenSafe(ValueError):
    """The reduction was asked for on a net not proven 1-safe."""


def proven_safe(s: Structure) -> bool:
    """Whether semi-positive P-invariants bound every place by 1 (Murata 1989, section
    VII): then no reachable marking has a second token, whatever the reduction skips."""
    bounds = invariant_bounds(s, s.initial_vector())
    return all(b is not None and b <= 1 for b in bounds)


def stutter_invariant(move: np.ndarray) -> bool:
    """Whether reading a letter twice leaves the observer where reading it once does, in
    every state: then runs that differ in repeated markings get one verdict."""
    table = move.reshape(-1, 16)
    return bool(np.all(table[table, np.arange(16)] == table))


# -- the observer as tables --------------------------------------------------------------------

def _atoms(prop: Property) -> list[Tokens]:
    """The ``Tokens`` comparisons of the property's four predicates, each once."""
    return list(dict.fromkeys(t for x in truths(prop) for t in atoms_of(x)))


def _letters(prop: Property, atoms: list[Tokens]) -> np.ndarray:
    """The observer's letter (P S Q R as bits 8 4 2 1) for each truth of the atoms (bit a:
    atom a holds)."""
    predicates = truths(prop)
    letters = np.zeros(1 << len(atoms), dtype=np.int64)
    for bits in range(len(letters)):
        truth = {a: bool(bits >> k & 1) for k, a in enumerate(atoms)}
        p, s, q, r = (evaluate(x, truth.__getitem__) for x in predicates)
        letters[bits] = 8 * p + 4 * s + 2 * q + r
    return letters


class _Automaton:
    """The observer's states reachable from its start under any letters, numbered, and its
    moves as a table (``move[state * 16 + letter]``)."""

    def __init__(self, prop: Property):
        self.states: list = [initial(prop.scope.kind)]
        number = {self.states[0]: 0}
        moves: list[int] = []
        k = 0
        while k < len(self.states):
            for letter in range(16):
                nxt = step(prop, self.states[k], bool(letter & 8), bool(letter & 4),
                           bool(letter & 2), bool(letter & 1))
                if nxt not in number:
                    number[nxt] = len(self.states)
                    self.states.append(nxt)
                moves.append(number[nxt])
            k += 1
        self.move = np.array(moves, dtype=np.int64)
        self.pending = np.array([pending(prop, o) and o is not BAD for o in self.states],
                                dtype=np.uint8)
        self.bad = number.get(BAD, -1)


# -- the search --------------------------------------------------------------------------------

class _Search:
    """The net's masks, worked out once for all its properties."""

    def __init__(self, s: Structure, loops: Loops, stubborn: bool = False):
        self.s, self.loops = s, loops
        self.words = word_count(s)
        need, take, give = masks(s, self.words)
        m0 = marking_row(s.initial_vector(), self.words)
        self.m0 = m0[0]
        self.net = safe_net(need, take, give, place_weights(m0))
        self.index = {p: k for k, p in enumerate(s.places)}
        self.stubborn = stubborn
        # (the loop reads them only when it reduces: empty ones otherwise)
        self.structure = _stubborn_rows(s) if stubborn else [Rows.of_sets([[]])] * 5

    def _visible(self, atoms: list[Tokens]) -> np.ndarray:
        """Per transition, 1 if it changes a place the atoms read (pre and post differ)."""
        read = {self.index[p] for a in atoms for p in a.places if p in self.index}
        return np.array([bool(read & (set(pre) ^ set(post)))
                         for pre, post in zip(self.s.pre, self.s.post)], dtype=np.uint8)

    def _atom_arrays(self, atoms: list[Tokens]) -> tuple[np.ndarray, np.ndarray]:
        sets = [[self.index[p] for p in a.places if p in self.index] for a in atoms]
        masks = masks_of(sets, self.words) if sets else np.zeros((0, self.words), np.uint64)
        return (np.ascontiguousarray(masks),
                np.array([a.at_least for a in atoms], dtype=np.int64))

    def footprint(self) -> int:
        """Bytes a product state costs at most: its row, its parent, transition and depth
        (each array up to twice its rows, as it doubles), and its share of the table."""
        return 2 * (8 * (self.words + 1) + 24) + 24

    def check(self, prop: Property, max_states: int, budget: int) -> Verdict:
        """The property's verdict: the product searched breadth first to its first
        violation, then, where the observer can stay pending, a lasso looked for."""
        fits = max(1, budget // self.footprint())
        limit = min(max_states, fits)
        atoms = _atoms(prop)
        if len(atoms) > ATOMS:
            raise _Refused
        auto = _Automaton(prop)
        letters = _letters(prop, atoms)
        atom_masks, least = self._atom_arrays(atoms)
        observer = Observer(atom_masks, least, letters, auto.move, auto.pending, auto.bad)
        reduce = self.stubborn and stutter_invariant(auto.move)
        visible = self._visible(atoms) if reduce else np.zeros(1, dtype=np.uint8)
        stubborn = Stubborn(*self.structure, visible, reduce)
        width = self.words + 1
        start = np.zeros(width, dtype=np.uint64)
        start[:-1] = self.m0
        bits0 = sum(1 << k for k, (mask, n) in enumerate(zip(atom_masks, least))
                    if sum(bin(int(w) & int(m)).count("1") for w, m in zip(self.m0, mask)) >= n)
        state0 = int(auto.move[letters[bits0]])   # the observer has read M0
        start[-1] = state0
        if state0 == auto.bad:
            return self._verdict(prop, Shape.PREFIX, [start], [], 1)
        search = self.loops.product_search(start, min(limit, 1 << 12) + self.net.transitions + 1)
        while True:
            search = self.loops.product_step(self.net, observer, stubborn, search, limit, SLICE)
            if search.code == Code.NOT_SAFE:
                raise _Refused
            if search.code == Code.LIMIT:
                reason = (f"more than {max_states:,} product states" if limit == max_states
                          else f"the memory budget ({size_text(budget)}) holds "
                               f"{limit:,} product states")
                return Verdict(prop, Status.UNKNOWN, states=search.count, reason=reason)
            if search.code != Code.GOING or search.head == search.count:
                break
        found_shape = {Code.FOUND_BAD: Shape.PREFIX, Code.FOUND_DEAD: Shape.FINITE}.get(search.code)
        bound = None if found_shape is None else int(search.depth[search.found])
        lasso = None
        if auto.pending.any():
            # a lasso shorter than the violation found: its rows are all explored
            lasso = self._lasso(observer, search, bound)
        if lasso is not None:
            rows, trans, loop = lasso
            return self._verdict(prop, Shape.LASSO, rows, trans, search.count, loop)
        if found_shape is not None:
            rows, trans = _way_back(search, search.found)
            return self._verdict(prop, found_shape, rows, trans, search.count)
        return Verdict(prop, Status.HOLDS, states=search.count)

    def _lasso(self, observer: Observer, search: ProductSearch, bound: int | None):
        """The rows, transitions and loop of the shortest lasso (shorter than ``bound``
        firings, if given) whose cycle keeps an obligation open; None if there is none.

        The arcs between pending rows are listed by the loops; scipy finds their strongly
        connected components; the entries are tried in breadth-first order, each with
        its shortest cycle within its component, until no later entry can be shorter.
        """
        # scipy.sparse.csgraph: 0.4 s to import, only where an obligation can stay open
        from scipy.sparse import csr_matrix
        from scipy.sparse.csgraph import breadth_first_order, connected_components
        queue, count, depth = search.queue, search.count, search.depth
        parts: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        first, room = 0, max(1 << 16, 4 * self.net.transitions)
        while first < count:
            first, *part = self.loops.product_edges(self.net, observer, search, first, room)
            parts.append(tuple(part))
        src, dst, trans = (np.concatenate(x) for x in zip(*parts))
        if not len(src):
            return None
        graph = csr_matrix((np.ones(len(src), dtype=np.int8), (src, dst)), shape=(count, count))
        _, label = connected_components(graph, directed=True, connection="strong")
        # an arc within one component lies on a cycle of pending rows
        inner = label[src] == label[dst]
        if not inner.any():
            return None
        src, dst, trans = src[inner], dst[inner], trans[inner]
        arc = {}
        for a, b, t in zip(src.tolist(), dst.tolist(), trans.tolist()):
            arc.setdefault((a, b), t)
        cyclic = np.unique(src)     # in row order: breadth first, so by depth
        best = None                 # (length, entry, cycle rows)
        inside = csr_matrix((np.ones(len(src), dtype=np.int8), (src, dst)),
                            shape=(count, count))
        into: dict[int, list[int]] = {}
        for a, b in zip(src.tolist(), dst.tolist()):
            into.setdefault(b, []).append(a)
        for entry in cyclic.tolist():
            d = int(depth[entry])
            limit = best[0] if best is not None else bound
            if limit is not None and d + 1 >= limit:
                break       # every later entry is as deep: no shorter lasso
            order, pred = breadth_first_order(inside, entry, directed=True,
                                              return_predecessors=True)
            reached = {int(u) for u in order}
            hops = {entry: 0}
            for u in order.tolist()[1:]:
                hops[u] = hops[int(pred[u])] + 1
            last = min((u for u in into.get(entry, ()) if u in reached), key=hops.__getitem__,
                       default=None)
            if last is None:
                continue
            length = d + hops[last] + 1
            if limit is None or length < limit:
                cycle = [last]
                while cycle[-1] != entry:
                    cycle.append(int(pred[cycle[-1]]))
                best = (length, entry, cycle[::-1])
        if best is None:
            return None
        _, entry, cycle = best
        rows, path = _way_back(search, entry)
        loop = len(rows) - 1
        for a, b in zip(cycle, cycle[1:] + [entry]):
            rows.append(queue[b])
            path.append(arc[(a, b)])
        return rows, path, loop

    def _verdict(self, prop: Property, shape: Shape, rows, trans, states: int,
                 loop: int | None = None) -> Verdict:
        places = self.s.places
        tids = self.s.transitions
        words = self.words

        def marked(row) -> tuple[tuple[str, int], ...]:
            out = []
            for w in range(words):
                x = int(row[w])
                while x:
                    low = x & -x
                    out.append(w * 64 + low.bit_length() - 1)
                    x ^= low
            return tuple((places[k], 1) for k in sorted(out))
        ms = [marked(r) for r in rows]
        names = [tids[t] for t in trans]
        if loop is not None:
            # the same infinite run, its loop entered earlier where the markings allow
            while loop > 0 and ms[loop - 1] == ms[-2] and names[loop - 1] == names[-1]:
                loop -= 1
                ms.pop()
                names.pop()
        return Verdict(prop, Status.FAILS, tuple(names), tuple(ms), shape, loop=loop,
                       states=states)


def _stubborn_rows(s: Structure) -> list[Rows]:
    """What the stubborn sets are grown from (:class:`~mcl2pnml.analysis.statespace.loops.interface.Stubborn`):
    the places each transition consumes and needs, the transitions consuming, needing
    and marking each place."""
    take = [set() for _ in s.places]
    need = [set() for _ in s.places]
    make = [set() for _ in s.places]
    for j, (pre, post, inputs) in enumerate(zip(s.pre, s.post, s.transition_inputs)):
        for p in pre:
            take[p].add(j)
        for p in inputs:
            need[p].add(j)
        for p in post:
            make[p].add(j)
    return [Rows.of_sets(r) for r in (s.pre, s.transition_inputs, take, need, make)]


def _way_back(search: ProductSearch, row: int) -> tuple[list, list[int]]:
    """The rows from the start to ``row`` and the transitions between them."""
    queue, parent, via = search.queue, search.parent, search.via
    rows, trans = [queue[row]], []
    while parent[row] >= 0:
        trans.append(int(via[row]))
        row = int(parent[row])
        rows.append(queue[row])
    return rows[::-1], trans[::-1]
