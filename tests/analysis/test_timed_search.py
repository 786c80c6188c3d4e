"""How the timed verdicts are searched (docs/time.md, "How it is computed"): on the fly,
with zone inclusion, every counterexample replayed without it, under the state and memory
limits. What they answer is held to independent readings in ``test_timed.py``."""
from __future__ import annotations

import re
from fractions import Fraction

from mcl2pnml import pipeline
from mcl2pnml.analysis.timed import zones
from mcl2pnml.core.timing import Assumptions
from mcl2pnml.core.vocabulary import CYCLE, ENDS as EVERY_RUN_ENDS
from mcl2pnml.timed_verdicts import ENDS, ends_property, semantics

#: A loop whose body holds for 5 s, in a monitor beside a 200 s time-out: dozens of
#: turns before the time-out, each its own zones (seconds of search, not milliseconds).
LOOP_BESIDE_TIMER = """
primitive Sonar();
primitive Hover();
primitive Wait();
task Check() = AchieveGoal(Sonar()) timeout 3;
task Hold() = KeepGoal(Hover()) timeout 5;
task Watch() = AchieveGoal(Wait()) timeout 200;
function Loop() { while (Check()) do { Hold(); } }
mission { monitor(Loop(), Watch()); }
"""


def test_a_mission_that_never_ends_is_found_before_the_whole_graph(examples):
    tn = semantics(examples.net("sampling"), Assumptions())
    (verdict,) = zones.check_timed_properties(tn, [ends_property()])
    assert verdict.status == "fails" and verdict.shape == "lasso"
    # found depth first, within its budget: no graph was built breadth first
    assert 0 < verdict.states <= zones.DEPTH_FIRST_STATES
    cycle = verdict.transitions[verdict.loop:]
    assert "FireBottle.achieved" in cycle and cycle


def test_a_counterexample_that_is_no_run_sends_the_search_to_the_exact_graph(examples,
                                                                               monkeypatch):
    tn = semantics(examples.net("docking"), Assumptions())
    (expected,) = zones.check_timed_properties(tn, [ends_property()])
    made = []
    real_graph, real_replay = zones.ZoneGraph, zones._replay

    def graph(*args, **kwargs):
        made.append(kwargs.get("subsume", True))
        return real_graph(*args, **kwargs)

    refused = []

    def replay(ts, trans, loop):
        if len(refused) < 2:       # the widened graph's and the inclusion's: no runs
            refused.append(trans)
            return None
        return real_replay(ts, trans, loop)

    monkeypatch.setattr(zones, "ZoneGraph", graph)
    monkeypatch.setattr(zones, "_replay", replay)
    (verdict,) = zones.check_timed_properties(tn, [ends_property()])
    assert len(refused) == 2 and made[-1] is False      # the exact graph answered
    assert verdict.status == expected.status == "fails"
    assert verdict.shape == "lasso"


