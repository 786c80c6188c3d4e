"""TAPAAL's timed-arc nets (``compile --format tapn``): what we write, read back in
structure, and verifydtapn's verdicts on it, held to our own timed checker where it exists.

The verdicts known by hand (shared/peers/README.md, "verifydtapn"): a one-task mission
with a time-out always ends when reports are at least 1 s apart; not when they may come
at one instant (a lasso of reports while the disable is pending), nor without the
time-out (the vehicle may never report). The paper's mission (``sauce``) alike.

With acknowledgements that may take K seconds, a primitive's disable is acknowledged by one
of three transitions (``off_C``, ``off_S1``, ``off_S2``, by the goal's state) sharing one
clock (``TimedNet.shared``): a report that moves the goal while the disable is pending does
not restart it. The one-task mission then always ends, at 10 + 2K s at the latest (written
with a clock each, it never would: reports a second apart restart the disable's delay for
ever); "always ends" and the latest end are held to our checker on it, on the paper's
mission and on a copy of it with short time-outs, and on small generated missions.
"""
from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

from mcl2pnml import pipeline
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import ArcKind, NetBuilder, Timing
from mcl2pnml.core.payloads import RESULT_PLACES, EventKind, read_transition
from mcl2pnml.core.patterns import (And, Const, Not, Or, Pattern, Property, Scope, ScopeKind,
                                    Tokens, describe)
from mcl2pnml.core.timing import Assumptions, mission_timing
from mcl2pnml.io import tapn

from helpers import ROOT, run_cli as run
from missions import missions
from peers import VERIFYDTAPN, need, verifydtapn
from sampling import sample

EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))
AT_ONCE = Assumptions(priority=False)
NO_GAP = Assumptions(report_gap=Fraction(0), priority=False)
ONE_TASK = """
primitive Go(x);
task GoTo(x) = AchieveGoal(Go(x)){timeout};
mission {{ GoTo(1); }}
"""
NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")


def one_task(timeout: str = " timeout 10"):
    return pipeline.compile_source(ONE_TASK.format(timeout=timeout), "one.mcl")


# -- the file, read back --------------------------------------------------------------------

def read_back(path: Path) -> dict:
    """The timed-arc file as data: places (tokens, invariant), transitions (urgent), arcs by
    kind, and the original ids of the comments beside the nodes."""
    text = path.read_text()
    root = ET.fromstring(text)
    ns = {"p": tapn.NAMESPACE}
    (net,) = root.findall("p:net", ns)
    places = {p.get("id"): (int(p.get("initialMarking")), p.get("invariant"))
              for p in net.findall("p:place", ns)}
    transitions = {t.get("id"): t.get("urgent") == "true" for t in net.findall("p:transition", ns)}
    arcs = {kind: [(a.get("source"), a.get("transition"), a.get("target"),
                    a.get("inscription"), a.get("weight", "1"))
                   for a in net.findall(f"p:{kind}", ns)]
            for kind in ("inputArc", "outputArc", "transportArc", "inhibitorArc")}
    originals = {m.group(1): json.loads(m.group(2).replace("\\u002d", "-"))
                 for m in re.finditer(r'<!-- (\w+): ("(?:[^"\\]|\\.)*") -->', text)}
    for p in places:
        assert p == net.find(f"p:place[@id='{p}']", ns).get("name")
    return {"places": places, "transitions": transitions, "arcs": arcs, "originals": originals}


