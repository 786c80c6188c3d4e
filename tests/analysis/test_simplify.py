"""Formulas simplified by what the structure proves (analysis/contest/simplify.py): the
rules carry constants up as both of the contest's readings do, and a simplified formula
has the answer the whole graph gives the original."""
from __future__ import annotations

from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.analysis.contest.answers import answer
from mcl2pnml.analysis.contest.reachability_queries import (_Bounds, _three_valued,
                                                            simplified_by_structure)
from mcl2pnml.analysis.contest.simplify import ByStructure, at_start, simplified
from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore
from mcl2pnml.analysis.structure import state_equation
from mcl2pnml.core import queries as q
from mcl2pnml.core.structure import structure
from sampling import sample
from strategies import nets
from test_state_equation import formulas

T, F = q.BoolConst(True), q.BoolConst(False)
A = q.IntLe(q.IntConst(1), q.TokensCount(("a",)))
B = q.IntLe(q.IntConst(1), q.TokensCount(("b",)))


def _known(values):
    return lambda phi: values.get(phi)


def test_constants_are_carried_up_where_both_readings_agree():
    never_a = _known({A: False})
    assert simplified(q.ExistsPath(q.Finally(A)), never_a) == F
    assert simplified(q.AllPaths(q.Globally(q.Neg(A))), never_a) == T
    assert simplified(q.ExistsPath(q.Until(B, A)), never_a) == F          # a U false
    assert simplified(q.ExistsPath(q.Until(A, B)), never_a) == B          # false U b
    assert simplified(q.AllPaths(q.Until(q.Neg(A), B)), never_a) == \
        q.AllPaths(q.Finally(B))                                          # true U b
    assert simplified(q.Conj((q.Disj((A, B)), B)), never_a) == q.Conj((B, B))
    # X: a dead marking has no next marking in CTL, and repeats in LTL: left alone,
    # but where the formula is read in LTL alone
    assert simplified(q.ExistsPath(q.Next(A)), never_a) == F     # no next one satisfies false
    assert simplified(q.AllPaths(q.Next(q.Neg(A))), never_a) == T    # every one satisfies true
    # E X true and A X false say whether the marking is dead: left to the graph
    assert simplified(q.ExistsPath(q.Next(q.Neg(A))), never_a) == q.ExistsPath(q.Next(T))
    assert simplified(q.AllPaths(q.Next(A)), never_a) == q.AllPaths(q.Next(F))
    assert simplified(q.ExistsPath(q.Until(B, q.Neg(q.AllPaths(q.Next(q.Neg(A)))))),
                      never_a) == F
    assert simplified(q.AllPaths(q.Next(q.Globally(q.Next(A)))), never_a, True) == F
    assert simplified(q.ExistsPath(q.Finally(B)), _known({})) == q.ExistsPath(q.Finally(B))
    # in LTL alone, X drops before what is purely eventual and purely universal: X F G b is
    # F G b, F X G b is F G b; not before F b (universal it is not), nor in CTL's reading
    none = _known({})
    fg, gf = q.Finally(q.Globally(B)), q.Globally(q.Finally(B))
    for g in (fg, gf, q.Neg(fg), q.Conj((fg, gf))):
        assert simplified(q.AllPaths(q.Next(g)), none, True) == q.AllPaths(g)
    assert simplified(q.AllPaths(q.Finally(q.Next(q.Globally(B)))), none, True) == \
        q.AllPaths(fg)
    assert simplified(q.AllPaths(q.Globally(q.Finally(q.Next(q.Next(q.Globally(B)))))),
                      none, True) == q.AllPaths(q.Globally(fg))         # every X of them
    assert simplified(q.AllPaths(q.Next(q.Finally(B))), none, True) == \
        q.AllPaths(q.Next(q.Finally(B)))
    assert simplified(q.AllPaths(q.Finally(q.Next(B))), none, True) == \
        q.AllPaths(q.Finally(q.Next(B)))
    assert simplified(q.AllPaths(q.Next(fg)), none) == q.AllPaths(q.Next(fg))


def _temporal(state):
    """CTL and LTL formulas over state formulas ``state``."""
    def path(inner):
        return st.one_of(inner.map(q.Finally), inner.map(q.Globally), inner.map(q.Next),
                         st.builds(q.Until, inner, inner))
    ctl = st.recursive(state, lambda inner: st.one_of(
        path(inner).map(q.ExistsPath), path(inner).map(q.AllPaths), inner.map(q.Neg),
        st.lists(inner, min_size=2, max_size=2).map(lambda xs: q.Conj(tuple(xs)))),
        max_leaves=4)
    ltl = st.recursive(state, lambda inner: st.one_of(path(inner), inner.map(q.Neg)),
                       max_leaves=3).map(q.AllPaths)
    return st.one_of(ctl, ltl)


