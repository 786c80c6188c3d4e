"""A mission's certificate (mcl2pnml/certify): built from its parts without exploring, re-checked
against the compiled PNML alone, and held to what exploring the net finds."""
from __future__ import annotations

import json
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from analysis.behaviour import behaviour
from analysis.statespace import ExplorationLimit, explore
from mcl2pnml import pipeline
from mcl2pnml.certify.certificate import certify
from mcl2pnml.certify.checker import check
from mcl2pnml.core.net import Net

from helpers import ROOT
from missions import missions

EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))


def _certified(path: Path):
    checked = pipeline.check_file(path)
    net = pipeline.compile_checked(checked)
    # the certificate travels as JSON: the checker reads it as a file gives it
    return net, json.loads(json.dumps(certify(checked)))


@pytest.mark.parametrize("mission", EXAMPLES, ids=lambda p: p.stem)
def test_every_example_is_certified_and_the_certificate_checks(mission):
    net, cert = _certified(mission)
    assert check(net, cert) == []
    assert cert["conclusion"]["safe"] and cert["conclusion"]["reusable"]


def test_a_net_one_arc_away_from_its_certificate_is_refused_naming_the_instance():
    """Every arc of the paper's mission removed in turn: the checker refuses each net."""
    from mcl2pnml.certify.templates import current
    net, cert = _certified(ROOT / "examples" / "sauce.mcl")
    proofs = current()
    for arc in net.arcs:
        mutant = Net(net.name, net.places, net.transitions,
                     tuple(a for a in net.arcs if a != arc), net.initial)
        problems = check(mutant, cert, proofs)
        assert problems, arc
        owner = arc.target if arc.target in net.transition_index else arc.source
        assert any(f"'{owner.rsplit('.', 1)[0]}" in p for p in problems) or \
            any(owner.startswith(p.split("'")[1]) for p in problems), (arc, problems)


def test_a_certificate_of_another_mission_is_refused():
    net, _ = _certified(ROOT / "examples" / "sauce.mcl")
    _, other = _certified(ROOT / "examples" / "docking.mcl")
    problems = check(net, other)
    assert any("has no node in the net" in p for p in problems)
    assert any("belongs to no instance" in p for p in problems)


def test_a_recursive_call_order_is_a_side_condition_broken():
    net, cert = _certified(ROOT / "examples" / "multi_leg.mcl")
    cert["functions"] = list(reversed(cert["functions"]))
    assert any("is not before it" in p for p in check(net, cert))


def _explored_agrees(text: str) -> bool | None:
    """Whether exploring the mission's net finds what its certificate concludes (1-safe,
    an end always reachable, reusable, every end mission.OK or mission.FAIL at rest), and
    the same with an abort pending (ends mission.ABORTED too); None when the net is too
    large to explore here."""
    from mcl2pnml.certify.certificate import certify as certify_
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "m.mcl"
        path.write_text(text)
        net, cert = _certified(path)
        checked = pipeline.check_file(path)
    assert check(net, cert) == []
    aborted = net.with_initial({**net.initial, "mission.A": 1})
    assert check(aborted, json.loads(json.dumps(certify_(checked, abort_pending=True)))) == []
    for start, allowed in ((net, {("mission.OK",), ("mission.FAIL",)}),
                           # the abort is left for the caller when the end is not ABORTED
                           (aborted, {("mission.A", "mission.OK"), ("mission.A", "mission.FAIL"),
                                      ("mission.ABORTED",)})):
        try:
            space = explore(start, max_states=20_000)
        except ExplorationLimit:
            return None
        b = behaviour(space)
        ends = {tuple(p for p in space.format(n) if p.startswith("mission.") and
                      p != "mission.MTX") for n in space.terminal}
        if not (space.safe and b.deadlock_free and b.final_always_reachable and b.reusable
                and ends <= allowed):
            return False
    return True


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(missions(depth=2, width=2, function_depth=1))
def test_the_certificate_s_conclusion_is_what_exploring_finds(text):
    assert _explored_agrees(text) in (True, None)


