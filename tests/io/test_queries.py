"""``compile --queries``: a mission's properties in the Model Checking Contest's XML
(mcl2pnml/io/mccquery.py), answered by verifypn and LoLA as our analysis answers them.

Without the peers, the formulas are evaluated here on the markings our
analysis finds (a proper end holds on exactly the dead markings that are
not deadlocks, "no transition fireable" on exactly the dead ones), and the
ids they name are the PNML's. With the peers (tests/support/peers.py), verifypn reads
the file written for it and LoLA the one written for it, on every example
mission from its compiled marking and with an abort pending, on the paper's
mission started without its mutex, on nets of the paper's mission with one
transition taken out (deadlocks, livelocks), and on generated missions;
each answer must be what ``pipeline.analyze`` says.
"""
from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, seed, settings

from mcl2pnml.analysis.statespace.explore import ExplorationLimit
from mcl2pnml import pipeline
from mcl2pnml.core.net import Net
from mcl2pnml.io import ids
from mcl2pnml.io.mccquery import TOOLS, mission_properties, to_queries

import peers
from helpers import ROOT, run_cli
from missions import missions

NS = "{http://mcc.lip6.fr/}"
EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))
SAUCE = ROOT / "examples" / "sauce.mcl"
#: The starts every example is compared from.
STARTS = ("compiled", "abort pending")
#: The most markings of a comparison in `make test`: the larger ones (an abort
#: pending in sampling, 114,620 markings, verifypn 6 s; dam_inspection, 197,331
#: from its compiled marking, 12 s) are the slow variant's.
FAST_STATES = 20_000
#: The slow variant's limit: dam_inspection with an abort pending has 3,105,724
#: markings, where verifypn takes more than 12 minutes (all three answers agree).
SLOW_STATES = 1_000_000
#: Transitions of the paper's mission taken out, one at a time: a net with
#: deadlocks, one with a livelock (deadlock-free, yet no end reachable from
#: some marking), one that still ends properly.
CUT = ("DetectCross.on", "AchieveWayPoint.t05", "GoToWayPoint.achieved")
GENERATED_EXAMPLES = 4
GENERATED_STATES = 5_000


def start(net: Net, name: str) -> Net:
    """``net`` from one of the starts the tests use, written as ``--initial`` takes it."""
    marked = list(net.initial.format())
    if name == "abort pending":
        marked.append("mission.A")
    elif name == "no mutex":
        marked.remove("mission.MTX")
    return net.with_initial(pipeline.parse_marking(",".join(marked), net))


def without(net: Net, transition: str) -> Net:
    """``net`` with one transition and its arcs taken out."""
    return Net(f"{net.name}-{transition}", net.places,
               [t for t in net.transitions if t.id != transition],
               [a for a in net.arcs if transition not in (a.source, a.target)], net.initial)


def expected(result: dict) -> dict[str, bool]:
    """What each property must be, by ``pipeline.analyze``'s keys."""
    return {"deadlock": bool(result["terminal_markings"]),
            "deadlock-not-an-end": not result["deadlock_free"],
            "end-always-reachable": result["final_always_reachable"]}


def analysed(net: Net, max_states: int = 5_000_000) -> dict:
    return pipeline.analyze(net, state_space_only=True, max_states=max_states).as_json()


# -- the formulas, evaluated here --------------------------------------------------------

def _marking(formatted: list[str]) -> dict[str, int]:
    """A marking as the analysis prints it (``P``, ``P*2``)."""
    out = {}
    for item in formatted:
        place, _, count = item.partition("*")
        out[place] = int(count) if count else 1
    return out


def _enabled(net: Net, marking: dict[str, int]) -> set[str]:
    need: dict[str, list] = {t.id: [] for t in net.transitions}
    for a in net.arcs:
        if a.target in need:   # a place's arc into a transition, consumed or read
            need[a.target].append((a.source, a.weight))
    return {t for t, arcs in need.items() if all(marking.get(p, 0) >= w for p, w in arcs)}


def _value(e: ET.Element, marking: dict[str, int]) -> int:
    tag = e.tag.removeprefix(NS)
    if tag == "tokens-count":
        return sum(marking.get(p.text, 0) for p in e)
    assert tag == "integer-constant", tag
    return int(e.text)