def test_every_node_and_arc_is_written_as_intended(tmp_path):
    net = one_task()
    out = tmp_path / "one.tapn"
    tapn.write_tapn(net, out, timing=AT_ONCE)
    got = read_back(out)
    tnet = tapn.timed_arc_net(net, AT_ONCE)
    names = tnet.names
    assert all(NAME.match(n) for n in list(got["places"]) + list(got["transitions"]))
    assert len(set(names.values())) == len(names)
    assert names["mission.OK"] == "mission_OK"
    # every original node, under its name; the comment gives the id back where they differ
    for p in net.places:
        assert got["places"][names[p.id]][0] == net.initial[p.id]
        assert got["originals"].get(names[p.id], names[p.id]) == p.id
    timed = mission_timing(net, AT_ONCE)
    inputs = {(s, t): g for s, _, t, g, _ in got["arcs"]["inputArc"]}
    transports = {(s, via) for s, via, t, _, _ in got["arcs"]["transportArc"] if s == t}
    outputs = {(s, t) for s, _, t, _, _ in got["arcs"]["outputArc"]}
    inhibitors = {(s, t) for s, _, t, _, _ in got["arcs"]["inhibitorArc"]}
    for t in net.transitions:
        (n, *again) = tnet.copies[t.id]
        interval = timed.intervals[t.id]
        event = read_transition(t).event
        for copy in (n, *again):
            assert got["transitions"][copy] == (interval == (0, 0)), t.id
            for a in net.pre[t.id]:   # read arcs are transport arcs back to the place
                if a.kind is ArcKind.READ:
                    assert (names[a.source], copy) in transports
                else:
                    assert inputs[(names[a.source], copy)] == "[0,inf)"
            for a in net.post[t.id]:
                assert (copy, names[a.target]) in outputs
        if t.timing is not None:     # the time-out: its clock, guarded [10,10], bounded by 10
            clock = f"CLK_{n}"
            assert interval == (10, 10)
            assert inputs[(clock, n)] == "[10,10]"
            assert got["places"][clock] == (0, "<= 10")
            assert got["transitions"][f"start_{n}"] is True
            assert (clock, f"start_{n}") in inhibitors
            for a in net.pre[t.id]:
                assert (names[a.source], f"start_{n}") in transports
                stop = f"stop_{n}_{names[a.source]}"
                assert inputs[(clock, stop)] == "[0,inf)" and (names[a.source], stop) in inhibitors
            # what marks its input places waits for a stale clock to go: GoTo.t01 (EXE), Go.on
            assert {t for s, t in inhibitors if s == clock and not t.startswith(("start_", "stop_"))
                    } == {names["GoTo.t01"], names["Go.on"]}
        elif event is not None and event.kind in (EventKind.ACHIEVED, EventKind.FAILED):
            # a report: the first of the run, or one at least a second after the last
            assert again, t.id
            assert inputs[("FIRST_Go", n)] == "[0,inf)"
            assert inputs[("GAP_Go", again[0])] == "[1,inf)"
            assert (n, "GAP_Go") in outputs and (again[0], "GAP_Go") in outputs
        else:
            assert not again and interval == (0, 0), t.id   # steps, acknowledgements at once
    assert got["places"]["FIRST_Go"] == (1, "< inf") and got["places"]["GAP_Go"] == (0, "< inf")


def test_acknowledgements_within_a_bound_get_clocks_in_a_finer_unit(tmp_path):
    out = tmp_path / "one.tapn"
    tapn.write_tapn(one_task(), out, timing=Assumptions(ack_within=Fraction(1, 2),
                                                       priority=False))
    text = out.read_text()
    assert "time unit: 0.1 s" in text
    got = read_back(out)
    assert got["places"]["CLK_Go_on"] == (0, "<= 5")
    assert got["places"]["CLK_GoTo_t03"] == (0, "<= 100")
    assert got["transitions"]["Go_on"] is False
    inputs = {(s, t): g for s, _, t, g, _ in got["arcs"]["inputArc"]}
    assert inputs[("CLK_Go_on", "Go_on")] == "[0,5]"
    assert inputs[("CLK_GoTo_t03", "GoTo_t03")] == "[100,100]"
    assert inputs[("GAP_Go", "Go_achieved_again")] == "[10,inf)"


def test_names_are_distinct_and_never_words_of_the_queries():
    b = NetBuilder("n")
    for p in ("a.b", "a_b", "a-b", "1x", "and", "deadlock"):
        b.place(p, 1)
    b.transition("t")
    b.arc("a.b", "t")
    tnet = tapn.timed_arc_net(b.build())
    names = list(tnet.names.values())
    assert len(set(names)) == len(names) and all(NAME.match(n) for n in names)
    assert tnet.names["and"] != "and" and tnet.names["deadlock"] != "deadlock"
    assert tnet.names["1x"][0].isalpha()


