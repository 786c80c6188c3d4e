"""Fault injection in simulated runs: the fault file and :class:`FaultyVehicle`.

A fault file's faults are each one message at their line and column; the
wrapper changes a mission's run as its faults say, replays a run by its seed,
flips reports as often as the file says, and ends a run whose report is lost
as docs/faults.md says (STALLED, naming what the mission waits for).
"""
from __future__ import annotations

import json
import random
from fractions import Fraction

import pytest

from mcl2pnml.campaign import wilson
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.language.semantics import check_program
from mcl2pnml.language.compiler import compile_checked
from mcl2pnml.language.parser import parse_file
from mcl2pnml.pipeline import check_source
from mcl2pnml.runtime.aal import (Action, ActionKind, EventKind, Reported, ScriptedVehicle,
                                  canonical_trace)
from mcl2pnml.runtime.engine import Outcome, run
from mcl2pnml.runtime.executor import PetriEngine
from mcl2pnml.runtime.faults import MAX_FAULTS, Faults, FaultyVehicle
from mcl2pnml.runtime.simulator import AUVSimulator, World

from helpers import DATA, ROOT

FAULTS = DATA / "faults"
INVALID = sorted(p.stem for p in FAULTS.glob("*.json"))
MAX_TIME = 2_000.0


def faults(spec: dict) -> Faults:
    return Faults.from_json(json.dumps(spec), "faults.json")


# -- the file ------------------------------------------------------------------------

@pytest.mark.parametrize("name", INVALID)
def test_an_invalid_fault_file_is_one_message_at_its_line_and_column(name):
    path = FAULTS / f"{name}.json"
    expected = (FAULTS / f"{name}.expected").read_text().strip()
    with pytest.raises(Mcl2PnmlError) as e:
        Faults.load(path)
    first = str(e.value).splitlines()[0]
    assert first == f"{path}:{expected}"
    assert e.value.location.line is not None and e.value.location.column is not None


def test_a_fault_file_is_read_exactly():
    f = faults({"faults": {"GetGPSFix": {"fail": "1/5"},
                           "*": {"lose": {"achieved": 0.01}, "duplicate": 0.005,
                                 "delay": {"p": 0.1, "seconds": 3}}}})
    gps, rest = f.of("GetGPSFix"), f.of("Other")
    assert (gps.fail, gps.lost(EventKind.ACHIEVED), gps.delay) == (Fraction(1, 5), 0, 0)
    assert rest.lost(EventKind.ACHIEVED) == Fraction(1, 100)
    assert (rest.duplicate, rest.delay, rest.delay_seconds) == (Fraction(1, 200),
                                                                Fraction(1, 10), 3.0)


def test_a_fault_file_past_its_bound_is_refused_before_it_is_read(tmp_path):
    big = tmp_path / "big.json"
    big.write_text('{"faults": {}, "description": "' + "x" * MAX_FAULTS + '"}')
    with pytest.raises(Mcl2PnmlError) as e:
        Faults.load(big)
    assert str(e.value).startswith(f"{big}: cannot read") and "limit" in str(e.value)


def test_faults_of_a_primitive_the_mission_does_not_use_are_refused():
    f = Faults.from_json('{"faults": {\n  "GetGPSFx": {"fail": 0.2}\n}}', "f.json")
    with pytest.raises(Mcl2PnmlError) as e:
        f.check_primitives({"GetGPSFix", "KeepDepth"})
    assert str(e.value).splitlines()[0] == (
        "f.json:2:15: the fault file names 'GetGPSFx', which the mission does not use; "
        "it uses GetGPSFix, KeepDepth")
    f.check_primitives({"GetGPSFx"})
    vehicle = FaultyVehicle(ScriptedVehicle({}), f, random.Random(0))
    with pytest.raises(Mcl2PnmlError):
        vehicle.check_primitives({"GetGPSFix"})


# -- the sauce mission on the simulator -----------------------------------------------

@pytest.fixture(scope="module")
def sauce():
    return PetriEngine(compile_checked(check_program(parse_file(str(ROOT / "examples" / "sauce.mcl")))))


def fly(sauce, spec: dict | None, seed: int = 0, world: World = World()):
    vehicle = AUVSimulator(world)
    if spec is not None:
        vehicle = FaultyVehicle(vehicle, faults(spec), random.Random(seed))
    return run(sauce.clone(), vehicle, max_time=MAX_TIME), vehicle


def enabled(result) -> list[str]:
    return [e.primitive for e in result.entries
            if isinstance(e, Action) and e.kind is ActionKind.ENABLE]


def test_without_faults_the_wrapper_changes_nothing(sauce):
    plain, _ = fly(sauce, None)
    wrapped, vehicle = fly(sauce, {"faults": {}})
    assert canonical_trace(wrapped.entries) == canonical_trace(plain.entries)
    assert (wrapped.outcome, wrapped.time) == (plain.outcome, plain.time)
    assert vehicle.injected == []


