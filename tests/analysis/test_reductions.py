"""Structural reductions keep what a reachability question sees
(analysis/structure/reductions.py): on random nets, and on nets grown to hold what each
rule looks for, the reduced net reaches exactly the visible places' markings the net
reaches, and the net reduced for paths answers CTL and LTL as the net does; on the
contest's models, the questions answered on their reduced nets get the 2021 consensus's
answers."""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.analysis.contest import answers as mcc
from mcl2pnml.analysis.contest.answers import reducible
from mcl2pnml.analysis.structure.reductions import RULES, Keep, reduced
from mcl2pnml.core import queries as q
from mcl2pnml.core.net import ArcKind, NetBuilder
from mcl2pnml.core.structure import structure
from mcl2pnml.io.mccquery import read_queries
from mcl2pnml import pipeline
from sampling import sample
from strategies import nets
from test_mcc import CORPUS, FILES, WITHOUT_GRAPH, _corpus, _oracle, _shown, _some
from test_simplify import _temporal
from test_state_equation import explored, formulas


def _seen(net, places) -> set[tuple[int, ...]]:
    space = explored(net, 20_000)
    if space is None:
        return None
    order = [p.id for p in net.places]
    at = [order.index(p) for p in places]
    return {tuple(int(m[i]) for i in at) for m in space.markings}


def _inputs(net, t) -> dict:
    return {(a.source, a.kind): a.weight for a in net.arcs if a.target == t}


def _holds(net, places, transitions):
    r = reduced(net, places, transitions)
    seen = sorted(set(places) | {a.source for a in net.arcs if a.target in transitions})
    for t in transitions:
        assert _inputs(r.net, t) == _inputs(net, t), (net, t)
    before, after = _seen(net, seen), _seen(r.net, seen)
    if before is not None:
        assert after == before, (net, places, transitions, r.removed)
    return r


@st.composite
def grown(draw):
    """A random net grown with what the rules look for: an arc cut by a new place and
    transition (a sequence to agglomerate), a place copied with more tokens (a parallel
    place), a transition copied (a duplicate)."""
    net = draw(nets(max_places=5, max_transitions=4))
    arcs = {(a.source, a.target, a.kind): a.weight for a in net.arcs}
    b = NetBuilder(net.name)
    for p in net.places:
        b.place(p.id, net.initial[p.id])
    for t in net.transitions:
        b.transition(t.id)
    for k in range(draw(st.integers(1, 6))):
        what = draw(st.sampled_from(("cut", "cut", "place", "transition")))
        if what == "cut" and arcs:
            (s, t, kind), w = draw(st.sampled_from(sorted(arcs.items(), key=str)))
            if kind is ArcKind.NORMAL and t in b._places:      # transition -> place
                del arcs[(s, t, kind)]
                b.place(f"mid{k}")
                b.transition(f"step{k}")
                arcs[(s, f"mid{k}", kind)] = 1
                arcs[(f"mid{k}", f"step{k}", kind)] = 1
                arcs[(f"step{k}", t, kind)] = w
        elif what == "place":
            p = draw(st.sampled_from(sorted(b._places)))
            b.place(f"copy{k}", net.initial[p] if p in net.initial else 0)
            for (s, t, kind), w in list(arcs.items()):
                if s == p:
                    arcs[(f"copy{k}", t, kind)] = w
                elif t == p:
                    arcs[(s, f"copy{k}", kind)] = w
        elif what == "transition":
            u = draw(st.sampled_from(sorted(b._transitions)))
            b.transition(f"twin{k}")
            for (s, t, kind), w in list(arcs.items()):
                if s == u:
                    arcs[(f"twin{k}", t, kind)] = w
                elif t == u:
                    arcs[(s, f"twin{k}", kind)] = w
    for (s, t, kind), w in arcs.items():
        b.arc(s, t, w, kind)
    return b.build()