def test_queries_name_the_result_places(tmp_path):
    written = {q.name: (path, q.text) for path, q, _ in
               tapn.write_queries(one_task(), tmp_path / "one.tapn", AT_ONCE)}
    assert written["ends"] == (tmp_path / "one.ends.q",
                               "AF (mission_OK = 1 or mission_FAIL = 1 or mission_ABORTED = 1)\n")
    assert written["deadlock"][1] == ("EF (deadlock and mission_OK = 0 and mission_FAIL = 0 and "
                                      "mission_ABORTED = 0)\n")
    assert written["safe"][1].startswith("AG (")
    assert all(path.read_text() == text for path, text in written.values())


def test_properties_that_one_state_formula_says():
    tnet = tapn.timed_arc_net(one_task(), AT_ONCE)
    on = Tokens(("Go.ON",), 1)
    never = Property("N", Pattern.ABSENCE, Not(on))
    always = Property("A", Pattern.UNIVERSALITY, on)
    after = Property("X", Pattern.ABSENCE, on, scope=Scope(ScopeKind.AFTER, q=on))
    assert tapn.property_query(never, tnet).text == "AG not (not (Go_ON >= 1))\n"
    assert tapn.property_query(always, tnet).text == "AG (Go_ON >= 1)\n"
    assert tapn.property_query(after, tnet) is None
    with pytest.raises(Mcl2PnmlError, match="no node 'Nowhere.ON'"):
        tapn.property_query(Property("Y", Pattern.ABSENCE, Tokens(("Nowhere.ON",), 1)), tnet)


def test_one_printer_of_predicates_in_the_reports_and_in_verifydtapn_syntax():
    """The reports and verifydtapn's queries print a predicate with one walker: the reports
    bracket each compound operand, verifydtapn every connective whole, with its names."""
    tnet = tapn.timed_arc_net(one_task(), AT_ONCE)
    p = And((Tokens(("Go.ON",), 1), Or((Not(Tokens(("Go.OFF",), 2)), Const(False))),
             Tokens((), 1)))
    assert describe(p) == "Go.ON >= 1 and ((not (Go.OFF >= 2)) or false) and 0 >= 1"
    assert tapn.predicate_text(p, tnet) == "(Go_ON >= 1 and (not (Go_OFF >= 2) or false) and false)"
    assert describe(And(())) == tapn.predicate_text(And(()), tnet) == "true"
    with pytest.raises(TypeError, match="not a predicate"):
        describe("Go.ON")


@pytest.mark.parametrize("assumptions, message", [
    (Assumptions(), "urgent transitions are not first"),
    (Assumptions(fair=True, priority=False), "reports eventually"),
])
def test_what_a_timed_arc_net_cannot_say_is_refused(assumptions, message, tmp_path):
    with pytest.raises(Mcl2PnmlError, match=message):
        tapn.write_tapn(one_task(), tmp_path / "x.tapn", timing=assumptions)
    assert not (tmp_path / "x.tapn").exists()


