"""A mission's certificate (mcl2pnml/certify): built from its parts without exploring, re-checked
against the compiled PNML alone, and held to what exploring the net finds."""
from __future__ import annotations

import functools
import json
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings

from mcl2pnml.analysis.behaviour import behaviour
from mcl2pnml.analysis.statespace.explore import ExplorationLimit
from mcl2pnml import pipeline
from mcl2pnml.certify.certificate import certify
from mcl2pnml.certify.recheck import check_certificate
from mcl2pnml.core.net import Net

from helpers import ROOT
from missions import missions, shaped_missions

EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))


def _certified(path: Path):
    """The mission's net and certificate, the certificate a copy of its own to spoil."""
    net, text = _certificate_text(path)
    return net, json.loads(text)


@functools.cache
def _certificate_text(path: Path):
    checked = pipeline.check_file(path)
    net = pipeline.compile_checked(checked)
    # the certificate travels as JSON: the checker reads it as a file gives it
    return net, json.dumps(certify(checked))


@pytest.mark.parametrize("mission", EXAMPLES, ids=lambda p: p.stem)
def test_every_example_is_certified_and_the_certificate_checks(mission):
    net, cert = _certified(mission)
    assert check_certificate(net, cert) == []
    assert cert["conclusion"]["safe"] and cert["conclusion"]["reusable"]


@pytest.mark.parametrize("mission,pending", [
    pytest.param(m, p, id=f"{m.stem}{'-aborted' if p else ''}",
                 # 3,105,724 markings: a few seconds with the compiled explorer
                 marks=[pytest.mark.slow] if (m.stem, p) == ("dam_inspection", True) else [])
    for m in EXAMPLES for p in (False, True)])
def test_every_example_s_certificate_is_what_exploring_finds(mission, pending):
    assert _agrees(mission.read_text(), (pending,), max_states=4_000_000) is True


def test_proofs_read_back_from_json_check_as_the_library_s_do():
    """The checker writes each part's own net from the library when the proofs come as
    plain data (a file read back), and holds the net to the same digests."""
    from mcl2pnml.certify.templates import current
    net, cert = _certified(ROOT / "examples" / "multi_leg.mcl")
    proofs = json.loads(json.dumps(current()))
    assert check_certificate(net, cert, proofs) == []
    proofs["sequence"]["local"] = "0" * 64       # a digest no part of the library has
    problems = check_certificate(net, cert, proofs)
    assert problems and all("is a sequence, which no stored proof covers" in p
                            or "its own digest is not sequence's" in p
                            for p in problems if "sequence" in p)


@pytest.mark.parametrize("stride", [pytest.param(1, marks=pytest.mark.slow), 3])
def test_a_net_one_arc_away_from_its_certificate_is_refused_naming_the_instance(stride):
    """Every arc of the paper's mission removed in turn (every third in ``make test``):
    the checker refuses each net."""
    from mcl2pnml.certify.templates import current
    net, cert = _certified(ROOT / "examples" / "sauce.mcl")
    proofs = current()
    for arc in net.arcs[::stride]:
        mutant = Net(net.name, net.places, net.transitions,
                     tuple(a for a in net.arcs if a != arc), net.initial)
        problems = check_certificate(mutant, cert, proofs)
        assert problems, arc
        owner = arc.target if arc.target in net.transition_index else arc.source
        assert any(f"'{owner.rsplit('.', 1)[0]}" in p for p in problems) or \
            any(owner.startswith(p.split("'")[1]) for p in problems), (arc, problems)


