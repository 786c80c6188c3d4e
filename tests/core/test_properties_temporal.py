"""The temporal forms of a property (core.temporal) against the observer's verdicts.

On random small nets, a property's LTL formula, evaluated on every run the
enumeration gives (finite runs stuttered, lassos), is true on all of them
exactly when the observer says the property holds; its CTL and reachability
forms, where it has them, are read on the same runs (the path quantifiers
each on the one run, which for these formulas is the LTL reading). The
peers' verdicts on the exported queries are tests/peers/test_properties_peers.py.
"""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings

from mcl2pnml.analysis.checking.on_graph import Status, check_property
from mcl2pnml.core.patterns import Pattern, Property, Scope, ScopeKind
from mcl2pnml.core.temporal import ctl, evaluate, ltl, reachability, show
from test_properties_check import _graph, chain, at, props, runs, small_nets
from sampling import sample


def _runs_satisfy(net, formula, length=7):
    marks, edges = _graph(net)
    for states, _, loop in runs(edges, length):
        if loop is not None:
            # runs() gives the lasso with its first state repeated last: word[loop] again
            states = states[:-1]
        if not evaluate(formula, [marks[m] for m in states], loop):
            return False
    return True


@settings(max_examples=sample(150, 50), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_nets(), props())
def test_the_ltl_form_means_what_the_observer_checks(net, prop):
    verdict = check_property(net, prop)
    formula = ltl(prop)
    assert _runs_satisfy(net, formula) is (verdict.status is Status.HOLDS), show(formula)
    for other in (ctl(prop), reachability(prop)):
        if other is not None:
            assert _runs_satisfy(net, other) is (verdict.status is Status.HOLDS), show(other)


@pytest.mark.slow
@settings(max_examples=3000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_nets(), props())
def test_the_ltl_form_means_what_the_observer_checks_long(net, prop):
    test_the_ltl_form_means_what_the_observer_checks.hypothesis.inner_test(net, prop)


def test_every_pattern_has_an_ltl_form_and_the_invariants_a_reachability_one():
    for pattern in Pattern:
        for kind in ScopeKind:
            prop = Property("x", pattern, at(1), s=at(2), bound=1,
                            scope=Scope(kind, q=at(0), r=at(3)))
            assert ltl(prop) is not None
            expect = kind is ScopeKind.GLOBALLY and pattern in (Pattern.ABSENCE,
                                                                 Pattern.UNIVERSALITY)
            assert (reachability(prop) is not None) is expect


def test_a_formula_reads_as_the_catalogue_writes_it():
    response = Property("x", Pattern.RESPONSE, at(1), s=at(2))
    assert show(ltl(response)) == "A [](!(m1 >= 1) | <>(m2 >= 1))"
    assert show(ctl(response)) == "A [](!(m1 >= 1) | A <>(m2 >= 1))"
    before = Property("x", Pattern.ABSENCE, at(1), scope=Scope(ScopeKind.BEFORE, r=at(3)))
    assert show(ltl(before)) == "A (!<>(m3 >= 1) | (!(m1 >= 1) U (m3 >= 1)) | []!(m1 >= 1))"


# -- the exported files: compile --properties ------------------------------------------------

def test_compile_writes_each_category_beside_the_net_with_the_pnml_ids(tmp_path):
    from lxml import etree

    from helpers import ROOT, run_cli
    mission = tmp_path / "m.mcl"
    mission.write_text((ROOT / "examples" / "sauce.mcl").read_text() + """
property Never: never enabled(GoToWayPoint) and enabled(ReleaseMarker);
property Responds: running(Survey) leads to ended(Survey, OK) or ended(Survey, FAIL)
    or ended(Survey, ABORTED) after outcome(OK) until false;
""")
    r = run_cli("compile", mission, "-o", tmp_path / "out.pnml", "--properties")
    assert r.returncode == 0, r.stderr
    pnml = etree.parse(str(tmp_path / "out.pnml"))
    places = {e.get("id") for e in pnml.iter("{*}place")}
    ids = {}
    for category in ("ReachabilityCardinality", "CTLCardinality", "LTLCardinality"):
        path = tmp_path / f"out.{category}.xml"
        assert f"wrote {path}" in r.stderr
        tree = etree.parse(str(path))
        ids[category] = [e.text for e in tree.iter("{http://mcc.lip6.fr/}id")]
        named = {e.text for e in tree.iter("{http://mcc.lip6.fr/}place")}
        assert named and named <= places, named - places
    assert ids["LTLCardinality"] == ["Never", "Responds"]
    assert ids["ReachabilityCardinality"] == ids["CTLCardinality"] == ["Never"]


def test_compile_properties_errors_are_one_message_and_write_nothing(tmp_path):
    from helpers import ROOT, run_cli
    mission = tmp_path / "m.mcl"
    mission.write_text("primitive P(x);\ntask T(x) = AchieveGoal(P(x));\nmission { T(1); }\n")
    r = run_cli("compile", mission, "-o", tmp_path / "m.pnml", "--properties")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "declares no property" in r.stderr
    r = run_cli("compile", mission, "-o", tmp_path / "m.pnml", "--properties", tmp_path / "no")
    assert r.returncode == 2 and "no file" in r.stderr
    side = tmp_path / "bad.props"
    side.write_text("property X: never enabled(Q);\n")
    r = run_cli("compile", mission, "-o", tmp_path / "m.pnml", "--properties", side)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert f"{side}:1:27: undeclared primitive 'Q'; declared primitives: P" in r.stderr
    assert not list(tmp_path.glob("m.*.xml")) and not (tmp_path / "m.pnml").exists()