def test_a_shared_clock_is_one_place_started_by_each_member_and_stopped_when_none_is(tmp_path):
    """The disable's three acknowledgements share ``CLK_Go_off``: each member starts it and
    takes it; it stops when D or ON is emptied, or C, S1 and S2 all are; a report that marks
    a member's goal place waits for a stale clock, or fires while another member is enabled
    (the clock runs on)."""
    one_s = Assumptions(ack_within=Fraction(1), priority=False)
    net = one_task()
    out = tmp_path / "one.tapn"
    tapn.write_tapn(net, out, timing=one_s)
    got = read_back(out)
    tnet = tapn.timed_arc_net(net, one_s)
    assert mission_timing(net, one_s).shared == (frozenset({"Go.off_C", "Go.off_S1",
                                                            "Go.off_S2"}),)
    clocks = {p for p in got["places"] if p.startswith("CLK_")}
    assert clocks == {"CLK_Go_off", "CLK_Go_on", "CLK_GoTo_t03"}
    assert got["places"]["CLK_Go_off"] == (0, "<= 1")
    inputs = {(s, t): g for s, _, t, g, _ in got["arcs"]["inputArc"]}
    inhibitors = {(s, t) for s, _, t, _, _ in got["arcs"]["inhibitorArc"]}
    transports = {(s, via) for s, via, _, _, _ in got["arcs"]["transportArc"]}
    outputs = {(s, t) for s, _, t, _, _ in got["arcs"]["outputArc"]}
    for member in ("Go_off_C", "Go_off_S1", "Go_off_S2"):
        assert inputs[("CLK_Go_off", member)] == "[0,1]"
        start = f"start_{member}"
        assert got["transitions"][start] is True and ("CLK_Go_off", start) in inhibitors
        assert (start, "CLK_Go_off") in outputs
        assert {s for s, via in transports if via == start} == {
            "Go_D", "Go_ON", member.replace("off_", "")}
    stops = {t: {s for s, u in inhibitors if u == t} for t in got["transitions"]
             if t.startswith("stop_Go_off_")}
    assert sorted(stops.values(), key=sorted) == [{"Go_C", "Go_S1", "Go_S2"}, {"Go_D"},
                                                  {"Go_ON"}]
    assert all(inputs[("CLK_Go_off", t)] == "[0,inf)" for t in stops)
    # lost marks S1 (off_S1's): at once after a stale clock, or while off_S2 is enabled
    # (off_C cannot be: C and S2 are never marked together, and lost takes S2)
    lost = tnet.copies["Go.lost"]
    assert len(lost) == 2 * 3       # the first report or one after a gap, times three ways
    assert ("CLK_Go_off", "Go_lost") in inhibitors
    assert {s for s, via in transports if via == "Go_lost_while_Go_off_S2"} == {
        "Go_ON", "Go_D"}
    assert ("CLK_Go_off", "Go_lost_while_Go_off_S2") not in inhibitors


def test_a_clock_on_a_place_of_two_tokens_is_refused():
    b = NetBuilder("n")
    b.place("p", 2)
    b.transition("t", timing=Timing.delay(3))
    b.arc("p", "t")
    with pytest.raises(Mcl2PnmlError, match="starts with 2 tokens"):
        tapn.timed_arc_net(b.build())


def test_a_net_without_results_has_no_end_queries():
    b = NetBuilder("n")
    b.place("p", 1)
    with pytest.raises(Mcl2PnmlError, match="not a compiled mission"):
        tapn.ends_query(tapn.timed_arc_net(b.build()))


def test_a_deadline_finer_than_the_unit_is_refused(tmp_path):
    with pytest.raises(Mcl2PnmlError, match="not a whole number"):
        tapn.write_deadline(one_task(), tmp_path / "late.tapn", Fraction(1, 2), AT_ONCE)
    net_path, query_path, _ = tapn.write_deadline(one_task(), tmp_path / "late.tapn", 12,
                                                  AT_ONCE)
    got = read_back(net_path)
    assert query_path.read_text() == "EF LATE = 1\n"
    assert got["places"]["CLOCK"] == (1, "< inf")
    assert ("CLOCK", None, "late", "[12,inf)", "1") in got["arcs"]["inputArc"]
    assert {s for s, _, t, _, _ in got["arcs"]["inhibitorArc"] if t == "late"} == {
        f"mission_{r.value}" for r in RESULT_PLACES}


# -- the command -------------------------------------------------------------------------

def test_compile_writes_the_net_and_its_queries(tmp_path):
    out = run("compile", ROOT / "examples" / "sauce.mcl", "--format", "tapn", "-o",
              tmp_path / "sauce.tapn", "--ack-within", "2", "--report-gap", "1.5")
    assert out.returncode == 0, out.stderr
    for name in ("ends", "deadlock", "safe"):
        assert (tmp_path / f"sauce.{name}.q").is_file()
        assert "verifydtapn -k " in out.stderr
    assert "acknowledgements within 2 s; a primitive's reports at least 1.5 s apart" in out.stderr
    text = (tmp_path / "sauce.tapn").read_text()
    assert "time unit: 0.1 s" in text and 'invariant="&lt;= 20"' in text


