"""Siphons, traps, and whether the siphons are controlled.

A *siphon* is a nonempty set of places S with •S ⊆ S• (Murata 1989):
every transition that puts a token into S also takes one from S, so
once S is empty it stays empty, and the transitions that need it are dead.
A *trap* is the dual, a nonempty Q with Q• ⊆ •Q: once marked, always marked.
A read arc counts both ways here (the transition is in •p and in p•), as
the self-loop it stands for: it needs a token of S to fire, and puts it back.
The pre- and post-sets come from
:class:`~mcl2pnml.core.structure.Structure`, which already counts read arcs
so.

* :func:`max_siphon_within` (and :func:`max_trap_within`): the largest
  siphon inside a set of places, in linear time. Siphons are closed under
  union, so it exists and holds every siphon inside the set.
* :func:`minimal_siphons` (and :func:`minimal_traps`): every minimal siphon,
  each exactly once, by the partition scheme of Cordone, Ferrarini and
  Piroddi (2005). Their number can grow exponentially, hence ``limit``.
* :func:`siphon_control`: whether each siphon is marked and *controlled* in
  the sense of Iordache and Antsaklis (2006), the check the paper uses
  (section 2.2): some P-invariant y has all its positively weighted places
  in S and y . M0 > 0. Then in every reachable M,
  sum over S of y_p M(p) >= y . M = y . M0 > 0: S never empties.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Mapping, Sequence

from mcl2pnml.core.structure import Structure

from mcl2pnml.analysis.structure.invariants import AnalysisLimit, integer_multiple

Sets = Sequence[frozenset[int]]


@dataclass(frozen=True)
class _Sides:
    """The adjacency a maximal siphon needs; with the directions swapped, a trap.

    For a siphon S, a place p may stay only if every transition in
    ``guard[p]`` (•p) has one of its ``inputs`` (•t) in S. ``users[p]`` (p•:
    the transitions p is an input of) and ``guards[t]`` (t•: the places t
    guards) are the same relations read the other way. For a trap every
    direction is reversed: each transition of p• must put into Q.
    """

    guard: Sets    # per place: transitions that must keep an input in the set
    inputs: Sets   # per transition: the places that count as its inputs
    users: Sets    # per place: transitions that count it as an input
    guards: Sets   # per transition: places whose guard it is


def _siphon_sides(s: Structure) -> _Sides:
    return _Sides(s.place_pre, s.transition_inputs, s.place_post, s.transition_outputs)


def _trap_sides(s: Structure) -> _Sides:
    return _Sides(s.place_post, s.transition_outputs, s.place_pre, s.transition_inputs)


def _collapse(sides: _Sides, inside: set[int], count: dict[int, int],
              queue: list[int]) -> None:
    """Take the ``queue`` places out of ``inside``, and all that follow.

    ``count[t]`` is how many of t's inputs are in ``inside`` (no entry for
    none). A transition left with no input cannot guard anything in the set:
    the places it guards leave too, which may leave more transitions without
    inputs. Each place leaves once and each arc is looked at a bounded number
    of times: linear in what leaves.
    """
    while queue:
        p = queue.pop()
        if p not in inside:
            continue  # queued twice
        inside.discard(p)
        for t in sides.users[p]:
            count[t] -= 1
            if count[t] == 0:
                del count[t]
                queue.extend(q for q in sides.guards[t] if q in inside)


def _largest(sides: _Sides, places: Iterable[int]) -> tuple[frozenset[int], dict[int, int]]:
    """The largest set inside ``places`` whose every guard keeps an input in it,
    with the input counts that go with it (to remove more places later)."""
    inside = set(places)
    count: dict[int, int] = {}
    for p in inside:
        for t in sides.users[p]:
            count[t] = count.get(t, 0) + 1
    _collapse(sides, inside, count,
              [p for p in inside if any(t not in count for t in sides.guard[p])])
    return frozenset(inside), count


def _max_within(sides: _Sides, places: Iterable[int]) -> frozenset[int]:
    """The largest set inside ``places`` whose every guard keeps an input in it."""
    return _largest(sides, places)[0]


def max_siphon_within(s: Structure, places: Iterable[int]) -> frozenset[int]:
    """The largest siphon inside ``places`` (place indices); empty if there is none.

    Linear time: a transition feeding a place of the set with none of its
    inputs in the set makes that place leave, and the counters of inputs
    left per transition say when that happens. Siphons are closed under
    union (Murata 1989), which makes the result unique.
    """
    return _max_within(_siphon_sides(s), places)


def max_trap_within(s: Structure, places: Iterable[int]) -> frozenset[int]:
    """The largest trap inside ``places`` (place indices); empty if there is none.

    The dual of :func:`max_siphon_within`: a transition taking from a place
    of the set must put into the set.
    """
    return _max_within(_trap_sides(s), places)


def _grown_within(sides: _Sides, within: frozenset[int],
                  required: frozenset[int]) -> frozenset[int]:
    """A siphon inside ``within`` holding ``required``, grown from it; ``within``
    must be a siphon that holds ``required``.

    Each transition guarding a chosen place gets one input chosen, the first
    in place order; ``within`` always has one, being a siphon. The result is
    usually far smaller than ``within``, so shrinking it is cheap.
    """
    chosen = set(required) or {min(within)}
    todo = sorted(chosen)
    while todo:
        p = todo.pop()
        for t in sorted(sides.guard[p]):
            if sides.inputs[t].isdisjoint(chosen):
                q = min(sides.inputs[t] & within)
                chosen.add(q)
                todo.append(q)
    return frozenset(chosen)


def _minimal_sets(sides: _Sides, nplaces: int, limit: int | None,
                  what: str, work: int | None = None) -> list[frozenset[int]]:
    """Every minimal set of the kind ``sides`` describes, each exactly once.

    A subproblem (P', R) asks for the minimal sets N with R ⊆ N ⊆ P'
    (Cordone, Ferrarini and Piroddi 2005). The largest set S inside P' holds
    them all; none if R ⊄ S. Inside S a set holding R is grown from R, then
    shrunk to M, minimal among the sets that hold R; M is output if it is
    minimal outright. (Growing first only saves time: shrinking S itself
    also gives such an M, at the cost of a linear pass per place of S.)
    Any other answer N lacks some place of M \\ R (otherwise N ⊇ M); the
    first such place, p_i, puts N in exactly one subproblem
    (P' - {p_i}, R + {p_1 ... p_i-1}). So the subproblems partition the
    rest, and nothing is found twice.

    ``limit`` bounds the subproblems, ``work`` the places they look at: a
    subproblem copies its parent's largest set, and shrinking a set of k
    places looks at k sets of up to k places, so a single siphon of a
    million places would take 10^12 steps before it is found.
    """
    found: list[frozenset[int]] = []
    # a subproblem: (the parent's largest set and its input counts, the
    # place p_i to take out of it, R). The largest set inside P' - {p_i} is
    # the largest inside the parent's largest minus p_i, so it is that set
    # with p_i removed and the removal followed through: a dict copy (fast)
    # and a walk over what leaves, not a pass over the whole net.
    # The places p_1 ... p_k of a subproblem's M \ R are kept once, as a tuple its
    # k children share, each child with its i: R + {p_1 ... p_i-1} is made when the
    # child is taken, not when it is pushed (k children holding their own sets
    # would be k^2/2 entries: 10^5 places of one siphon, 40 GB).
    root, root_count = _largest(sides, range(nplaces))
    stack: list[tuple[frozenset[int], dict[int, int], tuple[int, ...], int, frozenset[int]]] = [
        (root, root_count, (), -1, frozenset())]
    visited, steps = 0, 0

    def spend(n: int) -> None:
        nonlocal steps
        steps += n
        if work is not None and steps > work:
            raise AnalysisLimit(f"more than {work:,} steps enumerating the minimal {what} "
                                f"({visited:,} subproblems, {len(found):,} found)")

    spend(nplaces)
    while stack:
        parent, count, order, i, required = stack.pop()
        visited += 1
        if limit is not None and visited > limit:
            raise AnalysisLimit(f"more than {limit:,} subproblems enumerating the minimal "
                                f"{what}")
        largest = parent
        if i >= 0:
            leave = order[i]
            required = required | frozenset(order[:i])
            spend(len(parent) + len(count) + i)
            inside, count = set(parent), dict(count)
            _collapse(sides, inside, count, [leave])
            largest = frozenset(inside)
        if not largest or not required <= largest:
            continue
        current = _grown_within(sides, largest, required)
        # the shrinking below and the minimality test: two sets per place of current
        spend(2 * len(current) * len(current))
        # Shrink while the required places stay. One pass is enough: a place
        # whose removal loses R once loses it from every smaller set too.
        for p in sorted(current - required):
            if p in current:
                smaller = _max_within(sides, current - {p})
                if smaller and required <= smaller:
                    current = smaller
        # minimal among the sets holding R; minimal outright if no place can go
        if all(not _max_within(sides, current - {p}) for p in current):
            found.append(current)
        order = tuple(sorted(current - required))
        stack.extend((largest, count, order, i, required) for i in range(len(order)))
    return sorted(found, key=lambda x: (len(x), sorted(x)))


def minimal_siphons(s: Structure, limit: int | None = None,
                    work: int | None = None) -> list[frozenset[int]]:
    """Every minimal siphon, as a set of place indices (``s.names`` gives names).

    Exact enumeration by partitioning the search space (Cordone, Ferrarini
    and Piroddi 2005), each siphon found once; sorted by size, then by place
    order. There can be exponentially many: past ``limit`` subproblems it
    raises :class:`~mcl2pnml.analysis.structure.invariants.AnalysisLimit`, and past ``work``
    places looked at (see :func:`_minimal_sets`).
    """
    return _minimal_sets(_siphon_sides(s), len(s.places), limit, "siphons", work)


def minimal_traps(s: Structure, limit: int | None = None,
                  work: int | None = None) -> list[frozenset[int]]:
    """Every minimal trap, as a set of place indices.

    As :func:`minimal_siphons` (Cordone, Ferrarini and Piroddi 2005), with
    the directions of the arcs reversed.
    """
    return _minimal_sets(_trap_sides(s), len(s.places), limit, "traps", work)


def _around(sets: Sets, places: set[int]) -> set[int]:
    return set().union(*(sets[p] for p in places))


def is_siphon(s: Structure, places: Iterable[int]) -> bool:
    """Whether ``places`` (indices) is a siphon: nonempty, •S ⊆ S• (Murata 1989)."""
    places = set(places)
    return bool(places) and _around(s.place_pre, places) <= _around(s.place_post, places)


def is_trap(s: Structure, places: Iterable[int]) -> bool:
    """Whether ``places`` (indices) is a trap: nonempty, Q• ⊆ •Q (Murata 1989)."""
    places = set(places)
    return bool(places) and _around(s.place_post, places) <= _around(s.place_pre, places)


#: Above this many places the exact LP is not tried (it works on dense matrices).
LP_PLACES = 400


def control_by_lp(s: Structure, siphon: frozenset[int]) -> dict[str, int] | None:
    """A P-invariant y with its positive places in ``siphon`` and y . M0 > 0, if any.

    The control of Iordache and Antsaklis (2006) in full, by exact linear
    programming (sympy's simplex, over the rationals): maximise y . M0
    (capped at 1) over y^T C = 0 with y_p <= 0 outside the siphon. The
    minimal semi-positive invariants do not always suffice: the task's
    siphon {OFF, D, EXE, E_OK, E_FAIL} is controlled by the paper's equation
    10, which weighs E negatively.

    Every variable is written nonnegative (y_p = u_p - v_p inside the siphon,
    y_p = -z_p outside), the simplex's own form: sympy 1.14 mishandles an
    upper bound of 0 combined with equality constraints.
    """
    # sympy takes most of a second to import: only for a siphon no semi-positive invariant controls
    from sympy import Matrix
    from sympy.solvers.simplex import linprog

    m0 = s.initial_vector()
    if not any(m0[p] for p in siphon):
        return None  # y . M0 > 0 needs a marked positive place, all inside the siphon
    inside = sorted(siphon)
    outside = [p for p in range(len(s.places)) if p not in siphon]

    def row(coef: Mapping[int, int]) -> list[int]:
        """{place: factor} as one row over the columns u (inside), v (inside), z."""
        return ([coef.get(p, 0) for p in inside] + [-coef.get(p, 0) for p in inside]
                + [-coef.get(p, 0) for p in outside])

    eq = [row(col) for col in s.incidence if col]
    value = row({p: m0[p] for p in range(len(s.places)) if m0[p]})
    optimum, x = linprog(Matrix([[-v for v in value]]), Matrix([value]), Matrix([1]),
                         Matrix(eq) if eq else None, Matrix.zeros(len(eq), 1) if eq else None)
    if optimum >= 0:
        return None
    k = len(inside)
    y = {p: x[i] - x[k + i] for i, p in enumerate(inside)}
    y.update({p: -x[2 * k + i] for i, p in enumerate(outside)})
    ints = integer_multiple(y)
    return {s.places[p]: c for p, c in sorted(ints.items())}


@dataclass(frozen=True)
class SiphonReport:
    """One minimal siphon and why it can (or cannot) empty."""

    places: tuple[str, ...]
    marked: bool                          # holds a token at M0
    controlled_by: dict[str, int] | None  # a P-invariant that keeps it marked
    source: bool                          # •S empty: nothing in the net puts into it

    @property
    def controlled(self) -> bool:
        return self.controlled_by is not None


def siphon_control(s: Structure, siphons: Sequence[frozenset[int]],
                   semipositive_invariants: Sequence[Mapping[str, int]]
                   ) -> list[SiphonReport]:
    """For each siphon: marked at M0, controlled (and by which invariant), a source.

    Controlled is meant as Iordache and Antsaklis (2006): a P-invariant y
    has every positively weighted place in the siphon and y . M0 > 0.
    ``semipositive_invariants`` (the minimal ones, from
    :func:`~mcl2pnml.analysis.structure.invariants.minimal_semipositive_p_invariants`) are tried
    first, in order: for them the condition is that the support is inside
    the siphon. When none fits, an exact LP looks for any invariant that does
    (:func:`control_by_lp`), on nets of up to :data:`LP_PLACES` places.

    A *source* siphon has no input transition at all (•S empty; a read arc
    counts, as everywhere here): its places are written only from outside
    the net, by the structure it is composed into, so it needs no control
    within it.
    """
    m0 = s.initial_vector()
    idx = s.place_index
    reports = []
    for siphon in siphons:
        names = set(s.names(siphon))
        control = None
        for y in semipositive_invariants:
            positive = {p for p, c in y.items() if c > 0}
            if positive <= names and sum(c * m0[idx[p]] for p, c in y.items()) > 0:
                control = dict(y)
                break
        if control is None and len(s.places) <= LP_PLACES:
            control = control_by_lp(s, siphon)
        reports.append(SiphonReport(
            places=tuple(s.names(siphon)),
            marked=any(m0[p] for p in siphon),
            controlled_by=control,
            source=not _around(s.place_pre, set(siphon))))
    return reports