def test_a_cross_detection_that_always_fails_changes_the_run(sauce):
    plain, _ = fly(sauce, None)
    faulty, vehicle = fly(sauce, {"faults": {"DetectCross": {"fail": 1}}})
    assert plain.outcome is Outcome.OK and "ReleaseMarker" in enabled(plain)
    # the monitor's FindCross fails: no marker is dropped, the vehicle surfaces early
    assert "ReleaseMarker" not in enabled(faulty)
    assert faulty.time < plain.time
    assert canonical_trace(faulty.entries) != canonical_trace(plain.entries)
    failed = [e for e in faulty.entries if isinstance(e, Reported) and e.source == "fault"]
    assert [(e.primitive, e.kind) for e in failed] == [("DetectCross", EventKind.FAILED)]
    assert failed[0].why.startswith("injected: ")
    assert [what for _, _, what in vehicle.injected] == ["failed instead of achieved"]
    # every report failing: the first waypoint is not reached, the mission fails
    worst, _ = fly(sauce, {"faults": {"*": {"fail": 1}}})
    assert worst.outcome is not Outcome.OK


def test_the_same_seed_gives_the_same_run(sauce):
    spec = {"faults": {"*": {"fail": 0.1, "duplicate": 0.3,
                             "delay": {"p": 0.3, "seconds": 3}}}}
    # a coarser time step: a run that waits on a delayed event looks an hour ahead
    coarse = World(dt=0.5)
    runs = [fly(sauce, spec, seed, coarse) for seed in (7, 7, 8, 9)]
    (a, va), (b, vb) = runs[:2]
    assert canonical_trace(a.entries) == canonical_trace(b.entries)
    assert (a.outcome, a.time, va.injected) == (b.outcome, b.time, vb.injected)
    assert va.injected       # faults were injected at all
    # other seeds draw other faults
    assert len({tuple(map(tuple, v.injected)) for _, v in runs}) > 1


# -- a scripted vehicle ------------------------------------------------------------------

GPS = """\
primitive GetGPSFix();
task Fix() = AchieveGoal(GetGPSFix());
mission { Fix(); }
"""
GPS_TIMEOUT = GPS.replace("GetGPSFix());", "GetGPSFix()) timeout 30;")


def engine_of(source: str) -> PetriEngine:
    return PetriEngine(compile_checked(check_source(source, "gps.mcl")))


def scripted(spec: dict, seed: int) -> FaultyVehicle:
    return FaultyVehicle(ScriptedVehicle.from_json('{"GetGPSFix": ["ok@5"]}'), faults(spec),
                         random.Random(seed))


def test_a_fix_failing_one_time_in_five_fails_about_one_run_in_five():
    engine = engine_of(GPS)
    spec = {"faults": {"GetGPSFix": {"fail": "1/5"}}}
    n = 200
    outcomes = [run(engine.clone(), scripted(spec, seed), max_time=MAX_TIME).outcome
                for seed in range(n)]
    assert set(outcomes) <= {Outcome.OK, Outcome.FAIL}
    k = outcomes.count(Outcome.FAIL)
    low, high = wilson(k, n, 0.999)
    assert low <= 0.2 <= high, (k, n)


def test_a_lost_achieved_without_a_time_out_ends_stalled():
    spec = {"faults": {"GetGPSFix": {"lose": {"achieved": 1}}}}
    vehicle = scripted(spec, 0)
    r = run(engine_of(GPS).clone(), vehicle, max_time=MAX_TIME)
    assert r.outcome is Outcome.STALLED
    assert r.time == 0      # at the last event: the 'on'
    assert "GetGPSFix: waits for the vehicle's 'achieved'" in r.waiting
    assert [a.primitive for a in r.safe_stop] == ["GetGPSFix"]
    assert vehicle.injected == [(5.0, "GetGPSFix", "lost achieved")]
    # under a time-out, the task fails when it expires and the mission goes on to its result
    timed = run(engine_of(GPS_TIMEOUT).clone(), scripted(spec, 0), max_time=MAX_TIME)
    assert (timed.outcome, timed.time) == (Outcome.FAIL, 30)


class Drawn(random.Random):
    """Draws given in advance: which of one event's faults happen."""

    def __init__(self, draws):
        super().__init__(0)
        self.draws = list(draws)

    def random(self):
        return self.draws.pop(0)


def test_a_delayed_event_holds_back_the_later_ones_of_its_primitive():
    # the 'on' is delayed (draw 0.1 < 1/2), the 'achieved' is not (0.9): it waits behind
    # it; nor is the 'off' (0.9)
    spec = {"faults": {"GetGPSFix": {"delay": {"p": "1/2", "seconds": 8}}}}
    vehicle = FaultyVehicle(ScriptedVehicle.from_json('{"GetGPSFix": ["ok@5"]}'),
                            faults(spec), Drawn([0.1, 0.9, 0.9]))
    r = run(engine_of(GPS).clone(), vehicle, max_time=MAX_TIME)
    events = [(e.t, e.kind) for e in r.entries if not isinstance(e, Action)]
    assert events[:2] == [(8, EventKind.ON), (8, EventKind.ACHIEVED)]
    assert r.outcome is Outcome.OK
    assert [what for _, _, what in vehicle.injected] == [
        "delayed on by 8 s", "held achieved back to t=8 s behind a delayed event"]


def test_a_duplicated_report_is_delivered_twice_and_the_second_ignored():
    spec = {"faults": {"*": {"duplicate": 1}}}
    r = run(engine_of(GPS).clone(), scripted(spec, 0), max_time=MAX_TIME)
    assert r.outcome is Outcome.OK
    achieved = [e for e in r.entries if not isinstance(e, Action)
                and e.kind is EventKind.ACHIEVED]
    assert [e.t for e in achieved] == [5, 5]
