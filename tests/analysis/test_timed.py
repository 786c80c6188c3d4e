"""Timed verdicts (docs/time.md): the zone graph of :mod:`mcl2pnml.analysis.timed.zones` held to an
independent discrete-time reading of the same semantics, to the engines' own runs, and on
the examples.

* On generated missions (small time-outs) and on small copies of the examples, "an end is
  always reached" and the earliest and latest end times agree with
  :class:`timed_reference.Discrete` (one state per second), under several assumptions.
* The latest end of the paper's mission is the longest run the engines' own search finds
  (:mod:`timed_search`), and the script of that run ends there on both engines.
* A mission with an unbounded wait is named as such; every timed counterexample of the
  examples is replayed, as it is, on both engines.
"""
from __future__ import annotations

import json
from fractions import Fraction

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mcl2pnml import pipeline
from mcl2pnml.core.timing import Assumptions, mission_timing
from mcl2pnml.timed_verdicts import ENDS

from helpers import ROOT, both, cli, one_error, run_cli
from missions import missions
from timed_reference import Discrete
from timed_search import Search

EXAMPLES = ROOT / "examples"

ASSUMED = [Assumptions(), Assumptions(report_gap=Fraction(2)),
           Assumptions(ack_within=Fraction(1)), Assumptions(priority=False),
           Assumptions(ack_within=Fraction(2), report_gap=Fraction(3), priority=False)]


def _small(name: str, tmp_path) -> object:
    """An example with its time-outs cut to a few seconds: the same structure, a reference
    that one state per second can still explore."""
    import re
    text = (EXAMPLES / f"{name}.mcl").read_text()
    import itertools
    cut = itertools.cycle([5, 3, 2, 4])
    text = re.sub(r"timeout \d+", lambda _: f"timeout {next(cut)}", text)
    path = tmp_path / f"{name}.mcl"
    path.write_text(text)
    return pipeline.compile_file(path)


def _agree(net, assumptions: Assumptions, limit: int = 300_000,
           zones: int = pipeline.MAX_CHECK_STATES) -> None:
    if assumptions.ack_within > 1 and limit < 10_000:
        return          # late acknowledgements: too many zones for a quick comparison
    ours = pipeline.timed_ends(net, assumptions, max_states=zones)
    if ours.always_ends is None and ours.states >= zones:
        return          # our bound, as the reference's: too big for a quick comparison
    ref = Discrete(mission_timing(net, assumptions))
    if ours.always_ends and ours.latest is None:
        return          # the end times were not computed within the zones allowed
    if ours.always_ends is None:
        # undecided only where time may stand still along a cycle (a gap or time-out of 0)
        assert assumptions.report_gap == 0 or any(
            t.timing is not None and t.timing.earliest == 0 for t in net.transitions), ours.reason
        return
    assert ours.always_ends == ref.always_ends(ENDS, limit), assumptions.words()
    if ours.always_ends:
        assert (ours.earliest, ours.latest) == ref.end_times(ENDS, limit), assumptions.words()


IDS = ["defaults", "gap2", "ack1", "urgency", "ack2-gap3-urgency"]


@pytest.mark.parametrize("assumptions", [pytest.param(a, id=i, marks=[pytest.mark.slow]
                                                      if i in ("gap2", "ack1", "urgency",
                                                               "ack2-gap3-urgency")
                                                      else []) for a, i in zip(ASSUMED, IDS)])
def test_the_zone_graph_agrees_with_one_state_per_second_on_the_papers_mission(assumptions,
                                                                               tmp_path):
    _agree(_small("sauce", tmp_path), assumptions)


def _short(mission: str) -> str:
    """A generated mission with time-outs of 2 or 3 s (one state a second stays small)."""
    import re
    return re.sub(r"timeout (\d+)", lambda m: f"timeout {2 + int(m.group(1)) % 2}", mission)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["lawnmower", "multi_leg", "docking", "dam_inspection"])
@pytest.mark.parametrize("assumptions", ASSUMED[:3], ids=["defaults", "gap2", "ack1"])
def test_the_zone_graph_agrees_with_one_state_per_second_on_the_examples(name, assumptions,
                                                                          tmp_path):
    # our zones bounded: dam_inspection with late acknowledgements takes ours 485,000 zones
    # for its end times, and one state a second longer than a test may take
    _agree(_small(name, tmp_path), assumptions, zones=200_000)


@settings(max_examples=5, deadline=None, suppress_health_check=list(HealthCheck))
@given(mission=missions(depth=1, width=2), k=st.sampled_from(range(len(ASSUMED))))
def test_the_zone_graph_agrees_with_one_state_per_second_on_generated_missions(mission, k):
    net = pipeline.compile_source(_short(mission))
    try:
        # our zones bounded as the reference's states are: a draw of a few thousand
        # states a second could take ours to millions of zones (minutes, a gigabyte)
        _agree(net, ASSUMED[k], limit=4_000, zones=40_000)
    except RuntimeError:      # the reference's bound: too big for one state a second
        pass