def _changed(net: Net, how: str, k: int) -> Net | None:
    """``net`` changed in one way at its k-th place, transition or arc (None: no such
    change there that leaves a well-formed net)."""
    from mcl2pnml.core.net import Arc, ArcKind, Place, Transition
    places, transitions, arcs = net.places, net.transitions, net.arcs
    initial = dict(net.initial)
    if how == "arc added":
        place, transition = places[k % len(places)].id, transitions[k % len(transitions)].id
        if any({a.source, a.target} == {place, transition} for a in arcs):
            return None
        arcs = arcs + (Arc(place, transition),)
    elif how == "arc turned round":
        a = arcs[k % len(arcs)]
        if a.kind is ArcKind.READ or any((b.source, b.target) == (a.target, a.source)
                                          for b in arcs):
            return None
        arcs = tuple(b if b != a else Arc(a.target, a.source, a.weight) for b in arcs)
    elif how == "weight 2":
        a = arcs[k % len(arcs)]
        arcs = tuple(b if b != a else a._replace(weight=2) for b in arcs)
    elif how == "consuming arc made a read arc":
        a = arcs[k % len(arcs)]
        if a.kind is ArcKind.READ or a.source not in net.place_index:
            return None
        arcs = tuple(b if b != a else a._replace(kind=ArcKind.READ) for b in arcs)
    elif how == "token added":
        place = places[k % len(places)].id
        initial[place] = initial.get(place, 0) + 1
    elif how == "token taken":
        marked = sorted(initial)
        initial.pop(marked[k % len(marked)])
    elif how == "place renamed":
        old = places[k % len(places)].id
        new = old + "x"
        places = tuple(p if p.id != old else Place(new) for p in places)
        arcs = tuple(Arc(new if a.source == old else a.source,
                         new if a.target == old else a.target, a.weight, a.kind) for a in arcs)
        if old in initial:
            initial[new] = initial.pop(old)
    elif how == "transition added":
        owner = transitions[k % len(transitions)].id.rsplit(".", 1)[0]
        transitions = transitions + (Transition(f"{owner}.extra"),)
    return Net(net.name, places, transitions, arcs, initial)


@pytest.mark.parametrize("how", ["arc added", "arc turned round", "weight 2",
                                 "consuming arc made a read arc", "token added", "token taken",
                                 "place renamed", "transition added"])
@pytest.mark.parametrize("mission", ["sauce", "multi_leg"])
@pytest.mark.parametrize("step", [pytest.param(19, id="every-19th"),
                                  pytest.param(5, id="every-5th", marks=pytest.mark.slow)])
def test_a_net_changed_in_any_one_way_is_refused_saying_what_differs(mission, how, step):
    """Changed at many places, nodes and arcs in turn (every ``step``-th one), the net is
    refused each time, and the checker says so without a crash; the net as compiled holds."""
    net, cert = _certified(ROOT / "examples" / f"{mission}.mcl")
    assert check_certificate(net, cert) == []
    changed = 0
    for k in range(0, 600, step):
        other = _changed(net, how, k)
        if other is None:
            continue
        changed += 1
        problems = check_certificate(other, cert)
        assert problems, (how, k)
        assert all(isinstance(p, str) and p for p in problems)
    assert changed >= 10, f"only {changed} nets changed by {how}"


def test_a_certificate_of_another_mission_is_refused():
    net, _ = _certified(ROOT / "examples" / "sauce.mcl")
    _, other = _certified(ROOT / "examples" / "docking.mcl")
    problems = check_certificate(net, other)
    assert any("has no node in the net" in p for p in problems)
    assert any("belongs to no instance" in p for p in problems)


def test_the_functions_order_is_computed_and_a_call_cycle_is_refused():
    """The checker orders the functions itself: the list reversed changes nothing; a
    function made to call one that calls it is a cycle, refused whatever the list says."""
    net, cert = _certified(ROOT / "examples" / "multi_leg.mcl")
    cert["functions"] = list(reversed(cert["functions"]))
    assert check_certificate(net, cert) == []
    calls = {f: [n for n in cert["trees"][f] if n["rule"] == "call"
                 and n["callee"] in cert["functions"]] for f in cert["functions"]}
    caller = next(f for f in calls if calls[f])
    callee = calls[caller][0]["callee"]
    site = next(n for n in cert["trees"][callee] if n["rule"] == "call")
    site["callee"] = caller
    assert any("call each other in a cycle" in p for p in check_certificate(net, cert))


@functools.cache
def _proofs():
    """The library's proofs, read once for the many generated missions."""
    from mcl2pnml.certify.templates import current
    return current()


