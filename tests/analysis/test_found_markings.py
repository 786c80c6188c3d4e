"""Past its limit, an exploration hands back the markings it found (``ExplorationLimit.found``,
analysis/statespace/general.py): each is reachable, so a witness among them settles a
question (``settled_by_found``, analysis/contest/reachability_queries.py), and ``query``
answers with it where the graph is too large (EXPLICIT)."""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.analysis.contest.answers import answer
from mcl2pnml.analysis.contest.reachability_queries import settled_by_found
from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore
from mcl2pnml.core import queries as q
from mcl2pnml.core.net import NetBuilder
from mcl2pnml.core.structure import structure
from sampling import sample
from strategies import nets
from test_state_equation import formulas

SETTINGS = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                      HealthCheck.filter_too_much])


def _cut_short(net, limit: int):
    """The markings found by an exploration stopped at ``limit``, as tuples; None where it
    was not stopped or kept none."""
    try:
        explore(net, max_states=limit)
    except ExplorationLimit as e:
        if e.found is None:
            return None
        s = structure(net)
        columns = [e.found.tokens(i) for i in range(len(s.places))]
        return e, [tuple(int(c[k]) for c in columns) for k in range(e.found.states)]
    return None


def _whole(net):
    try:
        space = explore(net, max_states=5_000)
    except ExplorationLimit:
        return None
    return None if space.coverability else space


@settings(max_examples=sample(600, 80), **SETTINGS)
@given(st.data())
def test_the_markings_found_before_the_limit_are_reachable_and_distinct(data):
    net = data.draw(nets())
    space = _whole(net)
    if space is None:
        return
    cut = _cut_short(net, data.draw(st.integers(1, max(1, space.states - 1))))
    if cut is None:
        return
    error, found = cut
    reachable = {tuple(int(v) for v in m) for m in space.markings}
    assert set(found) <= reachable
    assert len(set(found)) == len(found) == error.explored


@settings(max_examples=sample(1500, 100), **SETTINGS)
@given(st.data())
def test_a_question_settled_by_a_found_marking_is_answered_as_the_whole_graph_answers(data):
    net = data.draw(nets())
    s = structure(net)
    phi = data.draw(formulas(list(s.places), list(s.transitions)))
    asks = data.draw(st.sampled_from([q.ExistsPath(q.Finally(phi)),
                                      q.AllPaths(q.Globally(phi)),
                                      q.Neg(q.ExistsPath(q.Finally(phi)))]))
    space = _whole(net)
    if space is None or space.states < 2:
        return
    try:
        explore(net, max_states=data.draw(st.integers(1, space.states - 1)))
    except ExplorationLimit as e:
        found = e.found
    if found is None:
        return
    x = q.Query("x", asks)
    settled = settled_by_found(net, [x], found)
    if "x" in settled:
        [truth] = answer(net, [x])
        assert settled["x"][0] is truth.value, (net, asks)


def _toggles(n: int, tokens: int = 1):
    """``n`` independent places that each go on and off (2^n markings; with ``tokens``
    more than 1 the net is not safe and the bounded explorer counts them)."""
    b = NetBuilder("toggles")
    for i in range(n):
        b.place(f"off{i}", tokens)
        b.place(f"on{i}", 0)
        b.transition(f"up{i}")
        b.arc(f"off{i}", f"up{i}")
        b.arc(f"up{i}", f"on{i}")
        b.transition(f"down{i}")
        b.arc(f"on{i}", f"down{i}")
        b.arc(f"down{i}", f"off{i}")
    return b.build()


