"""Invariants, siphons and traps: hand-checked nets, and random nets against brute force.

Every check here is made from the definitions, independently of the code
under test: y^T C = 0 on the dense incidence matrix, dimensions from
an exact rank of that matrix (fractions), siphons and traps by trying every subset of
places, minimal-support invariants by trying small coefficient vectors and
by the rank criterion (a semi-positive invariant has minimal support exactly
when the rows of C on its support have rank |support| - 1).
"""
from __future__ import annotations

import random
from fractions import Fraction
from itertools import combinations, product
from math import gcd

import pytest
import sympy
from hypothesis import given, settings
from hypothesis import strategies as st

from mcl2pnml.analysis.structure.invariants import (AnalysisLimit, format_invariant, invariant_value,
                                 is_p_invariant, minimal_semipositive_p_invariants,
                                 minimal_semipositive_t_invariants, p_invariant_basis,
                                 t_invariant_basis)
from mcl2pnml.analysis.structure.siphons import (SiphonReport, control_by_lp, is_siphon, is_trap,
                              max_siphon_within, max_trap_within, minimal_siphons,
                              minimal_traps, siphon_control)
from mcl2pnml.analysis.zoo import cycle, philosophers
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import ArcKind, Marking, Net, NetBuilder
from mcl2pnml.core.structure import structure
from sampling import sample

# ---------------------------------------------------------------------------
# hand-built nets


def guarded(link: str) -> Net:
    """t puts into q while it has g (``link``: how g joins t); v: q -> g.

    ``"read"``: a read arc; ``"loop"``: the self-loop g -> t -> g it stands
    for; ``"consume"``: t takes g; ``"none"``: g is not joined to t.
    """
    b = NetBuilder(f"guarded-{link}")
    b.place("g", 1)
    b.place("q")
    b.transition("t")
    b.transition("v")
    if link == "read":
        b.read("g", "t")
    elif link in ("loop", "consume"):
        b.arc("g", "t")
        if link == "loop":
            b.arc("t", "g")
    b.arc("t", "q")
    b.arc("q", "v")
    b.arc("v", "g")
    return b.build()


def names(s, sets):
    return [set(s.names(x)) for x in sets]


# ---------------------------------------------------------------------------
# the checks, from the definitions


def dense(s) -> list[list[int]]:
    return s.dense_incidence()


def rank(rows: list[list[int]]) -> int:
    """The rank by Gaussian elimination over the rationals, exact: neither the code under
    test's sparse elimination nor sympy's dense matrices (whose rank took a fifth of this
    file's time, called thousands of times on matrices of a few rows)."""
    left = [[Fraction(v) for v in row] for row in rows if any(row)]
    r = 0
    for col in range(len(left[0]) if left else 0):
        pivot = next((i for i in range(r, len(left)) if left[i][col]), None)
        if pivot is None:
            continue
        left[r], left[pivot] = left[pivot], left[r]
        for i in range(r + 1, len(left)):
            if left[i][col]:
                f = left[i][col] / left[r][col]
                left[i] = [a - f * b for a, b in zip(left[i], left[r])]
        r += 1
    return r


def left_null(s, y: dict[str, int], c=None) -> bool:
    """y^T C = 0 on the dense matrix (``c``, where the caller has it already)."""
    c = dense(s) if c is None else c
    return all(sum(y.get(p, 0) * c[i][j] for i, p in enumerate(s.places)) == 0
               for j in range(len(s.transitions)))


def right_null(s, x: dict[str, int], c=None) -> bool:
    """C x = 0 on the dense matrix (``c``, where the caller has it already)."""
    return all(sum(row[j] * x.get(t, 0) for j, t in enumerate(s.transitions)) == 0
               for row in (dense(s) if c is None else c))


def canonical(vec: list[int]) -> bool:
    """Coprime integers, the first nonzero positive."""
    nonzero = [v for v in vec if v]
    return bool(nonzero) and nonzero[0] > 0 and gcd(*nonzero) == 1


def as_rows(vectors: list[dict[str, int]], order) -> list[list[int]]:
    return [[v.get(k, 0) for k in order] for v in vectors]


def minimal_support(rows: list[list[int]], support: set[int]) -> bool:
    """The rank criterion: C restricted to the rows of ``support`` has a
    one-dimensional left nullspace."""
    sub = [rows[i] for i in sorted(support)]
    return len(support) - rank(sub) == 1


def brute_minimal(s, check) -> list[frozenset[int]]:
    n = len(s.places)
    found = [frozenset(c) for k in range(1, n + 1) for c in combinations(range(n), k)
             if check(s, c)]
    return sorted((x for x in found if not any(y < x for y in found)),
                  key=lambda x: (len(x), sorted(x)))


