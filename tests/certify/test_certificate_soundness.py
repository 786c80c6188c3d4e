"""The certificate's checker against hostile certificates: whatever it accepts, exploring
confirms.

Generated missions are certified, and their certificates (and with them, where a hostile
hand would, their nets) changed in every way the JSON allows (tests/support/certmutations.py).
A pair the checker refuses is fine; a pair it accepts must describe a net that exploring
finds 1-safe, always able to reach an end, with every dead marking a proper end, and ending
in exactly the conclusion's ends from the start it says. The checker is reached through
the pipeline alone (``certify_file``, ``check_certificate``), and must answer every
certificate with problems or :class:`Mcl2PnmlError`, never another exception.
"""
from __future__ import annotations

import json
import os
import random
from pathlib import Path

import pytest

import certmutations as cm
from helpers import ROOT, run_cli
from sessioncache import shared
from mcl2pnml import pipeline
from mcl2pnml.core.errors import Mcl2PnmlError

#: The pool of the normal run: missions certified from B, and missions that are not (their
#: certificates with an abort pending forged into ones from B), each with an abort too.
SEED, MISSIONS, NEVER_ENDING = 20_261_125, 12, 8
PER_MUTATION = 16
CHAINS = 300

def _drawn() -> tuple[list[cm.Base], int, list]:
    pool, drawn = cm.bases(SEED, MISSIONS, NEVER_ENDING)
    return pool, drawn, [(b.net, cm.explored(b.net)) for b in pool]


@pytest.fixture(scope="session")
def pool(tmp_path_factory) -> tuple[list[cm.Base], int]:
    """The normal run's pool, drawn once per session (each worker that ran one of these
    tests drew and certified it again, several seconds each), with what exploring found of
    its nets (explored while drawing it)."""
    bases, drawn, explored = shared(tmp_path_factory, "soundness-pool",
                                    (SEED, MISSIONS, NEVER_ENDING), _drawn)
    cm.remember(explored)
    return bases, drawn


def test_the_unmutated_certificates_are_accepted_and_the_forged_ones_refused(pool):
    """The campaign's ground: each certificate ``certify`` writes is accepted and is what
    exploring finds (a checker that refuses everything fails here); each forged one, of a
    mission exploring finds may never end, is refused."""
    pool, drawn = pool
    forged = [b for b in pool if b.kind == "forged"]
    assert len(pool) == 2 * (MISSIONS + NEVER_ENDING) and len(forged) == NEVER_ENDING
    for base in pool:
        problems = pipeline.check_certificate(base.net, base.cert())
        if base.kind == "forged":
            assert problems and cm.judged(base.net, base.cert()) is not None, base.text
        else:
            assert base.problems == () and problems == [], (base.kind, base.text, problems)
            assert cm.judged(base.net, base.cert()) is None, (base.kind, base.text)


@pytest.mark.parametrize("name", sorted(cm.MUTATIONS))
def test_a_mutated_certificate_is_accepted_only_where_exploring_agrees(name, pool):
    pool, _ = pool
    tally = cm.campaign(pool, [name], PER_MUTATION, cm.seed_of(name))
    assert tally.pairs == PER_MUTATION, f"{name} applied to only {tally.pairs} pairs"
    assert not tally.broken and not tally.crashes, tally.report()


def test_chains_of_mutations_are_accepted_only_where_exploring_agrees(pool):
    """One to three mutations at once (a renaming in the certificate and the net, then the
    nodes reordered, then the ends...): the checker is seen to accept some, refuse most."""
    pool, _ = pool
    tally = cm.campaign(pool, None, CHAINS, SEED)
    assert tally.pairs == CHAINS and tally.accepted > 0 and tally.refused > 0, tally.summary()
    assert not tally.broken and not tally.crashes, tally.report()


