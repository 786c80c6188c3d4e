"""The searches for reachability witnesses without a graph
(analysis/contest/reachability_queries.py): the best-first search by a formula's distance
(``settled_by_guided_search``; the distance is 0 exactly where the formula holds), a
witness found wherever one exists on a graph it can search whole; and the state
equation's solutions fired (``settled_by_equation_witness``). What each settles is what
exploring the whole graph says."""
from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.analysis.contest.reachability_queries import (ListedMarkings, Truths, distance,
                                                            settled_by_equation_witness,
                                                            settled_by_guided_search)
from mcl2pnml.core import queries as q
from mcl2pnml.core.structure import structure
from sampling import sample
from strategies import nets
from test_state_equation import explored, formulas

SETTINGS = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                      HealthCheck.filter_too_much])


def _markings(net):
    space = explored(net, max_states=2_000)
    return None if space is None else [[int(v) for v in m] for m in space.markings]


def _with_deadlocks(places, transitions):
    """:func:`formulas`, with a deadlock atom inside some of them."""
    return st.one_of(formulas(places, transitions),
                     st.just(q.Deadlock()), st.just(q.Neg(q.Deadlock())),
                     formulas(places, transitions).map(lambda f: q.Conj((f, q.Deadlock()))),
                     formulas(places, transitions).map(lambda f: q.Disj((q.Neg(q.Deadlock()),
                                                                         f))))


def _drawn(data):
    """A random net small enough to explore, its markings, and a formula over it; None
    where the net is too large or unbounded."""
    net = data.draw(nets())
    s = structure(net)
    markings = _markings(net)
    if not markings:
        return None
    return net, s, markings, data.draw(_with_deadlocks(list(s.places), list(s.transitions)))


@settings(max_examples=sample(800, 100), **SETTINGS)
@given(st.data())
def test_the_distance_is_zero_exactly_where_the_formula_holds(data):
    drawn = _drawn(data)
    if drawn is None:
        return
    net, s, markings, phi = drawn
    far = distance(phi, s)(np.asarray(markings, dtype=np.int64))
    holds = Truths(s, ListedMarkings(markings)).of(phi)
    assert ((far == 0) == np.asarray(holds, dtype=bool)).all(), (net, phi)
    assert (far >= 0).all()


def _asked(data):
    """:func:`_drawn`'s net and formula, asked as ``E F φ`` (id ``ef``) and ``A G φ``
    (``ag``), with the whole graph's answers; None as :func:`_drawn`."""
    drawn = _drawn(data)
    if drawn is None:
        return None
    net, s, markings, phi = drawn
    asks = [q.Query("ef", q.ExistsPath(q.Finally(phi))),
            q.Query("ag", q.AllPaths(q.Globally(phi)))]
    reached = Truths(s, ListedMarkings(markings)).of(phi)
    return net, phi, asks, {"ef": bool(np.any(reached)), "ag": bool(np.all(reached))}


@settings(max_examples=sample(300, 50), **SETTINGS)
@given(st.data())
def test_what_it_settles_is_what_the_whole_graph_says(data):
    asked = _asked(data)
    if asked is None:
        return
    net, phi, asks, truth = asked
    settled = settled_by_guided_search(net, asks, seconds=60)
    for k, (value, technique) in settled.items():
        assert value == truth[k] and technique == "EXPLICIT BEST_FIRST", (net, phi, k)
    # the graph is small: the search meets every marking before its time is out, so a
    # witness that exists is found
    assert ("ef" in settled) == truth["ef"] and ("ag" in settled) == (not truth["ag"])


@settings(max_examples=sample(300, 50), **SETTINGS)
@given(st.data())
def test_what_a_fired_solution_settles_is_what_the_whole_graph_says(data):
    asked = _asked(data)
    if asked is None:
        return
    net, phi, asks, truth = asked
    for k, (value, technique) in settled_by_equation_witness(net, asks).items():
        assert value == truth[k] and technique == "EXPLICIT STATE_EQUATION", (net, phi, k)


def test_a_solution_is_fired_to_its_marking():
    """``a -> b -> c``, one token: the solution t1 once, t2 once is a run to c."""
    from test_state_equation import _line
    c_marked = q.IntLe(q.IntConst(1), q.TokensCount(("c",)))
    got = settled_by_equation_witness(_line(), [
        q.Query("ef", q.ExistsPath(q.Finally(c_marked))),
        q.Query("ag", q.AllPaths(q.Globally(q.Neg(c_marked))))])
    assert got == {"ef": (True, "EXPLICIT STATE_EQUATION"),
                   "ag": (False, "EXPLICIT STATE_EQUATION")}