def brute_union(s, check) -> frozenset[int]:
    n = len(s.places)
    return frozenset().union(*(frozenset(c) for k in range(1, n + 1)
                               for c in combinations(range(n), k) if check(s, c)))


# ---------------------------------------------------------------------------
# a 4-place cycle


def test_cycle():
    s = structure(cycle(4))
    every_place = {f"p{i}": 1 for i in range(4)}
    assert p_invariant_basis(s) == [every_place]
    assert t_invariant_basis(s) == [{f"t{i}": 1 for i in range(4)}]
    assert minimal_semipositive_p_invariants(s) == [every_place]
    assert minimal_semipositive_t_invariants(s) == [{f"t{i}": 1 for i in range(4)}]
    assert is_p_invariant(s, every_place)
    assert invariant_value(s, every_place, s.net.initial) == 1
    assert invariant_value(s, every_place, Marking({"p2": 1})) == 1
    assert minimal_siphons(s) == minimal_traps(s) == [frozenset(range(4))]
    [report] = siphon_control(s, minimal_siphons(s), minimal_semipositive_p_invariants(s))
    assert report == SiphonReport(("p0", "p1", "p2", "p3"), True, every_place, False)
    assert report.controlled


# ---------------------------------------------------------------------------
# the dining philosophers


def test_philosophers_invariants_are_the_textbook_ones():
    s = structure(philosophers(3))
    textbook = ([{f"think{i}": 1, f"eat{i}": 1} for i in range(3)]
                + [{f"fork{i}": 1, f"eat{i}": 1, f"eat{(i - 1) % 3}": 1} for i in range(3)])
    semi = minimal_semipositive_p_invariants(s)
    assert sorted(map(sorted, (y.items() for y in semi))) == \
        sorted(map(sorted, (y.items() for y in textbook)))
    # 9 places, rank 3 (release i undoes take i): the textbook six are a basis
    basis = p_invariant_basis(s)
    assert len(basis) == 6 == len(s.places) - rank(dense(s))
    assert rank(as_rows(basis + textbook, s.places)) == 6
    assert all(is_p_invariant(s, y) and invariant_value(s, y, s.net.initial) == 1
               for y in textbook)
    assert minimal_semipositive_t_invariants(s) == [
        {f"take{i}": 1, f"release{i}": 1} for i in range(3)]
    assert len(t_invariant_basis(s)) == 3


def test_philosophers_siphons_and_traps_are_the_invariant_supports():
    s = structure(philosophers(3))
    supports = ([{f"think{i}", f"eat{i}"} for i in range(3)]
                + [{f"fork{i}", f"eat{i}", f"eat{(i - 1) % 3}"} for i in range(3)])
    expected = sorted(map(frozenset, supports), key=lambda x: (len(x), sorted(
        s.place_index[p] for p in x)))
    assert [frozenset(x) for x in names(s, minimal_siphons(s))] == expected
    assert [frozenset(x) for x in names(s, minimal_traps(s))] == expected
    semi = minimal_semipositive_p_invariants(s)
    for r in siphon_control(s, minimal_siphons(s), semi):
        assert r.marked and r.controlled and not r.source
        assert set(r.controlled_by) == set(r.places)  # its own invariant
    idx = s.place_index
    within = {idx["think0"], idx["eat0"], idx["fork0"]}
    # fork0 also feeds philosopher 2, whose eat2 is not in the set
    assert max_siphon_within(s, within) == {idx["think0"], idx["eat0"]}
    assert max_trap_within(s, within) == {idx["think0"], idx["eat0"]}
    assert max_siphon_within(s, range(len(s.places))) == set(range(len(s.places)))


# ---------------------------------------------------------------------------
# read arcs


def test_a_read_arc_counts_both_ways_for_siphons_and_traps():
    read, loop = structure(guarded("read")), structure(guarded("loop"))
    # as an input: q's only feeder t needs g, so {g, q} is a siphon; g
    # alone is not, since v feeds it from outside
    assert names(read, minimal_siphons(read)) == [{"g", "q"}]
    # as an output: t reads g and puts it back, so {g} is a trap
    assert names(read, minimal_traps(read)) == [{"g"}]
    # exactly the self-loop's siphons and traps
    assert names(loop, minimal_siphons(loop)) == [{"g", "q"}]
    assert names(loop, minimal_traps(loop)) == [{"g"}]
    # without the read arc t needs nothing: no siphon at all
    none = structure(guarded("none"))
    assert minimal_siphons(none) == []
    # a consuming arc is an input only: {g} is no longer a trap
    consume = structure(guarded("consume"))
    assert names(consume, minimal_traps(consume)) == [{"g", "q"}]
    # and a read arc adds nothing to C: the invariants are those without it
    assert dense(read) == dense(none) == dense(loop)
    assert p_invariant_basis(read) == p_invariant_basis(none)
    assert t_invariant_basis(read) == t_invariant_basis(none)