@pytest.mark.parametrize("args, message", [
    (("--format", "pnml", "--ack-within", "1"), "only a timed-arc net (--format tapn)"),
    (("--format", "tapn", "--report-gap", "soon"), "'soon' is not a number of seconds"),
    (("--format", "tapn", "--ack-within", "-1"), "not between 0 and"),
])
def test_compile_refuses_timing_it_cannot_use(tmp_path, args, message):
    out = run("compile", ROOT / "examples" / "sauce.mcl", "-o", tmp_path / "x.out", *args)
    assert out.returncode == 2 and message in out.stderr and "Traceback" not in out.stderr


# -- verifydtapn's verdicts ---------------------------------------------------------------

def verdicts(net, tmp_path: Path, assumptions: Assumptions, which=("ends", "deadlock"),
             timeout: float = 60.0) -> dict[str, bool | None]:
    """verifydtapn's verdict on each query ``which`` of the mission's timed-arc net."""
    path = tmp_path / f"{net.name}.tapn"
    tapn.write_tapn(net, path, timing=assumptions)
    out = {}
    for qpath, q, bound in tapn.write_queries(net, path, assumptions):
        if q.name in which:
            out[q.name], _ = verifydtapn(path, qpath, bound, timeout)
    return out


def our_ends(net, assumptions: Assumptions, max_states: int = 1_000_000):
    """Our checker's ``timed_ends`` within ``max_states`` zones; where its end times pass
    the limit (their clock of the whole run is never extrapolated), the "always ends"
    verdict it computes first, alone (its end times then None, as for an unknown verdict)."""
    from mcl2pnml.analysis.timed.zones import TimedLimit
    from mcl2pnml.timed_verdicts import TimedEnds, ends_property
    try:
        return pipeline.timed_ends(net, assumptions, max_states)
    except TimedLimit:
        (v,) = pipeline.check_properties_timed(net, [ends_property()], assumptions,
                                               max_states)
        status = {"holds": True, "fails": False}.get(v.status.value)
        return TimedEnds(assumptions, status, None, None, None, (), None, v.states)


def compare_with_our_checker(net, assumptions: Assumptions, found: dict,
                             max_states: int = 1_000_000) -> None:
    """Our timed checker's verdicts against verifydtapn's, where both give one."""
    timed_ends = getattr(pipeline, "timed_ends", None)
    if timed_ends is None:
        pytest.skip("timed checker not available")
    ours = our_ends(net, assumptions, max_states)
    if assumptions.report_gap == 0 and found.get("ends") is False:
        # verifydtapn's AF takes every infinite run, Zeno ones too (reports without end at one
        # instant); our checker takes the time-divergent runs only: not the same question
        found = {**found, "ends": None}
    if found.get("ends") is not None and ours.always_ends is not None:
        assert ours.always_ends == found["ends"], "always ends"
    if found.get("deadlock") is not None and ours.deadlock is not None:
        assert ours.deadlock == found["deadlock"], "a dead state that is not an end"


@pytest.mark.parametrize("timeout, assumptions, ends", [
    (" timeout 10", AT_ONCE, True),     # the time-out ends it; reports a second apart
    (" timeout 10", NO_GAP, False),     # a Zeno lasso of reports while the disable is pending
    ("", AT_ONCE, False),               # no time-out: the vehicle may never report
])
def test_verifydtapn_on_one_task_as_checked_by_hand(tmp_path, timeout, assumptions, ends):
    need(VERIFYDTAPN)
    net = one_task(timeout)
    found = verdicts(net, tmp_path, assumptions, ("ends", "deadlock", "safe"))
    # the safety the clocks rest on is asked only where there is a clock
    assert found == {"ends": ends, "deadlock": False, **({"safe": True} if timeout else {})}
    compare_with_our_checker(net, assumptions, found)


