"""The on-the-fly checker (mcl2pnml.analysis.checking.on_the_fly) against the reference method.

Both read the same observers; the on-the-fly one searches the product in C
(and, on small nets, in the loops' plain-Python reference: the ``loops``
parameter) and stops at the first violation. Their verdicts must be the same, their
counterexamples as short (a shortest one of all: prefix, dead end or lasso),
and each counterexample must show the violation when judged on its own
(``judge`` fires it on the net). The peers' verdicts are compared in
``test_properties_peers.py``, which runs the default (on-the-fly) checker.
"""
from __future__ import annotations

import contextlib

import pytest
from hypothesis import HealthCheck, assume, given, settings, strategies as st

from mcl2pnml.analysis.checking import on_the_fly as onthefly
from mcl2pnml.analysis.checking.on_graph import Status, check_properties, judge
from mcl2pnml.analysis.statespace.loops import backends
from helpers import ROOT
from mcl2pnml import pipeline
from mcl2pnml.core.bounds import MAX_CHECK_STATES
from mcl2pnml.core.net import NetBuilder
from mcl2pnml.core.patterns import Const, Not, Pattern, Property, Scope, ScopeKind, Tokens
from mcl2pnml.core.structure import structure
from test_properties_check import props, small_nets
from sampling import sample

C_BUILT = onthefly.available()
NOT_BUILT = "the loops in C were not built (no C compiler at install)"

#: The loops' backends, the C one skipped where it was not built.
LOOPS = [pytest.param("c", marks=pytest.mark.skipif(not C_BUILT, reason=NOT_BUILT)), "python"]


@contextlib.contextmanager
def searching_with(loops: str):
    """The on-the-fly checker on the loops named (``c`` or ``python``) meanwhile."""
    with pytest.MonkeyPatch.context() as monkeypatch:
        monkeypatch.setattr(onthefly, "c_loops", lambda: backends.named(loops))
        yield


#: For the tests in C alone (the examples' missions: too large for the Python loops).
in_c = pytest.mark.skipif(not C_BUILT, reason=NOT_BUILT)


#: The reference method's verdicts by (net, properties, bound), worked out once per process:
#: the examples' property files are compared with it by the on-the-fly test and by the
#: reduced one, the same reference twice (several seconds on the larger missions). Nets,
#: properties and verdicts are immutable.
_FULL: dict = {}


def full_verdicts(net, properties, max_states=MAX_CHECK_STATES):
    """``check_properties(..., method="full")``, the reference, once per input."""
    key = (net, tuple(properties), max_states)
    if key not in _FULL:
        _FULL[key] = check_properties(net, properties, max_states, method="full")
    return _FULL[key]


def assert_same(net, properties, max_states=1_000_000):
    fly = check_properties(net, properties, max_states, method="on-the-fly")
    full = full_verdicts(net, properties, max_states)
    for a, b in zip(fly, full):
        assert a.status is b.status, (a, b)
        assert len(a.transitions) == len(b.transitions), (a, b)
        if a.status is Status.HOLDS:
            assert a.states == b.states     # the same product, explored whole
        if a.status is Status.FAILS:
            shown = judge(net, a.property, a.transitions, loop=a.loop)
            assert shown is not None and shown.shape is a.shape, (a, shown)
            assert a.states <= b.states
    return fly, full


def _safe(net) -> bool:
    return onthefly.check_properties_on_the_fly(net, []) is not None


@pytest.mark.parametrize("loops", LOOPS)
@settings(max_examples=sample(100, 35), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_nets(), props())
def test_on_the_fly_agrees_with_the_full_exploration(loops, net, prop):
    with searching_with(loops):
        _agrees_with_the_full_exploration(net, prop)


def _agrees_with_the_full_exploration(net, prop):
    assume(_safe(net))
    try:
        assert_same(net, [prop])
    except ValueError as e:     # a second token in a place, met during the search
        assume("not for the on-the-fly checker" not in str(e))
        raise


