"""The state equation: markings that no run reaches, found without exploring.

Every marking M reached from M0 by a firing sequence is ``M = M0 + C x``, with C the
incidence matrix and x >= 0 the number of times each transition fired (Murata 1989,
section VI, the state equation). So where no integer x >= 0 gives an M >= 0 that
satisfies a condition, no reachable marking satisfies it. The converse is false (a
solution need not be a run: a transition may lack its tokens at the moment it would
fire), and nothing is concluded from a solution: the answer is "unreachable" or none.
A read arc adds nothing to C, as it changes no count; the condition only loses
precision, not soundness.

A state formula of the contest is put in disjunctive normal form over linear
constraints on M (``sum <= sum``; a transition enabled: each of its input places
holds its arc's weight), each disjunct an integer program solved by HiGHS (scipy's
``milp``): the formula is unreachable when every disjunct is infeasible. A deadlock
alone is one program of its own (:func:`dead_unreachable`); inside a larger formula, or
a normal form past :data:`MAX_DISJUNCTS`, it is not asked. This is the contest's
``STATE_EQUATION`` technique, as verifypn and LoLA use it (verifypn: Jensen, Nielsen,
Oestergaard and Srba, "TAPAAL and reachability analysis of P/T nets", 2016).

The same equation bounds a sum of places from above (:func:`upper_bound`): no
reachable marking holds more than the largest sum any solution allows.
"""
from __future__ import annotations

import time
from functools import lru_cache
from typing import Callable
from itertools import product

import numpy as np

from mcl2pnml.core import queries as q
from mcl2pnml.core.structure import Structure

#: The most disjuncts a formula's normal form may have before it is not asked.
MAX_DISJUNCTS = 64
#: Seconds HiGHS may take on one disjunct; past it, the formula is not decided.
SOLVE_SECONDS = 5.0

# A constraint: (coefficients by place index, upper bound): sum of c * M(p) <= bound.
Constraint = tuple[dict[int, int], int]


class _TooLarge(Exception):
    """The formula has no normal form this module takes (a deadlock, too many disjuncts)."""


def unreachable(s: Structure, phi, seconds: float = SOLVE_SECONDS,
                place_bound: Callable[[int], int | None] = lambda p: None) -> bool:
    """Whether the state equation proves that no reachable marking of ``s``'s net
    satisfies the state formula ``phi`` (True); False: not proven (it may be reachable,
    or ``seconds`` ran out). A place or transition the net does not have raises KeyError.
    ``place_bound``: proven upper bounds of single places, by index, for a deadlock
    (:func:`dead_unreachable`)."""
    if isinstance(phi, q.Deadlock):
        return dead_unreachable(s, seconds, place_bound)
    try:
        disjuncts = _normal_form(phi, s, True)
    except _TooLarge:
        return False
    end = time.monotonic() + seconds
    for conj in disjuncts:
        left = min(SOLVE_SECONDS, end - time.monotonic())
        if left <= 0 or not _infeasible(s, conj, left):
            return False
    return True


def _normal_form(f, s: Structure, positive: bool) -> list[list[Constraint]]:
    """``f`` (or its negation, ``positive`` False) as a list of conjunctions of
    constraints; [] is false, [[]] true."""
    if isinstance(f, q.BoolConst):
        return [[]] if f.value is positive else []
    if isinstance(f, q.Neg):
        return _normal_form(f.arg, s, not positive)
    if isinstance(f, (q.Conj, q.Disj)):
        parts = [_normal_form(a, s, positive) for a in f.args]
        if isinstance(f, q.Disj) is positive:     # a disjunction (De Morgan's, negated)
            return _capped([c for part in parts for c in part])
        out: list[list[Constraint]] = [[]]
        for part in parts:
            out = _capped([a + b for a, b in product(out, part)])
        return out
    if isinstance(f, q.IntLe):
        coefficients, constant = _difference(f.left, f.right, s)   # left - right
        # left - right <= 0, or (negated) right - left <= -1
        if positive:
            return [[(coefficients, -constant)]]
        return [[({p: -c for p, c in coefficients.items()}, constant - 1)]]
    if isinstance(f, q.Fireable):
        needs = []
        for t in f.transitions:
            j = s.transition_index[t]
            needs.append([(p, w) for arcs in (s.pre[j], s.read[j]) for p, w in arcs.items()])
        if positive:        # some transition has each of its inputs: -M(p) <= -w
            return _capped([[({p: -1}, -w) for p, w in need] for need in needs])
        # every transition lacks one of its inputs: M(p) <= w - 1 for one p each
        out = [[]]
        for need in needs:
            out = _capped([c + [({p: 1}, w - 1)] for c in out for p, w in need])
        return out
    raise _TooLarge     # a deadlock: a conjunction over every transition


def _capped(disjuncts: list) -> list:
    if len(disjuncts) > MAX_DISJUNCTS:
        raise _TooLarge
    return disjuncts


