"""Strongly connected state machines (analysis/structure/state_machine.py): where it says
every distribution of the tokens is reachable, the explored graph holds every one, and
the upper bounds it answers are the graph's."""
from __future__ import annotations

from math import comb

from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.analysis.contest.answers import answer
from mcl2pnml.analysis.contest.reachability_queries import settled_without_exploring
from mcl2pnml.analysis.statespace.explore import explore
from mcl2pnml.analysis.structure.state_machine import free_tokens
from mcl2pnml.core import queries as q
from mcl2pnml.core.net import ArcKind, NetBuilder
from mcl2pnml.core.structure import structure
from sampling import sample


@st.composite
def machines(draw):
    """Nets of one-in one-out transitions (a read arc or a weight of 2 now and then)."""
    places = draw(st.integers(1, 5))
    index = st.integers(0, places - 1)
    b = NetBuilder("machine")
    for i in range(places):
        b.place(f"p{i}", draw(st.integers(0, 2)))
    for j in range(draw(st.integers(1, 8))):
        b.transition(f"t{j}")
        taken = draw(index)
        b.arc(f"p{taken}", f"t{j}", draw(st.sampled_from([1, 1, 1, 2])))
        b.arc(f"t{j}", f"p{draw(index)}")
        read = draw(index)
        if read != taken and draw(st.integers(0, 9)) == 0:
            b.arc(f"p{read}", f"t{j}", 1, ArcKind.READ)
    return b.build()


@settings(max_examples=sample(500, 80), deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(machines(), st.data())
def test_where_every_distribution_is_said_reachable_the_graph_has_them_all(net, data):
    s = structure(net)
    tokens = free_tokens(s)
    if tokens is None:
        return
    space = explore(net, max_states=100_000)
    assert space.states == comb(tokens + len(s.places) - 1, len(s.places) - 1)
    named = tuple(data.draw(st.lists(st.sampled_from(s.places), min_size=1, max_size=3)))
    x = q.Query("b", q.PlaceBound(named))
    settled = settled_without_exploring(net, [x])
    [truth] = answer(net, [x])
    assert settled["b"][0] == truth.value


def test_a_machine_that_is_not_strongly_connected_is_not_claimed():
    b = NetBuilder("line")
    for p in ("a", "b"):
        b.place(p, 1)
    b.transition("t")
    b.arc("a", "t")
    b.arc("t", "b")
    assert free_tokens(structure(b.build())) is None
