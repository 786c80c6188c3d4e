"""LTL formulas decided on the fly from the net, under stubborn sets: no graph first.

The product of the net's markings (counters packed into words, as the bounded nets'
explorer keeps them: :mod:`mcl2pnml.analysis.statespace.counters`) and the generalised
Büchi automaton of the formula's negation (:mod:`mcl2pnml.analysis.contest.buchi`) is
searched depth first from the initial marking by Couvreur's check (1999), in the loops
(``ltl_search``, C or the Python reference), numbering only the product states it meets:
the first accepting cycle is a run that violates the formula (it stops there); a search
that ends without one proves it. The atoms are compiled to small postfix programs
(:func:`state_program`) that the loops evaluate on each marking met.

**Partial-order reduction** (Valmari's stubborn sets, for LTL without ``X``; Peled 1994;
Clarke, Grumberg and Peled, *Model Checking*, ch. 10): where the formula has no ``X`` (it
is then stutter-invariant), a marking fires only the enabled members of a stubborn set:

* grown from an enabled key: an enabled member brings every transition that takes
  tokens from a place it needs, and every one that needs a place it takes from (either
  may disable the other); a disabled member, every transition that adds to one place it
  lacks (nothing outside the set can enable it). So the set's transitions commute with
  every sequence outside it, and a dead marking stays reachable (C0, C1);
* with no **visible** member (C2): a transition is visible where it changes a place an
  atom counts, or a place a transition an atom names needs (its enabledness), or any
  place at all where an atom asks for a deadlock;
* the **proviso** (C3, the stack proviso of Peled 1994 and Holzmann): where a product
  state the reduced set leads to is on the depth-first search's stack, the marking fires
  everything instead; every cycle of a depth-first search closes on its stack, so no
  cycle is closed by reduced steps alone.

The smallest such set over the enabled keys is taken. Under these conditions the
reduced product has an accepting cycle exactly where the whole one has (Peled 1994;
Valmari 1991). With an ``X`` in the formula, every marking fires everything.

Counters start with room for twice the initial tokens; a counter that would overflow is
widened (twice as wide) and the search run again, within the same seconds. A net with a
transition that only adds tokens is left (unbounded).
"""
from __future__ import annotations

import time

import numpy as np

from mcl2pnml.core import queries as q
from mcl2pnml.core.bounds import MAX_STATES
from mcl2pnml.core.memory import default_memory
from mcl2pnml.core.net import Net
from mcl2pnml.core.structure import Structure, structure

from mcl2pnml.analysis.contest.buchi import negation_normal_form, tableau
from mcl2pnml.analysis.statespace.counters import Layout, counter_net
from mcl2pnml.analysis.statespace.loops.backends import chosen
from mcl2pnml.analysis.statespace.loops.interface import (Buchi, LtlCode, Op, Rows,
                                                          StateProgram, Stubborn)

#: Bytes a product state takes in the search (its row and automaton node, its slot in
#: the table, its place on the stacks), besides the marking's words.
STATE_BYTES = 48


class Unnamed(Exception):
    """An atom names a place or transition the net does not have."""