@pytest.mark.parametrize("tokens", [1, 3])
def test_past_the_graphs_limit_query_answers_with_a_found_witness(tokens):
    net = _toggles(16, tokens)        # 65,536 markings (safe) or 4^16: past 1,000
    on = [q.IntLe(q.IntConst(1), q.TokensCount((f"on{i}",))) for i in range(2)]
    asks = [q.Query("two-on", q.ExistsPath(q.Finally(q.Conj(tuple(on))))),
            q.Query("never-on", q.AllPaths(q.Globally(q.Neg(on[0])))),
            q.Query("down-fires", q.ExistsPath(q.Finally(q.Fireable(("down1",))))),
            q.Query("all-on", q.ExistsPath(q.Finally(q.Conj(tuple(
                q.IntLe(q.IntConst(1), q.TokensCount((f"on{i}",))) for i in range(16))))))]
    got = {a.id: a for a in answer(net, asks, max_states=1_000)}
    assert (got["two-on"].value, got["two-on"].technique) == (True, "EXPLICIT")
    assert (got["never-on"].value, got["never-on"].technique) == (False, "EXPLICIT")
    assert (got["down-fires"].value, got["down-fires"].technique) == (True, "EXPLICIT")
    # reachable, but 16 firings deep: past a breadth-first 1,000; the depth-first search
    # on the fly meets it (a random walk may, if that search was cut short by load)
    assert (got["all-on"].value, got["all-on"].technique) in {
        (True, "EXPLICIT LTL ON_THE_FLY STUBBORN_SETS"), (True, "RANDOM_WALK")}


def test_answers_come_out_as_they_are_settled_before_the_long_exploration(monkeypatch):
    import mcl2pnml.analysis.contest.answers as mcc
    explorations = []
    real = mcc._space

    def counted(net, max_states, max_memory):
        explorations.append(max_states)
        return real(net, max_states, max_memory)

    monkeypatch.setattr(mcc, "_space", counted)
    net = _toggles(18)                # 262,144 markings: past the first 100,000
    on = [q.IntLe(q.IntConst(1), q.TokensCount((f"on{i}",))) for i in range(18)]
    # E F E G: not a reachability question, a cycle of the graph explored so far shows it;
    # A G E F: every marking, the graph of the net reduced for on0 (the other toggles
    # become steps that change nothing, the second exploration) answers it
    asks = [q.Query("stays-on", q.ExistsPath(q.Finally(q.ExistsPath(q.Globally(on[0]))))),
            q.Query("always-back", q.AllPaths(q.Globally(q.ExistsPath(q.Finally(on[0]))))),
            q.Query("one-on", q.ExistsPath(q.Finally(on[0]))),
            q.Query("at-most-one", q.AllPaths(q.Globally(
                q.IntLe(q.TokensCount(("on0", "off0")), q.IntConst(1)))))]
    when = {a.id: (a.value, a.technique, len(explorations))
            for a in mcc.answers_as_found(net, asks, max_states=300_000)}
    assert when == {"one-on": (True, "EXPLICIT", 1),
                    "at-most-one": (True, "STATE_EQUATION", 1),
                    "stays-on": (True, "EXPLICIT CTL PARTIAL_STATE_SPACE", 1),
                    "always-back": (True, "STRUCTURAL_REDUCTION EXPLICIT CTL", 2)}
    assert explorations == [mcc.FIRST_STATES, mcc.FIRST_STATES]     # no long one left


def test_the_explorations_after_the_first_grow_tenfold_up_to_the_limit():
    import mcl2pnml.analysis.contest.answers as mcc
    first = mcc.FIRST_STATES
    assert mcc._stages(first) == []
    assert mcc._stages(first + 1) == [first + 1]
    assert mcc._stages(50 * first) == [10 * first, 50 * first]
    # each stage's markings are witnesses before the next: all cost about a tenth more
    # than the last alone
    stages = mcc._stages(10**9)
    assert sum(stages[:-1]) < stages[-1] / 8