def test_a_cycle_with_no_report_gap_is_decided_by_the_tick(examples):
    # reports 0 s apart: a cycle of reports may take no time, or some; the tick decides
    ends = pipeline.timed_ends(examples.net("docking"), Assumptions(report_gap=Fraction(0)))
    assert ends.always_ends is False, ends.reason
    assert ends.never.shape.value == "lasso"
    assert zones.TICK not in ends.never.transitions
    # the cycle in the mission's terms: its calls and structures, each on its line
    ends = ends.placed(pipeline.call_sites(examples.checked("docking")))
    loop = ends.never.transitions[ends.never.loop:]
    assert ends.cycle and loop == ends.cycle * (len(loop) // len(ends.cycle))   # once round
    steps = ends.cycle_steps()
    assert tuple(t for _, fired in steps for t in fired) == ends.cycle   # each firing, in order
    source = examples.mission("docking").read_text().splitlines()
    tasks = examples.checked("docking").tasks
    calls = set()
    for where, fired in steps:
        label, line = re.fullmatch(r"(.+) \(line (\d+)\)", where).groups()
        assert label.split("(")[0] in source[int(line) - 1], where
        # a task's own net is shared: its firings go with the call that entered it
        assert all(label.startswith(t.split(".")[0] + "(") for t in fired
                   if t.split(".")[0] in tasks), (where, fired)
        calls |= {label} if "(" in label else set()
    assert {"Goto(Approach)", "Home()"} <= calls
    assert ends.said()[-1].startswith(CYCLE) and all(c in ends.said()[-1] for c in calls)
    printed = "\n".join(ends.lines())
    assert f"{EVERY_RUN_ENDS}: no, {CYCLE}:" in printed
    assert all(f"    {where}: " in printed for where, _ in steps)


def test_a_replayed_run_that_cannot_fire_is_no_run(examples):
    tn = semantics(examples.net("sauce"), Assumptions())
    ts = zones._timed_structure(tn, None)
    # a time-out of the paper's mission cannot fire before anything else has
    timeout = next(j for j, t in enumerate(ts.transitions) if t.endswith(".t03"))
    assert zones._replay(ts, [timeout], None) is None


def test_the_timed_search_answers_unknown_past_its_limits(tmp_path):
    net = pipeline.compile_source(LOOP_BESIDE_TIMER)
    few = pipeline.timed_ends(net, max_states=50)
    assert few.always_ends is None and "more than 50 states" in few.reason
    times = pipeline.timed_ends(net, max_states=1_000)      # the end times need more
    assert times.always_ends is True and times.latest is None
    assert "more than 1,000 states" in times.reason
    # a budget below the process lets it grow by a few megabytes, as the exploration's
    # does: the run that ends latest beside a 10,000 s timer takes more
    longer = pipeline.compile_source(LOOP_BESIDE_TIMER.replace("timeout 200", "timeout 10000"))
    small = pipeline.timed_ends(longer, max_memory="1K")
    assert small.always_ends is True and small.latest is None
    assert "memory budget" in small.reason
    out = pipeline.timed_ends(net)
    assert out.always_ends is True and out.latest == 200


def test_the_end_times_count_their_own_zones(examples):
    ends = pipeline.timed_ends(examples.net("sauce"))
    assert ends.always_ends is True and ends.time_states > 0
    assert f"latest 730 s ({ends.time_states:,} zones)" in "\n".join(ends.lines())
    assert ends.as_json()["end_time_zones"] == ends.time_states
    assert 0 < ends.as_json()["latest_bound_zones"] == ends.latest_bound_states <= ends.time_states


def _loop_beside(seconds: int):
    net = pipeline.compile_source(LOOP_BESIDE_TIMER.replace("timeout 200", f"timeout {seconds}"))
    tn = semantics(net, Assumptions())
    return tn, zones._timed_structure(tn, ENDS)


def test_the_latest_end_beside_a_long_timer_is_bounded_in_zones_that_do_not_grow():
    # the widened graph: as many zones beside a 100 s timer as beside a 1,000 s one
    bounds = []
    for seconds in (100, 1000):
        tn, ts = _loop_beside(seconds)
        graph, bound = zones._latest_bound(tn, ts, zones.MAX_CHECK_STATES)
        assert bound * tn.unit == seconds          # a zone on the way was widened
        bounds.append(graph.states)
    assert bounds[0] == bounds[1]


def test_the_run_that_ends_latest_is_a_run_and_ends_at_the_bound():
    out = pipeline.timed_ends(pipeline.compile_source(LOOP_BESIDE_TIMER))
    assert out.latest == 200
    # the run the engines replay: the loop turned until the time-out, as the exact graph has it
    assert out.latest_run.count("Loop.t4") > 20 and out.latest_run[-1] == "mission.f7"


def test_a_widened_bound_that_no_run_reaches_sends_the_search_to_the_whole_graph(monkeypatch):
    expected = pipeline.timed_ends(pipeline.compile_source(LOOP_BESIDE_TIMER))
    real = zones._latest_bound

    def too_high(tn, ts, max_states):
        graph, bound = real(tn, ts, max_states)
        return graph, bound + 1
    monkeypatch.setattr(zones, "_latest_bound", too_high)
    forced = pipeline.timed_ends(pipeline.compile_source(LOOP_BESIDE_TIMER))
    assert (forced.earliest, forced.latest) == (expected.earliest, expected.latest) == (0, 200)
    assert forced.time_states > expected.time_states      # every state was searched