def test_a_read_only_place_is_a_siphon_but_not_a_source():
    b = NetBuilder("r")
    b.place("g")
    b.place("q")
    b.transition("t")
    b.read("g", "t")
    b.arc("t", "q")
    s = structure(b.build())
    [report] = siphon_control(s, minimal_siphons(s), minimal_semipositive_p_invariants(s))
    # t needs g and gives it back, like a self-loop: g empty stays empty
    assert report.places == ("g",) and not report.marked and not report.source
    assert not report.controlled


# ---------------------------------------------------------------------------
# siphons that are not controlled


def test_a_marked_siphon_that_can_empty_is_not_controlled():
    # a <-> b, and w drains b: {a, b} is a siphon, marked, and w empties it
    b = NetBuilder("leak")
    b.place("a", 1)
    b.place("b")
    for t, src, dst in (("t", "a", "b"), ("u", "b", "a"), ("w", "b", None)):
        b.transition(t)
        b.arc(src, t)
        if dst:
            b.arc(t, dst)
    s = structure(b.build())
    assert p_invariant_basis(s) == [] and minimal_semipositive_p_invariants(s) == []
    assert minimal_traps(s) == []
    [report] = siphon_control(s, minimal_siphons(s), [])
    assert report.places == ("a", "b") and report.marked
    assert not report.controlled and not report.source


def test_sources_unmarked_siphons_and_control_by_a_mixed_sign_invariant():
    # t needs a and b; b is never marked, so a keeps its token: a - b = 1
    b = NetBuilder("stuck")
    b.place("a", 1)
    b.place("b")
    b.transition("t")
    b.arc("a", "t")
    b.arc("b", "t")
    s = structure(b.build())
    assert minimal_semipositive_p_invariants(s) == []
    reports = {r.places: r for r in siphon_control(s, minimal_siphons(s), [])}
    assert set(reports) == {("a",), ("b",)}
    a, b_ = reports[("a",)], reports[("b",)]
    assert a.source and a.marked and a.controlled_by == {"a": 1, "b": -1}
    assert is_p_invariant(s, a.controlled_by)
    assert b_.source and not b_.marked and not b_.controlled
    assert control_by_lp(s, frozenset({s.place_index["b"]})) is None


# ---------------------------------------------------------------------------
# the small API details


def test_invariant_helpers():
    s = structure(cycle(3))
    assert not is_p_invariant(s, {"p0": 1})
    assert not is_p_invariant(s, {"p0": 0, "p1": 0})
    assert not is_p_invariant(s, {"p0": 1, "p1": 1, "p2": 1, "nowhere": 1})
    assert is_p_invariant(s, {"p0": -2, "p1": -2, "p2": -2})
    with pytest.raises(Mcl2PnmlError, match="nowhere"):
        invariant_value(s, {"nowhere": 1}, s.net.initial)
    assert format_invariant({"think0": 1, "eat0": 1}, 1) == "think0 + eat0 = 1"
    assert format_invariant({"E": -1, "OFF": 2}, -1) == "-E + 2 OFF = -1"
    assert format_invariant({}) == "0"


def test_limits_raise_analysis_limit():
    # t turns any of a0, a1, a2 into all of b0, b1, b2 at once: the nine
    # a_i + b_j are the minimal semi-positive invariants, nine rows at once
    b = NetBuilder("fan")
    b.transition("t")
    for i in range(3):
        b.arc(b.place(f"a{i}"), "t")
    for i in range(3):
        b.arc("t", b.place(f"b{i}"))
    s = structure(b.build())
    assert issubclass(AnalysisLimit, Mcl2PnmlError)
    with pytest.raises(AnalysisLimit, match="more than 8 intermediate rows"):
        minimal_semipositive_p_invariants(s, limit=8)
    assert minimal_semipositive_p_invariants(s, limit=9) == [
        {f"a{i}": 1, f"b{j}": 1} for i in range(3) for j in range(3)]
    s = structure(philosophers(4))
    with pytest.raises(AnalysisLimit, match="minimal siphons"):
        minimal_siphons(s, limit=3)
    with pytest.raises(AnalysisLimit, match="minimal traps"):
        minimal_traps(s, limit=3)
    assert len(minimal_siphons(s, limit=1000)) == len(minimal_traps(s, limit=1000)) == 8


