"""mcl2pnml.analysis.checking.on_graph.check against a reference that does not use its observers.

The reference enumerates runs of a small net directly (finite maximal paths
and lassos up to a length) and evaluates each pattern in each scope
literally from Dwyer, Avrunin and Corbett's definitions on the marking
sequence: every Q position opens an interval up to the next R, a response's
S is searched after its P, and so on.
"""
from __future__ import annotations

import itertools

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.analysis.checking.on_graph import Shape, Status, check_property
from mcl2pnml.analysis.checking.observers import ObserverTable
from mcl2pnml.core.net import NetBuilder
from mcl2pnml.core.patterns import Const, Not, Pattern, Property, Scope, ScopeKind, Tokens, holds
from sampling import sample

KINDS = list(ScopeKind)
PATTERNS = list(Pattern)


# -- the reference -------------------------------------------------------------------------

def _intervals(word, kind, starts):
    """(start, end, closed) of every scope interval starting before ``starts``."""
    n = len(word)
    if kind is ScopeKind.GLOBALLY:
        return [(0, n)]
    if kind is ScopeKind.BEFORE:
        k = next((i for i, w in enumerate(word) if w[3]), None)
        return [] if k is None else [(0, k)]   # Dwyer et al.: <>R -> ...
    if kind is ScopeKind.AFTER:
        k = next((i for i, w in enumerate(word) if w[2]), None)
        return [] if k is None else [(k, n)]
    out = []
    for i in range(min(starts, n)):
        if word[i][2] and not word[i][3]:
            j = next((k for k in range(i + 1, n) if word[k][3]), None)
            if j is not None:
                out.append((i, j))
            elif kind is ScopeKind.AFTER_UNTIL:
                out.append((i, n))
    return out


def violates(prop, word, period=0):
    """Whether the marking run ``word`` (tuples p, s, q, r) violates ``prop``.

    ``period`` > 0: the run is infinite, ``word`` its lasso unrolled so that the
    last ``period``-long stretches repeat forever (at least bound + 3 times).
    """
    n = len(word)
    starts = n - 2 * period if period else n
    lookahead = n - period if period else n   # positions whose future the word shows
    for i, j in _intervals(word, prop.scope.kind, starts):
        seg = word[i:j]
        ps = [w[0] for w in seg]
        pat = prop.pattern
        if pat is Pattern.ABSENCE and any(ps):
            return True
        if pat is Pattern.UNIVERSALITY and not all(ps):
            return True
        if pat is Pattern.EXISTENCE and not any(ps):
            return True
        if pat is Pattern.BOUNDED_EXISTENCE:
            rises = sum(1 for k, x in enumerate(ps) if x and (k == 0 or not ps[k - 1]))
            if rises > prop.bound:
                return True
        if pat is Pattern.PRECEDENCE:
            first = next((k for k, x in enumerate(ps) if x), None)
            if first is not None and not any(w[1] for w in seg[:first + 1]):
                return True
        if pat is Pattern.RESPONSE:
            for k, x in enumerate(ps):
                if x and i + k < lookahead and not any(w[1] for w in seg[k:]):
                    return True
    return False


def _graph(net):
    """Reachability graph by the firing rule itself: markings, edges (dst, transition id)."""
    ids = [p.id for p in net.places]
    pre = {t.id: {} for t in net.transitions}
    post = {t.id: {} for t in net.transitions}
    for a in net.arcs:
        if a.source in pre:
            post[a.source][a.target] = post[a.source].get(a.target, 0) + a.weight
        else:
            pre[a.target][a.source] = pre[a.target].get(a.source, 0) + a.weight
    m0 = tuple(net.initial.get(p, 0) for p in ids)
    index, marks, edges, todo = {m0: 0}, [m0], [[]], [m0]
    while todo:
        m = todo.pop()
        for t in pre:
            d = dict(zip(ids, m))
            if all(d[p] >= w for p, w in pre[t].items()):
                for p, w in pre[t].items():
                    d[p] -= w
                for p, w in post[t].items():
                    d[p] += w
                m2 = tuple(d[p] for p in ids)
                if m2 not in index:
                    index[m2] = len(marks)
                    marks.append(m2)
                    edges.append([])
                    todo.append(m2)
                edges[index[m]].append((index[m2], t))
    return [dict(zip(ids, m)) for m in marks], edges


def _letters(prop, marking):
    f = Const(False)
    return tuple(holds(x, marking) for x in (prop.p, prop.s or f, prop.scope.q or f,
                                              prop.scope.r or f))


