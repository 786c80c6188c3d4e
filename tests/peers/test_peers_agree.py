"""TAPAAL's verifypn and LoLA, run on every net we write, against every explorer of ours.

Each net is written as PNML and as LoLA text by our writers and handed to
the tools (``peers.py`` finds them and says how each is asked):

* with their reductions off, verifypn (the PNML) and LoLA (the PNML and the
  ``.lola`` file) must count the markings our explorers count and answer
  ``EF deadlock`` as our explorers find a dead marking or not;
* with their reductions on (verifypn's defaults: structural reductions and
  stubborn sets; LoLA's deadlock check with its defaults), the same verdict.

The nets: every template as the paper analyses it, from its M0; every
example mission from ``mission.B`` and again with an abort pending (a token
in ``mission.A``, as ``analyze --initial`` would start it); generated
missions (``missions.py``) from both starts; generated P/T nets
(``strategies.py``: weights, read arcs, several tokens a place, ids that are
neither XML nor LoLA names), and generated nets that no transition adds
tokens to (bounded whatever their arcs; up to some hundreds of markings,
some running for ever, some dying). A mission always has a dead marking, its proper end
(a result place marked, nothing enabled), so its verdict is TRUE; the
generated nets give both verdicts, and the tests check that both come up.

Our side: every explorer of ``mcl2pnml.analysis.statespace.explorers.CHOICES`` that applies to
the net (``auto``; the safe-net ones on a safe net with unit weights; the
counter one on a bounded net; the general one), which must first agree with
each other. The counter and general explorers start by computing the
minimal semi-positive P-invariants, which took 0.5 to 25 s on most generated
missions of 75 to 230 places (Farkas' algorithm up to its 20,000-row
limit): in ``make test`` they run on nets of at most ``SMALL`` places, in
the slow variants on every net of at most ``HEAVY_STATES`` markings.

A peer call is short (10 to 20 ms on these nets) and a net takes nine, so
the calls run on a pool of threads, one per core, while this process
explores the next net. A net our explorers cannot finish within the state
limit, or find unbounded, is not handed to the tools (their full
exploration would not end); the tallies make sure that most nets are judged.
"""
from __future__ import annotations

import os
import random
import re
import subprocess
from collections import Counter
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import pytest
from hypothesis import HealthCheck, given, seed, settings, strategies as st

import peers
from helpers import ROOT
from sampling import sample, variants
from missions import missions
from strategies import ids, nets
from mcl2pnml.analysis.statespace.explorers import CHOICES, EXPLORERS
from mcl2pnml.analysis.statespace.explore import ExplorationLimit
from mcl2pnml import pipeline
from mcl2pnml.core.net import ArcKind, Net, NetBuilder
from mcl2pnml.io.lola import to_lola

EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))
#: The example the quick suite hands the peers: the paper's mission (the others, which reach
#: no line or branch of ours that it and the generated missions do not, in ``make test-slow``)
QUICK_EXAMPLES = {"sauce"}
#: Examples whose state space from some start is in the millions: slow variant only.
LARGE_EXAMPLES = {"dam_inspection"}
#: The place a mission's abort arrives in (mcl.md's mission.A).
ABORT = "mission.A"
#: Nets up to this many places get the counter and general explorers in `make test`.
SMALL = 40
#: In the slow variants, the counter and general explorers up to this many markings
#: (the general one holds each marking as a Python tuple: millions would take minutes).
HEAVY_STATES = 200_000
#: Generated nets past this many markings are discarded (and counted).
MAX_STATES = 20_000
#: Generated missions and nets of each kind judged in `make test`, and their seed.
FAST_MISSIONS, FAST_NETS, FAST_SEED = sample(25, 12), sample(60, 30), 0
#: The slow variants: chunks of generated missions and nets, each chunk its own seed,
#: and the missions judged by every explorer whatever their size.
SLOW_CHUNKS, SLOW_MISSIONS, SLOW_NETS, EVERY_EXPLORER_MISSIONS = 4, 500, 500, 20
#: The share of drawn nets that must be judged (not over the state limit, not unbounded):
#: deep missions pass the state limit more often (one in seven), a third of
#: strategies.py's nets may be unbounded, none of ours.
MIN_JUDGED = {"missions": 0.9, "deep missions": 0.8, "any": 0.5, "bounded": 1.0}
WORKERS = max(2, os.cpu_count() or 2)