@pytest.mark.slow
@settings(max_examples=3000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_nets(), props())
def test_on_the_fly_agrees_with_the_full_exploration_long(net, prop):
    _agrees_with_the_full_exploration(net, prop)


#: Every example's property files; the dam inspection's holding ones behind ``slow`` (the
#: reference method takes about 9 s on them, the on-the-fly one 0.6 s).
PROPERTY_FILES = [pytest.param(p.name, marks=pytest.mark.slow)
                  if p.name == "dam_inspection.props" else p.name
                  for p in sorted((ROOT / "examples").glob("*.props"))]


@in_c
@pytest.mark.parametrize("file", PROPERTY_FILES)
def test_every_example_property_file_gets_the_same_verdicts(file):
    mission = ROOT / "examples" / (file.split(".")[0] + ".mcl")
    net, properties = pipeline.properties_of(mission, extra=ROOT / "examples" / file)
    fly, full = assert_same(net, properties)
    if file == "dam_inspection.false.props":
        # a large state space, a property failing early in it: the search stops there
        assert fly[0].status is Status.FAILS
        assert fly[0].states * 100 < full[0].states, (fly[0].states, full[0].states)


@pytest.mark.parametrize("loops", LOOPS)
def test_a_net_that_is_not_safe_goes_to_the_reference(loops):
    with searching_with(loops):
        _not_safe_goes_to_the_reference()


def _not_safe_goes_to_the_reference():
    b = NetBuilder("two")
    b.place("a", 2)
    b.place("b")
    b.transition("t")
    b.arc("a", "t")
    b.arc("t", "b")
    net = b.build()
    prop = Property("p", Pattern.ABSENCE, Tokens(("b",), 2))
    assert onthefly.check_properties_on_the_fly(net, [prop]) is None
    assert check_properties(net, [prop])[0].status is Status.FAILS     # auto: the reference
    with pytest.raises(ValueError, match="not for the on-the-fly checker"):
        check_properties(net, [prop], method="on-the-fly")


@pytest.mark.parametrize("loops", LOOPS)
def test_past_the_limit_the_verdict_is_unknown(loops):
    b = NetBuilder("chain")
    for k in range(6):
        b.place(f"m{k}", 1 if k == 0 else 0)
    for k in range(5):
        b.transition(f"t{k}")
        b.arc(f"m{k}", f"t{k}")
        b.arc(f"t{k}", f"m{k + 1}")
    with searching_with(loops):
        v = check_properties(b.build(), [Property("a", Pattern.ABSENCE, Const(False))],
                             max_states=3, method="on-the-fly")[0]
    assert v.status is Status.UNKNOWN and "product states" in v.reason


def test_a_method_is_one_of_three():
    with pytest.raises(ValueError, match="one of auto, full, on-the-fly"):
        check_properties(NetBuilder("n").build(), [], method="fast")


@in_c
def test_past_the_memory_budget_the_verdict_is_unknown_and_says_so():
    mission = ROOT / "examples" / "lawnmower.mcl"
    net, properties = pipeline.properties_of(mission, extra=ROOT / "examples" / "lawnmower.props")
    holds = [v for v in check_properties(net, properties) if v.status is Status.HOLDS]
    assert holds
    v = onthefly.check_properties_on_the_fly(net, [holds[0].property], max_memory=64 * 1024)[0]
    assert v.status is Status.UNKNOWN and "memory budget" in v.reason, v


# -- partial-order reduction -------------------------------------------------------------

