"""Reachability and coverability graphs, on nets whose answers are known by hand."""
import pytest
from hypothesis import given, settings, strategies as st

from analysis import packedspace, statespace
from analysis.behaviour import behaviour, final_markings_agree
from analysis.statespace import OMEGA, ExplorationLimit, explore
from mcl2pnml.net import ArcKind, NetBuilder

from strategies import nets


def cycle(k: int = 1):
    """k independent 4-place cycles: 4**k markings."""
    b = NetBuilder(f"cycles{k}")
    for c in range(k):
        for i in range(4):
            b.place(f"c{c}p{i}", 1 if i == 0 else 0)
            b.transition(f"c{c}t{i}")
        for i in range(4):
            b.arc(f"c{c}p{i}", f"c{c}t{i}")
            b.arc(f"c{c}t{i}", f"c{c}p{(i + 1) % 4}")
    return b.build()


def test_independent_cycles_have_4_to_the_k_markings():
    for k in (1, 2, 3):
        space = explore(cycle(k))
        assert space.states == 4 ** k and space.safe and not space.terminal
        assert behaviour(space).home_marking and behaviour(space).reusable


def test_a_producer_is_unbounded_and_gets_omega():
    b = NetBuilder("producer")
    b.place("ready", 1)
    b.place("buffer")
    b.transition("produce")
    b.arc("ready", "produce")
    b.arc("produce", "ready")
    b.arc("produce", "buffer")
    space = explore(b.build())
    assert not space.bounded and space.coverability
    assert any(m[1] == OMEGA for m in space.markings)
    assert ["buffer*w", "ready"] in [space.format(n) for n in range(space.states)]
    assert not behaviour(space).reusable


def test_a_bounded_net_with_two_tokens():
    b = NetBuilder("two")
    b.place("p", 2)
    b.place("q")
    b.transition("t")
    b.arc("p", "t")
    b.arc("t", "q")
    space = explore(b.build())
    assert space.bounded and not space.safe and space.bound == 2
    assert [space.format(n) for n in space.terminal] == [["q*2"]]


def test_read_arcs_test_without_consuming():
    b = NetBuilder("read")
    b.place("guard", 1)
    b.place("p", 1)
    b.place("q")
    b.transition("t")
    b.read("guard", "t")
    b.arc("p", "t")
    b.arc("t", "q")
    space = explore(b.build())
    assert [space.format(n) for n in space.terminal] == [["guard", "q"]]


def test_weights():
    b = NetBuilder("weights")
    b.place("p", 3)
    b.place("q")
    b.transition("t")
    b.arc("p", "t", 2)
    b.arc("t", "q", 3)
    space = explore(b.build())
    assert sorted(space.format(n) for n in range(space.states)) == [["p", "q*3"], ["p*3"]]


def test_deadlock_is_reported_as_improper():
    b = NetBuilder("stuck")
    b.place("B", 1)
    b.place("X")
    b.place("OK")
    b.place("Y")
    b.transition("go")
    b.arc("B", "go")
    b.arc("go", "X")
    b.transition("finish")
    b.arc("X", "finish")
    b.arc("Y", "finish")  # Y is never marked: X is a dead end
    b.arc("finish", "OK")
    space = explore(b.build())
    result = behaviour(space)
    assert not result.deadlock_free and result.improper == (("X",),)


def test_limit_and_progress():
    calls = []
    old = statespace.PROGRESS_EVERY
    statespace.PROGRESS_EVERY = 10
    try:
        explore(cycle(3), progress=lambda n, f: calls.append(n))
    finally:
        statespace.PROGRESS_EVERY = old
    assert calls and calls == sorted(calls)
    with pytest.raises(ExplorationLimit, match="more than 10 markings"):
        explore(cycle(3), max_states=10)


def test_graph_and_paths():
    space = explore(cycle(1))
    g = space.graph()
    assert g.number_of_nodes() == 4 and g.number_of_edges() == 4
    assert space.path_to(2) == ["c0t0", "c0t1"]


@settings(max_examples=80, deadline=None)
@given(nets(max_places=5, max_transitions=4))
def test_the_bitset_explorer_agrees_with_the_general_one(net):
    try:
        fast = explore(net, max_states=2000)
        slow = statespace._explore_general(fast.structure, tuple(fast.markings[0]), 2000, None)
    except ExplorationLimit:
        return
    assert set(fast.markings) == set(slow.markings)
    assert fast.states == slow.states and len(fast.src) == len(slow.src)
    assert fast.bounded == slow.bounded