def runs(edges, length, prefix=(0,)):
    """(states, transitions, loop) of every finite maximal run and every lasso that
    extends the path ``prefix`` by at most ``length`` steps."""
    stack = [(list(prefix), [None] * (len(prefix) - 1))]
    while stack:
        states, trans = stack.pop()
        if not edges[states[-1]]:
            yield states, trans, None
        for i in range(len(states) - 1):
            if states[i] == states[-1]:
                yield states, trans, i
        if len(trans) < length + len(prefix) - 1:
            for b, t in edges[states[-1]]:
                stack.append((states + [b], trans + [t]))


def reference_violates(prop, marks, states, loop):
    word = [_letters(prop, marks[m]) for m in states]
    if loop is None:
        return violates(prop, word)
    cycle = word[loop + 1:]
    times = (prop.bound or 0) + 4
    return violates(prop, word[:loop + 1] + cycle * times, period=len(cycle))


def assert_agrees(net, prop, length=9):
    marks, edges = _graph(net)
    verdict = check_property(net, prop)
    bad = [(s, t, l) for s, t, l in runs(edges, length) if reference_violates(prop, marks, s, l)]
    if verdict.status is Status.HOLDS:
        assert not bad, (prop, bad[0])
        return verdict
    assert verdict.status is Status.FAILS
    # the counterexample is a firing sequence from M0 ...
    index = {tuple(sorted((p, n) for p, n in m.items() if n)): k for k, m in enumerate(marks)}
    states = [index[tuple(sorted(m))] for m in verdict.markings]
    assert states[0] == 0 and len(states) == len(verdict.transitions) + 1
    for a, b, t in zip(states, states[1:], verdict.transitions):
        assert (b, t) in edges[a]
    # ... and violates the property by the reference
    if verdict.shape is Shape.FINITE:
        assert not edges[states[-1]]
        assert reference_violates(prop, marks, states, None)
    elif verdict.shape is Shape.LASSO:
        assert states[verdict.loop] == states[-1]
        assert reference_violates(prop, marks, states, verdict.loop)
    else:   # a prefix: every run extending it violates
        exts = [(s, l) for s, _, l in runs(edges, length, prefix=states)]
        assert exts
        for s, l in exts:
            assert reference_violates(prop, marks, s, l), (prop, s, l)
    # shortest: no violating finite run is shorter. A lasso u v^w is seen by the observer
    # (deterministic, of N states) within N turns of v, so the product holds it as a
    # lasso of at most |u| + N |v| steps, which bounds the one returned: no tighter, as the
    # loop the observer needs may be several turns of the net's (after Q, Q on the loop)
    turns = len(_observer_states(prop))
    lengths = [len(t) if l is None else l + turns * (len(t) - l) for _, t, l in bad]
    if lengths:
        assert len(verdict.transitions) <= min(lengths), (prop, verdict, min(lengths))
    return verdict


def _observer_states(prop) -> set[int]:
    """The observer states of ``prop`` reachable from its start, whatever is read."""
    table = ObserverTable(prop)
    seen, todo = {table.start}, [table.start]
    while todo:
        k = todo.pop()
        for code in range(16):
            nxt = table.after(k, code)
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return seen


# -- random nets ---------------------------------------------------------------------------

PLACES = ["a", "b", "c", "d"]


@st.composite
def small_nets(draw):
    """One or two tokens moving in a state machine: bounded, tiny, cycles and dead ends."""
    b = NetBuilder("n")
    tokens = draw(st.lists(st.sampled_from(PLACES), min_size=1, max_size=2))
    for p in PLACES:
        b.place(p, tokens.count(p))
    for k in range(draw(st.integers(1, 5))):
        t = f"t{k}"
        b.transition(t)
        b.arc(draw(st.sampled_from(PLACES)), t)
        out = draw(st.none() | st.sampled_from(PLACES))
        if out is not None:
            b.arc(t, out)
    return b.build()


atoms = st.sampled_from(PLACES).map(lambda p: Tokens((p,), 1))
preds = atoms | atoms.map(Not) | st.sampled_from([Const(True), Const(False)])


@st.composite
def props(draw):
    kind = draw(st.sampled_from(KINDS))
    pattern = draw(st.sampled_from(PATTERNS))
    return Property("x", pattern, draw(preds),
                    s=draw(preds) if pattern in (Pattern.PRECEDENCE, Pattern.RESPONSE) else None,
                    bound=draw(st.integers(0, 2)) if pattern is Pattern.BOUNDED_EXISTENCE else None,
                    scope=Scope(kind, q=draw(preds) if kind in (ScopeKind.AFTER, ScopeKind.BETWEEN,
                                                               ScopeKind.AFTER_UNTIL) else None,
                                r=draw(preds) if kind in (ScopeKind.BEFORE, ScopeKind.BETWEEN,
                                                          ScopeKind.AFTER_UNTIL) else None))