@dataclass(frozen=True)
class Case:
    """One net to judge, started from the marking to explore."""

    label: str
    net: Net
    #: how its PNML is laid out (positions change nothing for the tools; `none` is fast)
    layout: str = "none"
    #: the counter and general explorers too, whatever the net's size
    every: bool = False
    #: the MCL of a generated mission, shown when it fails
    source: str = ""


@dataclass(frozen=True)
class Facts:
    """What one exploration says that the tools say too."""

    states: int
    bounded: bool
    #: a dead marking is reachable: EF deadlock, as every tool reads it (a mission's
    #: proper end is one; the report's ``deadlock_free`` leaves those out)
    dead: bool


class Question(NamedTuple):
    """One peer call: which tool, on which file, asked what, with its reductions or not."""

    tool: str
    file: str
    what: str
    reductions: bool

    def __str__(self) -> str:
        return (f"{self.tool} on the {self.file} file, {self.what}, "
                f"reductions {'on' if self.reductions else 'off'}")

    def ask(self, files: dict[str, Path], scratch: Path):
        path = files[self.file]
        if self.tool == peers.VERIFYPN:
            if self.what == "states":
                return peers.verifypn_states(path)
            # a query file a call: the two verifypn deadlock calls run at once
            folder = scratch / f"query-{self.reductions}"
            folder.mkdir(exist_ok=True)
            return peers.verifypn_deadlock(path, folder, reductions=self.reductions)
        if self.what == "states":
            return peers.lola_states(path)
        return peers.lola_deadlock(path, reductions=self.reductions)

    def ours(self, facts: Facts):
        return facts.states if self.what == "states" else facts.dead


QUESTIONS = (
    Question(peers.VERIFYPN, "pnml", "states", False),
    Question(peers.VERIFYPN, "pnml", "deadlock", False),
    Question(peers.VERIFYPN, "pnml", "deadlock", True),
    *(Question(peers.LOLA, f, what, r)
      for f in ("pnml", "lola") for what, r in (("states", False), ("deadlock", False),
                                                 ("deadlock", True))),
)


# -- our side -------------------------------------------------------------------------


def _facts(result: dict) -> Facts:
    return Facts(result["states"], result["bounded"], bool(result["terminal_markings"]))


def explorers_for(net: Net, auto: dict, every: bool) -> list[str]:
    """The explorers of CHOICES that apply to ``net``, besides ``auto``.

    A safe-net explorer asked for another net, or the counter one for a net
    that may be unbounded, hands over to the next one: it would be judged on
    nothing of its own. The others (counter, general) are left out of large
    nets unless ``every`` (see the module's documentation).
    """
    unit = all(a.weight == 1 for a in net.arcs)
    heavy = every and auto["bounded"] and auto["states"] <= HEAVY_STATES
    chosen = []
    for name in CHOICES:
        e = EXPLORERS.get(name)
        if e is None or not e.can_run():
            continue
        if e.safe_only and not (unit and auto["safe"]):
            continue
        if name == "counters" and not auto["bounded"]:
            continue
        if not e.safe_only and not (heavy or len(net.places) <= SMALL):
            continue
        chosen.append(name)
    return chosen


def explore_all(case: Case, max_states: int | None) -> tuple[Facts | None, list[str]]:
    """Our facts (None past ``max_states``), and where our explorers disagree."""
    limit = {} if max_states is None else {"max_states": max_states}
    try:
        auto = pipeline.analyze(case.net, state_space_only=True, **limit).as_json()
    except ExplorationLimit:
        return None, []
    facts, wrong = _facts(auto), []
    for name in explorers_for(case.net, auto, case.every):
        other = _facts(pipeline.analyze(case.net, state_space_only=True, explorer=name).as_json())
        if other != facts:
            wrong.append(f"{case.label}: explorer {name} finds {other}, auto {facts}")
    return facts, wrong


