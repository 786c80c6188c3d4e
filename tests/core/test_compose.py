"""Composition by place fusion and its laws (section 2.5 of the paper)."""
from hypothesis import given, settings, strategies as st
import pytest

from mcl2pnml.core.compose import compose, fuse, union
from mcl2pnml.core.errors import NetError
from mcl2pnml.core.net import Marking, Net, NetBuilder

from strategies import nets
from sampling import sample


def chain(name: str) -> "Net":
    b = NetBuilder(name)
    b.place("B", 1, interface="B")
    b.place("OK", interface="OK")
    b.transition("run")
    b.arc("B", "run")
    b.arc("run", "OK")
    return b.build()


def test_union_prefixes_every_node():
    net = union({"T1": chain("a"), "T2": chain("b")}, name="seq")
    assert {p.id for p in net.places} == {"T1.B", "T1.OK", "T2.B", "T2.OK"}
    assert net.initial == Marking({"T1.B": 1, "T2.B": 1})
    assert net.place_index["T2.OK"].interface == "OK"


def test_fusion_keeps_the_first_member_and_all_arcs():
    net = compose({"T1": chain("a"), "T2": chain("b")}, [["T1.OK", "T2.B"]], name="seq")
    assert "T1.OK" in net.place_index and "T2.B" not in net.place_index
    # the fused place is marked because T2.B was: fused places are one place
    assert net.initial == Marking({"T1.B": 1, "T1.OK": 1})
    assert {(a.source, a.target) for a in net.arcs} == {
        ("T1.B", "T1.run"), ("T1.run", "T1.OK"), ("T1.OK", "T2.run"), ("T2.run", "T2.OK")}


def test_fusion_adds_up_arcs_that_come_to_join_the_same_ends():
    b = NetBuilder("n")
    b.place("p")
    b.place("q")
    b.transition("t")
    b.arc("t", "p")
    b.arc("t", "q", 2)
    net = fuse(b.build(), [["p", "q"]])
    assert [(a.source, a.target, a.weight) for a in net.arcs] == [("t", "p", 3)]


def test_fusing_differently_marked_places_is_an_error():
    b = NetBuilder("n")
    b.place("p", 1)
    b.place("q", 2)
    with pytest.raises(NetError, match="same marking"):
        fuse(b.build(), [["p", "q"]])
    with pytest.raises(NetError, match="no place"):
        fuse(b.build(), [["p", "zz"]])


def test_union_refuses_clashing_names():
    with pytest.raises(NetError, match="duplicate id"):
        union([("", chain("a")), ("", chain("b"))])


@st.composite
def net_and_groups(draw):
    net = draw(nets())
    ids = [p.id for p in net.places]
    groups = draw(st.lists(st.lists(st.sampled_from(ids), min_size=1, max_size=3),
                           max_size=3))
    return net, groups


def _fusable(net, groups):
    try:
        return fuse(net, groups)
    except NetError:
        return None  # differently marked members, or read and consumed alike


def _classes(net, groups):
    """Member -> representative: the first in the net's order of its class."""
    order = {p.id: i for i, p in enumerate(net.places)}
    cls = {m: {m} for g in groups for m in g}
    for g in groups:
        merged = set().union(*(cls[m] for m in g)) if g else set()
        for m in merged:
            cls[m] = merged
    return {m: min(c, key=order.__getitem__) for m, c in cls.items()}


@settings(max_examples=sample(100, 35), deadline=None)
@given(net_and_groups(), st.randoms())
def test_fusion_is_associative_and_loses_nothing(case, rnd):
    net, groups = case
    at_once = _fusable(net, groups)
    if at_once is None:
        return
    # fusing the groups one at a time, in any order, gives the same net
    shuffled = list(groups)
    rnd.shuffle(shuffled)
    one_by_one, done = net, []
    for g in shuffled:
        rep = _classes(net, done)  # where earlier fusions put each member
        one_by_one = fuse(one_by_one, [[rep.get(m, m) for m in g]])
        done.append(g)
    assert one_by_one == at_once
    rep = _classes(net, groups)
    assert len(at_once.places) == len(net.places) - len(rep) + len(set(rep.values()))
    assert set(rep.values()) <= set(at_once.place_index)
    assert at_once.transitions == net.transitions
    # every arc survives, with its weight, on the representative of its place
    assert sum(a.weight for a in at_once.arcs) == sum(a.weight for a in net.arcs)
    assert len({p.id for p in at_once.places}) == len(at_once.places)


@settings(max_examples=30, deadline=None)
@given(nets(), nets(), nets())
def test_union_is_associative(a, b, c):
    left = union({"ab": union({"a": a, "b": b}), "c": c})
    right = union({"a": union({"b": a}), "bc": union({"b": b, "c": c})})
    # same nets up to prefixes: compare after mapping both to the innermost names
    strip = lambda n: sorted((p.id.split(".", 1)[1] if p.id.startswith("ab.") else p.id)
                             for p in n.places)
    assert len(left.places) == len(right.places) == len(a.places) + len(b.places) + len(c.places)
    assert len(left.arcs) == len(right.arcs)
    assert sum(left.initial.values()) == sum(right.initial.values())
    assert strip(left) == sorted(p.id for p in union({"a": a, "b": b, "c": c}).places)


@st.composite
def components_and_groups(draw):
    parts = [(draw(st.sampled_from(["a", "b", "c"])) + str(i), draw(nets(max_places=4,
                                                                       max_transitions=3)))
             for i in range(draw(st.integers(1, 3)))]
    qualified = [f"{prefix}.{p.id}" for prefix, net in parts for p in net.places]
    groups = draw(st.lists(st.lists(st.sampled_from(qualified), min_size=1, max_size=3),
                           max_size=4))
    return parts, groups


@settings(max_examples=sample(150, 50), deadline=None)
@given(components_and_groups())
def test_one_pass_composition_is_union_then_fusion_and_valid(case):
    """compose() skips the full check of its result: the result must pass it anyway."""
    parts, groups = case
    try:
        at_once = compose(parts, groups, name="m")
    except NetError:
        # then fusing the plain union must fail too (markings or read/consume clash)
        with pytest.raises(NetError):
            fuse(Net(*_fields(union(parts, "m"))), groups)
        return
    rebuilt = Net(*_fields(at_once))          # runs every check of the constructor
    assert rebuilt == at_once
    plain = union(parts, "m")
    step_by_step, done = plain, []
    for g in groups:                           # fusion one group at a time agrees
        rep = _classes(plain, done)            # where earlier fusions put each member
        step_by_step = fuse(step_by_step, [[rep.get(m, m) for m in g]])
        done.append(g)
    assert step_by_step == at_once


def _fields(net):
    return net.name, net.places, net.transitions, net.arcs, net.initial


def test_composition_with_a_white_space_prefix_is_checked():
    with pytest.raises(NetError, match="white space"):
        compose([(" x", chain("a"))], [])