@settings(max_examples=sample(150, 50), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_nets(), props())
def test_check_agrees_with_the_reference(net, prop):
    assert_agrees(net, prop, length=7)


@pytest.mark.slow
@settings(max_examples=3000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_nets(), props())
def test_check_agrees_with_the_reference_long(net, prop):
    assert_agrees(net, prop, length=9)


# -- hand-made nets: every pattern in every scope, holding and failing ------------------------

def chain(*steps, loop_to=None):
    """A token through places m0, m1, ... by t0, t1, ...; ``loop_to``: the last goes back there."""
    b = NetBuilder("chain")
    n = len(steps)
    for k in range(n + 1):
        b.place(f"m{k}", 1 if k == 0 else 0)
    for k in range(n):
        b.transition(f"t{k}")
        b.arc(f"m{k}", f"t{k}")
        b.arc(f"t{k}", f"m{k + 1}" if not (loop_to is not None and k == n - 1) else f"m{loop_to}")
    return b.build()


def at(*ks):
    """True in the markings m_k of a chain."""
    return Tokens(tuple(f"m{k}" for k in ks), 1)


def test_every_pattern_in_every_scope_holds_and_fails():
    # markings m0 .. m5 in a line, a dead end at m5; the scope opens at m1 (Q) and closes at m4 (R)
    net = chain(*range(5))
    q, r = at(1), at(4)
    scopes = {ScopeKind.GLOBALLY: Scope(), ScopeKind.BEFORE: Scope(ScopeKind.BEFORE, r=r),
              ScopeKind.AFTER: Scope(ScopeKind.AFTER, q=q),
              ScopeKind.BETWEEN: Scope(ScopeKind.BETWEEN, q=q, r=r),
              ScopeKind.AFTER_UNTIL: Scope(ScopeKind.AFTER_UNTIL, q=q, r=r)}
    inside = {ScopeKind.GLOBALLY: at(0), ScopeKind.BEFORE: at(2), ScopeKind.AFTER: at(5),
              ScopeKind.BETWEEN: at(2), ScopeKind.AFTER_UNTIL: at(3)}
    outside = {ScopeKind.GLOBALLY: Const(False), ScopeKind.BEFORE: at(5),
               ScopeKind.AFTER: at(0), ScopeKind.BETWEEN: at(5), ScopeKind.AFTER_UNTIL: at(4)}
    for kind, scope in scopes.items():
        cases = {
            Pattern.ABSENCE: (outside[kind], inside[kind]),
            Pattern.UNIVERSALITY: (Not(outside[kind]), Not(inside[kind])),
            Pattern.EXISTENCE: (inside[kind], outside[kind]),
            Pattern.BOUNDED_EXISTENCE: (inside[kind], inside[kind]),
            Pattern.PRECEDENCE: (inside[kind], inside[kind]),
            Pattern.RESPONSE: (inside[kind], inside[kind]),
        }
        for pattern, (good, bad) in cases.items():
            if pattern is Pattern.BOUNDED_EXISTENCE:
                ok = Property("ok", pattern, good, bound=1, scope=scope)
                ko = Property("ko", pattern, good, bound=0, scope=scope)
            elif pattern is Pattern.PRECEDENCE:
                ok = Property("ok", pattern, good, s=good, scope=scope)
                ko = Property("ko", pattern, good, s=Const(False), scope=scope)
            elif pattern is Pattern.RESPONSE:
                ok = Property("ok", pattern, good, s=good, scope=scope)
                ko = Property("ko", pattern, good, s=Const(False), scope=scope)
            else:
                ok = Property("ok", pattern, good, scope=scope)
                ko = Property("ko", pattern, bad, scope=scope)
            assert assert_agrees(net, ok).status is Status.HOLDS, (kind, pattern)
            assert assert_agrees(net, ko).status is Status.FAILS, (kind, pattern)


def test_a_liveness_failure_is_a_lasso():
    # m0 -> m1 -> m2 -> m1 ...: m3 is never reached
    net = chain(0, 1, 2, loop_to=1)
    v = check_property(net, Property("e", Pattern.EXISTENCE, at(3)))
    assert v.status is Status.FAILS and v.shape is Shape.LASSO
    assert v.transitions == ("t0", "t1", "t2") and v.loop == 1
    assert_agrees(net, Property("e", Pattern.EXISTENCE, at(3)))
    resp = Property("r", Pattern.RESPONSE, at(1), s=at(0))
    v = assert_agrees(net, resp)
    assert v.status is Status.FAILS and v.shape is Shape.LASSO