def test_reduced_model_check_compares_projected_finals():
    def task(extra_step: bool):
        b = NetBuilder("t")
        b.place("B", 1)
        b.place("OK")
        b.place("MID")
        b.transition("go")
        b.arc("B", "go")
        if extra_step:
            b.arc("go", "MID")
            b.transition("end")
            b.arc("MID", "end")
            b.arc("end", "OK")
        else:
            b.arc("go", "OK")
        return b.build()
    agree = final_markings_agree(task(True), task(False), ["B", "OK"])
    assert agree.equal and agree.finals_a == {("OK",)}
    b = NetBuilder("other")
    b.place("B", 1)
    b.place("OK")
    assert not final_markings_agree(task(True), b.build(), ["B", "OK"]).equal


@st.composite
def spread_safe_nets(draw):
    """Safe-looking unit nets whose few places sit far apart among unconnected ones.

    So that markings take two or three 64-bit words and transitions test
    places in different words: the packed explorer's several-word path.
    """
    real = draw(st.integers(2, 8))
    fillers = draw(st.integers(60, 150))
    spots = sorted(draw(st.lists(st.integers(0, fillers), min_size=real, max_size=real)))
    b = NetBuilder("spread")
    names, k = [], 0
    for i in range(fillers + 1):
        while k < real and spots[k] == i:
            names.append(f"p{k}")
            b.place(f"p{k}", draw(st.integers(0, 1)))
            k += 1
        if i < fillers:
            b.place(f"f{i}", 0)
    for t in range(draw(st.integers(1, 6))):
        b.transition(f"t{t}")
        pre = draw(st.sets(st.sampled_from(names), max_size=2))
        for p in pre:
            b.arc(p, f"t{t}")
        for p in draw(st.sets(st.sampled_from(names), max_size=2)):
            b.arc(f"t{t}", p)
        for p in draw(st.sets(st.sampled_from(names), max_size=1)) - pre:
            b.arc(p, f"t{t}", kind=ArcKind.READ)
    return b.build()


def _same_space(fast, slow):
    assert set(fast.markings) == set(slow.markings)
    assert fast.markings[0] == slow.markings[0]
    assert fast.states == slow.states
    edges = lambda sp: {(sp.markings[a], t, sp.markings[b])
                        for a, t, b in zip(sp.src, sp.trans, sp.dst)}
    assert edges(fast) == edges(slow)
    assert {fast.markings[n] for n in fast.terminal} == {slow.markings[n] for n in slow.terminal}
    goal = slow.terminal or [0]
    reach_slow = dict(zip(slow.markings, slow.can_reach(goal)))
    goal_fast = [fast.markings.index(slow.markings[n]) for n in goal]
    assert dict(zip(fast.markings, fast.can_reach(goal_fast))) == reach_slow


@settings(max_examples=120, deadline=None)
@given(spread_safe_nets())
def test_the_packed_explorer_on_markings_of_several_words(net):
    fast = explore(net, max_states=5000)
    slow = statespace._explore_general(fast.structure, tuple(fast.markings[0]), 5000, None)
    if fast.bounded and max(max(m) for m in slow.markings) <= 1:
        assert type(fast).__name__ == "PackedStateSpace"
    _same_space(fast, slow)


def test_markings_that_share_a_key_fall_back_to_exact_exploration(monkeypatch):
    """A key collision (once in 2^64 pairs) must never merge two markings.

    A key made of the first word only collides whenever two markings differ
    in the second word alone; the explorer has to notice and answer right.
    """
    b = NetBuilder("two words")
    for i in range(130):
        b.place(f"p{i}", 1 if i in (0, 100) else 0)
    for t, before, after in (("low", "p0", "p1"), ("high", "p100", "p101")):
        b.transition(t)
        b.arc(before, t)
        b.arc(t, after)
    net = b.build()
    assert type(explore(net)).__name__ == "PackedStateSpace" and explore(net).states == 4
    monkeypatch.setattr(packedspace, "_keys",
                        lambda rows: rows[:, 0].copy() if rows.shape[1] > 1 else rows[:, 0])
    fooled = explore(net)
    assert fooled.states == 4
    _same_space(fooled, statespace._explore_general(fooled.structure,
                                                    tuple(fooled.markings[0]), 100, None))