def holds(e: ET.Element, marking: dict[str, int], enabled: set[str]) -> bool:
    """A state formula of the contest's language (the operators our files use)."""
    tag = e.tag.removeprefix(NS)
    if tag == "conjunction":
        return all(holds(c, marking, enabled) for c in e)
    if tag == "negation":
        return not holds(e[0], marking, enabled)
    if tag == "integer-le":
        return _value(e[0], marking) <= _value(e[1], marking)
    if tag == "is-fireable":
        return any(t.text in enabled for t in e)
    assert tag == "deadlock", tag
    return not enabled


def _key(net: Net, property_id: str) -> str:
    """A property's id less the net's name: ``deadlock``, ``end-always-reachable``..."""
    prefix = ids.encode(net.name) + "-"
    assert property_id.startswith(prefix), property_id
    return property_id[len(prefix):]


def _formulas(net: Net, tool: str) -> dict[str, ET.Element]:
    root = ET.fromstring(to_queries(mission_properties(net, tool)))
    return {_key(net, p.find(f"{NS}id").text): p.find(f"{NS}formula")[0]
            for p in root.findall(f"{NS}property")}


@pytest.mark.parametrize("case", ["compiled", "abort pending", "no mutex", *CUT])
def test_the_formulas_say_what_the_analysis_counts(case, examples):
    net = examples.net("sauce")
    net = without(net, case) if case in CUT else start(net, case)
    result = analysed(net)
    for tool in TOOLS:
        f = _formulas(net, tool)
        end = f["end-always-reachable"][0][0][0][0]          # AG EF end: the end
        stuck, not_end = f["deadlock-not-an-end"][0][0]       # EF (deadlock and not end)
        improper = [sorted(m) for m in result["deadlocks"]]
        for shown in result["terminal_markings"]:
            m = _marking(shown)
            assert _enabled(net, m) == set()
            assert holds(stuck, m, set()), (tool, shown)
            assert holds(not_end, m, set()) == (sorted(shown) in improper), (tool, shown)
        m0 = dict(net.initial)
        assert holds(stuck, m0, _enabled(net, m0)) == (not _enabled(net, m0))
        assert not holds(end, m0, _enabled(net, m0))      # nothing has ended yet
    assert result["terminal_markings"]


def test_the_forms_differ_in_the_deadlock_inside_a_formula_only(examples):
    net = examples.net("sauce")
    verifypn, lola = _formulas(net, "verifypn"), _formulas(net, "lola")
    assert ET.tostring(verifypn["end-always-reachable"]) == ET.tostring(lola["end-always-reachable"])
    assert ET.tostring(verifypn["deadlock"]) == ET.tostring(lola["deadlock"])
    assert verifypn["deadlock-not-an-end"].find(f".//{NS}deadlock") is not None
    fireable = lola["deadlock-not-an-end"].find(f".//{NS}is-fireable")
    assert sorted(t.text for t in fireable) == sorted(t.id for t in net.transitions)


def test_compile_writes_the_queries_with_the_ids_of_the_pnml(tmp_path):
    r = run_cli("compile", SAUCE, "-o", tmp_path / "sauce.pnml", "--queries",
                tmp_path / "q.xml", "--layout", "none")
    assert r.returncode == 0, r.stderr
    assert (f"wrote {tmp_path / 'q.xml'}: sauce-deadlock, sauce-deadlock-not-an-end, "
            "sauce-end-always-reachable (for verifypn)") in r.stderr
    pnml = (tmp_path / "sauce.pnml").read_text()
    places = set(re.findall(r'<place id="([^"]+)"', pnml))
    transitions = set(re.findall(r'<transition id="([^"]+)"', pnml))
    root = ET.parse(tmp_path / "q.xml").getroot()
    assert root.tag == f"{NS}property-set"
    named = {e.text for e in root.iter(f"{NS}place")}
    assert {"mission.OK", "mission.FAIL", "mission.ABORTED"} <= named <= places
    assert len(named) == len(places) - 2                  # all but mission.B and mission.A
    assert {e.text for e in root.iter(f"{NS}transition")} <= transitions


def test_compile_queries_errors_are_one_line(tmp_path):
    r = run_cli("compile", SAUCE, "-o", tmp_path / "s.pnml", "--queries", tmp_path / "s.pnml")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "--queries" in r.stderr and "a file of their own" in r.stderr
    assert not (tmp_path / "s.pnml").exists()
    r = run_cli("compile", SAUCE, "--queries", tmp_path / "q.xml", "--queries-for", "tina")
    assert r.returncode == 2 and "'tina' is not one of 'verifypn', 'lola'" in r.stderr
    (tmp_path / "ro").mkdir()
    (tmp_path / "ro" / "q.xml").mkdir()                   # a directory where the file goes
    r = run_cli("compile", SAUCE, "-o", tmp_path / "s.pnml", "--queries", tmp_path / "ro" / "q.xml")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert str(tmp_path / "ro" / "q.xml") in r.stderr