@st.composite
def two_machines(draw):
    """Two state machines of one token each, steps of one (perhaps testing a place of the
    other: a read arc), of the other, or of both at once, and a third machine on its own:
    1-safe (a P-invariant per machine proves it), with concurrency to reduce."""
    b = NetBuilder("two")
    for m in "abc":
        for k in range(3):
            b.place(f"{m}{k}", 1 if k == 0 else 0)
    # a third machine the properties never read: its steps invisible, the most to reduce
    for k in range(draw(st.integers(0, 3))):
        b.transition(f"u{k}")
        b.arc(f"c{draw(st.integers(0, 2))}", f"u{k}")
        b.arc(f"u{k}", f"c{draw(st.integers(0, 2))}")
    for k in range(draw(st.integers(2, 7))):
        t = f"t{k}"
        b.transition(t)
        moves = draw(st.sampled_from(["a", "b", "ab"]))
        for m in moves:
            b.arc(f"{m}{draw(st.integers(0, 2))}", t)
            b.arc(t, f"{m}{draw(st.integers(0, 2))}")
        if len(moves) == 1 and draw(st.booleans()):     # a test of the other machine
            b.read(f"{'b' if moves == 'a' else 'a'}{draw(st.integers(0, 2))}", t)
    return b.build()


SAFE_PLACES = [f"{m}{k}" for m in "ab" for k in range(3)]
safe_atoms = st.sampled_from(SAFE_PLACES).map(lambda p: Tokens((p,), 1))
safe_preds = safe_atoms | safe_atoms.map(Not) | st.sampled_from([Const(True), Const(False)])


@st.composite
def safe_props(draw):
    kind = draw(st.sampled_from(list(ScopeKind)))
    pattern = draw(st.sampled_from(list(Pattern)))
    two = pattern in (Pattern.PRECEDENCE, Pattern.RESPONSE)
    return Property("x", pattern, draw(safe_preds), s=draw(safe_preds) if two else None,
                    bound=draw(st.integers(0, 2)) if pattern is Pattern.BOUNDED_EXISTENCE
                    else None,
                    scope=Scope(kind, q=draw(safe_preds) if kind in (
                        ScopeKind.AFTER, ScopeKind.BETWEEN, ScopeKind.AFTER_UNTIL) else None,
                        r=draw(safe_preds) if kind in (ScopeKind.BEFORE, ScopeKind.BETWEEN,
                                                       ScopeKind.AFTER_UNTIL) else None))


def assert_reduced_same(net, properties, safe=False):
    reduced = check_properties(net, properties, stubborn=True, safe=safe)
    full = full_verdicts(net, properties)
    for a, b in zip(reduced, full):
        assert a.status is b.status, (a, b)
        if a.status is Status.FAILS:     # a real run that shows it, if not a shortest one
            shown = judge(net, a.property, a.transitions, loop=a.loop)
            assert shown is not None and shown.shape is a.shape, (a, shown)
        assert a.states <= b.states, (a.states, b.states)
    return reduced, full


