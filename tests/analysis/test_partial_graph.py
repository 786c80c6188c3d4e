"""Past its limit, the graph an exploration built is read three-valued
(analysis/statespace/partial.py, ``PartialGraph`` in analysis/contest/answers.py): what
it decides whatever its open frontier does is what the whole graph answers."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.analysis.contest.answers import (PartialGraph, _decide_partial, answer,
                                               settled_by_partial_graph)
from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore
from mcl2pnml.analysis.statespace.loops.backends import SWITCH, c_loops
from mcl2pnml.analysis.statespace.partial import partial_space
from mcl2pnml.core import queries as q
from mcl2pnml.core.net import NetBuilder
from mcl2pnml.core.structure import structure
from sampling import sample
from test_simplify import _temporal
from test_state_equation import formulas


@st.composite
def shrinking_nets(draw):
    """Nets whose firings never add tokens (each transition gives back at most what it
    takes): bounded, with state spaces of tens to hundreds of markings, cycles and dead
    ends, safe or not."""
    places, transitions = draw(st.integers(2, 7)), draw(st.integers(1, 6))
    index = st.integers(0, places - 1)
    b = NetBuilder("shrinking")
    for i in range(places):
        b.place(f"p{i}", draw(st.integers(1 if i < 2 else 0, 2)))
    for j in range(transitions):
        ins = draw(st.lists(index, min_size=1, max_size=2, unique=True))
        outs = draw(st.lists(index, min_size=0, max_size=len(ins), unique=True))
        b.transition(f"t{j}")
        for i in ins:
            b.arc(f"p{i}", f"t{j}")
        for i in outs:
            b.arc(f"t{j}", f"p{i}")
    return b.build()


def _stopped(net, limit: int):
    try:
        explore(net, max_states=limit)
    except ExplorationLimit as e:
        return e.found
    return None


@settings(max_examples=sample(1500, 100), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.data())
def test_what_the_partial_graph_decides_is_what_the_whole_graph_answers(data):
    net = data.draw(shrinking_nets())
    s = structure(net)
    state = st.one_of(formulas(list(s.places), list(s.transitions)), st.just(q.Deadlock()))
    f = data.draw(_temporal(state))
    try:
        whole = explore(net, max_states=3_000)
    except ExplorationLimit:
        return
    if whole.coverability or whole.states < 3:
        return
    found = _stopped(net, data.draw(st.integers(whole.states // 4 + 1, whole.states - 1)))
    space = None if found is None else partial_space(s, found)
    if space is None:
        return
    graph = PartialGraph(space)
    x = q.Query("f", f)
    [truth] = answer(net, [x])
    if q.is_ctl(f):
        surely, maybe = graph.check3(f, None)
        assert not (surely & ~maybe).any()
        assert truth.value is None or not surely[0] or truth.value is True, (net, f)
        assert truth.value is None or maybe[0] or truth.value is False, (net, f)
    got = _decide_partial(graph, x, None)
    assert got is None or truth.value is None or got is truth.value, (net, f)


def _chain(length: int):
    """A token moving down a line of places, then stopping: M0 is p0 marked."""
    b = NetBuilder("chain")
    for i in range(length):
        b.place(f"p{i}", int(i == 0))
    for i in range(length - 1):
        b.transition(f"t{i}")
        b.arc(f"p{i}", f"t{i}")
        b.arc(f"t{i}", f"p{i + 1}")
    return b.build()


def _marked(place: str):
    return q.IntLe(q.IntConst(1), q.TokensCount((place,)))


def test_an_open_frontier_leaves_open_what_lies_past_it():
    net = _chain(50)
    found = _stopped(net, 10)
    asked = {
        "near": q.ExistsPath(q.Finally(_marked("p3"))),          # met inside: true
        "next": q.ExistsPath(q.Next(_marked("p1"))),             # one step: true
        "not-far": q.AllPaths(q.Globally(q.Neg(_marked("p5")))),  # p5 met inside: false
        "far": q.ExistsPath(q.Finally(_marked("p40"))),          # past the frontier
        "ends": q.AllPaths(q.Finally(q.Deadlock())),             # past the frontier
        "ltl": q.AllPaths(q.Finally(q.Globally(_marked("p40")))),  # no lasso inside
    }
    settled = settled_by_partial_graph(net, [q.Query(k, f) for k, f in asked.items()], found)
    assert {k: v for k, (v, _) in settled.items()} == {"near": True, "next": True,
                                                       "not-far": False}


def _ring_beside_chain():
    """A token going round a ring of three beside a token down a line of fifty."""
    b = NetBuilder("ring-and-chain")
    for i in range(3):
        b.place(f"r{i}", int(i == 0))
        b.transition(f"u{i}")
        b.arc(f"r{i}", f"u{i}")
        b.arc(f"u{i}", f"r{(i + 1) % 3}")
    for i in range(50):
        b.place(f"p{i}", int(i == 0))
    for i in range(49):
        b.transition(f"t{i}")
        b.arc(f"p{i}", f"t{i}")
        b.arc(f"t{i}", f"p{i + 1}")
    return b.build()


def test_a_lasso_inside_shows_an_ltl_formula_false():
    # the run that keeps the ring turning never moves the line's token (no fairness)
    net = _ring_beside_chain()
    found = _stopped(net, 60)
    # turning for ever implies the line ends: LTL only (path operators nested under A)
    turning = q.Globally(q.Finally(_marked("r1")))
    f = q.AllPaths(q.Disj((q.Neg(turning), q.Finally(_marked("p40")))))
    assert not q.is_ctl(f) and q.is_ltl(f)
    settled = settled_by_partial_graph(net, [q.Query("f", f)], found)
    assert settled == {"f": (False, "EXPLICIT LTL PARTIAL_STATE_SPACE")}
    [truth] = answer(net, [q.Query("f", f)])
    assert truth.value is False


@pytest.mark.parametrize("limit", [4, 40, 120])
def test_either_backend_builds_the_same_partial_graph(limit, monkeypatch):
    if c_loops() is None:
        pytest.skip("the loops in C were not built here (no C compiler at install)")
    net = _ring_beside_chain()
    found = _stopped(net, limit)
    in_c = partial_space(structure(net), found)
    monkeypatch.setenv(SWITCH, "python")
    in_python = partial_space(structure(net), found)
    assert in_c.states == in_python.states == limit
    for a, b in ((in_c.src, in_python.src), (in_c.trans, in_python.trans),
                 (in_c.dst, in_python.dst), (in_c.open, in_python.open)):
        assert np.array_equal(a, b)
    assert in_c.open.any() and len(in_c.src)