def state_program(s: Structure, layout: Layout, atoms: list) -> StateProgram:
    """The state formulas ``atoms`` compiled to postfix programs on rows of ``layout``."""
    ops: list[tuple[int, int]] = []
    ptr = [0]
    lin_ptr, fields, bounds = [0], [], []
    place = s.place_index
    trans = {t: i for i, t in enumerate(s.transitions)}

    def total(e, sign: int, coef: dict, const: list):
        if isinstance(e, q.IntConst):
            const[0] += sign * e.value
            return
        for p in e.places:
            if p not in place:
                raise Unnamed(p)
            coef[place[p]] = coef.get(place[p], 0) + sign

    def emit(f):
        if isinstance(f, q.BoolConst):
            ops.append((Op.CONST, int(f.value)))
        elif isinstance(f, q.IntLe):            # left - right <= 0
            coef: dict[int, int] = {}
            const = [0]
            total(f.left, 1, coef, const)
            total(f.right, -1, coef, const)
            for p, c in sorted(coef.items()):
                if c:
                    fields.append((layout.word[p], layout.shift[p], layout.mask(p), c))
            lin_ptr.append(len(fields))
            bounds.append(-const[0])
            ops.append((Op.LINEAR, len(bounds) - 1))
        elif isinstance(f, q.Fireable):
            for t in f.transitions:
                if t not in trans:
                    raise Unnamed(t)
                ops.append((Op.ENABLED, trans[t]))
            ops.append((Op.OR, len(f.transitions)))
        elif isinstance(f, q.Deadlock):
            ops.append((Op.DEAD, 0))
        elif isinstance(f, q.Neg):
            emit(f.arg)
            ops.append((Op.NOT, 0))
        elif isinstance(f, (q.Conj, q.Disj)):
            for a in f.args:
                emit(a)
            ops.append((Op.AND if isinstance(f, q.Conj) else Op.OR, len(f.args)))
        else:
            raise ValueError(f"not a state formula: {f!r}")

    for f in atoms:
        emit(f)
        ptr.append(len(ops))
    word, shift, mask, coef = zip(*fields) if fields else ((), (), (), ())
    return StateProgram(np.array(ops, dtype=np.int64).reshape(-1, 2),
                        np.array(ptr, dtype=np.int64), np.array(lin_ptr, dtype=np.int64),
                        np.array(word, dtype=np.int64), np.array(shift, dtype=np.uint64),
                        np.array(mask, dtype=np.uint64), np.array(coef, dtype=np.int64),
                        np.array(bounds, dtype=np.int64))


class TooWide(Exception):
    """More than 64 atoms or acceptance sets: the loops hold a bit each in one word."""


def automaton(f: q.AllPaths) -> tuple[Buchi | None, list]:
    """The Büchi automaton of ``not φ`` for ``A φ`` on its atoms (state formulas, each
    negation included): None where it accepts nothing (``A φ`` holds); raises
    :class:`TooWide` past 64 atoms or acceptance sets."""
    atoms: list = []

    def atom(g, negate: bool) -> int:
        atoms.append(q.Neg(g) if negate else g)
        return len(atoms) - 1

    literals, accepting, initial, edges = tableau(negation_normal_form(f.arg, True, atom))
    if not literals or any(not members for members in accepting):
        return None, atoms
    if len(atoms) > 64 or len(accepting) > 64:
        raise TooWide(f"{len(atoms)} atoms and {len(accepting)} acceptance sets")
    k = len(literals)
    succ: list[list[int]] = [[] for _ in range(k)]
    for j, m in edges:
        succ[j].append(m)
    required = np.array([sum(1 << a for a in lits) for lits in literals], dtype=np.uint64)
    acc = np.zeros(k, dtype=np.uint64)
    for bit, members in enumerate(accepting):
        for j in members:
            acc[j] |= np.uint64(1 << bit)
    ptr = np.zeros(k + 1, dtype=np.int64)
    ptr[1:] = np.cumsum([len(x) for x in succ])
    return Buchi(ptr, np.array([m for x in succ for m in x], dtype=np.int64), required, acc,
                 (1 << len(accepting)) - 1, np.array(sorted(initial), dtype=np.int64)), atoms


def stubborn_tables(s: Structure, atoms: list, reduce: bool) -> Stubborn:
    """What stubborn sets grow from (the module's documentation), with the transitions
    the atoms see marked visible; raises :class:`Unnamed` at a name the net lacks."""
    places, transitions = len(s.places), len(s.transitions)
    needs = [sorted(inputs) for inputs in s.transition_inputs]    # what each needs
    takes = [sorted(p for p, w in col.items() if w < 0) for col in s.incidence]
    adds = [sorted(p for p, w in col.items() if w > 0) for col in s.incidence]
    takers: list[list[int]] = [[] for _ in range(places)]
    needers: list[list[int]] = [[] for _ in range(places)]
    makers: list[list[int]] = [[] for _ in range(places)]
    for t in range(transitions):
        for p in takes[t]:
            takers[p].append(t)
        for p in needs[t]:
            needers[p].append(t)
        for p in adds[t]:
            makers[p].append(t)
    seen: set[int] = set()           # places whose count or effect an atom sees
    trans = {t: i for i, t in enumerate(s.transitions)}
    dead = False

    def look(f):
        nonlocal dead
        if isinstance(f, q.IntLe):
            for e in (f.left, f.right):
                if isinstance(e, q.TokensCount):
                    for p in e.places:
                        if p not in s.place_index:
                            raise Unnamed(p)
                        seen.add(s.place_index[p])
        elif isinstance(f, q.Fireable):
            for t in f.transitions:
                if t not in trans:
                    raise Unnamed(t)
                seen.update(needs[trans[t]])
        elif isinstance(f, q.Deadlock):
            dead = True
        for g in q.children(f):
            look(g)

    for f in atoms:
        look(f)
    visible = np.array([dead and bool(col) or any(p in seen for p in col)
                        for col in s.incidence], dtype=np.uint8)
    return Stubborn(*map(Rows.of_sets, (takes, needs, takers, needers, makers)), visible,
                    reduce)