def test_results_do_not_depend_on_the_transition_order():
    net = philosophers(4)
    shuffled = list(net.transitions)
    random.Random(1).shuffle(shuffled)
    a, b = structure(net), structure(Net(net.name, net.places, tuple(shuffled), net.arcs,
                                         net.initial))
    # the basis comes from the reduced row echelon form of C^T: unique
    assert p_invariant_basis(a) == p_invariant_basis(b)
    assert minimal_semipositive_p_invariants(a) == minimal_semipositive_p_invariants(b)
    assert minimal_siphons(a) == minimal_siphons(b)


def test_degenerate_nets():
    b = NetBuilder("lonely")
    b.place("p", 2)
    b.place("q")
    s = structure(b.build())  # no transitions: every place is an invariant
    assert p_invariant_basis(s) == [{"p": 1}, {"q": 1}]
    assert minimal_semipositive_p_invariants(s) == [{"p": 1}, {"q": 1}]
    assert t_invariant_basis(s) == [] and minimal_semipositive_t_invariants(s) == []
    assert names(s, minimal_siphons(s)) == [{"p"}, {"q"}]
    b = NetBuilder("spark")
    b.transition("t")
    s = structure(b.build())  # no places: a transition with nothing to change
    assert p_invariant_basis(s) == [] and t_invariant_basis(s) == [{"t": 1}]
    assert minimal_semipositive_t_invariants(s) == [{"t": 1}]
    assert minimal_siphons(s) == minimal_traps(s) == []


# ---------------------------------------------------------------------------
# random nets


@st.composite
def small_nets(draw, max_places: int = 6, max_transitions: int = 5):
    """Nets with weights 1-2 and read arcs; the structure is all that counts."""
    np_ = draw(st.integers(1, max_places))
    nt = draw(st.integers(0, max_transitions))
    b = NetBuilder("random")
    for i in range(np_):
        b.place(f"p{i}", draw(st.integers(0, 1)))
    for j in range(nt):
        b.transition(f"t{j}")
    inputs: set = set()
    for _ in range(draw(st.integers(0, 3 * (np_ + nt))) if nt else 0):
        p, t = f"p{draw(st.integers(0, np_ - 1))}", f"t{draw(st.integers(0, nt - 1))}"
        kind, w = draw(st.sampled_from(["in", "out", "read"])), draw(st.integers(1, 2))
        if kind == "out":
            b.arc(t, p, w)
        elif (p, t) not in inputs:  # a transition may not both read and consume
            inputs.add((p, t))
            b.arc(p, t, w, ArcKind.READ if kind == "read" else ArcKind.NORMAL)
    return b.build()


@settings(max_examples=sample(250, 80), deadline=None)
@given(small_nets(max_places=8, max_transitions=6))
def test_minimal_siphons_and_traps_are_those_of_brute_force(net):
    s = structure(net)
    siphons, traps = minimal_siphons(s), minimal_traps(s)
    assert siphons == brute_minimal(s, is_siphon)
    assert traps == brute_minimal(s, is_trap)
    # the largest siphon (trap) is the union of all of them
    everything = range(len(s.places))
    assert max_siphon_within(s, everything) == brute_union(s, is_siphon)
    assert max_trap_within(s, everything) == brute_union(s, is_trap)
    for r in siphon_control(s, siphons, minimal_semipositive_p_invariants(s)):
        if r.controlled:  # Iordache and Antsaklis' condition, checked directly
            y = r.controlled_by
            assert left_null(s, y) and any(y.values())
            assert {p for p, c in y.items() if c > 0} <= set(r.places)
            assert sum(c * net.initial[p] for p, c in y.items()) > 0


@settings(max_examples=sample(250, 80), deadline=None)
@given(small_nets(max_places=6, max_transitions=5))
def test_invariant_bases_by_definition(net):
    s = structure(net)
    c = dense(s)
    r = rank(c)
    for basis, order, null in ((p_invariant_basis(s), s.places, left_null),
                               (t_invariant_basis(s), s.transitions, right_null)):
        assert len(basis) == len(order) - r
        rows = as_rows(basis, order)
        assert all(null(s, v) and canonical(row) for v, row in zip(basis, rows))
        assert all(0 not in v.values() for v in basis)
        assert rank(rows) == len(basis)  # independent, so a basis
    # the same space as plain sympy's dense nullspace
    theirs = sympy.Matrix(c).T.nullspace() if c and c[0] else []
    ours = as_rows(p_invariant_basis(s), s.places)
    if theirs:
        assert sympy.Matrix.hstack(sympy.Matrix(ours).T, *theirs).rank() == len(ours)
    for y in p_invariant_basis(s):
        assert is_p_invariant(s, y)


