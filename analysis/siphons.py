"""Siphons, traps, and whether the siphons are controlled.

A *siphon* is a nonempty set of places S with •S ⊆ S• (Iordache and
Antsaklis 2006): every transition that puts a token into S also takes one
from S, so once S is empty it stays empty, and the transitions that need it
are dead. A *trap* is the dual, Q• ⊆ •Q: once marked, always marked. A read
arc counts both ways here (the transition is in •p and in p•), as the
self-loop it stands for.

:func:`minimal_siphons` enumerates every minimal siphon exactly once by
partitioning the search space (after Cordone, Ferrarini and Piroddi 2005):
a subproblem is "the minimal siphons N with R ⊆ N ⊆ P'". The largest siphon
inside P' is found in linear time (:func:`max_siphon_within`); if it holds
R, it is shrunk to a siphon minimal among those that hold R, which is output
if it is minimal outright; then the subproblem splits on the places
p_1 ... p_k of that siphon outside R into (P' - {p_i}, R + {p_1 ... p_i-1}),
so that every other minimal siphon falls in exactly one part.

:func:`siphon_control` is the check the paper uses (section 2.2, after
Iordache and Antsaklis): a siphon is *controlled* when some P-invariant y
has all its positively weighted places inside S and y . M0 > 0. Then
sum over S of y_p M(p) >= y . M = y . M0 > 0 in every reachable marking: S
never empties.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Mapping, Sequence

from fractions import Fraction
from math import gcd

from .invariants import AnalysisLimit
from .matrix import Structure

Sets = Sequence[frozenset[int]]


@dataclass(frozen=True)
class _Sides:
    """The four adjacency maps a maximal siphon (or, swapped, trap) needs."""

    guard: Sets      # per place: transitions that must keep an input in the set (•p; traps p•)
    inputs: Sets     # per transition: the places that count as its inputs (•t; traps t•)
    users: Sets      # per place: transitions that count it as an input (p•; traps •p)
    fed: Sets        # per transition: places that depend on it (t•; traps •t)


def _siphon_sides(s: Structure) -> _Sides:
    return _Sides(s.place_pre, s.transition_inputs, s.place_post, s.transition_outputs)


def _trap_sides(s: Structure) -> _Sides:
    return _Sides(s.place_post, s.transition_outputs, s.place_pre, s.transition_inputs)


def _max_within(sides: _Sides, places: Iterable[int]) -> frozenset[int]:
    """The largest set inside ``places`` whose every guard transition keeps an input in it.

    A transition left without inputs in the set "unfeeds" every place it
    guards; removing those may unfeed more. Counters make it linear.
    """
    inside = set(places)
    count = {}
    for p in inside:
        for t in sides.users[p]:
            count[t] = count.get(t, 0) + 1
    queue = [p for p in inside if any(count.get(t, 0) == 0 for t in sides.guard[p])]
    while queue:
        p = queue.pop()
        if p not in inside:
            continue
        inside.discard(p)
        for t in sides.users[p]:
            count[t] -= 1
            if count[t] == 0:
                queue.extend(q for q in sides.fed[t] if q in inside)
    return frozenset(inside)


def max_siphon_within(s: Structure, places: Iterable[int]) -> frozenset[int]:
    """The largest siphon contained in ``places`` (empty if there is none)."""
    return _max_within(_siphon_sides(s), places)


def max_trap_within(s: Structure, places: Iterable[int]) -> frozenset[int]:
    """The largest trap contained in ``places`` (empty if there is none)."""
    return _max_within(_trap_sides(s), places)


def _minimal_sets(sides: _Sides, nplaces: int, limit: int | None,
                  what: str) -> list[frozenset[int]]:
    found: list[frozenset[int]] = []
    stack: list[tuple[frozenset[int], frozenset[int]]] = [
        (frozenset(range(nplaces)), frozenset())]
    visited = 0
    while stack:
        allowed, required = stack.pop()
        visited += 1
        if limit is not None and visited > limit:
            raise AnalysisLimit(f"more than {limit:,} subproblems enumerating minimal {what}")
        current = _max_within(sides, allowed)
        if not current or not required <= current:
            continue
        # shrink while the required places stay: a failed removal never
        # succeeds later (the sets only get smaller), so one pass is enough
        for p in sorted(current - required):
            if p in current:
                smaller = _max_within(sides, current - {p})
                if smaller and required <= smaller:
                    current = smaller
        if all(not _max_within(sides, current - {p}) for p in current):
            found.append(current)
        before: list[int] = []
        for p in sorted(current - required):
            stack.append((allowed - {p}, required | frozenset(before)))
            before.append(p)
    return sorted(found, key=lambda x: (len(x), sorted(x)))


def minimal_siphons(s: Structure, limit: int | None = None) -> list[frozenset[int]]:
    """Every minimal siphon, as sets of place indices (``s.names`` for names)."""
    return _minimal_sets(_siphon_sides(s), len(s.places), limit, "siphons")


def minimal_traps(s: Structure, limit: int | None = None) -> list[frozenset[int]]:
    """Every minimal trap, as sets of place indices."""
    return _minimal_sets(_trap_sides(s), len(s.places), limit, "traps")


def is_siphon(s: Structure, places: Iterable[int]) -> bool:
    places = set(places)
    feeders = set().union(*(s.place_pre[p] for p in places)) if places else set()
    takers = set().union(*(s.place_post[p] for p in places)) if places else set()
    return bool(places) and feeders <= takers


def is_trap(s: Structure, places: Iterable[int]) -> bool:
    places = set(places)
    takers = set().union(*(s.place_post[p] for p in places)) if places else set()
    feeders = set().union(*(s.place_pre[p] for p in places)) if places else set()
    return bool(places) and takers <= feeders


def _integers(vec: Mapping[int, Fraction]) -> dict[int, int]:
    """Coprime integers with the same signs (a positive multiple of ``vec``)."""
    lcm = 1
    for v in vec.values():
        lcm = lcm * v.denominator // gcd(lcm, v.denominator)
    ints = {p: int(v * lcm) for p, v in vec.items()}
    g = 0
    for v in ints.values():
        g = gcd(g, v)
    return {p: v // g for p, v in ints.items()}


#: Above this many places the exact LP is not tried (it works on dense matrices).
LP_PLACES = 400


def control_by_lp(s: Structure, siphon: frozenset[int]) -> dict[str, int] | None:
    """A P-invariant y with its positive places in ``siphon`` and y . M0 > 0, if any.

    Exact linear programming (sympy's simplex, over the rationals): maximise
    y . M0 (capped at 1) over y^T C = 0 with y_p <= 0 outside the siphon. The
    minimal semi-positive invariants do not always suffice: the task's siphon
    {OFF, D, EXE, E_OK, E_FAIL} is controlled by equation 10, which weighs E
    negatively.

    Every variable is written nonnegative (y_p = u_p - v_p inside the siphon,
    y_p = -z_p outside), the simplex's own form: sympy 1.14 mishandles an
    upper bound of 0 combined with equality constraints.
    """
    from sympy import Matrix
    from sympy.solvers.simplex import linprog

    m0 = s.initial_vector()
    if not any(m0[p] for p in siphon):
        return None  # y . M0 > 0 needs a marked positive place, all inside the siphon
    inside = sorted(siphon)
    outside = [p for p in range(len(s.places)) if p not in siphon]
    # columns: u (inside), v (inside), z (outside); y = u - v on inside, -z outside
    def row(coef):  # coef: {place: factor} -> one row over the columns
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
    ints = _integers({p: Fraction(int(v.p), int(v.q)) for p, v in y.items() if v})
    return {s.places[p]: c for p, c in sorted(ints.items())}


@dataclass(frozen=True)
class SiphonReport:
    """One minimal siphon and why it can (or cannot) empty."""

    places: tuple[str, ...]
    marked: bool                          # holds a token at M0
    controlled_by: dict[str, int] | None  # a P-invariant that keeps it marked
    source: bool                          # no transition writes to it: an input from outside

    @property
    def controlled(self) -> bool:
        return self.controlled_by is not None


def siphon_control(s: Structure, siphons: Sequence[frozenset[int]],
                   invariants: Sequence[Mapping[str, int]]) -> list[SiphonReport]:
    """For each siphon: marked at M0, controlled (and by which invariant), or a source.

    ``invariants`` are tried in order; the minimal semi-positive ones are the
    natural candidates (their positive places are their whole support). When
    none fits, an exact LP looks for any invariant that does
    (:func:`control_by_lp`), on nets of up to :data:`LP_PLACES` places.
    """
    m0 = s.initial_vector()
    idx = s.place_index
    reports = []
    for siphon in siphons:
        names = set(s.names(siphon))
        control = None
        for y in invariants:
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
            source=all(not s.place_pre[p] for p in siphon)))
    return reports