@pytest.mark.slow
@settings(max_examples=600, deadline=None, suppress_health_check=list(HealthCheck))
@given(mission=missions(depth=3, width=3), k=st.sampled_from(range(len(ASSUMED))))
def test_the_zone_graph_agrees_with_one_state_per_second_on_many_missions(mission, k):
    net = pipeline.compile_source(_short(mission))
    try:
        _agree(net, ASSUMED[k])
    except RuntimeError:
        pass


def test_the_latest_end_of_the_papers_mission_is_the_engines_longest_run(examples):
    net = examples.net("sauce")     # compiled once per process, shared with other tests
    ends = pipeline.timed_ends(net)
    assert ends.always_ends is True and ends.deadlock is False
    search = Search(net)
    longest, script = search.run()
    assert not search.never
    assert ends.latest == Fraction(longest) and ends.earliest == 0
    # the longest run's script ends there on both engines, with the same trace
    petri, reference = both(examples.checked("sauce"), script, net)
    assert petri == reference
    assert petri["time"] == longest, (script, petri["outcome"])


WAITS = """
primitive DetectCross();
primitive KeepDepth(d);
task Find() = AchieveGoal(DetectCross());
task Dive(d) = AchieveGoal(KeepDepth(d)) timeout 30;
mission { Dive(5); Find(); }
"""


def test_an_unbounded_wait_is_named(tmp_path):
    net = pipeline.compile_source(WAITS)
    ends = pipeline.timed_ends(net)
    assert ends.always_ends is False and ends.latest is None
    assert any("Find waits for DetectCross's report, and has no time-out" in w
               for w in ends.waits), ends.waits
    assert ends.never.shape.value == "finite"
    # a vehicle that always reports in the end: then every run ends, by the time-outs
    fair = pipeline.timed_ends(net, Assumptions(fair=True))
    assert fair.always_ends is True and fair.latest is None and fair.earliest == 0
    assert "latest unbounded (no bound: a report that comes eventually" in "\n".join(fair.lines())


def test_a_wait_for_ever_is_a_counterexample_both_engines_replay(tmp_path):
    mission = tmp_path / "w.mcl"
    mission.write_text(WAITS + "property Ends: eventually outcome(OK) or outcome(FAIL);\n")
    out = run_cli("analyze", mission, "--properties", "--no-progress", "--explain")
    assert out.returncode == 1, out.stderr
    assert "property Ends" in out.stdout and "counterexample (finite)" in out.stdout
    assert "both engines reach the violation" in out.stdout, out.stdout
    assert "Find waits for DetectCross's report" in out.stdout
    untimed = run_cli("analyze", mission, "--untimed", "--properties", "--no-progress")
    assert untimed.returncode == 1 and "timed (docs/time.md)" not in untimed.stdout


def test_the_cli_says_the_assumptions_and_the_times():
    out = run_cli("analyze", EXAMPLES / "sauce.mcl", "--timed", "--state-space", "--json")
    assert out.returncode == 0, out.stderr
    timed = json.loads(out.stdout)["timed"]
    assert timed["always_ends"] is True and timed["latest"] == 730
    assert timed["assumptions"] == {"ack_within": 0, "report_gap": 1, "fair": False,
                                    "priority": True}
    text = run_cli("analyze", EXAMPLES / "sauce.mcl", "--timed", "--report-gap", "0.5").stdout
    assert "acknowledgements at once; a primitive's reports at least 0.5 s apart" in text
    assert Assumptions(ack_within=Fraction(2)).words().startswith("acknowledgements within 2 s")
    assert "end time: earliest 0 s, latest" in text


@pytest.mark.parametrize("args, pieces", [
    (["--report-gap", "2"], ["--report-gap", "add --timed"]),
    (["--timed", "--report-gap", "-1"], ["--report-gap", "between 0 and"]),
    (["--timed", "--ack-within", "x"], ["--ack-within", "not a number of seconds"]),
    (["--timed", "--initial", "mission.B"], ["--timed", "leave out --initial"]),
])
def test_bad_timed_options_are_one_message(args, pieces):
    one_error(cli("analyze", EXAMPLES / "sauce.mcl", *args), *pieces)


def test_a_net_without_the_missions_payloads_is_refused(tmp_path):
    net = tmp_path / "n.net"
    net.write_text("net n\ntr t p -> q\npl p (1)\n")
    one_error(cli("analyze", net, "--timed"), "not a compiled mission")