@settings(max_examples=sample(400, 60), **SETTINGS)
@given(st.data())
def test_what_a_random_walk_settles_is_what_the_whole_graph_answers(data):
    from mcl2pnml.analysis.contest.reachability_queries import settled_by_walks
    net = data.draw(nets())
    s = structure(net)
    phi = data.draw(formulas(list(s.places), list(s.transitions)))
    asks = data.draw(st.sampled_from([q.ExistsPath(q.Finally(phi)),
                                      q.AllPaths(q.Globally(phi)),
                                      q.PlaceBound(tuple(s.places[:2]))]))
    if _whole(net) is None:
        return
    x = q.Query("x", asks)
    settled = settled_by_walks(net, [x], seconds=0.05)
    if "x" in settled:
        [truth] = answer(net, [x])
        assert settled["x"][0] == truth.value, (net, asks)


def test_a_random_walk_finds_a_witness_deep_past_the_breadth_first_limit():
    net = _toggles(10)
    all_on = q.Query("all-on", q.ExistsPath(q.Finally(q.Conj(tuple(
        q.IntLe(q.IntConst(1), q.TokensCount((f"on{i}",))) for i in range(10))))))
    # breadth first, 100 markings stay within three firings of M0; the walks go deeper
    from mcl2pnml.analysis.contest.reachability_queries import settled_by_walks
    with pytest.raises(ExplorationLimit):
        explore(net, max_states=100)
    assert settled_by_walks(net, [all_on], seconds=5.0) == {"all-on": (True, "RANDOM_WALK")}


@settings(max_examples=sample(400, 60), **SETTINGS)
@given(st.data())
def test_what_a_best_first_search_settles_is_what_the_whole_graph_answers(data):
    from mcl2pnml.analysis.contest.reachability_queries import settled_by_best_first
    net = data.draw(nets())
    s = structure(net)
    places = data.draw(st.lists(st.sampled_from(s.places), min_size=1, max_size=3))
    x = q.Query("x", q.PlaceBound(tuple(places)))
    if _whole(net) is None:
        return
    settled = settled_by_best_first(net, [x], seconds=1.0)
    if "x" in settled:
        [truth] = answer(net, [x])
        assert settled["x"][0] == truth.value, (net, places)


def _gathering(tokens: int, places: int):
    """``tokens`` tokens on a ring of ``places`` places, each able to step to the next
    while a switch is on (a read arc: no state machine): every place may hold them all,
    which few random markings do."""
    b = NetBuilder("gathering")
    b.place("switch", 1)
    for i in range(places):
        b.place(f"p{i}", tokens if i == 0 else 0)
    for i in range(places):
        b.transition(f"step{i}")
        b.arc(f"p{i}", f"step{i}")
        b.arc(f"step{i}", f"p{(i + 1) % places}")
        b.arc("switch", f"step{i}")
        b.arc(f"step{i}", "switch")
    return b.build()


def test_a_best_first_search_reaches_a_bound_that_random_walks_miss():
    # 30 tokens in p0 of a ring of 12 places: the P-invariant bounds p7 by 30, which a
    # walk, spreading the tokens, does not reach; the fullest marking fired first, and
    # among those the one whose tokens are fewest firings from p7, does
    from mcl2pnml.analysis.contest.reachability_queries import (settled_by_best_first,
                                                                settled_by_walks)
    net = _gathering(30, 12)
    x = q.Query("p7", q.PlaceBound(("p7",)))
    assert settled_by_walks(net, [x], seconds=1.0) == {}
    assert settled_by_best_first(net, [x], seconds=30.0) == {
        "p7": (30, "EXPLICIT BEST_FIRST STRUCTURAL P_INVARIANTS")}
    # in the portfolio, past the graph: the switch, which no transition changes, goes
    # with the reductions, and the ring alone is small enough to explore; seen, it stays,
    # and the search reaches the bound
    [got] = answer(net, [x], max_states=10_000)
    assert (got.value, got.technique) == (30, "STRUCTURAL_REDUCTION EXPLICIT STATE_SPACE")
    [got] = answer(net, [q.Query("p7", q.PlaceBound(("p7", "switch")))], max_states=10_000)
    assert got.value == 31 and got.technique.startswith("EXPLICIT BEST_FIRST")
    # a bound no proof gives is not searched for; a name the net lacks is left
    assert settled_by_best_first(net, [q.Query("x", q.PlaceBound(("nowhere",)))]) == {}