@pytest.mark.slow
def test_a_hundred_thousand_mutated_pairs_are_accepted_only_where_exploring_agrees():
    """The long campaign: 100,000 pairs (``MCL2PNML_SOUNDNESS_PAIRS`` for another count)
    from 200 missions, each mutation alone and in chains."""
    pairs = int(os.environ.get("MCL2PNML_SOUNDNESS_PAIRS", "100000"))
    pool, _ = cm.bases(SEED + 1, max(4, min(120, pairs // 800)), max(2, min(80, pairs // 1200)))
    names = sorted(cm.MUTATIONS)
    single = pairs // 2 // len(names)
    tallies = [cm.campaign(pool, [n], single, cm.seed_of(n, "slow")) for n in names]
    tallies.append(cm.campaign(pool, None, pairs - single * len(names), SEED + 1))
    total = sum(t.pairs for t in tallies)
    broken = [t for t in tallies if t.broken or t.crashes]
    # said with -s (or -rP): what the campaign ran
    print(f"{total} pairs, {sum(t.accepted for t in tallies)} accepted, "
          f"{sum(t.refused for t in tallies)} refused, "
          f"{sum(t.too_large for t in tallies)} too large to explore")
    assert total >= pairs * 0.95, total
    assert not broken, f"{total} pairs, {sum(t.accepted for t in tallies)} accepted\n" + \
        "\n".join(t.report(1) for t in broken)


def _verifypn_confirms(tmp_path, pool, pairs: int, sample: int, seed: int) -> int:
    """``sample`` accepted pairs of ``pairs`` mutated ones (one net each), as verifypn
    (reductions off) sees them: 1-safe, an end always reachable, no dead marking that is no
    proper end, and a dead marking with each result exactly when the certificate lists it
    among its ends. The number confirmed."""
    import peers
    from mcl2pnml.io import ids
    from mcl2pnml.io.mccquery import Element, Property, mission_properties, to_queries
    peers.need(peers.VERIFYPN)
    tally = cm.campaign(pool, None, pairs, seed)
    chosen, seen = [], set()
    for net, cert in tally.accepted_pairs:
        if net not in seen:
            seen.add(net)
            chosen.append((net, cert))
    chosen = random.Random(seed).sample(chosen, min(sample, len(chosen)))
    assert chosen, tally.summary()

    def e(tag, *children):
        return Element(tag, tuple(children))

    def at_most(places, n):
        return e("integer-le", e("tokens-count", *(Element("place", text=ids.encode(p))
                                                   for p in places)),
                 Element("integer-constant", text=str(n)))

    def at_least_one(place):
        return e("integer-le", Element("integer-constant", text="1"),
                 e("tokens-count", Element("place", text=ids.encode(place))))
    for k, (net, cert) in enumerate(chosen):
        pnml = pipeline.save_net(net, tmp_path / f"n{k}.pnml", layout="none")
        ends = ("mission.OK", "mission.FAIL", "mission.ABORTED")
        props = (*mission_properties(net),
                 Property("safe", "AG every place holds one token at most", e(
                     "all-paths", e("globally", e("conjunction", *(
                         at_most([p.id], 1) for p in net.places))))),
                 *(Property(f"ends-{end}", f"EF (deadlock and {end})", e(
                     "exists-path", e("finally", e("conjunction", e("deadlock"),
                                                   at_least_one(end)))))
                   for end in ends))
        queries = tmp_path / f"q{k}.xml"
        queries.write_text(to_queries(props))
        said = peers.verifypn_queries(pnml, queries, len(props))
        assert said.get("safe") is True, (said, cert.get("conclusion"))
        assert [v for key, v in said.items() if key.endswith("end-always-reachable")] == \
            [True], said
        assert [v for key, v in said.items() if key.endswith("deadlock-not-an-end")] == \
            [False], said
        assert {end for end in ends if said.get(f"ends-{end}")} == \
            set(cert["conclusion"]["ends"]), (said, cert["conclusion"]["ends"])
    return len(chosen)


def test_verifypn_confirms_a_sample_of_the_accepted_pairs(tmp_path, pool):
    assert _verifypn_confirms(tmp_path, pool[0], 300, 6, SEED + 2) >= 3


@pytest.mark.slow
def test_verifypn_confirms_two_hundred_accepted_pairs(tmp_path):
    # a pool of 400 missions and starts: most accepted pairs keep their base's net
    pool, _ = cm.bases(SEED + 3, 120, 80)
    assert _verifypn_confirms(tmp_path, pool, 20_000, 200, SEED + 3) >= 150


# -- the eight ways of the issue, each by name ---------------------------------------------

#: A mission whose loop never ends once A(1) has ended OK: Idle() can only end OK.
LOOP = ("primitive P(v);\ntask A(x) = AchieveGoal(P(x)) timeout 5;\nfunction Idle() { }\n"
        "mission { A(1); while (Idle()) { } }\n")


def _stripped():
    """LOOP's certificate with an abort pending, made to look like one from mission.B, and
    the net from B: exploring finds it may never end."""
    cert, net, problems = cm.certified(LOOP, abort_pending=True)
    assert problems == []
    cert, net = cm.forged(cert, net)
    assert cm.judged(net, cert) is not None
    return cert, net


def _refused(net, cert) -> list[str]:
    """What the checker says (never a crash); the pair is also confirmed hostile."""
    assert cm.judged(net, cert) is not None, "the pair is not hostile: exploring agrees"
    try:
        return pipeline.check_certificate(net, cert)
    except Mcl2PnmlError as e:
        return [str(e)]


def _node(cert, name: str) -> int:
    return next(k for k, n in enumerate(cert["trees"]["mission"]) if n["instance"] == name)


def test_1_a_root_listed_after_its_children_is_refused():
    cert, net = _stripped()
    nodes = cert["trees"]["mission"]
    order = [*range(1, len(nodes)), 0]
    at = {old: new for new, old in enumerate(order)}
    cert["trees"]["mission"] = [dict(nodes[k], parent=at.get(nodes[k]["parent"], -1))
                                for k in order]
    assert _refused(net, cert)


def test_2_the_mission_s_tree_under_another_key_is_refused():
    cert, net = _stripped()
    cert["trees"]["main"] = cert["trees"].pop("mission")
    assert _refused(net, cert)


def test_3_a_decoy_repeating_an_instance_s_name_is_refused():
    """A call of A named as the loop's condition, listed between the loop and its real
    condition: read bottom-up, it is the condition the loop is derived from."""
    cert, net = _stripped()
    nodes = cert["trees"]["mission"]
    condition = next(k for k, n in enumerate(nodes) if n.get("callee") == "Idle")
    decoy = {"instance": nodes[condition]["instance"], "rule": "call", "callee": "A",
             "parent": -1, "results": ["OK", "FAIL"]}
    cert["trees"]["mission"] = cm._inserted(nodes, condition, decoy)
    # the ends the loop would give on a condition that can fail
    cert["conclusion"]["ends"] = ["mission.OK", "mission.FAIL"]
    assert _refused(net, cert)


def test_4_two_call_sites_renamed_to_one_with_the_net_to_match_are_refused():
    """Two branches of a parallel each start their first call: named one, in the
    certificate and the net, both branches start the same call site (two tokens)."""
    text = LOOP.replace("A(1); while (Idle()) { }", "parallel({ A(1); A(2); }, { A(3); A(4); });")
    cert, net, problems = cm.certified(text)
    assert problems == []
    nodes = cert["trees"]["mission"]
    first, third = _node(cert, "A-1"), _node(cert, "A-3")
    assert nodes[first]["parent"] != nodes[third]["parent"]
    nodes[third]["instance"] = "A-1"
    net = cm.prefix_renamed(net, "A-3", "A-1")
    assert "two tokens" in cm.judged(net, cert)
    assert _refused(net, cert)


def test_5_slots_in_another_order_than_the_children_with_the_net_to_match_are_refused():
    """``while (A(1)) { Idle(); }`` with the loop's slots listed T2, T1 and its arcs to its
    two children exchanged: the net is ``while (Idle()) { A(1); }``, which can end only
    FAIL, while the certificate reads it as the loop it was, ending only OK."""
    text = LOOP.replace("A(1); while (Idle()) { }", "while (A(1)) { Idle(); }")
    cert, net, problems = cm.certified(text)
    assert problems == [] and cert["conclusion"]["ends"] == ["mission.OK"]
    got = None
    for k in range(50):     # the mutation exchanges the two slots (the only other order)
        got = cm.MUTATIONS["slots reordered, net too"](json.loads(json.dumps(cert)), net,
                                                       random.Random(k))
        if got is not None:
            break
    cert, net = got
    assert _node(cert, "mission") == 0 and cert["trees"]["mission"][0]["slots"] == ["T2", "T1"]
    assert _refused(net, cert)


def test_6_an_empty_start_with_mission_b_unmarked_is_refused():
    cert, net, problems = cm.certified(LOOP.replace("while (Idle()) { }", ""))
    assert problems == []
    cert["start"] = []
    net = net.with_initial({p: n for p, n in net.initial.items() if p != "mission.B"})
    assert _refused(net, cert)


#: A user's pattern that ends OK and may then take its own OK back and end FAIL: alone it
#: only ever ends FAIL, but a caller may take the OK first.
FLAKY = (ROOT / "templates" / "achieve_goal.pnt").read_text().replace(
    "pattern AchieveGoal alias task", "pattern AchieveFlaky") + \
    'transition t12: OK -> FAIL      "takes its own OK back"\n'
FLAKY_MISSION = """primitive P(v);
task U(x) = AchieveFlaky(P(x)) timeout 5;
function Idle() { }
mission {
    while (U(1)) { while (Idle()) { } }
}
"""


def _flaky(tmp_path):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "achieve_flaky.pnt").write_text(
        FLAKY.replace('pattern AchieveFlaky "', 'pattern AchieveFlaky "flaky: '))
    mission = tmp_path / "m.mcl"
    mission.write_text(FLAKY_MISSION)
    return mission, {**os.environ, "MCL2PNML_TEMPLATE_PATH": str(folder)}


def _explored_cli(path, env) -> dict:
    out = run_cli("analyze", path, "--state-space", "--json", "--explore", env=env)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def test_7_a_user_s_pattern_that_takes_its_own_ok_back_is_not_certified(tmp_path):
    mission, env = _flaky(tmp_path)
    out = run_cli("certify", mission, env=env)
    assert "Traceback" not in out.stderr
    # the contract (version 2, ``result final``) refuses the pattern itself, with its run
    assert out.returncode == 2 and out.stdout == "", out.stderr
    assert "template 'AchieveFlaky' breaks the interface contract" in out.stderr
    assert "result final: from rest + B" in out.stderr and "t12 can still fire" in out.stderr
    assert not (tmp_path / "m.cert.json").exists()
    # compiling refuses it too: a user's template is proven when it is used
    pnml = tmp_path / "m.pnml"
    compiled = run_cli("compile", mission, "-o", pnml, env=env)
    assert compiled.returncode == 2 and "AchieveFlaky" in compiled.stderr


def _flaky_net(tmp_path):
    """The net FLAKY_MISSION compiles to, made by hand: AchieveGoal's with t12 added to the
    task (the compiler need not accept the pattern for a hostile file to hold its net)."""
    from mcl2pnml.core.net import Arc, Transition
    net = pipeline.compile_source(FLAKY_MISSION.replace("AchieveFlaky", "AchieveGoal"), "m.mcl")
    return cm.rebuilt(net, arcs=(*net.arcs, Arc("U.OK", "U.t12"), Arc("U.t12", "U.FAIL")),
                      transitions=(Transition("U.t12"),))


def test_8_analyze_does_not_take_such_a_certificate_for_the_net(tmp_path):
    """``analyze NET`` with a certificate beside it reports the certificate's facts only if
    they hold: here exploring finds an end not always reachable, so analyze must not say
    otherwise (refusing the certificate, or the template, is fine)."""
    mission, env = _flaky(tmp_path)
    pnml = tmp_path / "m.pnml"
    made = run_cli("certify", mission, env=env)
    if made.returncode == 0 and run_cli("compile", mission, "-o", pnml,
                                        env=env).returncode == 0:
        cert = json.loads((tmp_path / "m.cert.json").read_text())
    else:
        # certify refuses it: the certificate is forged from the plain pattern's (with an
        # abort pending, stripped: from B the plain mission is not certified either)
        cert, net, _ = cm.certified(FLAKY_MISSION.replace("AchieveFlaky", "AchieveGoal"), True)
        cert, _ = cm.forged(cert, net)
        cert["conclusion"]["ends"] = ["mission.OK"]
        cert["tasks"]["U"].update(pattern="AchieveFlaky", subject="AchieveFlaky")
        pipeline.save_net(_flaky_net(tmp_path), pnml, layout="none")
    (tmp_path / "m.cert.json").write_text(json.dumps(cert))
    out = run_cli("analyze", pnml, "--state-space", "--json", env=env)
    assert "Traceback" not in out.stderr
    if out.returncode == 0:
        said = json.loads(out.stdout)
        assert said["final_always_reachable"] is False, out.stderr


# -- a user's generated patterns -------------------------------------------------------------

#: Places of a pattern a generated transition may take or give, and the primitive's
#: interface places it may read (as the library's patterns do).
_OWN = ["B", "A", "MTX", "OK", "FAIL", "ABORTED", "EXE", "E_OK", "E_FAIL", "W_OK", "W_FAIL",
        "W_A"]
_GIVEN = [*_OWN, "E", "D"]
_READ = ["?ON", "?OFF", "?S1", "?S2"]


def _pattern(rng: random.Random, name: str) -> str:
    """AchieveGoal changed at random into the pattern ``name``: transitions dropped, added
    (between its own places, perhaps reading the primitive) or given another output."""
    return _changed(rng, "achieve_goal.pnt", f'pattern {name} "generated"', _OWN, _GIVEN,
                    _READ)


#: A generated sequence's transitions take and give its own places and its children's
#: interface places (the mutex too: the contract's caller clause must catch that).
_SEQ_OWN = ["B", "A", "MTX", "OK", "FAIL", "ABORTED", "RUN1", "RUN2", "ABT1", "ABT2"]
_SEQ_CHILD = [f"T{k}_{p}" for k in (1, 2) for p in ("B", "A", "OK", "FAIL", "ABORTED", "MTX")]


def _sequence(rng: random.Random, name: str) -> str:
    """The sequence changed at random: a user's ``sequence.pnt`` takes the package's place
    in every block of a mission."""
    del name
    return _changed(rng, "sequence.pnt", 'structure sequence "generated"',
                    _SEQ_OWN + _SEQ_CHILD, _SEQ_OWN + _SEQ_CHILD, [])


def _changed(rng: random.Random, file: str, header: str, takes, gives, reads) -> str:
    """The package's template ``file`` with its header line ``header`` and one to three
    changes: a transition dropped, one added (taking ``takes``, perhaps reading ``reads``,
    giving ``gives``), or an output of one replaced."""
    lines = (ROOT / "templates" / file).read_text().splitlines()
    kind = header.split()[0]
    lines = [header if ln.startswith(f"{kind} ") else ln
             for ln in lines if not ln.startswith("#")]
    transitions = [k for k, ln in enumerate(lines) if ln.startswith("transition ")]
    for step in range(rng.randint(1, 3)):
        roll = rng.random()
        if roll < 0.3 and transitions:
            lines[rng.choice(transitions)] = ""
        elif roll < 0.7:
            ins = rng.sample(takes, rng.randint(1, 2)) + \
                (rng.sample(reads, rng.randint(0, 1)) if reads else [])
            outs = rng.sample(gives, rng.randint(1, 2))
            lines.append(f"transition g{step}: {', '.join(ins)} -> {', '.join(outs)}")
        elif transitions:
            k = rng.choice(transitions)
            head, _, out = lines[k].partition("->")
            words = out.split('"')[0].split()
            if words:
                words[rng.randrange(len(words))] = rng.choice(gives) + \
                    ("," if words[-1] != words[0] else "")
                lines[k] = f"{head}-> {' '.join(words).rstrip(',')}"
    return "\n".join(lines) + "\n"


#: Missions that put a user's pattern U where what it gives matters: a loop's condition
#: (one on a body that never ends too), a branch, beside a task, and under a monitor.
_PROBES = ["while (U(1)) { A(2); }", "while (U(1)) { while (E()) { } }",
           "if (U(1)) then { A(1); } else { E(); }", "parallel(U(1), A(2));",
           "monitor(U(1), A(2));", "monitor(A(2), U(1));", "U(1); U(2);"]

#: Missions whose blocks are sequences: a user's sequence where it starts, is aborted,
#: loops, runs beside another and holds a loop that never ends.
_SEQ_PROBES = ["A(1); A(2);", "while (A(1)) { A(2); A(3); }",
               "parallel({ A(1); F(2); }, A(3));", "monitor({ A(1); E(); }, A(2));",
               "if (A(1)) then { A(2); F(3); } else { E(); }", "A(1); while (E()) { }"]

#: What each kind of generated template is: its maker, its file and name, how its net is
#: checked against the contract, and the missions it is tried in.
_USER = {
    "pattern": (_pattern, lambda k: (f"gen{k}.pnt", f"Gen{k}"), (), _PROBES),
    "sequence": (_sequence, lambda k: ("sequence.pnt", "sequence"), ("T1_", "T2_"),
                 _SEQ_PROBES),
}


def _parse_package_templates_once(monkeypatch, ours: Path) -> None:
    """Each library loaded below parses the package's templates again (two thirds of the
    time of sixty candidates): the same file read back is the same template, so the
    package's files are parsed once; every generated file is still loaded as a user's is."""
    from mcl2pnml.language import library
    real, parsed = library.load_template, {}

    def load_template(path, *args):
        path = Path(path)
        if path.parent != ours:
            return real(path, *args)
        key = (path, path.read_bytes(), args)
        if key not in parsed:
            parsed[key] = real(path, *args)
        return parsed[key]
    monkeypatch.setattr(library, "load_template", load_template)


def _user_templates(tmp_path, monkeypatch, kind: str, candidates: int, used: int,
                    seed: int) -> tuple[int, int, cm.Tally]:
    """``candidates`` generated templates of ``kind``, those that keep the contract kept,
    ``used`` of them put in missions as a user's template: (kept, certified, tally)."""
    from mcl2pnml.analysis.checking.contract import check_contract as contract
    from mcl2pnml.language.library import Library, default_library
    make, named, children, probes = _USER[kind]
    rng = random.Random(seed)
    ours = ROOT / "templates"
    _parse_package_templates_once(monkeypatch, ours)
    kept, tally, certified_ = [], cm.Tally(), 0
    for k in range(candidates):
        folder = tmp_path / f"t{k}"
        folder.mkdir()
        file, name = named(k)
        (folder / file).write_text(make(rng, name))
        try:
            lib = Library.load([ours, folder])
            verdict = contract(lib.composed(name), children=children)
        except Mcl2PnmlError:
            continue
        if verdict.kept:
            kept.append((folder, name))
    try:
        for folder, name in kept[:used]:
            monkeypatch.setenv("MCL2PNML_TEMPLATE_PATH", str(folder))
            default_library.cache_clear()
            for body in probes:
                text = cm.HEADER + f"task U(x) = {name}(Pa(x)) timeout 3;\n" * (
                    kind == "pattern") + f"mission {{ {body} }}\n"
                for pending in (False, True):
                    try:
                        cert, net, problems = cm.certified(text, pending)
                    except Mcl2PnmlError:
                        continue        # not certified (or the template refused): fine
                    certified_ += not problems
                    base = cm.Base(text, "abort pending" if pending else "from B", net,
                                   json.dumps(cert))
                    cm.judge(tally, base, [f"user {kind} {folder.name}"], cert, net)
    finally:
        monkeypatch.delenv("MCL2PNML_TEMPLATE_PATH")
        default_library.cache_clear()
    return len(kept), certified_, tally


@pytest.mark.parametrize("kind", sorted(_USER))
def test_generated_user_templates_that_keep_the_contract_are_certified_only_as_explored(
        kind, tmp_path, monkeypatch):
    """Random patterns of one primitive slot, and random sequences (a user's file in the
    package's place), those whose net keeps the contract kept, each a user's template
    (``$MCL2PNML_TEMPLATE_PATH``) in missions that use it: a certificate the checker
    accepts is what exploring finds (one of them in the missions here, each one kept of
    thousands behind ``slow``)."""
    kept, certified_, tally = _user_templates(tmp_path, monkeypatch, kind, 60, 1, SEED)
    assert kept >= 3, f"only {kept} of 60 generated {kind}s keep the contract"
    assert certified_ > 0, f"no mission on {kept} generated {kind}s was certified"
    assert not tally.broken and not tally.crashes, tally.report()


@pytest.mark.slow
@pytest.mark.parametrize("kind", sorted(_USER))
def test_thousands_of_generated_user_templates_are_certified_only_as_explored(
        kind, tmp_path, monkeypatch):
    """The long run: 3,000 candidates of each kind, every one that keeps the contract put
    in the missions."""
    kept, certified_, tally = _user_templates(tmp_path, monkeypatch, kind, 3_000, 3_000,
                                              SEED + 7)
    print(f"{kind}: {kept} of 3,000 keep the contract; {certified_} missions certified; "
          f"{tally.summary()}")
    assert kept >= 30 and certified_ > 0, (kept, certified_)
    assert not tally.broken and not tally.crashes, tally.report()


def test_a_user_pattern_an_idle_task_of_which_reads_its_primitive_is_refused(tmp_path):
    """Found by the generated user patterns: AchieveGoal with ``g0: MTX, ?S1 -> OK``
    keeps every clause read on its own markings (at rest its primitive is off), but in
    ``parallel(U(1), A(2))`` the task A drives the primitive both share to S1 while U is at
    rest, and U ends OK with nobody having called it: two tokens in a place. The lock keeps
    two tasks' runs apart, not what an idle task reads; the contract's ``asleep`` clause
    (each own transition needs B or an own place empty at rest) refuses the pattern."""
    folder = tmp_path / "mine"
    folder.mkdir()
    text = (ROOT / "templates" / "achieve_goal.pnt").read_text().replace(
        "pattern AchieveGoal alias task", "pattern Woken") + "transition g0: MTX, ?S1 -> OK\n"
    (folder / "woken.pnt").write_text(text)
    mission = tmp_path / "m.mcl"
    mission.write_text(cm.HEADER + "task U(x) = Woken(Pa(x)) timeout 3;\n"
                       "mission { parallel(U(1), A(2)); }\n")
    env = {**os.environ, "MCL2PNML_TEMPLATE_PATH": str(folder)}
    out = run_cli("certify", mission, env=env)
    assert out.returncode == 2 and "Traceback" not in out.stderr, out.stderr
    assert "template 'Woken' breaks the interface contract" in out.stderr
    assert "asleep: from the net, after (no firing): g0 needs neither B nor a place of its " \
           "own that is empty at rest" in out.stderr
    # what it would have certified: the same net, made by hand, is not 1-safe
    net = pipeline.compile_source(mission.read_text().replace("Woken", "AchieveGoal"), "m.mcl")
    from mcl2pnml.core.net import Arc, ArcKind, Transition
    net = cm.rebuilt(net, arcs=(*net.arcs, Arc("U.MTX", "U.g0"),
                                Arc("Pa.S1", "U.g0", kind=ArcKind.READ),
                                Arc("U.g0", "U.OK")), transitions=(Transition("U.g0"),))
    assert cm.judged(net, json.loads(json.dumps(cm.certified(
        mission.read_text().replace("Woken", "AchieveGoal"))[0]))) is not None
