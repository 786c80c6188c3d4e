"""Reachability and coverability graphs, on nets whose answers are known by hand.

One suite for every explorer: the tests take the ``backend`` fixture, so
each runs against the native (C), the numpy, the counter and the general
explorer (the safe-net ones hand over to the general one on nets that are
not safe, which these tests cover too); the explorers built on the loops
(native, counters) run twice, on the loops in C and on their plain-Python
reference (``native-python``, ``counters-python``).
"""
import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

from mcl2pnml.analysis.statespace import compiled as compiledspace
from mcl2pnml.analysis.statespace import counters as counterspace
from mcl2pnml.analysis.statespace import general as generalspace
from mcl2pnml.analysis.statespace import packed as packedspace
from mcl2pnml.analysis.statespace import packedmarkings
from mcl2pnml.analysis.statespace import explore as statespace
from mcl2pnml.analysis.statespace.explorers import EXPLORERS
from mcl2pnml.analysis.behaviour import behaviour, final_markings_agree
from mcl2pnml.analysis.statespace.explore import OMEGA, ExplorationLimit, MemoryLimit, explore
from mcl2pnml.analysis.statespace.loops import backends, python as python_loops
from mcl2pnml.analysis.zoo import cycles, kanban
from mcl2pnml.core.net import ArcKind, NetBuilder
from mcl2pnml.core.structure import structure

from strategies import nets
from sampling import sample


#: The safe-net explorers; ``native-python``: the native one on the Python loops.
SAFE_BACKENDS = ("native", "native-python", "packed")

#: The loops' backends (tests/analysis/test_graph_kernels.py and test_onthefly.py run them too).
LOOPS = [pytest.param("c", marks=pytest.mark.skipif(
             backends.c_loops() is None,
             reason="the loops in C were not built (mcl2pnml installed without a C compiler)")),
         "python"]


def use_loops(monkeypatch, loops) -> None:
    """Every explorer built on the loops, and the state spaces they answer for, on ``loops``."""
    for module in (compiledspace, packedmarkings):
        monkeypatch.setattr(module, "c_loops", lambda: loops)
    monkeypatch.setattr(counterspace, "chosen", lambda: loops)


def runnable(name: str) -> str:
    """``name``, or a skip saying why that explorer cannot run on this machine."""
    if name != "auto" and not EXPLORERS[name].can_run():
        pytest.skip(f"the {name} explorer cannot run here: {EXPLORERS[name].doc}; "
                    "mcl2pnml was installed without a C compiler")
    return name


def explorer(request_param: str, monkeypatch) -> str:
    """The explorer a parameter names; with ``-python``, on the Python loops."""
    name, _, loops = request_param.partition("-")
    if loops == "python":
        use_loops(monkeypatch, python_loops)
    return runnable(name)


@pytest.fixture(params=[b for b in statespace.BACKENDS if b != "auto"]
                + ["native-python", "counters-python"])
def backend(request, monkeypatch):
    """Every explorer; those on the loops twice, in C and in Python."""
    return explorer(request.param, monkeypatch)


#: The safe-net explorers as parameters, each skipped with its reason where it cannot run.
SAFE = [pytest.param(b, marks=pytest.mark.skipif(
            b == "native" and backends.c_loops() is None,
            reason="the native explorer cannot run here: the loops in C were not built"))
        for b in SAFE_BACKENDS]

#: The same, but the Python loops, which the drawn nets' tests run on fewer examples
#: (:data:`PYTHON_EXAMPLES`): their pace is the interpreter's.
SAFE_IN_C = [b for b in SAFE if b.values[0] != "native-python"]
PYTHON_EXAMPLES = 20


def test_independent_cycles_have_4_to_the_k_markings(backend):
    for k in (1, 2, 3):
        space = explore(cycles(k), backend=backend)
        assert space.states == 4 ** k and space.safe and not space.terminal
        assert behaviour(space).home_marking and behaviour(space).reusable


def test_a_place_s_tokens_in_every_node_are_its_column_of_the_markings(backend):
    """``tokens(p)``, what a property reads (analysis/checking/on_graph.py), is the p-th count of
    each node's marking, in node order, on every explorer: on a safe net and on nets of
    counters (Kanban's, up to one and up to two tokens a place)."""
    from mcl2pnml.analysis.zoo import kanban
    for net in (cycles(2), kanban(1), kanban(2)):
        space = explore(net, backend=backend)
        markings = list(space.markings)      # decoded once
        for p in range(len(net.places)):
            assert space.tokens(p).tolist() == [m[p] for m in markings], (net.name, p)