@pytest.mark.parametrize("tokens", [1, 2])
def test_each_explorers_found_markings_decode_to_reachable_ones(tokens):
    # the safe explorer packs a bit a place, the bounded one a counter: both decoded
    net = _toggles(9, tokens)          # 512 markings, or 3^9
    space = explore(net, max_states=10**5)
    cut = _cut_short(net, 200)
    assert cut is not None
    _, found = cut
    reachable = {tuple(int(v) for v in m) for m in space.markings}
    assert len(found) == 200 and set(found) <= reachable
    assert tuple(structure(net).initial_vector()) in set(found)


@pytest.mark.timeout(120)
def test_a_query_cut_short_keeps_the_lines_it_printed(tmp_path):
    # 2^26 markings: past every stage of the exploration. The found witness is printed
    # at once, before the long explorations; a SIGTERM then ends the command, and the
    # line is already out
    import signal
    import subprocess
    import sys
    from mcl2pnml import pipeline
    net_path, formulas = tmp_path / "toggles.pnml", tmp_path / "q.xml"
    pipeline.save_net(_toggles(26), net_path, layout="none")
    formulas.write_text(
        '<?xml version="1.0"?><property-set xmlns="http://mcc.lip6.fr/"><property>'
        '<id>on</id><description/><formula><exists-path><finally><integer-le>'
        '<integer-constant>1</integer-constant><tokens-count><place>on0</place>'
        '</tokens-count></integer-le></finally></exists-path></formula></property>'
        '<property><id>stays</id><description/><formula><exists-path><finally>'
        '<exists-path><globally><integer-le><integer-constant>1</integer-constant>'
        '<tokens-count><place>on0</place></tokens-count></integer-le></globally>'
        '</exists-path></finally></exists-path></formula></property></property-set>')
    child = subprocess.Popen([sys.executable, "-m", "mcl2pnml", "query", str(net_path),
                              str(formulas)], stdout=subprocess.PIPE, text=True)
    try:
        first = child.stdout.readline()          # bounded by the test's timeout
        assert first == "FORMULA on TRUE TECHNIQUES EXPLICIT\n"
        child.send_signal(signal.SIGTERM)
        rest, _ = child.communicate(timeout=60)
    finally:
        child.kill()
    assert child.returncode in (143, -signal.SIGTERM, 3)   # stopped (3: it had ended)
    assert "FORMULA on" not in rest                        # said once


def test_walks_of_another_seed_are_other_walks_and_every_marking_they_meet_is_reachable():
    from mcl2pnml.analysis.statespace.walks import random_walks
    net = _toggles(9, 2)
    s = structure(net)
    reachable = {tuple(int(v) for v in m) for m in explore(net, max_states=10**5).markings}
    first = [next(random_walks(s, 10.0, walkers=8, seed=k)) for k in (0, 1)]
    assert not (first[0] == first[1]).all()
    assert all(tuple(int(v) for v in row) in reachable for batch in first for row in batch)


def test_walks_on_a_wide_net_hold_a_bounded_memory(monkeypatch):
    # fewer walkers and shorter runs where a marking is wide: what they hold stays
    # within the module's bounds, shrunk here so that a small net is "wide"
    import mcl2pnml.analysis.statespace.walks as walks
    monkeypatch.setattr(walks, "WALKER_BYTES", 8 * 20 * 3)       # three walkers
    monkeypatch.setattr(walks, "RUN_BYTES", 8 * 3 * 20 * 5)       # runs of five
    s = structure(_toggles(10))                                    # 20 places
    batch = next(walks.random_walks(s, 10.0))
    assert batch.shape[1] == 20 and len(batch) % 3 == 0 and len(batch) <= 3 * walks.STEPS
    for markings, back in walks.runs(s, 0.5):
        assert len(markings) <= 6