def test_verifydtapn_on_the_papers_mission_without_a_gap(tmp_path, examples):
    need(VERIFYDTAPN)
    net = examples.net("sauce")
    found = verdicts(net, tmp_path, NO_GAP, ("ends",))
    assert found == {"ends": False}
    compare_with_our_checker(net, NO_GAP, found)


def test_the_observer_of_a_deadline(tmp_path):
    """The one task ends at 10 s at the latest (the time-out, then the disable at once)."""
    need(VERIFYDTAPN)
    net = one_task()
    late = {}
    for w in (10, 11):
        net_path, query_path, bound = tapn.write_deadline(net, tmp_path / f"late{w}.tapn", w,
                                                          AT_ONCE)
        late[w], _ = verifydtapn(net_path, query_path, bound, 60)
    assert late == {10: True, 11: False}
    timed_ends = getattr(pipeline, "timed_ends", None)
    if timed_ends is None:
        pytest.skip("timed checker not available")
    latest = timed_ends(net, AT_ONCE).latest
    if latest is not None:
        assert latest == 10


def late_at(net, tmp_path: Path, assumptions: Assumptions, *seconds: int,
            timeout: float = 120) -> dict[int, bool | None]:
    """verifydtapn's answer to "some run has no result at W" for each W of ``seconds``."""
    late = {}
    for w in seconds:
        net_path, query_path, bound = tapn.write_deadline(net, tmp_path / f"late{w}.tapn", w,
                                                          assumptions)
        late[w], _ = verifydtapn(net_path, query_path, bound, timeout)
    return late


def acks_within(k: int) -> Assumptions:
    return Assumptions(ack_within=Fraction(k), priority=False)


@pytest.mark.parametrize("k", [1, 3])
def test_a_report_while_a_disable_is_pending_does_not_restart_its_delay(tmp_path, k):
    """The time-out fires 10 s after the enable's acknowledgement (K s at most), the
    disable is acknowledged K s later at most, whatever the reports meanwhile: the mission
    always ends, at 10 + 2K s at the latest, for verifydtapn and for our checker."""
    need(VERIFYDTAPN)
    net, assumptions = one_task(), acks_within(k)
    found = verdicts(net, tmp_path, assumptions, ("ends", "deadlock", "safe"))
    assert found == {"ends": True, "deadlock": False, "safe": True}
    compare_with_our_checker(net, assumptions, found)
    latest = 10 + 2 * k
    assert pipeline.timed_ends(net, assumptions).latest == latest
    assert late_at(net, tmp_path, assumptions, latest, latest + 1) == {latest: True,
                                                                      latest + 1: False}


def short_sauce():
    """The paper's mission with time-outs of 5, 3 and 2 s (300, 60 and 10 s in the paper)."""
    source = (ROOT / "examples" / "sauce.mcl").read_text()
    for long, short in (("300", "5"), ("60", "3"), ("10", "2")):
        source = source.replace(f"timeout {long};", f"timeout {short};")
    return pipeline.compile_source(source, "short_sauce.mcl")


def _latest_end_of_short_sauce(tmp_path, k):
    need(VERIFYDTAPN)
    net, assumptions = short_sauce(), acks_within(k)
    ours = pipeline.timed_ends(net, assumptions)
    assert ours.always_ends is True and ours.latest is not None
    latest = int(ours.latest)
    assert late_at(net, tmp_path, assumptions, latest, latest + 1) == {latest: True,
                                                                      latest + 1: False}
    return latest


def test_the_latest_end_of_the_papers_mission_with_short_time_outs(tmp_path):
    """Our latest end time is verifydtapn's: some run still running at it, none after."""
    assert _latest_end_of_short_sauce(tmp_path, 0) == 18


@pytest.mark.slow
def test_the_latest_end_of_the_papers_mission_with_short_time_outs_and_late_acks(tmp_path):
    assert _latest_end_of_short_sauce(tmp_path, 1) == 28