def test_a_producer_is_unbounded_and_gets_omega(backend):
    b = NetBuilder("producer")
    b.place("ready", 1)
    b.place("buffer")
    b.transition("produce")
    b.arc("ready", "produce")
    b.arc("produce", "ready")
    b.arc("produce", "buffer")
    space = explore(b.build(), backend=backend)
    assert not space.bounded and space.coverability
    assert any(m[1] == OMEGA for m in space.markings)
    assert ["buffer*w", "ready"] in [space.format(n) for n in range(space.states)]
    assert not behaviour(space).reusable


def test_a_bounded_net_with_two_tokens(backend):
    b = NetBuilder("two")
    b.place("p", 2)
    b.place("q")
    b.transition("t")
    b.arc("p", "t")
    b.arc("t", "q")
    space = explore(b.build(), backend=backend)
    assert space.bounded and not space.safe and space.bound == 2
    assert [space.format(n) for n in space.terminal] == [["q*2"]]


def test_read_arcs_test_without_consuming(backend):
    b = NetBuilder("read")
    b.place("guard", 1)
    b.place("p", 1)
    b.place("q")
    b.transition("t")
    b.read("guard", "t")
    b.arc("p", "t")
    b.arc("t", "q")
    space = explore(b.build(), backend=backend)
    assert [space.format(n) for n in space.terminal] == [["guard", "q"]]


def test_weights(backend):
    b = NetBuilder("weights")
    b.place("p", 3)
    b.place("q")
    b.transition("t")
    b.arc("p", "t", 2)
    b.arc("t", "q", 3)
    space = explore(b.build(), backend=backend)
    assert sorted(space.format(n) for n in range(space.states)) == [["p", "q*3"], ["p*3"]]


def test_deadlock_is_reported_as_improper(backend):
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
    space = explore(b.build(), backend=backend)
    result = behaviour(space)
    assert not result.deadlock_free and result.improper == (("X",),)


def test_limit_and_progress(backend):
    calls = []
    old = generalspace.PROGRESS_EVERY
    generalspace.PROGRESS_EVERY = 10
    try:
        explore(cycles(3), backend=backend, progress=lambda n, f: calls.append(n))
    finally:
        generalspace.PROGRESS_EVERY = old
    assert calls and calls == sorted(calls)
    with pytest.raises(ExplorationLimit, match="more than 10 markings"):
        explore(cycles(3), max_states=10, backend=backend)


def test_graph_and_paths(backend):
    space = explore(cycles(1), backend=backend)
    g = space.graph()
    assert g.number_of_nodes() == 4 and g.number_of_edges() == 4
    assert space.path_to(2) == ["c0t0", "c0t1"]


@pytest.mark.parametrize("backend", SAFE_IN_C)
@settings(max_examples=sample(80, 30), deadline=None)
@given(nets(max_places=5, max_transitions=4))
def test_the_bitset_explorers_agree_with_the_general_one(backend, net):
    with pytest.MonkeyPatch.context() as monkeypatch:
        _the_bitset_explorer_agrees_with_the_general_one(explorer(backend, monkeypatch), net)


@settings(max_examples=PYTHON_EXAMPLES, deadline=None)
@given(nets(max_places=5, max_transitions=4))
def test_the_python_loops_agree_with_the_general_one(net):
    with pytest.MonkeyPatch.context() as monkeypatch:
        _the_bitset_explorer_agrees_with_the_general_one(explorer("native-python", monkeypatch),
                                                         net)


def _the_bitset_explorer_agrees_with_the_general_one(backend, net):
    try:
        fast = explore(net, max_states=2000, backend=backend)
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


@pytest.mark.parametrize("backend", SAFE_IN_C)
@settings(max_examples=sample(120, 40), deadline=None)
@given(spread_safe_nets())
def test_the_bitset_explorers_on_markings_of_several_words(backend, net):
    with pytest.MonkeyPatch.context() as monkeypatch:
        _the_bitset_explorer_on_markings_of_several_words(explorer(backend, monkeypatch), net)


@settings(max_examples=PYTHON_EXAMPLES, deadline=None)
@given(spread_safe_nets())
def test_the_python_loops_on_markings_of_several_words(net):
    with pytest.MonkeyPatch.context() as monkeypatch:
        _the_bitset_explorer_on_markings_of_several_words(
            explorer("native-python", monkeypatch), net)


