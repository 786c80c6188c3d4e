"""The assumptions of the timed verdicts, watched while a mission runs (docs/time.md).

A vehicle that breaks one (an acknowledgement later than ``--ack-within``, a primitive's
reports closer than ``--report-gap``) is said on both engines alike, in the live log,
the run's ``--json`` and its log; ``--stop-on-breach`` stops the run there, safely.
"""
from __future__ import annotations

import json
import os
from fractions import Fraction

import pytest

from mcl2pnml.core.timing import Assumptions, seconds_text as seconds
from mcl2pnml.pipeline import check_source
from mcl2pnml.runtime.aal import Action, ActionKind, Event, EventKind
from mcl2pnml.runtime.engine import Outcome, run
from mcl2pnml.runtime.watch import Watch, exact

from helpers import ENGINES, Engine, cli, one_error, run_cli

#: Two legs of one primitive: its second report comes after its first.
TWO_LEGS = "primitive Go(x);\ntask Leg(x) = AchieveGoal(Go(x));\nmission { Leg(1); Leg(2); }\n"
#: Every enable and disable of Go acknowledged 2.5 s late (and its reports with them).
LATE = {"faults": {"Go": {"delay": {"p": 1, "seconds": 2.5}}}}

#: Each way to break an assumption: the script, the faults (None: none), the assumption
#: broken first and what the first breach says after its time.
BREAKING = {
    "reports too close": ({"Go": ["ok@0.8", "ok@0.8"]}, None, "report_gap",
                          "at 1.6 s: Go reported achieved 0.8 s after its previous report "
                          "(achieved at 0.8 s), closer than the 1 s assumed"),
    "two reports at t=0": ({"Go": ["ok@0", "ok@0"]}, None, "report_gap",
                           "at 0 s: Go reported achieved 0 s after its previous report "
                           "(achieved at 0 s), closer than the 1 s assumed"),
    "late acknowledgement": ({"Go": ["ok@1", "ok@1"]}, LATE, "ack_within",
                             "at 0 s: Go's enable, sent at 0 s, was not acknowledged at once"),
}
ENDING = "; the proven bounds no longer apply"


@pytest.fixture
def mission(tmp_path):
    """The two legs, in a file of their own."""
    (tmp_path / "legs.mcl").write_text(TWO_LEGS)
    return tmp_path / "legs.mcl"


def files(tmp_path, script: dict, faults: dict | None) -> list[str]:
    """The options that give the vehicle: the script, and its faults."""
    (tmp_path / "script.json").write_text(json.dumps(script))
    out = ["--vehicle", str(tmp_path / "script.json")]
    if faults is not None:
        (tmp_path / "faults.json").write_text(json.dumps(faults))
        out += ["--faults", str(tmp_path / "faults.json")]
    return out


def run_json(mission, vehicle: list[str], engine: str, *more) -> tuple[int, dict]:
    out = cli("run", mission, "--engine", engine, "--json", *vehicle, *more)
    return out.exit_code, json.loads(out.output)


@pytest.mark.parametrize("case", BREAKING)
def test_a_breach_is_said_on_both_engines_in_text_and_json(tmp_path, mission, case):
    script, faults, assumption, said = BREAKING[case]
    vehicle = files(tmp_path, script, faults)
    words = f"the vehicle broke assumption {assumption} {said}{ENDING}"
    runs = []
    for engine in ENGINES:
        status, got = run_json(mission, vehicle, engine)
        assert status == 0 and got["outcome"] == "OK", got      # said, not stopped
        assert got["breaches"][0]["message"] == words
        assert got["breaches"][0]["breach"] == assumption
        runs.append(got)
        text = cli("run", mission, "--engine", engine, *vehicle).output
        live = [line for line in text.splitlines() if " breach " in line]
        assert live and live[0].endswith(words), text          # as it happens
        assert f"  {words}" in text.splitlines()                # and under the outcome
    assert runs[0] == runs[1]


@pytest.mark.parametrize("case", BREAKING)
def test_stop_on_breach_stops_the_run_safely_at_the_first(tmp_path, mission, case):
    script, faults, assumption, said = BREAKING[case]
    vehicle = files(tmp_path, script, faults)
    runs = []
    for engine in ENGINES:
        log = tmp_path / f"{engine}.jsonl"
        status, got = run_json(mission, vehicle, engine, "--stop-on-breach", "--log", log)
        assert status == Outcome.BREACH.exit_status == 7
        assert got["outcome"] == "BREACH" and len(got["breaches"]) == 1, got
        assert got["breaches"][0]["breach"] == assumption
        assert got["time"] == got["breaches"][0]["t"]           # stopped at the breach
        # the mission's Go was enabled: the safe stop disables it
        assert [a["primitive"] for a in got["safe_stop"]] == ["Go"]
        assert any(assumption in line for line in got["diagnosis"])
        lines = [json.loads(line) for line in log.read_text().splitlines()]
        assert [x["breach"] for x in lines if "breach" in x] == [assumption]
        assert lines[-1]["outcome"] == "BREACH"
        runs.append(got)
    assert runs[0] == runs[1]


def test_a_vehicle_within_the_assumptions_breaks_none(tmp_path, mission):
    vehicle = files(tmp_path, {"Go": ["ok@1", "ok@1"]}, None)
    for engine in ENGINES:
        status, got = run_json(mission, vehicle, engine, "--stop-on-breach")
        assert status == 0 and got["outcome"] == "OK" and "breaches" not in got, got
        assert "broke assumption" not in cli("run", mission, "--engine", engine,
                                             *vehicle).output


