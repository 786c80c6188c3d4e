"""The state equation never calls a reachable marking unreachable, and does prove the
markings the paper's kind of invariant rules out (analysis/structure/state_equation.py);
past the graph's limits, ``query`` answers with it (STATE_EQUATION)."""
from __future__ import annotations

from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.analysis.contest.answers import answer
from mcl2pnml.analysis.contest.reachability_queries import ListedMarkings, Truths
from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore
from mcl2pnml.analysis.structure.state_equation import (dead_unreachable, unreachable,
                                                        upper_bound)
from mcl2pnml.core import queries as q
from mcl2pnml.core.net import NetBuilder
from mcl2pnml.core.structure import structure
from sampling import sample
from strategies import nets


def explored(net, max_states: int = 5_000):
    """``net``'s whole state space, or None where it is past ``max_states`` or unbounded
    (a coverability graph does not list its markings)."""
    try:
        space = explore(net, max_states=max_states)
    except ExplorationLimit:
        return None
    return None if space.coverability else space


def formulas(places, transitions):
    """State formulas over the names of a net: sums compared, transitions enabled, and
    their negations, conjunctions and disjunctions."""
    sums = st.one_of(st.integers(0, 3).map(q.IntConst),
                     st.lists(st.sampled_from(places), min_size=1, max_size=3)
                     .map(lambda ps: q.TokensCount(tuple(ps))))
    atoms = st.one_of(st.builds(q.IntLe, sums, sums),
                      st.lists(st.sampled_from(transitions), min_size=1, max_size=2)
                      .map(lambda ts: q.Fireable(tuple(ts))),
                      st.booleans().map(q.BoolConst))
    return st.recursive(atoms, lambda inner: st.one_of(
        inner.map(q.Neg),
        st.lists(inner, min_size=2, max_size=3).map(lambda xs: q.Conj(tuple(xs))),
        st.lists(inner, min_size=2, max_size=3).map(lambda xs: q.Disj(tuple(xs)))),
        max_leaves=5)


@settings(max_examples=sample(1500, 150), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.data())
def test_what_it_calls_unreachable_no_run_reaches(data):
    net = data.draw(nets())
    s = structure(net)
    phi = data.draw(formulas(list(s.places), list(s.transitions)))
    if not unreachable(s, phi):
        return
    space = explored(net)
    if space is None:
        return
    markings = [[int(v) for v in m] for m in space.markings]
    reached = Truths(s, ListedMarkings(markings)).of(phi)
    assert not reached.any(), (net, phi, markings[int(reached.argmax())])


def _mutex(extra_token: bool = False):
    """Two processes around one lock: ``idle_i -> busy_i`` takes it, ``busy_i -> idle_i``
    gives it back; lock + busy1 + busy2 = 1 is a P-invariant."""
    b = NetBuilder("mutex")
    for p, tokens in (("idle1", 1), ("idle2", 1), ("busy1", 0), ("busy2", 0),
                      ("lock", 2 if extra_token else 1)):
        b.place(p, tokens)
    for i in ("1", "2"):
        b.transition(f"enter{i}")
        b.arc(f"idle{i}", f"enter{i}")
        b.arc("lock", f"enter{i}")
        b.arc(f"enter{i}", f"busy{i}")
        b.transition(f"leave{i}")
        b.arc(f"busy{i}", f"leave{i}")
        b.arc(f"leave{i}", f"idle{i}")
        b.arc(f"leave{i}", "lock")
    return b.build()


BOTH_BUSY = q.IntLe(q.IntConst(2), q.TokensCount(("busy1", "busy2")))


def test_mutual_exclusion_is_proven_and_a_second_token_is_not():
    assert unreachable(structure(_mutex()), BOTH_BUSY)
    # reachable markings are never claimed: both busy with a second lock token, and one
    # of the two entries enabled (at M0 already)
    assert not unreachable(structure(_mutex(extra_token=True)), BOTH_BUSY)
    assert not unreachable(structure(_mutex()), q.Fireable(("enter1", "enter2")))