def _the_bitset_explorer_on_markings_of_several_words(backend, net):
    try:
        fast = explore(net, max_states=5000, backend=backend)
    except ExplorationLimit:
        assume(False)       # a drawn net past the limit compares nothing: another is drawn
    slow = statespace._explore_general(fast.structure, tuple(fast.markings[0]), 5000, None)
    if fast.bounded and max(max(m) for m in slow.markings) <= 1:
        assert type(fast).__name__ == "PackedStateSpace"
    _same_space(fast, slow)


@pytest.mark.parametrize("backend", SAFE)
def test_markings_that_share_a_key_fall_back_to_exact_exploration(backend, monkeypatch):
    """A key collision (once in 2^64 pairs) must never merge two markings.

    A key made of the first word only collides whenever two markings differ
    in the second word alone; the explorer has to notice and answer right.
    """
    backend = explorer(backend, monkeypatch)
    b = NetBuilder("two words")
    for i in range(130):
        b.place(f"p{i}", 1 if i in (0, 100) else 0)
    for t, before, after in (("low", "p0", "p1"), ("high", "p100", "p101")):
        b.transition(t)
        b.arc(before, t)
        b.arc(t, after)
    net = b.build()
    space = explore(net, backend=backend)
    assert type(space).__name__ == "PackedStateSpace" and space.states == 4
    first_word = lambda rows: rows[:, 0].copy() if rows.shape[1] > 1 else rows[:, 0]
    monkeypatch.setattr(packedspace, "_keys", first_word)
    monkeypatch.setattr(compiledspace, "_keys", first_word)
    fooled = explore(net, backend=backend)
    assert fooled.states == 4
    _same_space(fooled, statespace._explore_general(fooled.structure,
                                                    tuple(fooled.markings[0]), 100, None))


def test_markings_that_differ_in_the_top_bits_of_two_words_have_two_keys():
    """Two markings a small mission reaches (4,773 markings, two words), that differ in
    bit 62 of the first word and bits 33, 34, 62 and 63 of the second: a multiply and one
    shift a word gave them one key; the avalanche step gives every such pair two, as it
    does every pair of markings one or two bits apart in each word."""
    from mcl2pnml.analysis.statespace.packedmarkings import keys_of
    pair = np.array([[0x0809120090049292, 0x8000000E02020202],
                     [0x4809120090049292, 0x4000000802020202]], dtype=np.uint64)
    assert keys_of(pair)[0] != keys_of(pair)[1]
    bits = [np.uint64(1) << np.uint64(b) for b in range(64)]
    rows = np.array([[a, b] for a in (np.uint64(0), *bits[::7], bits[62] | bits[63])
                     for b in (np.uint64(0), *bits, bits[33] | bits[34] | bits[62] | bits[63])],
                    dtype=np.uint64)
    assert len(np.unique(rows, axis=0)) == len(rows)
    assert len(np.unique(keys_of(rows))) == len(rows)


@pytest.mark.parametrize("backend", SAFE)
def test_a_second_token_hands_over_to_the_general_explorer(backend, monkeypatch):
    backend = explorer(backend, monkeypatch)
    b = NetBuilder("two tokens later")
    b.place("p", 1)
    b.place("q")
    b.transition("t")
    b.arc("p", "t")
    b.arc("t", "q")
    b.arc("t", "p")   # p stays marked, and q gets a second token at the second firing
    space = explore(b.build(), backend=backend)
    assert type(space) is statespace.StateSpace and not space.bounded


@pytest.mark.parametrize("name", ["native", "native-python"])
def test_the_native_explorer_reports_progress_between_slices(name, monkeypatch):
    backend = explorer(name, monkeypatch)
    monkeypatch.setattr(compiledspace, "SLICE", 4)
    calls = []
    space = explore(cycles(3), backend=backend, progress=lambda n, f: calls.append((n, f)))
    assert space.states == 64 and len(calls) >= 64 // 4 and calls[-1] == (64, 0)
    assert [n for n, _ in calls] == sorted(n for n, _ in calls)


def test_auto_takes_the_native_explorer_where_it_was_built(monkeypatch):
    runnable("native")
    used = []
    monkeypatch.setattr(compiledspace, "explore_native",
                        lambda *a, _real=compiledspace.explore_native: used.append(1) or _real(*a))
    assert explore(cycles(1)).states == 4 and used == [1]