def _difference(left, right, s: Structure) -> tuple[dict[int, int], int]:
    """``left - right`` as (coefficients by place index, constant)."""
    coefficients: dict[int, int] = {}
    constant = 0
    for e, sign in ((left, 1), (right, -1)):
        if isinstance(e, q.IntConst):
            constant += sign * e.value
            continue
        for p in e.places:
            i = s.place_index[p]
            coefficients[i] = coefficients.get(i, 0) + sign
    return {p: c for p, c in coefficients.items() if c}, constant


@lru_cache(maxsize=4)
def incidence_matrix(s: Structure):
    """C as a sparse matrix (places x transitions, integers) and M0 (floats), once per
    net: every disjunct of every question of a file shares them, and the walks fire by
    C's columns."""
    from scipy.sparse import coo_matrix     # scipy: only when asked (as below)
    rows, cols, values = [], [], []
    for j, column in enumerate(s.incidence):
        for p, v in column.items():
            rows.append(p)
            cols.append(j)
            values.append(v)
    c = coo_matrix((values, (rows, cols)), shape=(len(s.places), len(s.transitions)))
    return c.tocsr(), np.asarray(s.initial_vector(), dtype=float)


def _infeasible(s: Structure, conjunction: list[Constraint], seconds: float) -> bool:
    """Whether no integer x >= 0 gives M = M0 + C x >= 0 meeting every constraint."""
    return _solve(s, conjunction, seconds, False)[0] == 2


def _solve(s: Structure, conjunction: list[Constraint], seconds: float, fewest: bool
           ) -> tuple[int, np.ndarray | None]:
    """HiGHS's status on the equation with ``conjunction`` (0: solved, 2: infeasible,
    anything else: nothing known) and its integer solution x, if any; ``fewest``: the
    solution with the fewest firings."""
    # scipy's optimize and sparse, 0.7 s (python -X importtime): only when a question
    # is asked, not at every command's start
    from scipy.optimize import Bounds, LinearConstraint, milp
    from scipy.sparse import coo_matrix

    c, m0 = incidence_matrix(s)
    places, transitions = len(s.places), len(s.transitions)
    if transitions == 0:        # M0 is the only marking
        ok = all(sum(v * m0[p] for p, v in k.items()) <= b for k, b in conjunction)
        return (0, np.zeros(0, dtype=np.int64)) if ok else (2, None)
    # each constraint a . M <= b is a . C x <= b - a . M0
    a = coo_matrix(([v for k, _ in conjunction for v in k.values()],
                    ([i for i, (k, _) in enumerate(conjunction) for _ in k],
                     [p for k, _ in conjunction for p in k])),
                   shape=(len(conjunction), places)).tocsr()
    bound = np.asarray([b for _, b in conjunction], dtype=float) - a @ m0
    constraints = [LinearConstraint(c, -m0, np.inf)]          # M >= 0
    if conjunction:
        constraints.append(LinearConstraint(a @ c, -np.inf, bound))
    result = milp(np.ones(transitions) if fewest else np.zeros(transitions),
                  constraints=constraints, integrality=np.ones(transitions),
                  bounds=Bounds(0, np.inf), options={"time_limit": seconds, "presolve": True})
    x = None if result.x is None else np.rint(result.x).astype(np.int64)
    return result.status, x


def firing_counts(s: Structure, phi, seconds: float = SOLVE_SECONDS) -> list[np.ndarray]:
    """For each disjunct of ``phi`` that the equation does not rule out, its solution with
    the fewest firings: how often each transition would fire on a run to a marking that
    satisfies it, were the solution a run (it need not be: the caller fires it to see).
    Within ``seconds``; [] where ``phi`` has no normal form taken here."""
    try:
        disjuncts = _normal_form(phi, s, True)
    except _TooLarge:
        return []
    end = time.monotonic() + seconds
    found = []
    for conj in disjuncts:
        left = min(SOLVE_SECONDS, end - time.monotonic())
        if left <= 0:
            break
        status, x = _solve(s, conj, left, True)
        if x is not None and status in (0, 1):
            found.append(x)
    return found