@pytest.mark.slow
@pytest.mark.parametrize("k", [1, 3])
def test_verifydtapn_on_the_papers_mission_with_late_acknowledgements(tmp_path, k, examples):
    """The paper's mission always ends with acknowledgements within 1 or 3 s: verifydtapn's
    verdict (16 s and 47 s here) and ours."""
    need(VERIFYDTAPN)
    net, assumptions = examples.net("sauce"), acks_within(k)
    found = verdicts(net, tmp_path, assumptions, ("ends",), timeout=300)
    assert found == {"ends": True}
    compare_with_our_checker(net, assumptions, found)


@pytest.mark.slow
@pytest.mark.parametrize("mission", EXAMPLES, ids=lambda p: p.stem)
def test_verifydtapn_on_every_example(tmp_path, mission):
    """Each example's verdicts, acknowledgements at once, reports a second apart; a verdict
    not given within the time (discrete time multiplies the states by the time-outs) is not
    compared. The paper's mission is known by hand to end always."""
    need(VERIFYDTAPN)
    net = pipeline.compile_file(mission)
    found = verdicts(net, tmp_path, AT_ONCE, timeout=180)
    if mission.stem == "sauce" and found["ends"] is not None:
        assert found == {"ends": True, "deadlock": False}
    compare_with_our_checker(net, AT_ONCE, found)


@pytest.mark.slow
def test_the_papers_mission_is_still_running_at_730_seconds(tmp_path):
    need(VERIFYDTAPN)
    net = pipeline.compile_file(ROOT / "examples" / "sauce.mcl")
    net_path, query_path, bound = tapn.write_deadline(net, tmp_path / "late.tapn", 730, AT_ONCE)
    late, _ = verifydtapn(net_path, query_path, bound, 300, ptrie=True)
    assert late in (True, None)


SMALL = missions(depth=1, width=2, function_depth=0).filter(
    lambda s: s.count("parallel(") + s.count("monitor(") <= 1)


def _generated(tmp_path_factory, source, assumptions=AT_ONCE, max_states=1_000_000):
    need(VERIFYDTAPN)
    net = pipeline.compile_source(source, "generated.mcl")
    found = verdicts(net, tmp_path_factory.mktemp("gen"), assumptions, ("ends",), timeout=20)
    if getattr(pipeline, "timed_ends", None) is not None:
        compare_with_our_checker(net, assumptions, found, max_states)


@seed(7)
@settings(max_examples=sample(15, 6), deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(source=SMALL)
def test_verifydtapn_on_generated_missions(tmp_path_factory, source):
    """Small generated missions: verifydtapn gives a verdict on "an end is always reached"
    (a time-out bounds every task of some; others may wait for ever for a report), held to
    our own checker (a few here, fifteen when thorough, two thousand larger ones in the slow
    variant)."""
    _generated(tmp_path_factory, source)


@pytest.mark.slow
@seed(7)
@settings(max_examples=2000, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(source=missions(depth=2, width=2, function_depth=0))
def test_verifydtapn_on_two_thousand_generated_missions(tmp_path_factory, source):
    _generated(tmp_path_factory, source)


@seed(11)
@settings(max_examples=3, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(source=SMALL, k=st.sampled_from([1, 3]))
def test_verifydtapn_on_generated_missions_with_late_acknowledgements(tmp_path_factory,
                                                                       source, k):
    """Acknowledgements within 1 or 3 s: the disables' shared clocks on generated missions.
    Our checker within 20,000 zones here (its end times take most of the time: a minute
    on some of these), in full in the slow variant."""
    _generated(tmp_path_factory, source, acks_within(k), 20_000)


@pytest.mark.slow
@seed(11)
@settings(max_examples=50, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(source=SMALL, k=st.sampled_from([1, 3]))
def test_verifydtapn_on_fifty_generated_missions_with_late_acknowledgements(
        tmp_path_factory, source, k):
    _generated(tmp_path_factory, source, acks_within(k))