@settings(max_examples=sample(400, 100), deadline=None)
@given(small_nets(max_places=8, max_transitions=7))
def test_the_dense_and_the_sparse_elimination_give_the_same_basis(net):
    # FLINT's dense nullspace and our sparse elimination read the same unique RREF:
    # vector for vector, in the same order
    from mcl2pnml.analysis.structure import invariants as inv
    s = structure(net)
    for rows, n in ((s.incidence, len(s.places)), (s.incidence_rows, len(s.transitions))):
        assert inv._nullspace(rows, n) == inv._nullspace_dense(rows, n)


@pytest.mark.parametrize("name", ["dam_inspection", "docking", "lawnmower", "sauce"])
def test_a_mission_stays_sparse(examples, name):
    # the bound past which FLINT takes over is never reached on a compiled mission
    from mcl2pnml.analysis.structure import invariants as inv
    s = structure(examples.net(name))
    for rows, n in ((s.incidence, len(s.places)), (s.incidence_rows, len(s.transitions))):
        assert inv._reduced_rows(rows, inv.FILL_IN * len(rows) * n) is not None, (name, n)


def test_a_dense_matrix_goes_to_flint():
    # a random dense matrix fills in past the bound: the same basis, by FLINT
    from mcl2pnml.analysis.structure import invariants as inv
    rng = random.Random(1)
    rows = [{j: rng.randint(-3, 3) for j in range(160)} for _ in range(150)]
    assert inv._reduced_rows(rows, max(inv.FILL_IN * 150 * 160, inv.SMALL_WORK)) is None
    basis = inv._nullspace(rows, 160)
    assert basis == inv._nullspace_dense(rows, 160) and len(basis) == 10
    assert all(sum(r.get(j, 0) * v for j, v in y.items()) == 0 for y in basis for r in rows)


def _check_farkas(found, order, rows, is_null, n_max):
    """Semi-positive, invariant, coprime, minimal support; and complete."""
    index = {k: i for i, k in enumerate(order)}
    supports = [frozenset(index[k] for k in y) for y in found]
    for y, support in zip(found, supports):
        assert min(y.values()) > 0 and gcd(*y.values()) == 1
        assert is_null(y) and minimal_support(rows, set(support))
    assert not any(a < b or (a == b and i != j) for i, a in enumerate(supports)
                   for j, b in enumerate(supports))
    assert supports == sorted(supports, key=lambda x: (len(x), sorted(x)))
    vectors = {tuple(v.get(k, 0) for k in order) for v in found}
    verdicts: dict[frozenset, bool] = {}
    for vec in product(range(3), repeat=min(len(order), n_max)):
        y = {order[i]: v for i, v in enumerate(vec) if v}
        if not y or not is_null(y):
            continue
        support = frozenset(index[k] for k in y)
        # every semi-positive invariant covers a minimal one that was found
        assert any(m <= support for m in supports)
        if support not in verdicts:
            verdicts[support] = minimal_support(rows, set(support))
        if verdicts[support] and gcd(*y.values()) == 1:
            assert tuple(y.get(k, 0) for k in order) in vectors


def _farkas_both_ways(net):
    s = structure(net)
    c = dense(s)
    _check_farkas(minimal_semipositive_p_invariants(s), s.places, c,
                  lambda y: left_null(s, y, c), 5)
    transposed = [list(col) for col in zip(*c)] if c else []
    _check_farkas(minimal_semipositive_t_invariants(s), s.transitions, transposed,
                  lambda x: right_null(s, x, c), 4)


@settings(max_examples=sample(250, 80), deadline=None)
@given(small_nets(max_places=6, max_transitions=4))
def test_farkas_finds_exactly_the_minimal_support_semipositive_invariants(net):
    _farkas_both_ways(net)


def test_farkas_drops_new_rows_that_contain_other_new_rows():
    # some rows made by one elimination step hold the support of another
    # made by the same step (a net found by a random search): kept, they
    # would end as non-minimal invariants
    b = NetBuilder("overlap")
    for i in range(6):
        b.place(f"p{i}")
    b.transition("t0")
    b.transition("t1")
    for p in ("p0", "p2"):
        b.arc(p, "t0")
    b.arc("t0", "p4")
    b.arc("t0", "p5", 2)
    b.arc("p0", "t1")
    for p in ("p1", "p2", "p3", "p5"):
        b.arc("t1", p)
    net = b.build()
    _farkas_both_ways(net)
    assert len(minimal_semipositive_p_invariants(structure(net))) == 6