def _line():
    """``a -> b -> c``, one token: the invariant a + b + c = 1 bounds each place by 1,
    which leaves "a and c marked at once" open; the equation closes it (a = 1 - x1 >= 1
    needs x1 = 0, so b = x1 - x2 >= 0 needs x2 = 0, so c = x2 = 0)."""
    b = NetBuilder("line")
    for p, tokens in (("a", 1), ("b", 0), ("c", 0)):
        b.place(p, tokens)
    for t, src, dst in (("t1", "a", "b"), ("t2", "b", "c")):
        b.transition(t)
        b.arc(src, t)
        b.arc(t, dst)
    return b.build()


A_AND_C = q.Conj((q.IntLe(q.IntConst(1), q.TokensCount(("a",))),
                  q.IntLe(q.IntConst(1), q.TokensCount(("c",)))))


def test_past_the_graphs_limit_query_answers_by_the_state_equation():
    asks = [q.Query("never", q.AllPaths(q.Globally(q.Neg(A_AND_C)))),
            q.Query("ever", q.ExistsPath(q.Finally(A_AND_C))),
            q.Query("c-marked", q.ExistsPath(q.Finally(
                q.IntLe(q.IntConst(1), q.TokensCount(("c",))))))]
    # one marking allowed: no graph; the net is not safe for the on-the-fly search's
    # sake (a weight 2 arc would do): here it is, but the search stops at its limit too
    got = answer(_line(), asks, max_states=1)
    assert [(a.id, a.value, a.technique) for a in got[:2]] == [
        ("never", True, "STATE_EQUATION"), ("ever", False, "STATE_EQUATION")]
    # reachable: the equation proves nothing and says nothing; a random walk meets it
    assert (got[2].value, got[2].technique) == (True, "RANDOM_WALK")


@settings(max_examples=sample(600, 80), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.data())
def test_the_equations_upper_bound_is_never_below_a_reached_sum(data):
    net = data.draw(nets())
    s = structure(net)
    places = data.draw(st.lists(st.sampled_from(list(s.places)), min_size=1, max_size=3))
    bound = upper_bound(s, places)
    space = explored(net)
    if space is None:
        return
    most = max(sum(int(m[s.place_index[p]]) for p in places) for m in space.markings)
    assert bound is None or bound >= most, (net, places, bound, most)


def test_the_equation_bounds_the_mutex_and_query_answers_with_a_witness():
    s = structure(_mutex())
    assert upper_bound(s, ["busy1", "busy2"]) == 1
    assert upper_bound(s, ["busy1", "busy2", "lock"]) == 1
    # past the graph's limit (one marking), the found marking (M0: none busy) does not
    # reach the busy places' bound (a random walk may); it reaches the lock's
    got = answer(_mutex(), [q.Query("busy", q.PlaceBound(("busy1", "busy2"))),
                            q.Query("lock", q.PlaceBound(("lock",)))], max_states=1)
    assert (got[0].value, got[0].technique) in {(None, ""), (1, "RANDOM_WALK STATE_EQUATION"),
                                                (1, "RANDOM_WALK STRUCTURAL P_INVARIANTS")}
    assert (got[1].value, got[1].technique) == (1, "EXPLICIT STRUCTURAL P_INVARIANTS")
    got = answer(_mutex(), [q.Query("busy", q.PlaceBound(("busy1", "busy2")))], max_states=2)
    assert (got[0].value, got[0].technique) in {(1, "EXPLICIT STRUCTURAL P_INVARIANTS"),
                                                (1, "EXPLICIT STATE_EQUATION")}


@settings(max_examples=sample(800, 100), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.data())
def test_what_it_calls_deadlock_free_has_no_reachable_dead_marking(data):
    net = data.draw(nets())
    s = structure(net)
    space = explored(net)
    if space is None:
        return
    # the big M from each place's true largest count (the tightest a proof can give), or
    # from none (the equation's relaxation): neither may leave a dead marking out
    most = [max(int(m[i]) for m in space.markings) for i in range(len(s.places))]
    given_bounds = data.draw(st.booleans())
    proven = dead_unreachable(s, place_bound=(lambda p: most[p]) if given_bounds
                              else (lambda p: None))
    assert not (proven and space.terminal), (net, given_bounds)


def test_the_mutex_is_proven_deadlock_free_and_the_line_is_not():
    assert dead_unreachable(structure(_mutex()))
    assert unreachable(structure(_mutex()), q.Deadlock())
    assert not dead_unreachable(structure(_line()))      # its last marking is dead