def test_without_its_c_code_the_native_explorer_says_what_it_needs(monkeypatch):
    monkeypatch.setenv(backends.SWITCH, "python")   # as on a machine without a C compiler
    with pytest.raises(statespace.Mcl2PnmlError, match="the native explorer needs its C code, "
                       "built when mcl2pnml is installed on a machine with a C compiler"):
        explore(cycles(1), backend="native")
    # auto goes on without it: numpy for a safe net, the general explorer for the others
    assert type(explore(cycles(2))) is packedspace.PackedStateSpace
    assert type(explore(kanban(2))) is statespace.StateSpace
    # the counter explorer, asked for, runs on the Python loops
    assert type(explore(kanban(1), backend="counters")).__name__ == "CounterStateSpace"


def test_an_unknown_explorer_is_named_with_the_known_ones():
    with pytest.raises(statespace.Mcl2PnmlError, match="unknown explorer 'fast'; known: auto, "
                       "native, packed, counters, general"):
        explore(cycles(1), backend="fast")


# -- bounded nets that are not safe, unbounded ones, and the memory budget -------------------

def test_a_bounded_net_that_is_not_safe(backend):
    """Kanban (Ciardo and Tilgner): 160 and 4,600 markings, bounded by its P-invariants."""
    for n, states in ((1, 160), (2, 4_600)):
        space = explore(kanban(n), backend=backend)
        assert space.states == states and space.bounded and space.bound == n and space.safe == (n == 1)
        assert not space.terminal and space.home_initial and behaviour(space).reusable
        assert space.format(0) == [f"Pkan{i}" + (f"*{n}" if n > 1 else "") for i in range(1, 5)]


def test_counters_grow_past_their_first_width():
    """No invariant bounds the place, so its counter starts narrow and is widened."""
    b = NetBuilder("fill")
    b.place("src", 40)
    b.place("sink")
    b.transition("t")
    b.arc("src", "t")
    b.arc("t", "sink", 3)
    b.transition("drain")
    b.arc("sink", "drain", 120)
    space = explore(b.build(), backend="counters")
    assert type(space).__name__ == "CounterStateSpace"
    assert space.states == 42 and space.bound == 120
    assert sorted(space.format(n) for n in space.terminal) == [[]]


@settings(max_examples=sample(150, 50), deadline=None)
@given(nets(max_places=5, max_transitions=4))
def test_the_counter_explorer_agrees_with_the_general_one(net):
    try:
        fast = explore(net, max_states=3000, backend="counters")
        slow = statespace._explore_general(fast.structure, tuple(fast.markings[0]), 3000, None)
    except ExplorationLimit:
        return
    assert fast.bounded == slow.bounded
    if fast.bounded:
        _same_space(fast, slow)
    else:
        assert list(fast.markings) == list(slow.markings)


def _karp_miller_walking_every_ancestor(s, m0, max_states):
    """The coverability graph as it was built before the incremental filter, for comparison."""
    need = [sorted({**dict(read), **{p: max(w, read.get(p, 0)) for p, w in pre.items()}}.items())
            for pre, read in zip(s.pre, s.read)]
    delta = [sorted(c.items()) for c in s.incidence]
    markings, parent, index, edges = [tuple(m0)], [-1], {tuple(m0): 0}, []
    head = 0
    while head < len(markings):
        m = markings[head]
        for t in range(len(need)):
            if all(m[p] >= w for p, w in need[t]):
                m2 = list(m)
                for p, d in delta[t]:
                    m2[p] += d
                m2 = tuple(m2)
                if m2 not in index:
                    m2, _ = generalspace._accelerate(m2, head, markings, parent)
                if m2 not in index:
                    if len(markings) >= max_states:
                        raise ExplorationLimit("limit")
                    index[m2] = len(markings)
                    markings.append(m2)
                    parent.append(head)
                edges.append((head, t, index[m2]))
        head += 1
    return markings, edges


@settings(max_examples=sample(200, 60), deadline=None)
@given(nets(max_places=5, max_transitions=4))
def test_incremental_karp_miller_builds_the_graph_of_the_full_walk(net):
    s = structure(net)
    try:
        old = _karp_miller_walking_every_ancestor(s, s.initial_vector(), 2000)
    except ExplorationLimit:
        return
    new = statespace._explore_general(s, s.initial_vector(), 2000, None)
    assert list(new.markings) == old[0]
    assert list(zip(new.src, new.trans, new.dst)) == old[1]


def test_incremental_karp_miller_on_unbounded_nets_with_invariants():
    """A covered cycle beside a growing place: omega appears where the full walk puts it."""
    b = NetBuilder("pump")
    b.place("a", 1)
    b.place("b")
    b.place("pool")
    b.transition("go")
    b.arc("a", "go")
    b.arc("go", "b")
    b.transition("back")
    b.arc("b", "back")
    b.arc("back", "a")
    b.arc("back", "pool", 2)
    s = structure(b.build())
    old = _karp_miller_walking_every_ancestor(s, s.initial_vector(), 100)
    new = explore(b.build(), backend="general")
    assert list(new.markings) == old[0] and new.coverability
    assert ["a", "pool*w"] in [new.format(n) for n in range(new.states)]