@st.composite
def processes(draw):
    """Cyclic processes sharing resources, as the contest's models are made: each a cycle
    of places, some steps with a second way to go on (a choice), a resource taken at
    one step and given back at a later one, a place that mirrors the cycle's first;
    bounded, so both nets are explored."""
    b = NetBuilder("processes")
    resources = [b.place(f"r{i}", draw(st.integers(0, 2)))
                 for i in range(draw(st.integers(0, 2)))]
    for k in range(draw(st.integers(1, 3))):
        n = draw(st.integers(2, 5))
        ring = [b.place(f"p{k}_{i}", 1 if i == 0 else 0) for i in range(n)]
        steps = []
        for i in range(n):
            steps.append([f"t{k}_{i}"] + ([f"u{k}_{i}"] if draw(st.booleans()) else []))
            for t in steps[-1]:
                b.transition(t)
                b.arc(ring[i], t)
                skip = draw(st.integers(0, 1)) if t[0] == "u" else 0    # a step or two
                b.arc(t, ring[(i + 1 + skip) % n])
        if draw(st.booleans()):                     # a parallel place
            b.place(f"mirror{k}", draw(st.integers(1, 2)))
            for t in steps[0]:
                b.arc(f"mirror{k}", t)
            for t in steps[-1]:
                b.arc(t, f"mirror{k}")
        if resources and n > 2 and draw(st.booleans()):
            r = draw(st.sampled_from(resources))
            take = draw(st.integers(0, n - 2))
            give = draw(st.integers(take + 1, n - 1))
            for t in draw(st.sampled_from(steps[take:take + 1] + [steps[take][:1]])):
                b.arc(r, t)
            for t in steps[give]:
                b.arc(t, r)
    return b.build()


def _drawn(data, fewest_places: int):
    """A net (random, grown, or processes), up to three of its places and two of its
    transitions."""
    net = data.draw(st.one_of(nets(), grown(), processes()))
    places = data.draw(st.lists(st.sampled_from([p.id for p in net.places]),
                                min_size=fewest_places, max_size=3, unique=True))
    names = [t.id for t in net.transitions]
    transitions = data.draw(st.lists(st.sampled_from(names), max_size=2, unique=True)) \
        if names else []
    return net, places, transitions


@settings(max_examples=sample(1500, 200), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.data())
def test_the_reduced_net_reaches_what_the_net_reaches_on_the_visible_places(data):
    net, places, transitions = _drawn(data, fewest_places=0)
    _holds(net, places, transitions)


def _line(n: int, tokens: int = 1):
    """``a0 -> t1 -> a1 -> ... -> an``, ``tokens`` in a0; ``back`` returns one token from
    an to a0, and ``twin`` copies ``t1``; ``shadow`` is a copy of a0 with one more token."""
    b = NetBuilder("line")
    for i in range(n + 1):
        b.place(f"a{i}", tokens if i == 0 else 0)
    b.place("shadow", tokens + 1)
    for i in range(1, n + 1):
        b.transition(f"t{i}")
        b.arc(f"a{i - 1}", f"t{i}")
        b.arc(f"t{i}", f"a{i}")
    b.place("idle")
    for t in ("back", "twin", "never"):      # never: needs a place nothing marks
        b.transition(t)
    for source, target in ((f"a{n}", "back"), ("back", "a0"), ("back", "shadow"),
                           ("shadow", "t1"), ("a0", "twin"), ("shadow", "twin"),
                           ("twin", "a1"), ("idle", "never"), ("never", "a2")):
        b.arc(source, target)
    return b.build()


def _net(marking: dict, arcs: str):
    """A net from its arcs, ``"a>t t>b ..."`` (a name starting with t is a transition;
    ``a>>t`` a read arc)."""
    b = NetBuilder("small")
    for arc in arcs.split():
        for name in arc.replace(">>", ">").split(">"):
            if name not in b._places and name not in b._transitions:
                if name.startswith("t"):
                    b.transition(name)
                else:
                    b.place(name, marking.get(name, 0))
        if ">>" in arc:
            b.read(*arc.split(">>"))
        else:
            b.arc(*arc.split(">"))
    return b.build()