def ltl_on_the_fly(net: Net, f: q.AllPaths, max_states: int, seconds: float,
                   max_memory: int | None = None, loops=None) -> bool | None:
    """Whether ``A φ`` holds, by the search on the fly (the module's documentation); None
    where it stops at its limits (``max_states`` product states, ``seconds``, the memory
    budget), the net is unbounded, or the automaton is past 64 atoms or sets."""
    try:
        buchi, atoms = automaton(f)
    except TooWide:
        return None
    if buchi is None:
        return True
    s = structure(net)
    m0 = s.initial_vector()
    # as wide as the initial tokens need, widened where a firing overflows: the
    # P-invariants' bounds (the explorer's widths) can take longer than the search
    widths = [max(1, (2 * n + 1).bit_length()) for n in m0]
    reduce = not q.contains(f, q.Next)
    stubborn = stubborn_tables(s, atoms, reduce)
    loops = loops or chosen()
    deadline = time.monotonic() + seconds
    while True:
        layout = Layout(widths)
        budget = default_memory() if max_memory is None else max_memory
        limit = min(max_states, budget // (STATE_BYTES + 8 * (layout.words + 1)))
        code, _, info = loops.ltl_search(
            counter_net(s, layout), state_program(s, layout, atoms), buchi, stubborn,
            layout.pack(np.array([m0], dtype=np.int64))[0], limit,
            max(0.0, deadline - time.monotonic()))
        if code == LtlCode.OVERFLOW and widths[info] < 32:
            widths[info] = min(32, 2 * widths[info])
            continue
        return {LtlCode.HOLDS: True, LtlCode.ACCEPTING: False}.get(code)



#: The seconds a formula's first search on the fly may take: a counterexample is usually
#: met in milliseconds, a reduced product proved in a few seconds or not at all.
FLY_SECONDS = 2.0


def path_formula(f) -> tuple[bool, q.AllPaths] | None:
    """``(negated, A φ)``: ``f`` is ``A φ`` (or ``E ψ`` = not ``A`` not ψ) under negations,
    φ free of path quantifiers, decided by one LTL search; None for any other formula,
    and for one that is CTL too and has an ``X`` (CTL and LTL read a dead marking's next
    one differently: the graph decides those, both ways)."""
    shaped = q.path_quantified(f)
    if shaped is None:
        return None
    negated, g = shaped
    if q.contains(g, q.Next) and q.is_ctl(g):
        return None
    if isinstance(g, q.ExistsPath):       # E ψ = not A not ψ
        return not negated, q.AllPaths(q.Neg(g.arg))
    return negated, g


def settled_by_ltl_on_the_fly(net: Net, queries, seconds: float = FLY_SECONDS,
                              max_states: int = MAX_STATES,
                              max_memory: int | None = None) -> dict[str, tuple[bool, str]]:
    """The path formulas (:func:`path_formula`) one search on the fly each decides, within
    ``seconds`` each."""
    settled: dict[str, tuple[bool, str]] = {}
    for x in queries:
        shaped = path_formula(x.asks)
        if shaped is None:
            continue
        negated, f = shaped
        try:
            holds = ltl_on_the_fly(net, f, max_states, seconds, max_memory)
        except Unnamed:
            continue
        if holds is not None:
            reduced = " STUBBORN_SETS" if not q.contains(f, q.Next) else ""
            settled[x.id] = (holds is not negated, f"EXPLICIT LTL ON_THE_FLY{reduced}")
    return settled