# -- the tools' side ------------------------------------------------------------------


def write(case: Case, folder: Path) -> dict[str, Path]:
    """The net as PNML and as LoLA text: the bytes ``save_net`` writes, without its fsync
    (hundreds of nets, two files each)."""
    folder.mkdir(parents=True, exist_ok=True)
    pnml, lola = folder / "net.pnml", folder / "net.lola"
    pnml.write_bytes(pipeline.to_pnml_bytes(case.net, case.layout))
    lola.write_bytes(to_lola(case.net).encode("utf-8"))     # as write_lola encodes it
    return {"pnml": pnml, "lola": lola}


def lola_never_ends(net: Net, facts: Facts) -> bool:
    """Whether ``net`` is one that this LoLA build explores for ever.

    A net of two places or more where no transition changes the marking
    (each consumes what it produces, or has no arcs at all) and one is
    enabled: its one marking, with a loop on itself, is all there is, yet
    LoLA's full exploration and its ``EF DEADLOCK`` search never end (with
    one place, or none enabled, they do). verifypn and our explorers find
    the one marking.
    """
    if len(net.places) < 2 or facts.dead:
        return False
    for t in net.transitions:
        consume: Counter = Counter()
        produce: Counter = Counter()
        for a in net.pre[t.id]:
            consume[a.source] += a.weight
            if a.kind is ArcKind.READ:
                produce[a.source] += a.weight
        for a in net.post[t.id]:
            produce[a.target] += a.weight
        if consume != produce:
            return False
    return True


def _answer(question: Question, files: dict[str, Path], scratch: Path):
    try:
        return question.ask(files, scratch)
    except subprocess.TimeoutExpired:
        return f"no answer within {peers.TIMEOUT:.0f} s"


@dataclass
class Judgement:
    """What a batch of nets came to: counts, and every disagreement said in full."""

    tally: Counter
    disagreements: list[str]

    def check(self) -> None:
        shown = "\n\n".join(self.disagreements[:10])
        more = len(self.disagreements) - 10
        assert not self.disagreements, (
            f"{len(self.disagreements)} disagreements ({dict(self.tally)}):\n\n{shown}"
            + (f"\n\n... and {more} more" if more > 0 else ""))


def need_peers() -> None:
    """Both tools, or the test skips saying which is missing and why."""
    peers.need(peers.VERIFYPN)
    peers.need(peers.LOLA)


def judge(cases, scratch: Path, max_states: int | None = None) -> Judgement:
    """Each case explored by us, written, and asked of the tools; every answer compared."""
    need_peers()
    tally: Counter = Counter()
    wrong: list[str] = []
    asked: list[tuple[Case, Facts, Path, dict[Question, Future]]] = []
    with ThreadPoolExecutor(WORKERS) as pool:
        for k, case in enumerate(cases):
            facts, disagree = explore_all(case, max_states)
            wrong += disagree
            if facts is None:
                tally["over the state limit"] += 1
                continue
            if not facts.bounded:
                tally["unbounded"] += 1
                continue
            folder = scratch / f"{k:05d}"
            files = write(case, folder)
            questions = QUESTIONS
            if lola_never_ends(case.net, facts):
                questions = tuple(q for q in QUESTIONS if q.tool != peers.LOLA)
                tally["LoLA left out: one marking, looping on itself"] += 1
            asked.append((case, facts, folder, {
                q: pool.submit(_answer, q, files, folder) for q in questions}))
            tally["judged"] += 1
            tally["states"] += facts.states
            tally["dead" if facts.dead else "live"] += 1
        for case, facts, folder, answers in asked:
            for q, future in answers.items():
                theirs, ours = future.result(), q.ours(facts)
                if theirs != ours:
                    wrong.append(f"{case.label}: {q}: {theirs}; ours {ours} "
                                 f"(files in {folder})" + (f"\n{case.source}" if case.source
                                                           else ""))
    return Judgement(tally, wrong)