# -- the peers ---------------------------------------------------------------------------

def answers(net: Net, folder: Path,
            max_states: int) -> tuple[dict[str, bool], dict[str, bool], dict[str, bool]]:
    """Ours, verifypn's and LoLA's answers on ``net``, keyed by property (its id less the
    net's name). Ours first: past ``max_states`` the peers are not asked. Then the two
    peers at once."""
    peers.need(peers.VERIFYPN), peers.need(peers.LOLA)
    ours = expected(analysed(net, max_states))
    folder.mkdir(parents=True, exist_ok=True)
    pnml = pipeline.save_net(net, folder / "net.pnml", layout="none")
    files = {tool: folder / f"{tool}.xml" for tool in TOOLS}
    count = len(pipeline.save_queries(net, files["verifypn"], "verifypn"))
    pipeline.save_queries(net, files["lola"], "lola")
    with ThreadPoolExecutor(2) as pool:
        v = pool.submit(peers.verifypn_queries, pnml, files["verifypn"], count)
        lola = pool.submit(peers.lola_queries, pnml, files["lola"])
        theirs = v.result(), lola.result()
    return ours, *({_key(net, k): answer for k, answer in t.items()} for t in theirs)


def assert_agree(net: Net, folder: Path, max_states: int = 5_000_000) -> dict[str, bool]:
    ours, verifypn, lola = answers(net, folder, max_states)
    assert verifypn == ours, f"verifypn on {net.name}: {verifypn}, ours {ours}"
    assert lola == ours, f"LoLA on {net.name}: {lola}, ours {ours}"
    return ours


def _every_example(max_states: int, scratch: Path) -> Counter:
    """Each example from each start, compared where it has at most ``max_states`` markings."""
    tally = Counter()
    for example in EXAMPLES:
        net = pipeline.compile_file(example)
        for name in STARTS:
            folder = scratch / f"{example.stem}-{name.replace(' ', '-')}"
            try:
                ours = assert_agree(start(net, name), folder, max_states)
            except ExplorationLimit:
                tally["left to the slow variant"] += 1
                continue
            assert ours == {"deadlock": True, "deadlock-not-an-end": False,
                            "end-always-reachable": True}, (example.name, name)
            tally["compared"] += 1
            tally[example.stem] += 1
    return tally


def test_peers_answer_as_we_do_on_the_examples(tmp_path):
    tally = _every_example(FAST_STATES, tmp_path)
    # every example but the largest from its compiled marking, most with an abort pending
    assert tally["compared"] >= len(EXAMPLES) + 2 and len(tally) >= len(EXAMPLES) + 1, tally


@pytest.mark.slow
def test_peers_answer_as_we_do_on_every_example_from_every_start(tmp_path):
    tally = _every_example(SLOW_STATES, tmp_path)
    assert all(tally[e.stem] >= 1 for e in EXAMPLES), tally
    assert tally["compared"] >= len(EXAMPLES) * len(STARTS) - 1, tally


def test_peers_answer_as_we_do_on_broken_missions(tmp_path, examples):
    net = examples.net("sauce")
    cases = [start(net, "no mutex")] + [without(net, t) for t in CUT]
    seen = Counter()
    for i, case in enumerate(cases):
        ours = assert_agree(case, tmp_path / str(i))
        seen[(ours["deadlock-not-an-end"], ours["end-always-reachable"])] += 1
    # deadlocks, a livelock, and nets that still end: every answer each property can give
    assert set(seen) == {(True, False), (False, False), (False, True)}, seen


def test_peers_answer_as_we_do_on_generated_missions(tmp_path_factory):
    peers.need(peers.VERIFYPN), peers.need(peers.LOLA)
    tally = Counter()

    @seed(0)
    @settings(max_examples=GENERATED_EXAMPLES, deadline=None, database=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
    @given(missions(depth=2, width=2))
    def one(source: str):
        net = pipeline.compile_source(source, "generated.mcl")
        tally["drawn"] += 1
        try:
            for name in ("compiled", "abort pending"):
                assert_agree(start(net, name), tmp_path_factory.mktemp("generated"),
                             GENERATED_STATES)
        except ExplorationLimit:
            assume(False)
        tally["compared"] += 1

    one()
    assert tally["compared"] >= GENERATED_EXAMPLES // 2, tally