def test_a_safety_failure_is_the_shortest_prefix():
    # two ways to m3: a long one and a short one
    b = NetBuilder("n")
    for p in ("m0", "m1", "m2", "m3"):
        b.place(p, 1 if p == "m0" else 0)
    for t, (x, y) in {"long1": ("m0", "m1"), "long2": ("m1", "m2"), "long3": ("m2", "m3"),
                      "short": ("m0", "m3"), "back": ("m3", "m0")}.items():
        b.transition(t)
        b.arc(x, t)
        b.arc(t, y)
    v = check_property(b.build(), Property("a", Pattern.ABSENCE, at(3)))
    assert v.status is Status.FAILS and v.shape is Shape.PREFIX and v.transitions == ("short",)


def test_the_state_limit_gives_unknown():
    net = chain(*range(6))
    v = check_property(net, Property("a", Pattern.ABSENCE, Const(False)), max_states=3)
    assert v.status is Status.UNKNOWN and v.states


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("pattern", PATTERNS)
def test_every_combination_on_a_cycle_with_a_dead_end(kind, pattern):
    # m0 -> m1 -> m2 -> m0, and m1 -> m3 dead: both finite and infinite runs
    b = NetBuilder("n")
    for p in ("m0", "m1", "m2", "m3"):
        b.place(p, 1 if p == "m0" else 0)
    for t, (x, y) in {"a": ("m0", "m1"), "b": ("m1", "m2"), "c": ("m2", "m0"),
                      "d": ("m1", "m3")}.items():
        b.transition(t)
        b.arc(x, t)
        b.arc(t, y)
    net = b.build()
    for p, s, q, r in itertools.product([at(1), at(3), Not(at(2))], [at(0), at(3)],
                                        [at(1), at(2)], [at(0), at(3)]):
        prop = Property("x", pattern, p, s=s, bound=1, scope=Scope(kind, q=q, r=r))
        assert_agrees(net, prop)


# -- the command line ---------------------------------------------------------------------------

def test_analyze_properties_of_the_papers_mission(tmp_path):
    import json
    from pathlib import Path

    from helpers import run_cli

    sauce = Path(__file__).parents[2] / "examples" / "sauce.mcl"
    true = sauce.with_name("sauce.props")
    # on the untimed net (--untimed) "Ends" fails: a goal lost and regained for ever
    out = run_cli("analyze", str(sauce), "--untimed", "--state-space", "--properties", str(true))
    assert out.returncode == 1, out.stderr
    lines = out.stdout.splitlines()
    ends = next(k for k, l in enumerate(lines) if l.startswith("property Ends ("))
    assert "sauce.props:" in lines[ends] and lines[ends].endswith(": fails")
    assert lines[ends + 1] == "  counterexample (lasso):" and lines[ends + 2].strip().startswith("1. ")
    js = json.loads(run_cli("analyze", str(sauce), "--untimed", "--state-space", "--properties",
                            str(true), "--json").stdout)
    verdicts = {v["name"]: v for v in js["properties"]}
    assert verdicts["Ends"]["status"] == "fails"
    assert verdicts["Ends"]["counterexample"]["shape"] == "lasso"
    # in time (the default) and without FILE, sauce.props beside the mission: every one
    # holds, "Ends" too, exit 0
    out = run_cli("analyze", str(sauce), "--state-space", "--properties")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert any(l.startswith("property MarkerOnlyOverCross (") and l.endswith(": holds")
               for l in lines)
    assert any(l.startswith("property Ends (") and l.endswith(": holds") for l in lines)
    assert lines[0].startswith("timed (docs/time.md): acknowledgements at once")
    # only holding ones: exit 0 (analyze's own state limit is exit 2, as without properties)
    holding = tmp_path / "ok.props"
    holding.write_text("property Never: never outcome(OK) and outcome(FAIL);\n")
    assert run_cli("analyze", str(sauce), "--state-space", "--properties",
                   str(holding)).returncode == 0
    assert run_cli("analyze", str(sauce), "--properties", str(tmp_path / "no")).returncode == 2


def test_before_a_scope_never_closed_holds_by_default():
    # Dwyer et al.'s "<>R -> ...": a run where R never holds has nothing before R to speak of
    net = chain(*range(5))
    never_closed = Scope(ScopeKind.BEFORE, r=at(7))
    for pattern in PATTERNS:
        prop = Property("b", pattern, at(2), s=Const(False), bound=0, scope=never_closed)
        assert assert_agrees(net, prop).status is Status.HOLDS, pattern
    closed = Scope(ScopeKind.BEFORE, r=at(4))
    v = assert_agrees(net, Property("b", Pattern.ABSENCE, at(2), scope=closed))
    assert v.status is Status.FAILS and v.transitions == ("t0", "t1", "t2", "t3")