def dead_unreachable(s: Structure, seconds: float = SOLVE_SECONDS,
                     place_bound: Callable[[int], int | None] = lambda p: None) -> bool:
    """Whether no integer solution of the state equation is a dead marking, so that no
    reachable marking is (True; False: not proven).

    A transition is disabled where one of its input places p holds less than its arc's
    weight w: one binary ``y[p, w]`` per (place, weight) says ``M(p) <= w - 1``, and each
    transition needs one of its own set. ``y`` is tied to M by a big M, which must be a
    proven bound of M(p), or the program would leave out markings that hold more (and
    prove "unreachable" wrongly): ``M(p) <= w - 1 + B(p) (1 - y)``, ``B(p)`` from
    ``place_bound`` (the P-invariants), else from the equation's linear relaxation. A
    transition with an unbounded input place is left out of the program: the markings it
    asks about are then more, never fewer, and an infeasible program still proves.
    A transition without input places is always enabled: no marking is dead."""
    # scipy's optimize and sparse, 0.7 s: only when asked, as in _solve
    from scipy.optimize import Bounds, LinearConstraint, linprog, milp
    from scipy.sparse import coo_matrix, csr_matrix, hstack

    end = time.monotonic() + seconds
    c, m0 = incidence_matrix(s)
    if any(not pre and not read for pre, read in zip(s.pre, s.read)):
        return True
    bounds: dict[int, float | None] = {}

    def bound(p: int) -> float | None:
        if p not in bounds:
            b = place_bound(p)
            if b is None and time.monotonic() < end:
                # max M(p) = M0(p) + C[p] x over the real solutions: an upper bound of
                # every integer one
                r = linprog(-c[p].toarray().ravel(), A_ub=-c, b_ub=m0, bounds=(0, None),
                            method="highs",
                            options={"time_limit": max(0.01, end - time.monotonic())})
                b = None if r.status != 0 else np.floor(m0[p] - r.fun + 1e-6)
            bounds[p] = b
        return bounds[p]
    ys: dict[tuple[int, int], int] = {}        # (place, weight): its binary's column
    choices: list[list[int]] = []              # each transition kept: its binaries
    for pre, read in zip(s.pre, s.read):
        needs = {**read, **pre}          # a net never both reads and takes one place
        if any(bound(p) is None for p in needs):
            continue                            # left out: more markings, still sound
        choices.append([ys.setdefault((p, w), len(ys)) for p, w in needs.items()])
    if time.monotonic() >= end:
        return False
    transitions, n = len(s.transitions), len(s.transitions) + len(ys)
    rows, cols, values, upper = [], [], [], []
    for (p, w), k in ys.items():               # C[p] x + B y <= w - 1 + B - M0(p)
        big = bound(p)
        row = len(upper)
        start, stop = c.indptr[p], c.indptr[p + 1]
        rows += [row] * (stop - start) + [row]
        cols += list(c.indices[start:stop]) + [transitions + k]
        values += list(c.data[start:stop]) + [big]
        upper.append(w - 1 + big - m0[p])
    tied = coo_matrix((values, (rows, cols)), shape=(len(upper), n)).tocsr()
    pick = coo_matrix(([1.0] * sum(map(len, choices)),
                       ([i for i, ks in enumerate(choices) for _ in ks],
                        [transitions + k for ks in choices for k in ks])),
                      shape=(len(choices), n)).tocsr()
    marking = hstack([c, csr_matrix((c.shape[0], len(ys)))]).tocsr()
    constraints = [LinearConstraint(marking, -m0, np.inf)]           # M >= 0
    if len(upper):
        constraints.append(LinearConstraint(tied, -np.inf, np.asarray(upper)))
    if choices:
        constraints.append(LinearConstraint(pick, 1, np.inf))
    upper_x = np.concatenate([np.full(transitions, np.inf), np.ones(len(ys))])
    result = milp(np.zeros(n), constraints=constraints, integrality=np.ones(n),
                  bounds=Bounds(0, upper_x),
                  options={"time_limit": max(0.01, end - time.monotonic()),
                           "presolve": True})
    return result.status == 2


def upper_bound(s: Structure, places, seconds: float = SOLVE_SECONDS) -> int | None:
    """An upper bound of the token sum of ``places`` (names, repeats counted) over every
    reachable marking: the largest ``a . M`` with ``M = M0 + C x``, ``M, x >= 0``
    integers, by HiGHS; None where the equation does not bound it (or ``seconds`` ran
    out with no bound). The solver's dual bound is read, not its best solution: a
    solution within the optimality gap would understate the maximum, the dual bound
    never does. A place the net does not have raises KeyError."""
    from scipy.optimize import Bounds, LinearConstraint, milp   # as in _infeasible

    weights = np.zeros(len(s.places))
    for p in places:
        weights[s.place_index[p]] += 1
    c, m0 = incidence_matrix(s)
    start = float(weights @ m0)
    if len(s.transitions) == 0:
        return int(round(start))
    gain = np.asarray(c.T @ weights).ravel()          # a . C x: the sum's growth
    result = milp(-gain, constraints=[LinearConstraint(c, -m0, np.inf)],
                  integrality=np.ones(len(s.transitions)), bounds=Bounds(0, np.inf),
                  options={"time_limit": seconds, "presolve": True})
    # minimising -gain: every solution's -gain is at least the dual bound, so no
    # reachable sum passes start - dual bound (a tolerance of the solver's own size)
    dual = getattr(result, "mip_dual_bound", None)
    if result.status not in (0, 1) or dual is None or not np.isfinite(dual):
        return None
    return int(np.floor(start - dual + 1e-6))
