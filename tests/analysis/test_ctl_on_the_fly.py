"""CTL on the fly (analysis/contest/ctl_on_the_fly.py): the dependency graph's answer is
the whole graph's labelling, and it needs only the markings the answer does."""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.analysis.contest.answers import Graph, answer
from mcl2pnml.analysis.contest.ctl_on_the_fly import (NotCTL, ctl_on_the_fly,
                                                      settled_by_ctl_on_the_fly)
from mcl2pnml.analysis.contest.ltl_on_the_fly import Unnamed
from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore
from mcl2pnml.core import queries as q
from mcl2pnml.core.net import NetBuilder
from mcl2pnml.core.structure import structure
from sampling import sample
from strategies import nets
from test_found_markings import _toggles
from test_partial_graph import shrinking_nets
from test_simplify import _temporal
from test_state_equation import formulas


def _whole(net, f):
    """The whole graph's CTL labelling at M0, or None where the graph is large or the net
    unbounded."""
    try:
        space = explore(net, max_states=3_000)
    except ExplorationLimit:
        return None
    if space.coverability:
        return None
    return bool(Graph(space).check(f, None)[0])


@settings(max_examples=sample(1500, 100), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.data())
def test_the_search_answers_what_the_whole_graph_does(data):
    # any nets (read arcs, weights, dead ends, cycles) and the bounded shrinking ones, with
    # deadlock atoms: every nesting of quantifiers, negations and until
    net = data.draw(st.one_of(nets(), shrinking_nets()))
    s = structure(net)
    state = st.one_of(formulas(list(s.places), list(s.transitions)), st.just(q.Deadlock()))
    g = data.draw(_temporal(state))
    # a quantifier over a state formula (CTL*'s A not E G ...) is that state formula
    f = data.draw(st.sampled_from([g, q.AllPaths(q.Neg(g)), q.ExistsPath(q.Conj((g, g)))]))
    if not q.is_ctl(f):
        return
    want = _whole(net, f)
    if want is None:
        return
    assert ctl_on_the_fly(net, f, 100_000, 30.0) is want, (net, f)


def test_a_local_answer_needs_only_the_markings_near_m0():
    # 2^40 markings: only the answer's neighbourhood is explored (for A X A X E X, three
    # firings deep: the 10,701 markings within three firings of M0)
    net = _toggles(40)
    on = lambda i: q.IntLe(q.IntConst(1), q.TokensCount((f"on{i}",)))   # noqa: E731
    ax_ax_ex = q.AllPaths(q.Next(q.AllPaths(q.Next(q.ExistsPath(q.Next(
        q.Disj((on(0), q.Neg(on(0))))))))))
    assert ctl_on_the_fly(net, ax_ax_ex, 20_000, 30.0) is True
    # a witness deep in the net, found depth first: E F (ten counters on at once)
    ten = q.Conj(tuple(on(i) for i in range(10)))
    assert ctl_on_the_fly(net, q.ExistsPath(q.Finally(ten)), 50_000, 30.0) is True
    # A G fails at its first violation; A G E F holds only over the whole space: unknown
    assert ctl_on_the_fly(net, q.AllPaths(q.Globally(q.Neg(on(3)))), 1_000, 30.0) is False
    home = q.AllPaths(q.Globally(q.ExistsPath(q.Finally(q.Neg(on(0))))))
    assert ctl_on_the_fly(net, home, 1_000, 30.0) is None
    assert ctl_on_the_fly(_toggles(4), home, 1_000, 30.0) is True
    # the memory budget counts what the search holds: a mebibyte stops it, unknown
    assert ctl_on_the_fly(net, home, 10 ** 9, 30.0, max_memory=1 << 20) is None


def test_what_the_search_cannot_read_is_refused_or_left():
    net = _toggles(2)
    with pytest.raises(Unnamed):
        ctl_on_the_fly(net, q.ExistsPath(q.Finally(q.Fireable(("nowhere",)))))
    with pytest.raises(NotCTL):
        ctl_on_the_fly(net, q.AllPaths(q.Finally(q.Globally(q.Fireable(("up0",))))))
    queries = [q.Query("unnamed", q.ExistsPath(q.Finally(q.Fireable(("nowhere",))))),
               q.Query("ltl", q.AllPaths(q.Finally(q.Globally(q.Fireable(("up0",)))))),
               # CTL and LTL with an X: the readings differ at a dead M0 only
               q.Query("both", q.AllPaths(q.Next(q.Fireable(("down0", "down1"))))),
               # what the LTL search reads, it has searched just before
               q.Query("reach", q.ExistsPath(q.Finally(q.Fireable(("down0",))))),
               q.Query("ctl", q.ExistsPath(q.Next(q.Fireable(("down0",)))))]
    assert settled_by_ctl_on_the_fly(net, queries) == {
        "ctl": (True, "EXPLICIT CTL ON_THE_FLY"), "both": (True, "EXPLICIT CTL ON_THE_FLY")}
    dead = _dying()
    dead = dead.with_initial({"p": 0})
    ax_p = q.AllPaths(q.Next(q.IntLe(q.IntConst(1), q.TokensCount(("p",)))))
    assert ctl_on_the_fly(dead, ax_p) is True          # CTL: no next marking; LTL: false
    assert settled_by_ctl_on_the_fly(dead, [q.Query("both", ax_p)]) == {}


def test_the_portfolio_answers_by_it_past_the_first_exploration():
    # past the first exploration's limit (near M0) nothing else settles this CTL formula
    # (not LTL: the E X inside), whose witness is eleven firings deep: the search does
    net = _toggles(40)
    on = [q.IntLe(q.IntConst(1), q.TokensCount((f"on{i}",))) for i in range(11)]
    f = q.ExistsPath(q.Finally(q.Conj((*on[:10], q.ExistsPath(q.Next(q.Conj(tuple(on))))))))
    [got] = answer(net, [q.Query("f", f)], max_states=200_000)
    assert got.value is True and got.technique == "EXPLICIT CTL ON_THE_FLY"


def _dying():
    """Two firings, then a dead marking."""
    b = NetBuilder("dies")
    b.place("p", 2)
    b.transition("t")
    b.arc("p", "t")
    return b.build()


def test_a_quantifier_over_a_state_formula_is_that_formula():
    # A not E G E X true (a CTL-cardinality file's shape): CTL, read as not E G E X true,
    # which fails where every maximal path meets a dead marking
    eg_live = q.ExistsPath(q.Globally(q.ExistsPath(q.Next(q.BoolConst(True)))))
    f = q.AllPaths(q.Neg(eg_live))
    assert q.is_ctl(f) and q.is_closed(f.arg) and not q.is_ltl(f)
    assert not q.is_ctl(q.AllPaths(q.Neg(q.Finally(q.Deadlock()))))   # LTL, not CTL
    live, dying = _toggles(2), _dying()
    for net, holds in ((live, False), (dying, True)):
        [got] = answer(net, [q.Query("f", f)])
        assert got.value is holds and _whole(net, f) is holds
        assert ctl_on_the_fly(net, f) is holds

