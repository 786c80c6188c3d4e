"""LTL on the fly from the net (analysis/contest/ltl_on_the_fly.py): the product searched
depth first, under stubborn sets where the formula has no X, answers as the whole graph
does; both backends of the loops, one suite."""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.analysis.contest.answers import answer
from mcl2pnml.analysis.contest.ltl_on_the_fly import (ltl_on_the_fly, path_formula,
                                                       settled_by_ltl_on_the_fly)
from mcl2pnml.analysis.statespace.loops.backends import named
from mcl2pnml.core import queries as q
from mcl2pnml.core.net import NetBuilder
from mcl2pnml.core.structure import structure
from sampling import sample
from test_partial_graph import shrinking_nets
from test_simplify import _temporal
from test_state_equation import formulas


@pytest.fixture(params=["c", "python"])
def loops(request):
    chosen = named(request.param)
    if chosen is None:
        pytest.skip("the loops in C were not built here (no C compiler at install)")
    return chosen


def _ltl(state):
    """The contest's LTL over state formulas ``state``: ``A φ``, φ free of quantifiers."""
    def path(inner):
        return st.one_of(inner.map(q.Finally), inner.map(q.Globally), inner.map(q.Next),
                         st.builds(q.Until, inner, inner), inner.map(q.Neg),
                         st.lists(inner, min_size=2, max_size=2).map(
                             lambda xs: q.Disj(tuple(xs))))
    return st.recursive(state, path, max_leaves=4).map(q.AllPaths)


@settings(max_examples=sample(600, 60), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much,
                                 HealthCheck.function_scoped_fixture])   # a backend: no state
@given(data=st.data())
def test_the_search_on_the_fly_answers_as_the_whole_graph(loops, data):
    net = data.draw(shrinking_nets())
    s = structure(net)
    state = st.one_of(formulas(list(s.places), list(s.transitions)), st.just(q.Deadlock()))
    f = data.draw(_ltl(state))
    [truth] = answer(net, [q.Query("f", f)])
    if truth.value is None:
        return
    got = ltl_on_the_fly(net, f, max_states=100_000, seconds=30.0, loops=loops)
    assert got is truth.value, (net, f)


@settings(max_examples=sample(600, 60), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(data=st.data())
def test_what_it_settles_of_any_formula_is_what_the_whole_graph_answers(data):
    # E ψ as not A not ψ, negations outside, and the CTL formulas with an X left alone
    net = data.draw(shrinking_nets())
    s = structure(net)
    f = data.draw(_temporal(formulas(list(s.places), list(s.transitions))))
    x = q.Query("f", f)
    settled = settled_by_ltl_on_the_fly(net, [x], seconds=30.0)
    if "f" in settled:
        [truth] = answer(net, [x])
        assert truth.value is None or settled["f"][0] is truth.value, (net, f)


def test_the_shapes_one_search_decides():
    a = q.IntLe(q.IntConst(1), q.TokensCount(("a",)))
    assert path_formula(q.Neg(q.ExistsPath(q.Finally(a)))) == \
        (False, q.AllPaths(q.Neg(q.Finally(a))))
    assert path_formula(q.AllPaths(q.Globally(q.Finally(a)))) == \
        (False, q.AllPaths(q.Globally(q.Finally(a))))
    assert path_formula(q.AllPaths(q.Next(a))) is None          # CTL too, with an X
    assert path_formula(q.AllPaths(q.Finally(q.ExistsPath(q.Next(a))))) is None
    assert path_formula(a) is None


def _shots_beside_a_ring(n: int):
    """A token going round a ring of two places beside ``n`` tokens each moved once, in
    any order: 2^(n+1) markings."""
    b = NetBuilder("shots")
    b.place("on", 0)
    b.place("off", 1)
    for t, x, y in (("up", "off", "on"), ("down", "on", "off")):
        b.transition(t)
        b.arc(x, t)
        b.arc(t, y)
    for i in range(n):
        b.place(f"a{i}", 1)
        b.place(f"b{i}", 0)
        b.transition(f"shot{i}")
        b.arc(f"a{i}", f"shot{i}")
        b.arc(f"shot{i}", f"b{i}")
    return b.build()


def test_stubborn_sets_decide_within_a_limit_the_whole_product_is_past(loops):
    # a million markings; the formulas see the ring alone, and the shots are invisible
    # and independent: fired one order only, the reduced product is tens of states
    net = _shots_beside_a_ring(19)
    on = q.IntLe(q.IntConst(1), q.TokensCount(("on",)))
    limit = dict(max_states=10_000, seconds=30.0, loops=loops)
    one_token = q.AllPaths(q.Globally(q.IntLe(q.TokensCount(("on", "off")), q.IntConst(1))))
    assert ltl_on_the_fly(net, one_token, **limit) is True
    # once the shots are spent the ring turns for ever
    assert ltl_on_the_fly(net, q.AllPaths(q.Globally(q.Finally(on))), **limit) is True
    assert ltl_on_the_fly(net, q.AllPaths(q.Globally(q.Neg(on))), **limit) is False
    # with an X the formula is not stutter-invariant: no reduction, past the limit
    step = q.AllPaths(q.Globally(q.Disj((q.Neg(on), q.Next(q.Neg(on)), q.Next(on)))))
    assert ltl_on_the_fly(net, step, **limit) is None


def test_a_name_the_net_lacks_is_left_to_the_graphs_message():
    # the query's file may name anything: the search leaves it to the graph's path, which
    # says what the net lacks (tests/analysis/test_mcc.py)
    net = _shots_beside_a_ring(3)
    nowhere = q.IntLe(q.IntConst(1), q.TokensCount(("nowhere",)))
    fires = q.Fireable(("no-such-transition",))
    asked = [q.Query("p", q.AllPaths(q.Globally(q.Finally(nowhere)))),
             q.Query("t", q.ExistsPath(q.Globally(fires)))]
    for x in asked:
        assert settled_by_ltl_on_the_fly(net, [x], seconds=5.0) == {}