#: For each rule, a net where it applies, the places and transitions seen, and what
#: must be left of the net.
WHERE = {
    # t2 needs a place nothing marks
    "DEAD": (_net({"a": 1}, "a>t1 t1>b idle>t2 t2>b"), ["b"], [], {"a", "b"}),
    # k is never changed: its read arc goes, and t2, which needs more than k has, too
    "CONSTANT": (_net({"a": 1, "k": 1}, "a>t1 t1>b k>>t1 a>t2 t2>c k>t2 k>t2 t2>k t2>k"),
                 ["b"], [], {"a", "b"}),
    # nothing the seen place depends on: z, w and t2
    "IRRELEVANT": (_net({"x": 1, "z": 1}, "x>t1 t1>y z>t2 t2>w"), ["y"], [], {"x", "y"}),
    "DUPLICATE_TRANSITION": (_net({"a": 1}, "a>t1 t1>b a>t2 t2>b b>t3 t3>a"), ["a", "b"],
                             [], {"a", "b"}),
    # c holds twice what a holds, plus one, and t1 needs of it twice as much
    "IMPLICIT_PLACE": (_net({"a": 1, "c": 3}, "a>t1 c>t1 c>t1 t1>b b>t2 t2>a t2>c t2>c"),
                       ["a", "b"], [], {"a", "b"}),
    # p's one consumer t2 goes on at once: t1 puts in q, t2 and p go
    "SEQUENTIAL_PLACE": (_net({"a": 1}, "a>t1 t1>p p>t2 t2>q q>t3 t3>a"), ["a"], [],
                         {"a", "q"}),
    # p has two consumers, each taking only p: two pairs for two and one
    "POST_AGGLOMERATION": (_net({"a": 1}, "a>t1 t1>p p>t2 p>t3 t2>q t3>r q>t4 r>t5 "
                                          "t4>a t5>a"),
                           ["a"], [], {"a", "q", "r"}),
    # t1's only output p is taken by t2 with the lock: t1 waits for t2 and fires with it
    # (t4 competes for a, which would otherwise go on through t1 at once)
    "PRE_AGGLOMERATION": (_net({"a": 1, "lock": 1}, "a>t1 t1>p p>t2 lock>t2 t2>b "
                                                    "b>t3 t3>lock t3>a a>t4 t4>d"),
                          ["b", "lock"], [], {"a", "b", "lock"}),
}


@pytest.mark.parametrize("rule", RULES)
def test_each_rule_applies_where_its_conditions_hold(rule):
    net, places, transitions, left = WHERE[rule]
    r = _holds(net, places, transitions)
    assert rule in dict(r.removed), r.removed
    assert {p.id for p in r.net.places} == left, r.net


def test_a_place_that_is_seen_stops_the_agglomerations_there():
    net = _line(6, tokens=2)
    r = _holds(net, ["a0"], [])
    # the line's inner places are agglomerated away: t1 ... t6 and back become one cycle
    assert len(r.net.places) < len(net.places) and len(r.net.transitions) <= 2
    r = _holds(net, ["a0", "a3"], ["t5"])
    assert {"a3", "a4"} <= {p.id for p in r.net.places}


def test_a_name_the_net_lacks_is_refused():
    with pytest.raises(KeyError):
        reduced(_line(2), [], ["nowhere"])


@pytest.mark.parametrize("model", _some(WITHOUT_GRAPH))
def test_on_the_contests_models_the_reduced_nets_answer_as_the_consensus(model):
    _corpus()
    folder = CORPUS / model
    net = pipeline.load_net(folder / "model.pnml")
    oracle = _oracle(model)
    asked = 0
    for name in FILES:
        for x in read_queries(folder / f"{name}.xml"):
            keep = reducible(x)
            if keep is None:
                continue
            places, transitions = q.seen(x.asks)
            r = reduced(net, places, transitions, keep=keep)
            got = mcc.answer(r.net, [x])[0]
            assert got.value is not None, (model, x.id, got.reason)
            if oracle[x.id] != "?":
                assert _shown(got.value) == oracle[x.id], (model, x.id, r.removed)
            asked += 1
    assert asked and structure(net)