@pytest.mark.parametrize("loops", LOOPS)
@settings(max_examples=sample(80, 30), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(two_machines(), safe_props())
def test_the_reduction_keeps_every_verdict(loops, net, prop):
    assert onthefly.proven_safe(structure(net))
    with searching_with(loops):
        assert_reduced_same(net, [prop])


@pytest.mark.slow
@settings(max_examples=3000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(two_machines(), safe_props())
def test_the_reduction_keeps_every_verdict_long(net, prop):
    assert_reduced_same(net, [prop])


@in_c
@pytest.mark.parametrize("file", [pytest.param(p.name, marks=pytest.mark.slow)
                                  if p.name.startswith("dam_inspection") else p.name
                                  for p in sorted((ROOT / "examples").glob("*.props"))])
def test_the_reduction_keeps_the_examples_verdicts(file):
    """The missions are proven 1-safe by their certificates (the facade's proof)."""
    name = file.split(".")[0]
    cert, net, problems = pipeline.certify_file(ROOT / "examples" / f"{name}.mcl")
    assert problems == []
    _, properties = pipeline.properties_of(ROOT / "examples" / f"{name}.mcl",
                                           extra=ROOT / "examples" / file)
    assert_reduced_same(net, properties, safe=True)


def chains(n: int, length: int):
    """``n`` independent chains of ``length`` steps, each with its token at its start."""
    b = NetBuilder("chains")
    for c in range(n):
        for k in range(length + 1):
            b.place(f"c{c}.{k}", 1 if k == 0 else 0)
        for k in range(length):
            b.transition(f"c{c}.t{k}")
            b.arc(f"c{c}.{k}", f"c{c}.t{k}")
            b.arc(f"c{c}.t{k}", f"c{c}.{k + 1}")
    return b.build()


@pytest.mark.parametrize("loops", LOOPS)
@pytest.mark.parametrize("pattern", [Pattern.ABSENCE, Pattern.EXISTENCE, Pattern.RESPONSE])
def test_the_reduction_explores_one_order_of_independent_steps(pattern, loops):
    """Six chains of three steps (four in C): 4**6 markings; a property of one chain's
    end sees one order of the others' steps, with the same verdict (absence fails, the
    others hold)."""
    with searching_with(loops):
        _explores_one_order(chains(6, 3), pattern)


def _explores_one_order(net, pattern):
    end, start = Tokens(("c0.3",), 1), Tokens(("c0.0",), 1)
    prop = Property("p", pattern, end if pattern is not Pattern.RESPONSE else start,
                    s=end if pattern is Pattern.RESPONSE else None)
    reduced, full = assert_reduced_same(net, [prop])
    plain = check_properties(net, [prop])[0]
    if plain.status is Status.HOLDS:    # every order explored without the reduction
        assert reduced[0].states * 10 < plain.states, (reduced[0].states, plain.states)
    else:                               # a violation found either way, the first one
        assert reduced[0].states <= plain.states


@in_c
def test_the_reduction_needs_a_net_proven_safe():
    b = NetBuilder("maybe")
    for p, k in (("a", 1), ("b", 1), ("c", 0)):
        b.place(p, k)
    for t, x in (("t", "a"), ("u", "b")):
        b.transition(t)
        b.arc(x, t)
        b.arc(t, "c")       # both may mark c: not 1-safe, and nothing proves otherwise
    prop = Property("p", Pattern.ABSENCE, Tokens(("c",), 1))
    with pytest.raises(onthefly.NotProvenSafe, match="not proven 1-safe"):
        check_properties(b.build(), [prop], stubborn=True)


@in_c
def test_analyze_stubborn_gives_the_same_verdicts_on_the_certified_mission():
    import json
    from helpers import run_cli
    args = ["analyze", ROOT / "examples" / "sauce.mcl", "--untimed", "--state-space",
            "--properties", ROOT / "examples" / "sauce.false.props", "--json"]
    plain, reduced = run_cli(*args), run_cli(*args, "--stubborn")
    assert plain.returncode == reduced.returncode == 1, reduced.stderr
    a, b = json.loads(plain.stdout), json.loads(reduced.stdout)
    assert b["stubborn"] is True and "stubborn" not in a
    assert [p["status"] for p in a["properties"]] == [p["status"] for p in b["properties"]]


@in_c
def test_analyze_stubborn_is_refused_where_it_does_not_apply():
    from helpers import run_cli
    out = run_cli("analyze", ROOT / "examples" / "sauce.mcl", "--properties",
                  ROOT / "examples" / "sauce.false.props", "--stubborn")   # timed
    assert out.returncode == 2 and "--stubborn" in out.stderr and "Traceback" not in out.stderr


@pytest.mark.parametrize("loops", LOOPS)
def test_a_violation_found_before_the_limit_is_kept(loops):
    """The limit met while the violation's level is being finished: the violation found
    is a real run, and the verdict says fails, not unknown."""
    b = NetBuilder("fan")
    for k in range(5):
        b.place(f"a{k}", 1)
        b.place(f"b{k}")
        b.transition(f"t{k}")
        b.arc(f"a{k}", f"t{k}")
        b.arc(f"t{k}", f"b{k}")
    net = b.build()
    prop = Property("p", Pattern.ABSENCE, Tokens(("b0",), 1))
    with searching_with(loops):
        v = check_properties(net, [prop], max_states=2, method="on-the-fly")[0]
    assert v.status is Status.FAILS and judge(net, prop, v.transitions, loop=v.loop) is not None
