"""The net core: immutable nets, markings kept apart, rules checked at construction."""
import pytest
from hypothesis import given, settings, strategies as st

from mcl2pnml.core.errors import NetError
from mcl2pnml.core.net import (Arc, ArcKind, FrozenDict, Marking, Net, NetBuilder, Place,
                          Timing, Transition, freeze, thaw)
from sampling import sample


def small() -> Net:
    b = NetBuilder("small")
    b.place("p", 1, interface="B")
    b.place("q")
    b.transition("t", timing=Timing.delay(2.5), payload={"enable": "KeepDepth", "args": [4.0]})
    b.arc("p", "t")
    b.arc("t", "q", 2)
    return b.build()


def test_net_is_immutable_and_keeps_what_it_was_given():
    net = small()
    with pytest.raises(AttributeError):
        net.name = "other"  # type: ignore[misc]
    assert net.place_index["p"].interface == "B"
    assert net.transition_index["t"].timing == Timing(2.5, 2.5)
    assert net.transition_index["t"].payload == {"enable": "KeepDepth", "args": (4.0,)}
    assert net.initial == Marking({"p": 1})
    assert [a.weight for a in net.post["t"]] == [2]


def test_marking_is_separate_and_hashable():
    net = small()
    m = Marking({"p": 0, "q": 2})
    assert m == Marking(["q", "q"]) and hash(m) == hash(Marking(["q", "q"]))
    assert m["p"] == 0 and "p" not in m and m.format() == ["q*2"]
    assert net.with_initial(m).initial == m and net.initial == Marking({"p": 1})


def test_equality_ignores_order_and_drawing_positions():
    a = small()
    b = Net(a.name, tuple(reversed(a.places)),
            tuple(Transition(t.id, t.name, t.timing, t.payload, (1.0, 2.0)) for t in a.transitions),
            tuple(reversed(a.arcs)), a.initial)
    assert a == b and hash(a) == hash(b)
    assert a != a.with_initial({"q": 1})


def test_payload_is_frozen_json():
    frozen = freeze({"a": [1, {"b": None}], "c": "x"})
    assert isinstance(frozen, FrozenDict) and frozen["a"] == (1, FrozenDict({"b": None}))
    assert thaw(frozen) == {"a": [1, {"b": None}], "c": "x"}
    hash(frozen)
    with pytest.raises(NetError, match="JSON-like"):
        freeze({"a": object()})
    with pytest.raises(NetError, match="finite"):
        freeze(float("nan"))


@pytest.mark.parametrize("build, message", [
    (lambda: Net("n", (Place("p"), Transition("p")), (), ()), "duplicate id 'p'"),
    (lambda: Net("n", (Place("p"),), (Transition("t"),), (Arc("p", "x"),)), "no place or transition 'x'"),
    (lambda: Net("n", (Place("p"), Place("q")), (), (Arc("p", "q"),)), "joins two places"),
    (lambda: Net("n", (Place("p"),), (Transition("t"),), (Arc("t", "p", kind=ArcKind.READ),)),
     "read arc goes from a place"),
    (lambda: Net("n", (Place("p"),), (Transition("t"),), (Arc("p", "t", 0),)), "positive integer"),
    (lambda: Net("n", (Place("p"),), (Transition("t"),), (Arc("p", "t"), Arc("p", "t"))),
     "same ends"),
    (lambda: Net("n", (Place("p"),), (Transition("t"),),
                 (Arc("p", "t"), Arc("p", "t", kind=ArcKind.READ))), "both reads and consumes"),
    (lambda: Net("n", (Place("p"),), (Transition("t"),), (), Marking({"t": 1})), "not a place"),
    (lambda: Marking({"p": -1}), "negative"),
    (lambda: Net("n", (Place(" p"),), (), ()), "white space"),
    (lambda: Timing(5, 3), "empty"),
    (lambda: Timing(-1), ">= 0"),
])
def test_construction_rejects_broken_nets_with_a_clear_message(build, message):
    with pytest.raises(NetError, match=message):
        build()


def test_name_equal_to_id_is_canonical():
    assert Place("p", "p") == Place("p") and Place("p", "p").name is None
    assert Place("p", "Begin").label == "Begin"


def test_builder_adds_up_parallel_arcs():
    b = NetBuilder("n")
    b.place("p")
    b.transition("t")
    b.arc("p", "t")
    b.arc("p", "t", 2)
    assert b.build().arcs == (Arc("p", "t", 3),)
    with pytest.raises(NetError, match="duplicate"):
        b.place("t")


# -- the fast validity check and the walk that explains its faults agree ------

_node_ids = st.sampled_from(["p", "q", "t", "u", " p", "", "p "])
_broken_arcs = st.builds(
    Arc, _node_ids, _node_ids, st.sampled_from([1, 2, 0, -1, True, 1.5]),
    st.sampled_from([ArcKind.NORMAL, ArcKind.READ, "read"]))


@settings(max_examples=sample(300, 100), deadline=None)
@given(st.lists(_node_ids, max_size=3), st.lists(_node_ids, max_size=3),
       st.lists(_broken_arcs, max_size=4),
       st.dictionaries(_node_ids, st.integers(1, 2), max_size=2),
       st.sampled_from(["n", "bad\x00name"]))
def test_fast_check_accepts_exactly_what_the_walk_accepts(places, transitions, arcs,
                                                          marking, name):
    """Every fault the set-based check sees, the node-by-node walk names (and no other)."""
    parts = (name, tuple(Place(p) for p in places), tuple(Transition(t) for t in transitions),
             tuple(arcs), Marking(marking))
    probe = Net._trusted(*parts)
    try:
        probe._explain()
        explained = None
    except NetError as e:
        explained = str(e)
    try:
        Net(*parts)
        accepted = True
    except NetError as e:
        accepted = False
        assert str(e) == explained  # the message is the walk's
    assert accepted == (explained is None)


def test_derived_nets_check_only_what_changed():
    b = NetBuilder("n")
    b.place("p", 1)
    b.transition("t", payload={"call": "Go"})
    b.arc("p", "t")
    net = b.build()
    assert net.with_initial({"p": 2}).initial == Marking({"p": 2})
    with pytest.raises(NetError, match="not a place"):
        net.with_initial({"t": 1})
    stamped = net.with_payloads({"t": {"call": "Go", "bind": {"wp": [1, 2]}}})
    assert stamped.transition_index["t"].payload == {"call": "Go", "bind": {"wp": (1, 2)}}
    assert net.transition_index["t"].payload == {"call": "Go"}  # the original is untouched
    with pytest.raises(NetError, match="no transition 'x'"):
        net.with_payloads({"x": None})
    with pytest.raises(NetError, match="control characters"):
        net.renamed("a\x01b")


def test_summary_names_a_few_marked_places_and_counts_the_rest():
    b = NetBuilder("big")
    for i in range(40):
        b.place(f"p{i:02}", 1)
    text = b.build().summary()
    assert "p00" in text and "p39" not in text and "... 28 more" in text
