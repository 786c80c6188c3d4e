"""Invariants, siphons and traps, checked by their definitions and by brute force."""
from itertools import combinations, product

import sympy
from hypothesis import given, settings

from mcl2pnml.analysis.structure.invariants import (format_invariant, minimal_semipositive_p_invariants,
                                 minimal_semipositive_t_invariants, p_invariant_basis,
                                 t_invariant_basis)
from mcl2pnml.analysis.structure.siphons import (is_siphon, is_trap, max_siphon_within, minimal_siphons,
                              minimal_traps, siphon_control)
from mcl2pnml.analysis.zoo import philosophers
from mcl2pnml.core.net import NetBuilder
from mcl2pnml.core.structure import structure

from strategies import nets


def test_philosophers_invariants_are_the_textbook_ones():
    s = structure(philosophers(3))
    semi = minimal_semipositive_p_invariants(s)
    expected = ([{f"think{i}": 1, f"eat{i}": 1} for i in range(3)]
                + [{f"fork{i}": 1, f"eat{i}": 1, f"eat{(i - 1) % 3}": 1} for i in range(3)])
    assert sorted(map(sorted, (y.items() for y in semi))) == \
        sorted(map(sorted, (y.items() for y in expected)))
    assert len(p_invariant_basis(s)) == 6
    assert [sorted(x.items()) for x in minimal_semipositive_t_invariants(s)] == [
        [(f"release{i}", 1), (f"take{i}", 1)] for i in range(3)]
    assert format_invariant({"think0": 1, "eat0": 1}, 1) == "think0 + eat0 = 1"
    assert format_invariant({"E": -1, "OFF": 1}, -1) == "-E + OFF = -1"


def test_philosophers_siphons_are_controlled():
    s = structure(philosophers(3))
    siphons = minimal_siphons(s)
    reports = siphon_control(s, siphons, minimal_semipositive_p_invariants(s))
    assert all(r.controlled and r.marked and not r.source for r in reports)
    assert {frozenset(r.places) for r in reports} >= {frozenset({"think0", "eat0"})}


def test_an_empty_siphon_is_not_controlled_and_a_source_is_named():
    b = NetBuilder("n")
    b.place("in")
    b.place("x")
    b.place("y")
    b.transition("t")
    b.arc("in", "t")
    b.arc("t", "x")
    b.transition("u")
    b.arc("x", "u")
    b.arc("y", "u")
    b.arc("u", "y")
    s = structure(b.build())
    reports = {r.places: r for r in siphon_control(s, minimal_siphons(s), [])}
    assert reports[("in",)].source and not reports[("in",)].controlled
    assert not reports[("y",)].marked and not reports[("y",)].controlled


def test_a_read_arc_counts_both_ways_for_siphons():
    b = NetBuilder("r")
    b.place("guard", 1)
    b.place("p", 1)
    b.place("q")
    b.transition("t")
    b.read("guard", "t")
    b.arc("p", "t")
    b.arc("t", "q")
    s = structure(b.build())
    assert is_siphon(s, [s.place_index["guard"]]) and is_trap(s, [s.place_index["guard"]])


def _brute_force(s, check):
    n = len(s.places)
    found = [frozenset(c) for k in range(1, n + 1) for c in combinations(range(n), k)
             if check(s, c)]
    return sorted((x for x in found if not any(y < x for y in found)),
                  key=lambda x: (len(x), sorted(x)))


# Thirty nets each in the three tests below: test_structural.py holds the same results
# to their definitions and to brute force on 250 nets each.
@settings(max_examples=30, deadline=None)
@given(nets(max_places=7, max_transitions=5))
def test_minimal_siphons_and_traps_match_brute_force(net):
    s = structure(net)
    assert minimal_siphons(s) == _brute_force(s, is_siphon)
    assert minimal_traps(s) == _brute_force(s, is_trap)
    everything = frozenset(range(len(s.places)))
    biggest = max_siphon_within(s, everything)
    assert (not biggest) or is_siphon(s, biggest)
    assert all(x <= biggest for x in minimal_siphons(s))


@settings(max_examples=30, deadline=None)
@given(nets(max_places=6, max_transitions=5))
def test_invariant_bases_have_the_right_dimension(net):
    s = structure(net)
    c = sympy.Matrix(s.dense_incidence()) if s.places and s.transitions else None
    rank = c.rank() if c is not None else 0
    basis = p_invariant_basis(s)
    assert len(basis) == len(s.places) - rank
    for y in basis:  # y^T C = 0, checked on the dense matrix
        assert all(sum(y.get(s.places[i], 0) * c[i, j] for i in range(len(s.places))) == 0
                   for j in range(len(s.transitions)))
    tb = t_invariant_basis(s)
    assert len(tb) == len(s.transitions) - rank
    if basis:
        assert sympy.Matrix([[y.get(p, 0) for p in s.places] for y in basis]).rank() == len(basis)


@settings(max_examples=30, deadline=None)
@given(nets(max_places=5, max_transitions=4))
def test_farkas_finds_every_minimal_support_semipositive_invariant(net):
    s = structure(net)
    found = minimal_semipositive_p_invariants(s)
    cols = s.incidence
    def invariant(y):
        return all(sum(y[p] * v for p, v in col.items()) == 0 for col in cols)
    for y in found:
        vec = [y.get(p, 0) for p in s.places]
        assert min(vec) >= 0 and invariant(vec)
    supports = {frozenset(y) for y in found}
    # brute force over small coefficients: every semi-positive invariant's
    # support contains the support of one that was found
    n = len(s.places)
    for vec in product(range(3), repeat=n):
        if any(vec) and invariant(vec):
            support = frozenset(s.places[i] for i, v in enumerate(vec) if v)
            assert any(m <= support for m in supports)
    assert all(not (a < b) for a in supports for b in supports)