@pytest.mark.slow
@settings(max_examples=10_000, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(missions(depth=2, width=2, function_depth=1))
def test_ten_thousand_certificates_are_what_exploring_finds(text):
    assert _explored_agrees(text) in (True, None)


# -- the command line ----------------------------------------------------------------------

def test_certify_writes_the_certificate_and_check_re_reads_it(tmp_path):
    from helpers import run_cli
    mission = tmp_path / "sauce.mcl"
    mission.write_text((ROOT / "examples" / "sauce.mcl").read_text())
    out = run_cli("certify", mission)
    assert out.returncode == 0, out.stderr
    assert "certified from its parts" in out.stdout and "1-safe" in out.stdout
    cert = tmp_path / "sauce.cert.json"
    assert json.loads(cert.read_text())["conclusion"]["reusable"]
    assert run_cli("compile", mission, "-o", tmp_path / "sauce.pnml").returncode == 0
    again = run_cli("certify", cert, "--check", tmp_path / "sauce.pnml")
    assert again.returncode == 0 and "certified from its parts" in again.stdout
    other = tmp_path / "docking.pnml"
    assert run_cli("compile", ROOT / "examples" / "docking.mcl", "-o", other).returncode == 0
    wrong = run_cli("certify", cert, "--check", other)
    assert wrong.returncode == 1 and "the certificate does not hold" in wrong.stdout


@pytest.mark.parametrize("args,message", [
    (["{tmp}/bad.json", "--check", "{pnml}"], "bad.json:2:3: not a certificate: Expecting"),
    (["{tmp}/other.json", "--check", "{pnml}"], "not a certificate of format 1"),
    (["{mission}", "--net", "x"], "only --check reads a net file"),
    (["{tmp}/other.json"], "is not a mission (.mcl)"),
])
def test_certify_errors_are_one_message(args, message, tmp_path):
    from helpers import run_cli
    (tmp_path / "bad.json").write_text("{\n  oops\n")
    (tmp_path / "other.json").write_text('{"format": 7}')
    pnml = tmp_path / "s.pnml"
    assert run_cli("compile", ROOT / "examples" / "sauce.mcl", "-o", pnml).returncode == 0
    args = [a.format(tmp=tmp_path, pnml=pnml, mission=ROOT / "examples" / "sauce.mcl")
            for a in args]
    out = run_cli("certify", *args)
    assert out.returncode == 2 and message in out.stderr, out.stderr
    assert "Traceback" not in out.stderr


def test_analyze_takes_the_certificate_beside_the_mission_and_says_so(tmp_path):
    from helpers import run_cli
    mission = tmp_path / "sauce.mcl"
    mission.write_text((ROOT / "examples" / "sauce.mcl").read_text())
    assert run_cli("certify", mission).returncode == 0
    out = run_cli("analyze", mission, "--state-space", "--json")
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout)
    assert "the certificate holds" in out.stderr and r["states"] is None
    assert r["safe"] and r["reusable"] and r["final_always_reachable"]
    assert r["certificate"]["holds"]
    explored = json.loads(run_cli("analyze", mission, "--state-space", "--json",
                                  "--explore").stdout)
    assert explored["states"] == 1_509 and explored["reusable"]
    # a certificate that is not this mission's is said, and the markings explored
    (tmp_path / "sauce.cert.json").write_text(
        json.dumps(_certified(ROOT / "examples" / "docking.mcl")[1]))
    stale = run_cli("analyze", mission, "--state-space", "--json")
    assert "the certificate does not hold for this net" in stale.stderr
    assert json.loads(stale.stdout)["states"] == 1_509


# -- mutated templates: never certifying a broken net -----------------------------------------