def test_a_memory_budget_stops_every_explorer_with_what_it_found(backend):
    with pytest.raises(MemoryLimit, match="memory budget of 1.0 KB") as stopped:
        explore(cycles(4), backend=backend, max_memory=1024)
    assert 0 < stopped.value.explored < 256
    with pytest.raises(MemoryLimit) as stopped:
        explore(kanban(2), backend=backend, max_memory=20_000)
    assert 0 < stopped.value.explored < 4_600
    assert stopped.value.deadlocks in (0, None)   # Kanban has no dead marking
    assert explore(kanban(2), backend=backend, max_memory=1 << 30).states == 4_600


def test_dead_markings_met_before_the_budget_are_counted(backend):
    b = NetBuilder("halt or count")
    for p, n in (("start", 1), ("halted", 0), ("run", 0), ("p", 30), ("q", 0)):
        b.place(p, n)
    for t, before, after in (("halt", "start", "halted"), ("go", "start", "run"),
                             ("count", "p", "q")):
        b.transition(t)
        b.arc(before, t)
        b.arc(t, after)
    b.read("run", "count")
    with pytest.raises(ExplorationLimit) as stopped:
        explore(b.build(), backend=backend, max_states=20)
    assert stopped.value.explored == 20 and stopped.value.deadlocks in (1, None)
    if backend in ("general", "counters"):
        assert stopped.value.deadlocks == 1


@pytest.mark.parametrize("loops", LOOPS[:1])
@settings(max_examples=sample(80, 30), deadline=None)
@given(st.one_of(spread_safe_nets(), nets(max_places=6, max_transitions=5)),
       st.data())
def test_the_loops_and_numpy_answer_alike_for_a_packed_state_space(loops, net, data):
    """Terminal markings, backward reachability and edges: the loops in C and numpy alike."""
    _answer_alike(backends.named(loops), net, data)


@settings(max_examples=PYTHON_EXAMPLES, deadline=None)
@given(st.one_of(spread_safe_nets(), nets(max_places=6, max_transitions=5)),
       st.data())
def test_the_python_loops_and_numpy_answer_alike_for_a_packed_state_space(net, data):
    """The same, the loops in Python and numpy."""
    _answer_alike(python_loops, net, data)


def _answer_alike(kernels, net, data):
    space = explore(net, max_states=5000, backend="packed")
    if type(space).__name__ != "PackedStateSpace":
        return   # not safe: another explorer's space
    goal = data.draw(st.lists(st.integers(0, space.states - 1), max_size=3))
    numpy_reach = space._can_reach_numpy(goal)
    space._kernels = lambda: kernels
    space.__dict__.pop("out_degree", None)
    space.__dict__.pop("terminal", None)
    dead = space.terminal   # the kernels' first-enabled test, before any degree is counted
    assert space.can_reach(goal) == numpy_reach
    assert space.always_can_reach(goal) == all(numpy_reach)
    loops_degree = list(space.out_degree)
    loops_edges = [a.tolist() for a in space._edges]
    # numpy's own firing
    space._kernels = lambda: None
    space.__dict__.pop("_edges", None)
    assert loops_edges == [a.tolist() for a in space._edges]
    numpy_degree = np.bincount(space.src, minlength=space.states).tolist()
    assert loops_degree == numpy_degree
    assert dead == [n for n, d in enumerate(numpy_degree) if d == 0]


@pytest.mark.parametrize("loops", LOOPS)
def test_the_empty_marking_is_reached_backwards_too(loops):
    """A table of markings by value has no slot for the empty one: it is kept apart."""
    b = NetBuilder("drain")
    b.place("a", 1)
    b.place("b")
    b.transition("t")
    b.transition("u")
    b.arc("a", "t")
    b.arc("t", "b")
    b.arc("b", "u")   # u empties the net
    space = explore(b.build(), backend="packed")
    kernels = backends.named(loops)
    space._kernels = lambda: kernels
    empty = next(n for n in range(space.states) if not space.marking(n))
    assert space.states == 3 and space.terminal == [empty]
    assert space.can_reach([empty]) == [True, True, True]
    assert space.can_reach([0]) == [n == 0 for n in range(3)]