def test_only_what_the_reductions_keep_is_asked_of_a_reduced_net():
    a = q.IntLe(q.IntConst(1), q.TokensCount(("a0",)))
    asked = {"ef": q.ExistsPath(q.Finally(a)), "not-ag": q.Neg(q.AllPaths(q.Globally(a))),
             "bound": q.PlaceBound(("a0",)),
             "deadlock": q.ExistsPath(q.Finally(q.Disj((a, q.Deadlock())))),
             "af": q.AllPaths(q.Finally(a)), "eg": q.ExistsPath(q.Globally(a)),
             "ax": q.AllPaths(q.Next(a)), "ltl-x": q.AllPaths(q.Finally(q.Next(a)))}
    keeps = {k: reducible(q.Query(k, f)) for k, f in asked.items()}
    assert keeps == {"ef": Keep.REACHABLE, "not-ag": Keep.REACHABLE, "bound": Keep.REACHABLE,
                     "deadlock": None, "af": Keep.PATHS, "eg": Keep.PATHS, "ax": None,
                     "ltl-x": None}
    # in the portfolio, past a first graph too small, no question with X or a deadlock is
    # answered on a reduced net, and every answer is the whole graph's
    net = _line(6, tokens=2)
    queries = [q.Query(k, f) for k, f in asked.items()]
    got = {x.id: x for x in mcc.answers_as_found(net, queries, max_states=3)}
    truth = {x.id: x.value for x in mcc.answer(net, queries)}
    for k in ("deadlock", "ax", "ltl-x"):
        assert not got[k].technique.startswith("STRUCTURAL_REDUCTION"), got[k]
    assert all(x.value == truth[k] for k, x in got.items() if x.value is not None), got


@settings(max_examples=sample(3000, 60), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.data())
def test_the_net_reduced_for_paths_answers_ctl_and_ltl_as_the_net(data):
    # CTL and LTL formulas without X and deadlock, over a few of the net's names, on the
    # net reduced by the rules that keep paths: the whole graphs answer alike (with every
    # rule, the irrelevant transitions that may fire for ever make LTL's answers differ)
    net, places, transitions = _drawn(data, fewest_places=1)
    f = data.draw(_temporal(formulas(places, transitions or places[:1])))
    if q.contains(f, q.Next) or q.contains(f, q.Deadlock) \
            or not q.seen(f)[1] <= {t.id for t in net.transitions}:
        return
    r = reduced(net, *q.seen(f), keep=Keep.PATHS)
    if not r.smaller or explored(net, 3_000) is None:
        return
    x = q.Query("f", f)
    assert mcc.answer(r.net, [x])[0].value == mcc.answer(net, [x])[0].value, \
        (net, f, r.removed)


def test_transitions_that_may_fire_alone_for_ever_stay_for_paths():
    # tl1 and tl2 pass a token round for ever beside t: A F (p = 0) is false (a run may
    # never fire t); without them, every run fires t. Removed for the reachable markings,
    # they stay where the paths are kept; gone once they cannot go round for ever.
    p_empty = q.AllPaths(q.Finally(q.IntLe(q.TokensCount(("p",)), q.IntConst(0))))
    x = q.Query("f", p_empty)
    for arcs, loops in (("p>t t>q r1>tl1 tl1>r2 r2>tl2 tl2>r1", True),
                        ("p>t t>q r1>tl1 tl1>r2", False)):
        net = _net({"p": 1, "r1": 1}, arcs)
        truth = mcc.answer(net, [x])[0].value
        for_paths = reduced(net, ["p"], [], keep=Keep.PATHS).net
        assert mcc.answer(for_paths, [x])[0].value == truth
        assert ({t.id for t in for_paths.transitions} != {"t"}) is loops    # a loop kept
        reachable = reduced(net, ["p"], []).net
        assert {t.id for t in reachable.transitions} == {"t"}
        assert mcc.answer(reachable, [x])[0].value is True
    assert truth is True