def _explored(net: Net, max_states: int = 20_000):
    """What exploring ``net`` from its M0 finds about the claims of a certificate's
    conclusion: (holds, ends), ``holds`` when it is 1-safe, an end always reachable, every
    dead marking an end, reusable, every place but the mission's own at rest whenever a
    result is marked, and every end one result, ABORTED exactly when A was marked and is
    consumed, and reachable then (the abort honoured); ``ends`` the mission places marked
    in the dead markings. None when the net has more markings than ``max_states``."""
    from mcl2pnml.analysis.statespace.explorers import EXPLORERS
    from mcl2pnml.analysis.statespace.packedmarkings import NotSafe
    from mcl2pnml.core.structure import structure
    # a safe-net explorer, which stops at the first place holding two tokens: that alone
    # is a fault of the claims (1-safe), and a mutant's net may pile tokens up for ever
    explorer = EXPLORERS["native" if EXPLORERS["native"].can_run() else "packed"]
    s = structure(net)
    try:
        space = explorer.explore(s, s.initial_vector(), max_states,
                                 ExplorationLimit("too many markings"))
    except NotSafe:
        return False, set()
    except ExplorationLimit:
        return None
    b = behaviour(space)
    ends = {tuple(p for p in space.format(n) if p.startswith("mission.") and p != "mission.MTX")
            for n in space.terminal}
    ended = sum(space.tokens(s.place_index[f"mission.{r}"]) for r in ("OK", "FAIL", "ABORTED"))
    rest = [None if p.startswith("mission.") else net.initial.get(p, 0) for p in s.places]
    at_rest = all(all(r is None or m[k] == r for k, r in enumerate(rest))
                  for m in (space.markings[int(n)] for n in ended.nonzero()[0]))
    if net.initial.get("mission.A"):
        shapes = {("mission.A", "mission.OK"), ("mission.A", "mission.FAIL"),
                  ("mission.ABORTED",)}
        shaped = ends <= shapes and ("mission.ABORTED",) in ends
    else:
        shaped = ends <= {("mission.OK",), ("mission.FAIL",)}
    return (space.safe and b.deadlock_free and b.final_always_reachable and b.reusable
            and at_rest and shaped), ends


def _ends_said(cert, pending: bool) -> set[tuple[str, ...]]:
    """The certificate's ends as exploring's dead markings show them: mission.A is left
    marked by every end but ABORTED when an abort is pending."""
    return {(e,) if e == "mission.ABORTED" or not pending else ("mission.A", e)
            for e in cert["conclusion"]["ends"]}


def _agrees(text: str, pending=(False, True), max_states: int = 20_000) -> bool | None:
    """Whether the certificate's verdict on a mission is what exploring its net finds,
    from mission.B and with mission.A pending too: certified, and the exploration holds
    with exactly the certified ends (mission.A left marked when the end is not ABORTED);
    or refused, and the exploration finds a fault. None when a net is too large to
    explore here."""
    from mcl2pnml.certify.certificate import NotCertified
    from mcl2pnml.certify.certificate import certify as certify_
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "m.mcl"
        path.write_text(text)
        checked = pipeline.check_file(path)
        net = pipeline.compile_checked(checked)
    aborted = net.with_initial({**net.initial, "mission.A": 1})
    verdicts = []
    for start, pending in [(aborted if p else net, p) for p in pending]:
        try:
            cert = json.loads(json.dumps(certify_(checked, abort_pending=pending,
                                                  proofs=_proofs())))
        except NotCertified:
            cert = None
        found = _explored(start, max_states)
        if found is None:
            return None
        holds, ends = found
        if cert is None:
            verdicts.append(not holds)
            continue
        assert check_certificate(start, cert, _proofs()) == []
        verdicts.append(holds and ends == _ends_said(cert, pending))
    return all(verdicts)


