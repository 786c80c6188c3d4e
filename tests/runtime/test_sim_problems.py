"""Why the simulator failed a primitive reaches the user: the live log, --log and --json."""
from __future__ import annotations

import json

import pytest

from mcl2pnml.runtime.aal import Action, ActionKind, EventKind, Reported
from mcl2pnml.runtime.simulator import AUVSimulator, World

from helpers import ENGINES, cli

DEEP = ("primitive KeepDepth(d);\ntask Dive(d) = AchieveGoal(KeepDepth(d));\n"
        "mission { Dive(10.0); }\n")
WHY = "depth 10.0 is outside the tank (0 to 5 m)"


@pytest.fixture
def deep(tmp_path):
    path = tmp_path / "deep.mcl"
    path.write_text(DEEP)
    return path


def test_the_live_log_says_why_next_to_the_failure(deep):
    r = cli("run", deep)
    code, out = r.exit_code, r.output
    assert code == 1, out
    failed = [line for line in out.splitlines() if "failed" in line]
    assert failed == [f"t=    0.000  event     failed    KeepDepth  (simulator: {WHY})"]
    assert "outcome FAIL at t=0 s" in out


def test_the_json_lines_log_says_why(deep, tmp_path):
    log = tmp_path / "run.jsonl"
    assert cli("run", deep, "--log", log).exit_code == 1
    lines = [json.loads(line) for line in log.read_text().splitlines()]
    failed = [line for line in lines if line.get("event") == "failed"]
    assert failed == [{"t": 0, "event": "failed", "primitive": "KeepDepth",
                       "source": "simulator", "why": WHY}]


@pytest.mark.parametrize("engine", ENGINES)
def test_json_lists_the_problems_beside_an_unchanged_trace(deep, engine):
    r = cli("run", deep, "--json", "--engine", engine)
    assert r.exit_code == 1
    result = json.loads(r.output)
    assert result["outcome"] == "FAIL"
    # the trace keeps its shape: an event is {t, event, primitive}
    assert {"t": 0, "event": "failed", "primitive": "KeepDepth"} in result["trace"]
    assert result["problems"] == [{"t": 0, "primitive": "KeepDepth", "why": WHY,
                                   "source": "simulator"}]


def test_the_engines_agree_on_the_problems(deep):
    outs = [cli("run", deep, "--json", "--engine", engine).output for engine in ENGINES]
    assert outs[0] == outs[1]


def test_a_run_without_problems_has_no_problems_key(tmp_path):
    path = tmp_path / "ok.mcl"
    path.write_text(DEEP.replace("10.0", "2.0"))
    r = cli("run", path, "--json")
    assert r.exit_code == 0 and "problems" not in json.loads(r.output)


def test_a_failure_at_once_is_reported_with_the_simulators_words():
    sim = AUVSimulator()
    sim.act(Action(0.0, ActionKind.ENABLE, "GoToWayPoint", ((40.0, 0.0, 2.0),)))
    assert sim.take_event().kind is EventKind.ON
    failed = sim.take_event()
    assert isinstance(failed, Reported) and failed.kind is EventKind.FAILED
    assert failed.source == "simulator" and "outside the 16 x 8 x 5 m tank" in failed.why
    assert sim.problems == [(0.0, "GoToWayPoint", failed.why)]


def test_a_failure_after_the_start_says_why_too():
    """A latch checked away from any dock fails after its time: the simulator says how."""
    sim = AUVSimulator(World(dock=None))
    sim.act(Action(0.0, ActionKind.ENABLE, "CheckLatch"))
    assert sim.take_event().kind is EventKind.ON
    failed = sim.take_event()
    assert isinstance(failed, Reported) and failed.kind is EventKind.FAILED
    assert failed.source == "simulator" and "away from the dock" in failed.why
    assert sim.problems == [(failed.t, "CheckLatch", failed.why)]


def test_an_achieved_stays_a_plain_event():
    sim = AUVSimulator()
    sim.act(Action(0.0, ActionKind.ENABLE, "KeepDepth", (2.0,)))
    sim.take_event()
    achieved = sim.take_event()
    assert achieved.kind is EventKind.ACHIEVED and not isinstance(achieved, Reported)