# -- the nets -------------------------------------------------------------------------


def pending_abort(net: Net) -> Net:
    """The mission started with an abort already pending, written as ``--initial`` takes it."""
    text = ",".join([*net.initial.format(), ABORT])
    return net.with_initial(pipeline.parse_marking(text, net))


def mission_cases(label: str, net: Net, source: str = "", layout: str = "none",
                  every: bool = False) -> list[Case]:
    """A mission from ``mission.B``, and with an abort pending."""
    return [Case(f"{label} from mission.B", net, layout, every, source),
            Case(f"{label} with {ABORT} pending", pending_abort(net), "none", every, source)]


def drawn(strategy, examples: int, chunk: int) -> list:
    """``examples`` draws of ``strategy``, from seed ``chunk``: the same ones every run."""
    found: list = []

    @settings(max_examples=examples, deadline=None, database=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
    @given(strategy)
    def one(value):
        found.append(value)

    seed(chunk)(one)()
    return found


#: Small missions: many nets and short peer calls (about 1,500 markings a start).
SMALL_MISSIONS = missions(depth=2, width=2, function_depth=1).filter(
    lambda s: s.count("parallel(") + s.count("monitor(") <= 1)
#: The slow variant's: as deep as tests/language/test_generated_missions.py draws them.
DEEP_MISSIONS = missions(depth=3, width=2, function_depth=1).filter(
    lambda s: s.count("parallel(") + s.count("monitor(") <= 2)


@st.composite
def bounded_nets(draw, max_places: int = 6, max_transitions: int = 6) -> Net:
    """A net no transition adds tokens to: each puts back at most what it takes, so
    M0's tokens bound every marking whatever the arcs. Weights, read arcs (some of
    a place the transition also fills), several tokens a place, ids of every kind.

    The ids are drawn as strategies.py draws them; the shape comes from a
    random generator seeded by a drawn number, since Hypothesis's own draws
    (its randoms too) lean to the smallest choice, which here is a net of one
    or two markings.
    """
    rng = random.Random(draw(st.integers(0, 2**32 - 1)))
    size = rng.randint(3, max_places) + rng.randint(3, max_transitions)
    names = draw(st.lists(ids, min_size=size, max_size=size, unique=True))
    places, transitions = names[:size // 2], names[size // 2:]
    b = NetBuilder(draw(ids))
    # half the nets put back all they take (they may run for ever), half may lose tokens
    lossy = rng.random() < 0.5
    for p in places:
        b.place(p, rng.choice([0, 1, 2, 3]))
    for t in transitions:
        b.transition(t)
        inputs = rng.sample(places, rng.randint(1, 2))
        weights = [rng.choice([1, 1, 1, 2]) for _ in inputs]
        for p, w in zip(inputs, weights):
            b.arc(p, t, w)
        back = rng.randrange(sum(weights)) if lossy and rng.random() < 0.3 else sum(weights)
        for p in rng.choices(places, k=back):
            b.arc(t, p)
        others = [p for p in places if p not in inputs]
        if others and rng.random() < 0.3:
            b.read(rng.choice(others), t, rng.choice([1, 1, 2]))
    return b.build()


def generated_missions(strategy, examples: int, chunk: int, every: bool) -> list[Case]:
    cases = []
    for k, source in enumerate(drawn(strategy, examples, chunk)):
        net = pipeline.compile_source(source, f"generated-{chunk}-{k}.mcl")
        cases += mission_cases(f"generated mission {chunk}-{k}", net, source, every=every)
    return cases


def generated_nets(strategy, label: str, examples: int, chunk: int) -> list[Case]:
    return [Case(f"{label} {chunk}-{k}", net, every=True)
            for k, net in enumerate(drawn(strategy, examples, chunk))]


def check_tally(j: Judgement, drawn_nets: int, kind: str) -> None:
    """Most nets judged, not discarded: a generator drifting to huge nets proves nothing."""
    assert j.tally["judged"] >= MIN_JUDGED[kind] * drawn_nets, (
        f"only {j.tally['judged']} of {drawn_nets} nets judged: {dict(j.tally)}")


# -- the tests ------------------------------------------------------------------------


TEMPLATES = [names.split(", ")[0] for names, _, _ in pipeline.templates()]


@pytest.mark.parametrize("name", TEMPLATES)
def test_templates(name, tmp_path):
    need_peers()
    net = pipeline.template_net(name)
    judged = judge([Case(f"template {name}", net, "auto", every=True)], tmp_path)
    judged.check()
    assert judged.tally["judged"] == 1


@pytest.mark.parametrize("example", variants(
    EXAMPLES, [p for p in EXAMPLES if p.stem in QUICK_EXAMPLES], ids=[p.stem for p in EXAMPLES],
    slow=[p for p in EXAMPLES if p.stem in LARGE_EXAMPLES]))
def test_examples(example, tmp_path):
    need_peers()
    net = pipeline.compile_file(example)
    judged = judge(mission_cases(example.name, net, layout="auto"), tmp_path)
    judged.check()
    assert judged.tally["judged"] == 2 and judged.tally["dead"] == 2


@pytest.mark.slow
@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.stem)
def test_examples_every_explorer(example, tmp_path):
    need_peers()
    net = pipeline.compile_file(example)
    judge(mission_cases(example.name, net, every=True), tmp_path).check()


def test_generated_missions(tmp_path):
    need_peers()
    cases = generated_missions(SMALL_MISSIONS, FAST_MISSIONS, FAST_SEED, every=False)
    judged = judge(cases, tmp_path, MAX_STATES)
    judged.check()
    check_tally(judged, len(cases), "missions")
    assert judged.tally["dead"] == judged.tally["judged"], "a mission always ends"


NET_KINDS = [pytest.param(nets(), "any", id="any"),
             pytest.param(bounded_nets(), "bounded", id="bounded")]


@pytest.mark.parametrize("strategy, kind", NET_KINDS)
def test_generated_nets(strategy, kind, tmp_path):
    need_peers()
    cases = generated_nets(strategy, f"generated net ({kind})", FAST_NETS, FAST_SEED)
    judged = judge(cases, tmp_path, MAX_STATES)
    judged.check()
    check_tally(judged, len(cases), kind)
    # both verdicts come up, so that neither answer is taken on trust
    assert judged.tally["dead"] > 0 and judged.tally["live"] > 0, dict(judged.tally)


def awkward_names() -> Net:
    """Ids that are keywords, numbers, or hold white space, punctuation, a comment's start,
    an escape or a letter outside ASCII, in a net whose name spans lines and holds braces.
    Two tokens cycle until both have left the first place, then the net ends."""
    places = ["PLACE", "a b", "x:y", "(p)", "/*c", "12", "\u00e9t\u00e9", "_x0041_"]
    transitions = ["TRANSITION", "t {1}", "CONSUME", "99", "u;v", "//w", "\u00fc", "SAFE"]
    b = NetBuilder("two lines\n{and braces}\r")
    for p in places:
        b.place(p, 2 if p == places[0] else 0)
    for k, t in enumerate(transitions[:-1]):
        b.transition(t)
        b.arc(places[k], t)
        b.arc(t, places[k + 1])
    # back from the last place to the second while the first is still marked (a read arc)
    b.transition(transitions[-1])
    b.read(places[0], transitions[-1])
    b.arc(places[-1], transitions[-1])
    b.arc(transitions[-1], places[1])
    return b.build()


def reads_and_fills() -> Net:
    """A transition that reads a place and also puts tokens into it."""
    b = NetBuilder("reads and fills")
    b.place("p", 1)
    b.place("q", 3)
    b.place("r", 0)
    b.transition("t")                   # while p is marked, move q's tokens into p
    b.read("p", "t")
    b.arc("q", "t")
    b.arc("t", "p", 2)
    b.transition("u")
    b.arc("p", "u", 3)
    b.arc("u", "r")
    return b.build()


def test_awkward_names_keep_to_lolas_syntax(tmp_path):
    """LoLA refused a keyword as a name, and a line break in the net's name, which our
    file shows in a comment (LoLA's comments end with their line): keywords are escaped,
    the comment stays on its line, and our reader gets the net back."""
    net = awkward_names()
    path = pipeline.save_net(net, tmp_path / "net.lola", "lola")
    text = path.read_text()
    assert re.match(r"\{[^\n}]*\}\n", text), text.splitlines()[:2]
    names = re.findall(r"^\s*([^\s:,;]+)[,;]?$", text.partition("MARKING")[0], re.M)
    keywords = {"PLACE", "MARKING", "TRANSITION", "CONSUME", "PRODUCE", "SAFE"}
    assert not keywords & set(names[1:]), names
    # LoLA has no read arcs: ours come back as the self-loop the file says
    back = pipeline.load_net(path)
    assert (_flow(back), back.initial) == (_flow(net), net.initial)


def _flow(net: Net) -> list[tuple[str, str, int]]:
    """The arcs as a P/T tool sees them: a read arc is the self-loop it fires as."""
    return sorted([(a.source, a.target, a.weight) for a in net.arcs]
                  + [(a.target, a.source, a.weight) for a in net.arcs if a.kind is ArcKind.READ])


def test_awkward_names_read_by_the_tools(tmp_path):
    judged = judge([Case("awkward names", awkward_names(), "auto", every=True)], tmp_path)
    judged.check()
    assert judged.tally["judged"] == 1


def test_no_two_arcs_between_the_same_nodes(tmp_path):
    """The read arc's return and the transition's own arc into the place are one arc in
    the file: two arcs between the same nodes are read differently by each tool (LoLA
    crashed on them, pm4py kept one, SNAKES refused them). Our reader gets the net back."""
    net = reads_and_fills()
    path = pipeline.save_net(net, tmp_path / "net.pnml", layout="none")
    ends = re.findall(r'<arc id="[^"]*" source="([^"]*)" target="([^"]*)"', path.read_text())
    assert len(ends) == len(set(ends)), f"two arcs between the same nodes: {sorted(ends)}"
    assert sorted(pipeline.load_net(path).arcs) == sorted(net.arcs)
    # SNAKES, which refuses a second arc between two nodes, finds our markings
    import snakes.pnml
    from snakes.nets import StateGraph
    graph = StateGraph(snakes.pnml.loads(path.read_text()))
    graph.build()
    assert len(graph) == pipeline.analyze(net, state_space_only=True).facts.states


def test_a_transition_that_reads_a_place_and_fills_it(tmp_path):
    judged = judge([Case("reads and fills", reads_and_fills(), every=True)], tmp_path)
    judged.check()
    assert judged.tally["judged"] == 1


@pytest.mark.slow
@pytest.mark.parametrize("chunk", range(SLOW_CHUNKS))
def test_thousands_of_generated_missions(chunk, tmp_path):
    need_peers()
    cases = generated_missions(DEEP_MISSIONS, SLOW_MISSIONS, 1 + chunk, every=False)
    judged = judge(cases, tmp_path, MAX_STATES)
    judged.check()
    check_tally(judged, len(cases), "deep missions")
    print(f"\nchunk {chunk}: {dict(judged.tally)}")


@pytest.mark.slow
def test_generated_missions_every_explorer(tmp_path):
    need_peers()
    cases = generated_missions(SMALL_MISSIONS, EVERY_EXPLORER_MISSIONS, 99, every=True)
    judged = judge(cases, tmp_path, MAX_STATES)
    judged.check()
    check_tally(judged, len(cases), "missions")


@pytest.mark.slow
@pytest.mark.parametrize("chunk", range(SLOW_CHUNKS))
@pytest.mark.parametrize("strategy, kind", NET_KINDS)
def test_thousands_of_generated_nets(strategy, kind, chunk, tmp_path):
    need_peers()
    cases = generated_nets(strategy, f"generated net ({kind})", SLOW_NETS, 1 + chunk)
    judged = judge(cases, tmp_path, MAX_STATES)
    judged.check()
    check_tally(judged, len(cases), kind)
    print(f"\nchunk {chunk}: {dict(judged.tally)}")