def _bounded_net_and_formula(data):
    """A random net whose whole graph is small, its structure, and a CTL or LTL formula
    over its names; None where the graph is large or the net unbounded."""
    net = data.draw(nets())
    s = structure(net)
    f = data.draw(_temporal(formulas(list(s.places), list(s.transitions))))
    try:
        space = explore(net, max_states=3_000)
    except ExplorationLimit:
        return None
    return None if space.coverability else (net, s, f)


@settings(max_examples=sample(800, 60), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.data())
def test_a_simplified_formula_has_the_original_answer(data):
    drawn = _bounded_net_and_formula(data)
    if drawn is None:
        return
    net, s, f = drawn
    bounds = _Bounds(s)
    decide = ByStructure(s, 5.0, lambda phi: _three_valued(phi, s, bounds.invariant),
                         state_equation.unreachable)
    g = simplified(f, decide, q.is_ltl(f) and not q.is_ctl(f))
    [before, after] = answer(net, [q.Query("f", f), q.Query("g", g)])
    if before.value is not None and after.value is not None:
        assert before.value is after.value, (net, f, g)
    settled, _ = simplified_by_structure(net, [q.Query("f", f)])
    if "f" in settled and before.value is not None:
        assert settled["f"][0] is before.value, (net, f)


def test_the_initial_marking_decides_what_every_path_from_it_decides():
    def a_now(phi):              # a marked, b not
        return not a_now(phi.arg) if isinstance(phi, q.Neg) else {A: True, B: False}[phi]

    assert at_start(q.AllPaths(q.Finally(A)), a_now) is True
    assert at_start(q.ExistsPath(q.Globally(B)), a_now) is False
    assert at_start(q.AllPaths(q.Until(B, A)), a_now) is True
    assert at_start(q.AllPaths(q.Until(B, q.Neg(A))), a_now) is False
    assert at_start(q.AllPaths(q.Globally(A)), a_now) is None       # later markings
    assert at_start(q.ExistsPath(q.Next(A)), a_now) is None         # the next one
    assert at_start(q.Conj((q.AllPaths(q.Finally(A)), q.ExistsPath(q.Next(B)))),
                    a_now) is None
    assert at_start(q.Disj((q.AllPaths(q.Finally(A)), q.ExistsPath(q.Next(B)))),
                    a_now) is True


@settings(max_examples=sample(800, 60), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.data())
def test_what_one_run_of_a_walker_settles_is_what_the_whole_graph_answers(data):
    # a lasso or a maximal run that violates A ψ (or satisfies E ψ) is a run of the net
    from mcl2pnml.analysis.contest.answers import settled_by_runs
    drawn = _bounded_net_and_formula(data)
    if drawn is None:
        return
    net, _, f = drawn
    settled = settled_by_runs(net, [q.Query("f", f)], seconds=0.05)
    if "f" in settled:
        [truth] = answer(net, [q.Query("f", f)])
        assert truth.value is None or settled["f"][0] is truth.value, (net, f)


def test_a_run_of_a_cycle_shows_what_every_run_does_not_keep():
    # a ring of two places, one token: the walker's run is a lasso back to M0; on it
    # "a is marked for ever" fails, so A G a is false; E G F a is neither CTL nor the
    # contest's LTL (a path quantifier E over nested operators): not decided, not said
    from mcl2pnml.analysis.contest.answers import settled_by_runs
    from mcl2pnml.core.net import NetBuilder
    b = NetBuilder("ring")
    b.place("a", 1)
    b.place("b", 0)
    for t, x, y in (("ab", "a", "b"), ("ba", "b", "a")):
        b.transition(t)
        b.arc(x, t)
        b.arc(t, y)
    net = b.build()
    a = q.IntLe(q.IntConst(1), q.TokensCount(("a",)))
    got = settled_by_runs(net, [q.Query("always", q.AllPaths(q.Globally(a))),
                                q.Query("returns", q.ExistsPath(q.Globally(q.Finally(a)))),
                                q.Query("not-always", q.Neg(q.AllPaths(q.Globally(a))))],
                          seconds=5.0)
    assert got == {"always": (False, "RANDOM_WALK"), "not-always": (True, "RANDOM_WALK")}


def test_each_shape_counts_its_negations_alike():
    """The reachability shape and the one-run shape read ``not`` the same way."""
    from mcl2pnml.analysis.contest.answers import _on_one_run
    from mcl2pnml.analysis.contest.reachability_queries import reachability
    eventually_a = q.ExistsPath(q.Finally(A))
    one_run = q.AllPaths(q.Conj((q.Finally(A), q.Globally(B))))
    for k in range(4):
        def negated(f, k=k):
            for _ in range(k):
                f = q.Neg(f)
            return f
        assert q.unnegated(negated(A)) == (k % 2 == 1, A)
        assert reachability(negated(eventually_a)) == \
            ((True, A) if k % 2 == 0 else (False, q.Neg(A)))
        assert _on_one_run(negated(one_run)) == (True, one_run, k % 2 == 1)