ALL_TEMPLATES = """primitive P(v);
primitive Q(v);
primitive R(v);
task A(x) = AchieveGoal(P(x)) timeout 5;
task K(x) = KeepGoal(Q(x)) timeout 5;
task K2(x) = KeepTwoGoals(P(x), R(1)) timeout 5;
mission { if (A(1)) then { parallel(K(1), A(2)); } else { } while (A(3)) { monitor(K(2), K2(3)); } }
"""


def _mutants():
    """(template, arc) of every arc of every pattern and structure: the template without it."""
    from mcl2pnml.language.template_parser import TemplateKind
    from mcl2pnml.language.library import default_library
    lib = default_library()
    return [(t.name, a) for t in lib.unique()
            if t.kind in (TemplateKind.PATTERN, TemplateKind.STRUCTURE) for a in t.net.arcs]


def _with_mutant(name: str, arc):
    """The library with template ``name`` missing ``arc`` (its aliases too)."""
    from dataclasses import replace

    from mcl2pnml.language.library import Library, default_library
    lib = default_library()
    t = lib.get(name)
    net = t.net
    mutant = replace(t, net=Net(net.name, net.places, net.transitions,
                                tuple(a for a in net.arcs if a != arc), net.initial))
    return Library({k: (mutant if v is t else v) for k, v in lib.templates.items()},
                   lib.primitive, lib.reduced)


def _judged(name: str, arc) -> tuple[bool, bool]:
    """(certified, explored well) of the mission of every template, with one mutated."""
    from mcl2pnml.certify.templates import BrokenTemplate, current
    from mcl2pnml.language.compiler import compile_checked
    lib = _with_mutant(name, arc)
    checked = pipeline.check_source(ALL_TEMPLATES, "all.mcl")
    net = compile_checked(checked, lib)
    try:
        proofs = current(lib)
        cert = certify(checked, lib, proofs=proofs)
        certified = check(net, json.loads(json.dumps(cert)), proofs) == []
    except BrokenTemplate:
        certified = False
    try:
        space = explore(net, max_states=200_000)
    except ExplorationLimit:
        # the mission has 2,426 markings unmutated: a mutant past 200,000 lets tokens pile
        # up (unbounded, or far from 1-safe), which no certified net may do
        return certified, False
    b = behaviour(space)
    return certified, space.safe and b.deadlock_free and b.reusable


MUTANTS = _mutants()


@pytest.mark.parametrize("name,arc", MUTANTS[::40], ids=lambda x: getattr(x, "source", x))
def test_a_template_missing_an_arc_is_never_certified_into_a_broken_net(name, arc):
    certified, fine = _judged(name, arc)
    assert fine or not certified, (name, arc)


@pytest.mark.slow
def test_every_template_missing_an_arc_is_never_certified_into_a_broken_net():
    """All 528 mutants (every arc of every pattern and structure); says how many the
    certificate refuses though this mission, explored, shows no fault (a breach its runs
    never reach: 334 of 528 when last run)."""
    cautious = 0
    for name, arc in MUTANTS:
        certified, fine = _judged(name, arc)
        assert fine or not certified, (name, arc)
        cautious += fine and not certified
    print(f"{len(MUTANTS)} mutants; refused though this mission explores well: {cautious}")


def test_certify_with_an_abort_pending_ends_aborted_too(tmp_path):
    from helpers import run_cli
    mission = tmp_path / "dam.mcl"
    mission.write_text((ROOT / "examples" / "dam_inspection.mcl").read_text())
    out = run_cli("certify", mission, "--abort-pending")
    assert out.returncode == 0, out.stderr
    assert "mission.OK, mission.FAIL, mission.ABORTED" in out.stdout
    cert = json.loads((tmp_path / "dam.cert.json").read_text())
    assert cert["start"] == ["mission.B", "mission.A"] and "abort" in cert["conclusion"]
    # the net without the abort is not the one it proves
    net, _ = _certified(mission)
    assert any("does not mark mission.A" in p for p in check(net, cert))