def test_the_assumptions_are_the_users(tmp_path, mission):
    """--report-gap and --ack-within say what the verdicts assumed: a vehicle within
    them breaks nothing, one outside a smaller gap does."""
    close = files(tmp_path, {"Go": ["ok@0.8", "ok@0.8"]}, None)
    assert "breaches" not in run_json(mission, close, "petri", "--report-gap", "0.8")[1]
    got = run_json(mission, close, "reference", "--report-gap", "0.9")[1]
    assert "closer than the 0.9 s assumed" in got["breaches"][0]["message"]
    late = files(tmp_path, {"Go": ["ok@1", "ok@1"]}, LATE)
    assert "breaches" not in run_json(mission, late, "petri", "--ack-within", "2.5")[1]
    got = run_json(mission, late, "petri", "--ack-within", "2")[1]
    assert got["breaches"][0]["message"].startswith(
        "the vehicle broke assumption ack_within at 2 s: Go's enable, sent at 0 s, was not "
        "acknowledged within 2 s")


@pytest.mark.parametrize("option", ["--ack-within", "--report-gap"])
@pytest.mark.parametrize("value", ["-1", "soon", "1e-9", "nan"])
def test_a_bad_assumption_is_one_message(mission, option, value):
    one_error(cli("run", mission, option, value), option)


def test_times_are_compared_exactly():
    """Reports 1 s apart stay 1 s apart, whatever the floats of their sums."""
    assert 1.4 - (0.3 + 0.1) < 1                     # the floats say otherwise
    watch = Watch(Assumptions(report_gap=Fraction(1)))
    watch.request(Action(0, ActionKind.ENABLE, "Go"))
    assert watch.event(Event(0, EventKind.ON, "Go"), True) == []
    assert watch.event(Event(0.3 + 0.1, EventKind.ACHIEVED, "Go"), True) == []
    assert watch.event(Event(1.4, EventKind.FAILED, "Go"), True) == []
    assert exact(0.3 + 0.1) == Fraction(2, 5)
    assert seconds(Fraction(1234567891, 1000)) == "1234567.891"


def test_an_event_the_mission_ignores_breaks_nothing():
    """Only the events the mission takes count: one it ignores fires nothing."""
    watch = Watch()
    assert watch.event(Event(0, EventKind.ACHIEVED, "Go"), True) == []
    assert watch.event(Event(0.5, EventKind.ACHIEVED, "Go"), False) == []
    assert [b.assumption for b in watch.event(Event(0.5, EventKind.FAILED, "Go"), True)] \
        == ["report_gap"]


class LateAck:
    """A vehicle that acknowledges each request ``delay`` seconds late, and never reports."""

    primitives = None

    def __init__(self, delay: float):
        self.delay, self.pending = delay, []

    def act(self, action):
        kind = EventKind.ON if action.kind is ActionKind.ENABLE else EventKind.OFF
        self.pending.append(Event(action.t + self.delay, kind, action.primitive))

    def next_event_time(self):
        return self.pending[0].t if self.pending else None

    def take_event(self):
        return self.pending.pop(0)

    def advance(self, t):
        pass


@pytest.mark.parametrize("engine", ENGINES)
def test_both_engines_watch_when_driven_directly(engine):
    source = ("primitive Go(x);\ntask Leg(x) = AchieveGoal(Go(x)) timeout 10;\n"
              "mission { Leg(1); }\n")
    checked = check_source(source, "late.mcl")
    late = run(Engine(engine)(checked), LateAck(3), assumptions=Assumptions(Fraction(1)))
    assert [(b.assumption, b.t) for b in late.breaches] == [("ack_within", 1.0),
                                                            ("ack_within", 14.0)]
    assert late.outcome is Outcome.FAIL           # said, and the mission went on
    ok = run(Engine(engine)(checked), LateAck(1), assumptions=Assumptions(Fraction(1)))
    assert ok.breaches == [] and ok.outcome is Outcome.FAIL
    stopped = run(Engine(engine)(checked), LateAck(3), assumptions=Assumptions(Fraction(1)),
                  stop_on_breach=True)
    assert stopped.outcome is Outcome.BREACH and stopped.time == 1
    assert [a.primitive for a in stopped.safe_stop] == ["Go"]


def test_a_resumed_run_watches_what_its_journal_recorded(tmp_path, mission):
    vehicle = files(tmp_path, {"Go": ["ok@0.8", "ok@0.8"]}, None)
    journal = tmp_path / "run.journal"
    # the journal's test hook kills the first run part-way, as a crash would
    env = {**os.environ, "MCL2PNML_JOURNAL_KILL_AFTER": "4"}
    killed = run_cli("run", mission, *vehicle, "--journal", journal, "--report-gap", "0.9",
                     env=env)
    assert killed.returncode != 0
    header = json.loads(journal.read_text().splitlines()[0])
    assert (header["ack_within"], header["report_gap"], header["stop_on_breach"]) \
        == ("0", "0.9", False)
    # each resume a process of its own, as a user's: a refused one lets go of the journal
    one_error(run_cli("run", mission, "--resume", journal, "--report-gap", "0.5"),
              "the journal's run has --report-gap 0.9, not 0.5")
    resumed = run_cli("run", mission, "--resume", journal, "--json")
    assert "closer than the 0.9 s assumed" in json.loads(resumed.stdout)["breaches"][0][
        "message"]