@settings(max_examples=30, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(shaped_missions(depth=2))
def test_the_certificate_s_verdict_is_what_exploring_finds(text):
    """Thirty small missions (ten thousand, deeper, behind ``slow``) on callees of every shape (ending OK or FAIL, only FAIL,
    only OK), loops on any structure: certified with the ends exploring finds, or refused
    where exploring finds a run that never ends (one too large to explore here is drawn
    again)."""
    verdict = _agrees(text)
    assume(verdict is not None)
    assert verdict


@pytest.mark.slow
@settings(max_examples=10_000, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(shaped_missions(depth=3) | missions(depth=2, width=2, function_depth=1,
                                           any_condition=True))
def test_ten_thousand_certificates_are_what_exploring_finds(text):
    verdict = _agrees(text)
    assume(verdict is not None)
    assert verdict


# -- the command line ----------------------------------------------------------------------

def test_certify_writes_the_certificate_and_check_re_reads_it(tmp_path, examples):
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
    wrong = run_cli("certify", cert, "--check", examples.pnml("docking"))
    assert wrong.returncode == 1 and "the certificate does not hold" in wrong.stdout


@pytest.mark.parametrize("args,message", [
    (["{tmp}/bad.json", "--check", "{pnml}"], "bad.json:2:3: not a certificate: Expecting"),
    (["{tmp}/other.json", "--check", "{pnml}"], "not a certificate of format 2"),
    (["{mission}", "--net", "x"], "only --check reads a net file"),
    (["{tmp}/other.json"], "is not a mission (.mcl)"),
])
def test_certify_errors_are_one_message(args, message, tmp_path, examples):
    from helpers import run_cli
    (tmp_path / "bad.json").write_text("{\n  oops\n")
    (tmp_path / "other.json").write_text('{"format": 7}')
    pnml = examples.pnml("sauce")
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


# -- mutated templates: refused exactly when exploring finds a fault --------------------------

#: Missions that use every pattern and structure in the ways the compiler joins them: in a
#: loop (started again after each result), aborted from outside (a monitor, and
#: mission.A), sharing primitives and callees, with and without a time-out, ending the
#: mission (where a result given early shows).
PROBES = ["""primitive P(v);
primitive Q(v);
primitive R(v);
task A(x) = AchieveGoal(P(x)) timeout 5;
task N(x) = AchieveGoal(R(x));
task K(x) = KeepGoal(Q(x)) timeout 5;
task K2(x) = KeepTwoGoals(P(x), R(1)) timeout 5;
task KN(x) = KeepGoal(Q(x));
task K2N(x) = KeepTwoGoals(P(x), R(1));
""" + f"mission {{ {body} }}\n" for body in (
    "if (A(1)) then { parallel(K(1), A(2)); } else { } while (A(3)) { monitor(K(2), K2(3)); }",
    "while (A(1)) { monitor(K(1), N(2)); }",
    "while (N(1)) { parallel(A(2), K2(1)); }",
    "while (A(1)) { if (N(1)) then { K(1); } else { A(3); } }",
    "while (A(1)) { while (N(2)) { } }",
    "monitor(K(1), { while (A(1)) { N(2); } });",
    "while (A(1)) { monitor(KN(1), A(2)); monitor(K2N(1), N(3)); }",
    "",
)]


def _mutants():
    """(template, what was done, its net) for every pattern and structure: each transition
    removed (with its arcs), each arc removed, each arc redirected (its place end moved to
    the template's next place, when no such arc is there already)."""
    from mcl2pnml.language.library import default_library
    from mcl2pnml.language.template_parser import TemplateKind
    out = []
    for t in default_library().unique():
        if t.kind not in (TemplateKind.PATTERN, TemplateKind.STRUCTURE):
            continue
        net, places = t.net, [p.id for p in t.net.places]
        for tr in net.transitions:
            out.append((t.name, f"without {tr.id}", Net(
                net.name, net.places, tuple(x for x in net.transitions if x != tr),
                tuple(a for a in net.arcs if tr.id not in (a.source, a.target)), net.initial)))
        for a in net.arcs:
            rest = tuple(x for x in net.arcs if x != a)
            out.append((t.name, f"without {a.source} -> {a.target}",
                        Net(net.name, net.places, net.transitions, rest, net.initial)))
            end = a.source if a.source in places else a.target
            moved = places[(places.index(end) + 1) % len(places)]
            b = a._replace(source=moved) if end == a.source else a._replace(target=moved)
            if all((x.source, x.target) != (b.source, b.target) for x in rest):
                out.append((t.name, f"{a.source} -> {a.target} as {b.source} -> {b.target}",
                            Net(net.name, net.places, net.transitions, (*rest, b),
                                net.initial)))
    return out


def _with_mutant(name: str, net: Net):
    """The library with template ``name``'s net replaced (its aliases too)."""
    from dataclasses import replace

    from mcl2pnml.language.library import Library, default_library
    lib = default_library()
    t = lib.get(name)
    mutant = replace(t, net=net)
    return Library({k: (mutant if v is t else v) for k, v in lib.templates.items()},
                   lib.primitive, lib.reduced)


@functools.cache
def _probe(k: int):
    """Probe ``k`` parsed (a frozen tree), once for every mutant: a tenth of judging one."""
    from mcl2pnml.language.parser import parse
    return parse(PROBES[k], f"probe{k}.mcl")


@functools.lru_cache(maxsize=128)
def _explored_probe(net: Net):
    """:func:`_explored` of a probe's net, remembered: a probe that does not use the mutated
    template compiles to the net it had before, explored once for every such mutant."""
    return _explored(net, 200_000)


def _judged(name: str, net: Net) -> tuple[bool, bool, list[str]]:
    """(certified, explored well, what the certificate got wrong) of the probes with one
    template mutated: certified when every probe is, from mission.B and with mission.A
    pending; explored well when every exploration holds; wrong: a probe certified whose
    exploration does not hold or ends otherwise."""
    from mcl2pnml.certify.certificate import NotCertified
    from mcl2pnml.certify.templates import BrokenTemplate, current
    from mcl2pnml.language.semantics import check_program
    from mcl2pnml.language.compiler import compile_checked
    lib = _with_mutant(name, net)
    try:
        proofs = current(lib)
    except BrokenTemplate:
        proofs = None
    certified, fine, wrong = proofs is not None, True, []
    for k, text in enumerate(PROBES):
        checked = check_program(_probe(k), lib)
        compiled = compile_checked(checked, lib)
        for pending in (False, True):
            start = compiled.with_initial({**compiled.initial, "mission.A": 1}) \
                if pending else compiled
            holds, ends = _explored_probe(start) or (False, None)
            fine &= holds
            if proofs is None:
                continue
            try:
                cert = json.loads(json.dumps(certify(checked, lib, abort_pending=pending,
                                                     proofs=proofs)))
            except NotCertified:
                certified = False
                continue
            if check_certificate(start, cert, proofs):
                certified = False
            elif not holds or ends != _ends_said(cert, pending):
                wrong.append(f"probe{k}{' with an abort pending' if pending else ''}")
    return certified, fine, wrong


MUTANTS = _mutants()


@pytest.mark.parametrize("name,how,net", MUTANTS[::40], ids=lambda x: getattr(x, "name", x))
def test_a_mutated_template_is_refused_exactly_when_exploring_finds_a_fault(name, how, net):
    certified, fine, wrong = _judged(name, net)
    assert not wrong and certified == fine, (name, how, certified, fine, wrong)


@pytest.mark.slow
def test_every_mutated_template_is_refused_exactly_when_exploring_finds_a_fault():
    """All of them: 1,158 mutants of the 9 patterns and structures when last run."""
    for name, how, net in MUTANTS:
        certified, fine, wrong = _judged(name, net)
        assert not wrong and certified == fine, (name, how, certified, fine, wrong)


LOOP = """primitive P(v);
task A(x) = AchieveGoal(P(x)) timeout 5;
function Idle() { }
mission {
    A(1);
    while (Idle()) { }
}
"""


def test_a_loop_that_never_ends_is_not_certified_and_the_message_points_at_it(tmp_path):
    """Idle() can only end OK, and the empty body too: the loop never ends, though every
    part keeps the contract. Certifying refuses the mission at the loop; with an abort
    pending it is certified, ending only ABORTED or FAIL (A(1) failing first)."""
    from helpers import run_cli
    mission = tmp_path / "loop.mcl"
    mission.write_text(LOOP)
    out = run_cli("certify", mission)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert f"{mission}:6:12: 'while-1' never ends unless it is aborted" in out.stderr
    assert "    while (Idle()) { }\n" in out.stderr and "^" in out.stderr
    assert not (tmp_path / "loop.cert.json").exists()
    explored = json.loads(run_cli("analyze", mission, "--state-space", "--json").stdout)
    assert not explored["final_always_reachable"]
    aborted = run_cli("certify", mission, "--abort-pending")
    assert aborted.returncode == 0, aborted.stderr
    cert = json.loads((tmp_path / "loop.cert.json").read_text())
    assert cert["conclusion"]["ends"] == ["mission.FAIL", "mission.ABORTED"]
    assert cert["trees"]["mission"][0]["may run for ever"]
    # the same certificate, read as a proof of the mission with no abort pending, is refused
    net = pipeline.compile_checked(pipeline.check_file(mission))
    cert["start"] = ["mission.B"]
    assert any("may run for ever (from 'while-1')" in p for p in check_certificate(net, cert))


def test_a_certificate_claiming_other_ends_is_refused():
    net, cert = _certified(ROOT / "examples" / "docking.mcl")
    cert["conclusion"]["ends"] = ["mission.OK"]
    assert any("the conclusion is not the one derived from the parts" in p
               for p in check_certificate(net, cert))


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
    assert any("does not mark mission.A" in p for p in check_certificate(net, cert))


@pytest.mark.parametrize("spoil,message", [
    (lambda c: c["trees"].update(mission="not a list"),
     "malformed at $.trees.mission: 'not a list' is not of type 'array'"),
    (lambda c: c.pop("conclusion"), "malformed at $: 'conclusion' is a required property"),
    (lambda c: c.pop("tasks"), "malformed at $: 'tasks' is a required property"),
    (lambda c: c["tasks"]["DropMarker"].update(subject=["a", "list"]),
     "malformed at $.tasks.DropMarker.subject: ['a', 'list'] is not of type 'string'"),
    (lambda c: c["trees"]["mission"][0].pop("instance"),
     "malformed at $.trees.mission[0]: 'instance' is a required property"),
    (lambda c: c["trees"]["mission"][1].update(parent="0"),
     "malformed at $.trees.mission[1].parent: '0' is not of type 'integer'"),
    (lambda c: c["conclusion"].update(safe=False),
     "malformed at $.conclusion.safe: True was expected"),
    (lambda c: c.update(start=[]), "malformed at $.start: [] should be non-empty"),
], ids=["tree not a list", "no conclusion", "no tasks", "subject a list",
        "node without a name", "parent a string", "safe false", "no start"])
def test_a_certificate_not_of_its_shape_is_one_message_at_its_json_path(spoil, message,
                                                                       tmp_path, examples):
    """A certificate is input like any other: spoilt by hand, it is refused with one line
    naming the file and the JSON path of the fault, exit 2, never a crash."""
    from helpers import run_cli
    net, cert = _certified(ROOT / "examples" / "sauce.mcl")
    spoil(cert)
    (tmp_path / "c.json").write_text(json.dumps(cert))
    out = run_cli("certify", tmp_path / "c.json", "--check", examples.pnml("sauce"))
    assert out.returncode == 2 and out.stdout == "", out.stderr
    assert out.stderr.startswith(f"{tmp_path / 'c.json'}: the certificate is ")
    assert message in out.stderr and out.stderr.count("\n") == 1, out.stderr
    assert check_certificate(net, cert) and all(p.startswith("the certificate is malformed")
                                    for p in check_certificate(net, cert))


def test_a_parent_out_of_range_is_a_certificate_that_does_not_hold(tmp_path, examples):
    from helpers import run_cli
    net, cert = _certified(ROOT / "examples" / "sauce.mcl")
    cert["trees"]["mission"][1]["parent"] = 10_000
    (tmp_path / "c.json").write_text(json.dumps(cert))
    out = run_cli("certify", tmp_path / "c.json", "--check", examples.pnml("sauce"))
    assert out.returncode == 1 and "Traceback" not in out.stderr + out.stdout
    assert "parent 10000 is no other node of the tree" in out.stdout


#: Missions whose verdicts differ, with whether each is certified from mission.B alone: a
#: loop that never ends, one whose body can fail, a goal kept for ever under a monitor that
#: ends it, and a loop that may end or may run on for ever (with an abort pending, each is
#: certified).
PEER_MISSIONS = {
    "idle loop": (LOOP, False),
    "loop that can fail": (LOOP.replace("while (Idle()) { }", "while (Idle()) { A(2); }"),
                           True),
    "watched for ever": ("""primitive P(v);
primitive Q(v);
task A(x) = AchieveGoal(P(x)) timeout 5;
task Keep(x) = KeepGoal(Q(x));
mission { monitor(Keep(1), A(2)); }
""", True),
    "loop that may run on": (LOOP.replace("A(1);\n    while (Idle()) { }",
                                          "while (A(1)) { while (Idle()) { } }"), False),
}


@pytest.mark.parametrize("pending", [False, True], ids=["from B", "abort pending"])
@pytest.mark.parametrize("name", PEER_MISSIONS)
def test_verifypn_and_lola_find_what_the_certificate_says(name, pending, tmp_path):
    """The certificate against tools we did not write: verifypn and LoLA answer AG EF end
    and EF (deadlock and not end) (mcl2pnml/io/mccquery.py) on the compiled net; a mission
    is certified exactly when both say an end is always reachable and no dead marking is
    improper."""
    from mcl2pnml.certify.certificate import NotCertified
    from mcl2pnml.certify.certificate import certify as certify_
    from test_queries import answers
    text, from_b = PEER_MISSIONS[name]
    checked = pipeline.check_source(text, f"{name}.mcl")
    net = pipeline.compile_checked(checked)
    if pending:
        net = net.with_initial({**net.initial, "mission.A": 1})
    try:
        certify_(checked, abort_pending=pending, proofs=_proofs())
        certified = True
    except NotCertified:
        certified = False
    assert certified == (from_b or pending)
    _, verifypn, lola = answers(net, tmp_path, 200_000)
    for tool, said in (("verifypn", verifypn), ("LoLA", lola)):
        ends_well = said["end-always-reachable"] and not said["deadlock-not-an-end"]
        assert ends_well == certified, (tool, said, certified)


def test_a_user_s_reduced_model_is_no_ground_for_a_certificate(tmp_path, examples):
    """The proofs stand each child by the package's reduced model (Fig. 3): one a user puts
    in its place (here one that can only be aborted before it starts, which once crashed
    certifying with an abort pending) is refused by certify and by the checker, one
    message naming its file, never a traceback."""
    from helpers import run_cli
    folder = tmp_path / "mine"
    folder.mkdir()
    text = (ROOT / "templates" / "task_reduced.pnt").read_text()
    (folder / "task_reduced.pnt").write_text(
        text.replace('transition t4: EXE, A -> ABORTED, MTX     "aborted while running"\n', ""))
    env = {**__import__("os").environ, "MCL2PNML_TEMPLATE_PATH": str(folder)}
    net, cert = _certified(ROOT / "examples" / "sauce.mcl")
    (tmp_path / "s.cert.json").write_text(json.dumps(cert))
    for args in ([ROOT / "examples" / "sauce.mcl", "-o", tmp_path / "x.json", "--abort-pending"],
                 [tmp_path / "s.cert.json", "--check", examples.pnml("sauce")]):
        out = run_cli("certify", *args, env=env)
        assert out.returncode in (1, 2) and "Traceback" not in out.stderr + out.stdout
        assert "the reduced task 'task-reduced' is not the package's" in out.stderr + out.stdout
    assert not (tmp_path / "x.json").exists()


def test_a_primitive_no_task_uses_is_covered_by_no_proof():
    """A primitive is proven idle at rest only within its tasks' proofs: one listed with no
    task using it (its net added to match) is refused, not taken as idle."""
    net, cert = _certified(ROOT / "examples" / "sauce.mcl")
    cert["primitives"]["Spare"] = dict(cert["primitives"]["DetectCross"])
    assert any("primitive 'Spare' is used by no task" in p for p in check_certificate(net, cert))


def test_hostile_certificates_are_refused_at_once_with_one_message(tmp_path, examples):
    """Bounds before work: a file over the size limit is refused before it is read (here a
    sparse file of 17 MiB), and the limit can be raised; a certificate naming more
    instances than the net has nodes is refused before its trees are read; one with a
    thousand decoys says at most twenty faults and how many more; analyze, finding a
    malformed certificate beside a net, says so at its JSON path and stops."""
    from helpers import run_cli
    net, cert = _certified(ROOT / "examples" / "sauce.mcl")
    pnml = tmp_path / "s.pnml"      # a copy: analyze reads the certificate written beside it
    shutil.copyfile(examples.pnml("sauce"), pnml)
    big = tmp_path / "big.json"
    with open(big, "wb") as f:
        f.truncate(17 * 2**20)
    out = run_cli("certify", big, "--check", pnml)
    assert out.returncode == 2 and out.stderr == (
        f"{big}: cannot read the certificate: it is 17.0 MiB, over the limit of 16.0 MiB "
        "(--max-certificate-size to raise it)\n")
    out = run_cli("certify", big, "--check", pnml, "--max-certificate-size", "32M")
    assert out.returncode == 2 and "not a certificate" in out.stderr
    node = cert["trees"]["mission"][-1]
    padded = json.loads(json.dumps(cert))
    padded["trees"]["mission"] += [{**node, "instance": f"x{k}", "parent": 0}
                                   for k in range(500)]
    (tmp_path / "padded.json").write_text(json.dumps(padded))
    out = run_cli("certify", tmp_path / "padded.json", "--check", pnml)
    assert out.returncode == 1 and out.stdout.splitlines()[1:] == [
        "  the certificate names 521 instances, and the net has 421 nodes: every instance "
        "has nodes of its own"]
    decoys = json.loads(json.dumps(cert))
    decoys["trees"]["mission"] += [{**node, "instance": f"x{k}", "parent": 10_000}
                                   for k in range(300)]
    (tmp_path / "decoys.json").write_text(json.dumps(decoys))
    out = run_cli("certify", tmp_path / "decoys.json", "--check", pnml)
    lines = out.stdout.splitlines()
    # 300 parents out of range, and the tree left with nodes its root does not reach
    assert out.returncode == 1 and len(lines) == 1 + 20 + 1 and lines[-1] == "  and 281 more"
    (tmp_path / "s.cert.json").write_text(json.dumps({**cert, "tasks": []}))
    out = run_cli("analyze", pnml)
    assert out.returncode == 2 and out.stdout == "" and out.stderr == (
        f"{tmp_path / 's.cert.json'}: the certificate is malformed at $.tasks: [] is not of "
        "type 'object'\n")
    assert run_cli("analyze", pnml, "--explore", "--state-space").returncode == 0


@pytest.mark.parametrize("spoil,said", [
    (lambda c: c["trees"]["mission"][1].update(parent=0.0), None),     # JSON's integer 0
    (lambda c: c["trees"]["mission"][1].update(parent=True), "is not of type 'integer'"),
    (lambda c: c["trees"]["mission"][1].update(parent=10**300), "is greater than the maximum"),
    (lambda c: c["trees"]["mission"][1].update(parent=-1.0), "must have one root"),
], ids=["parent 0.0", "parent true", "parent 10**300", "parent -1.0"])
def test_numbers_in_a_certificate_are_read_as_json_means_them(spoil, said):
    """JSON Schema's integers include 1.0, not true: the checker reads 0.0 as the index 0
    and never fails on a number of another type or size."""
    net, cert = _certified(ROOT / "examples" / "sauce.mcl")
    spoil(cert)
    problems = check_certificate(net, cert)
    assert (problems == []) if said is None else any(said in p for p in problems), problems


def test_a_certificate_with_nan_is_not_json(tmp_path):
    from helpers import run_cli
    _, cert = _certified(ROOT / "examples" / "sauce.mcl")
    text = json.dumps(cert).replace('"timeout": 10', '"timeout": NaN')
    (tmp_path / "c.json").write_text(text)
    out = run_cli("certify", tmp_path / "c.json", "--check", ROOT / "examples" / "sauce.mcl")
    assert out.returncode == 2 and "NaN is not a number" in out.stderr, out.stderr
