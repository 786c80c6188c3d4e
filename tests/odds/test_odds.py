"""`mcl2pnml odds`: the exact odds of a mission with a vehicle model (docs/odds.md).

Three kinds of evidence. Missions small enough to work the answer out by hand
from the model's numbers (not from ours): a time-out racing a report, a
report that never comes, a tie at the time-out's instant (the vehicle's event
first, as the engines take it). Simulated runs: the same vehicle model drawing
its choices (``ModelVehicle`` with a seeded ``Draw``) flies the mission on
*both engines* through the run loop users run, and the frequencies and mean
end time must fall within their 99.9% intervals of the exact figures. And a
bad vehicle model is one message at its line and column.
(tests/peers/test_odds_storm.py holds the exact figures to Storm's.)
"""
from __future__ import annotations

import json
import math
import random
from fractions import Fraction

import pytest

from helpers import ROOT, one_error, run_cli
from mcl2pnml import pipeline
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.runtime.engine import run
from mcl2pnml.runtime.executor import PetriEngine
from mcl2pnml.odds import TooManyStates, chain_of, odds, odds_of
from mcl2pnml.runtime.reference import ReferenceEngine
from mcl2pnml.runtime.vehicle_model import Draw, ModelVehicle, VehicleModel

SAUCE = ROOT / "examples" / "sauce.mcl"
ONE_TASK = """primitive P();
task T() = AchieveGoal(P()) timeout {timeout};
mission {{ T(); }}
"""


def _net(text: str):
    return pipeline.compile_checked(pipeline.check_source(text))


def _model(spec: dict) -> VehicleModel:
    return VehicleModel.from_json(json.dumps(spec), "model.json")


# -- worked out by hand ------------------------------------------------------------------

@pytest.mark.parametrize("achieve, fail, ok_after, fail_after, timeout", [
    ("7/10", "1/5", 5, 3, 10), ("1/2", "1/2", 12, 2, 10), ("1/3", "0", 4, 1, 8),
    ("1", "0", 10, 1, 10)])
def test_a_task_racing_its_time_out(achieve, fail, ok_after, fail_after, timeout):
    """OK if the report achieved comes by the time-out (at its very instant too: the
    vehicle's event is taken first); FAIL if it fails, or nothing comes by then."""
    a, f = Fraction(achieve), Fraction(fail)
    model = _model({"primitives": {"P": {"achieve": achieve, "fail": fail,
                                         "achieved_after": {"fixed": ok_after},
                                         "failed_after": {"fixed": fail_after}}}})
    o = odds(_net(ONE_TASK.format(timeout=timeout)), model)
    ok = a if ok_after <= timeout else 0
    assert o.outcomes["OK"] == pytest.approx(float(ok), abs=1e-12)
    assert o.outcomes["FAIL"] == pytest.approx(float(1 - ok), abs=1e-12)
    times = [(a, min(ok_after, timeout)), (f, min(fail_after, timeout)),
             (1 - a - f, timeout)]
    assert o.mean == pytest.approx(float(sum(p * t for p, t in times)), abs=1e-9)


def test_a_uniform_delay_against_a_time_out_counts_the_tie_as_in_time():
    model = _model({"primitives": {"P": {"achieve": 1, "after": {"uniform": [2, 12]}}}})
    o = odds(_net(ONE_TASK.format(timeout=10)), model)
    assert o.outcomes["OK"] == pytest.approx(9 / 11, abs=1e-12)     # 2..10 of 2..12
    assert o.quantiles["p50"] is not None and o.distribution[-1][1] == pytest.approx(1.0)


def test_a_report_that_never_comes_without_a_time_out_is_a_mission_that_never_ends():
    text = "primitive P();\ntask T() = AchieveGoal(P());\nmission { T(); }\n"
    model = _model({"primitives": {"P": {"achieve": "1/4", "fail": "1/4"}}})
    o = odds(_net(text), model)
    assert o.outcomes["never"] == pytest.approx(0.5, abs=1e-12)
    assert o.outcomes["OK"] == pytest.approx(0.25, abs=1e-12)
    assert o.mean == pytest.approx(1.0)        # the default: a report one second later


def test_a_loop_until_failure_ends_surely_after_a_geometric_number_of_rounds():
    """``while (T()) {}`` runs T until it fails: rounds ~ Geometric(fail), each round
    its report's delay; the mission then ends OK (a while ends OK when its condition
    fails)."""
    text = "primitive P();\ntask T() = AchieveGoal(P()) timeout 100;\n" \
           "mission { while (T()) { } }\n"
    f = Fraction(1, 4)
    model = _model({"primitives": {"P": {"achieve": "3/4", "fail": "1/4",
                                         "after": {"fixed": 2}}}})
    o = odds(_net(text), model)
    assert o.outcomes["OK"] + o.outcomes["FAIL"] == pytest.approx(1.0, abs=1e-12)
    assert o.mean == pytest.approx(2 / float(f), rel=1e-9)    # E[rounds] = 1/f, 2 s each


def test_the_chain_is_bounded_and_says_so(examples):
    model = _model({"primitives": {"GoToWayPoint": {"achieve": "1/2", "fail": "1/4",
                                                    "after": {"uniform": [1, 200]}}}})
    with pytest.raises(TooManyStates, match="more than 5 states"):
        chain_of(examples.net("sauce"), model, 5)


@pytest.mark.parametrize("calls, ok", [
    # the primitive's own settings for both enablings: both must achieve
    ([], Fraction(1, 4)),
    # the enabling with argument 2 always achieves (2.0 is the trace's 2)
    ([{"args": [2.0], "achieve": 1, "fail": 0}], Fraction(1, 2)),
    # ... and the one with 1 never reports: its time-out fails it
    ([{"args": [1], "achieve": 0, "fail": 0}, {"args": [2], "achieve": 1, "fail": 0}],
     Fraction(0)),
    # arguments no enabling has change nothing
    ([{"args": [3], "achieve": 0}], Fraction(1, 4))])
def test_a_call_s_arguments_choose_its_settings(calls, ok):
    net = _net("primitive P(x);\ntask T(x) = AchieveGoal(P(x)) timeout 10;\n"
               "mission { T(1); T(2); }\n")
    model = _model({"primitives": {"P": {"achieve": "1/2", "fail": "1/2", "calls": calls}}})
    assert odds(net, model).exact["OK"] == ok


# -- the properties, worked out by hand ---------------------------------------------------

LOOP = """primitive P();
task T() = AchieveGoal(P()) timeout 100;
mission { while (T()) { } }
property Responds: ended(T, OK) leads to running(T);
property NeverDone: never ended(T, OK);
property Ends: eventually outcome(OK) or outcome(FAIL) or outcome(ABORTED);
"""


@pytest.mark.parametrize("achieve, held", [
    # T always achieves: the loop runs for ever, in one bottom component of the chain
    # where a response's obligations are met again and again (it holds), the absence
    # is broken (it fails) and no end comes (it fails)
    ("1", {"Responds": 1, "NeverDone": 0, "Ends": 0}),
    # T fails one round in four: the loop (and the mission, OK) ends after a geometric
    # number of rounds; no round ends OK only if the first one fails
    ("3/4", {"Responds": 1, "NeverDone": Fraction(1, 4), "Ends": 1})])
def test_the_probability_of_each_property(achieve, held, tmp_path):
    mission = tmp_path / "loop.mcl"
    mission.write_text(LOOP)
    net, props = pipeline.properties_of(mission)
    model = _model({"primitives": {"P": {"achieve": achieve, "fail": str(1 - Fraction(achieve)),
                                         "after": {"fixed": 2}}}})
    o = odds_of(chain_of(net, model, properties=props))
    assert {p.name: p.exact for p in o.properties} == held
    assert {p.name: p.holds for p in o.properties} == pytest.approx(
        {k: float(v) for k, v in held.items()}, abs=1e-12)


def test_the_properties_are_judged_on_every_marking_of_an_instant(tmp_path):
    """The markings an instant passes through, not only the settled ones: the call is
    entered and left again within the instant its report comes, a marking no settled
    state shows."""
    mission = tmp_path / "one.mcl"
    mission.write_text(ONE_TASK.format(timeout=10) +
                       "property NeverOK: never ended(T, OK);\n")
    net, props = pipeline.properties_of(mission)
    model = _model({"primitives": {"P": {"achieve": "2/3", "fail": "1/3",
                                         "after": {"fixed": 1}}}})
    o = odds_of(chain_of(net, model, properties=props))
    assert o.properties[0].exact == Fraction(1, 3)


# -- simulated runs on both engines ------------------------------------------------------

def _wilson(k: int, n: int, z: float = 3.29) -> tuple[float, float]:
    """The Wilson score interval of k successes in n (z 3.29: 99.9%)."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


MODELS = {
    "sonar": ROOT / "examples" / "sauce.model.json",
    "unreliable": {"defaults": {"achieve": "9/10", "fail": "1/20", "after": {"fixed": 5},
                                "ack": {"table": {"0": 0.5, "1": 0.5}}},
                   "primitives": {
                       "DetectCross": {"achieve": "2/3", "after": {"uniform": [20, 40]}},
                       "GoToWayPoint": {"after": {"table": {"30": 0.5, "400": 0.5}}},
                       "KeepDepth": {"achieve": 0.8, "fail": 0.1, "after": {"uniform": [5, 70]},
                                     "lose": 0.2, "lost_after": {"fixed": 3},
                                     # the surfacing: its own odds
                                     "calls": [{"args": [0], "achieve": 0.6, "fail": 0.4,
                                                "after": {"fixed": 9}, "lose": 0}]},
                       "ReleaseMarker": {"achieve": 0.7, "fail": 0.2, "after": {"fixed": 2}}}},
}


@pytest.mark.parametrize("name", MODELS)
def test_simulated_runs_on_both_engines_agree_with_the_exact_odds(name, examples):
    spec = MODELS[name]
    model = VehicleModel.load(spec) if not isinstance(spec, dict) else _model(spec)
    checked, net = examples.checked("sauce"), examples.net("sauce")
    exact = odds(net, model)
    runs = 200
    for engine in (lambda: PetriEngine(net), lambda: ReferenceEngine(checked)):
        ends, times = {}, []
        for seed in range(runs):
            r = run(engine(), ModelVehicle(model, Draw(random.Random(seed))), max_time=1e5)
            ends[r.outcome.value] = ends.get(r.outcome.value, 0) + 1
            times.append(r.time)
        for outcome in ("OK", "FAIL"):
            low, high = _wilson(ends.get(outcome, 0), runs)
            assert low <= exact.outcomes[outcome] <= high, (name, outcome, ends, exact.outcomes)
        mean = sum(times) / runs
        se = math.sqrt(sum((t - mean) ** 2 for t in times) / (runs - 1) / runs)
        assert abs(mean - exact.mean) <= 3.29 * se + 1e-9, (name, mean, se, exact.mean)


def test_a_run_is_replayed_by_its_seed(examples):
    model = VehicleModel.load(MODELS["sonar"])
    net = examples.net("sauce")
    first, again = (run(PetriEngine(net), ModelVehicle(model, Draw(random.Random(7))))
                    .as_json() for _ in range(2))
    assert first == again


# -- the command and bad models ---------------------------------------------------------

def test_odds_prints_the_outcomes_and_writes_the_chain(tmp_path):
    pm = tmp_path / "sauce.pm"
    out = run_cli("odds", SAUCE, "--vehicle-model", MODELS["sonar"], "--json", "--prism", pm)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert set(data["outcomes"]) == {"OK", "FAIL", "ABORTED", "never"}
    assert sum(data["outcomes"].values()) == pytest.approx(1.0)
    assert data["end_time"]["p5"] <= data["end_time"]["p50"] <= data["end_time"]["p95"]
    text = pm.read_text()
    assert text.count("[] s=") == data["states"] and 'rewards "time"' in text
    assert f"wrote {pm}" in out.stderr


def test_odds_weighs_the_mission_s_properties(tmp_path):
    """``--properties FILE``: the mission's own (none in sauce.mcl), then the file's; a
    property that says "it ends OK" holds exactly as often as the mission does."""
    out = run_cli("odds", SAUCE, "--vehicle-model", MODELS["sonar"], "--json",
                  "--properties", ROOT / "examples" / "sauce.false.props")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    held = {p["property"]: p for p in data["properties"]}
    assert held["AlwaysOK"]["exact_holds"] == data["exact_outcomes"]["OK"]
    assert 0 < held["SurveyAlwaysFlown"]["holds"] < 1
    text = run_cli("odds", SAUCE, "--vehicle-model", MODELS["sonar"], "--properties")
    assert text.returncode == 0, text.stderr
    assert "the properties (the probability that each holds):" in text.stdout
    bad = tmp_path / "bad.props"
    bad.write_text("property X: never enabled(Nothing);\n")
    one_error(run_cli("odds", SAUCE, "--vehicle-model", MODELS["sonar"], "--properties", bad),
              "bad.props:1:")


def test_sensitivity_ranks_the_primitives_by_their_swing(examples):
    """Ranked by swing; KeepDepth, which the mission's last step needs, never achieving
    leaves no OK; and a better sonar lowers P(OK) (a cross found starts the dive and the
    release, which can fail), which a ranking by swing shows as a negative one."""
    model = VehicleModel.load(MODELS["sonar"])
    net = examples.net("sauce")
    from mcl2pnml.odds import sensitivity
    rows = {r["primitive"]: r for r in sensitivity(net, model,
                                                    PetriEngine(net).primitives_used())}
    swings = [r["swing"] for r in rows.values()]
    assert swings == sorted(swings, reverse=True)
    base = odds(net, model).outcomes["OK"]
    assert all(r["ok"] == pytest.approx(base, abs=1e-12) for r in rows.values())
    assert rows["KeepDepth"]["ok_if_it_never_achieves"] == pytest.approx(0.0, abs=1e-12)
    assert rows["DetectCross"]["swing"] < 0


BAD = [  # the file, what its message says, and where its caret points (the value's start)
    ("{", "not a vehicle model", None),
    ('{"primitives": {"P": {"achieve": 0.5, "speed": 3}}}', "unknown setting", "3}}}"),
    ('{\n "primitives": {"P": {"achieve": 0.8, "fail": 0.3}}}', "add up to more than 1",
     '{"achieve": 0.8'),
    ('{"primitives": {"P": {"after": {"table": {"1": 0.5, "2": 0.4}}}}}', "add up to 9/10",
     '{"1": 0.5'),
    ('{"primitives": {"P": {"after": {"uniform": [9, 3]}}}}', "is empty", "[9, 3]"),
    ('{"primitives": {"P": {"achieve": "1/0"}}}', "divides by zero", '"1/0"'),
    ('{"primitives": {"P": {"achieve": "most"}}}', "is not a probability", '"most"'),
    ('{"primitives": {"P": {"achieve": 1.5}}}', "greater than the maximum", "1.5"),
    ('{"primitives": {"P": {"achieve": NaN}}}', "NaN is not a number", "NaN"),
    ('{"primitives": {"P": {"fail": -0.5}}}', "less than the minimum", "-0.5"),
    ('{"primitives": {"Q": {}}}', "which the mission does not use", "{}"),
    ('{"primitives": {"P": {"calls": [{"args": [1]}, {"args": [1.0]}]}}}',
     "the same arguments as calls[0]", "[1.0]"),
    ('{"primitives": {"P": {"calls": [{"achieve": 1}]}}}', "'args' is a required property",
     '{"achieve": 1}'),
    ('{"primitives": {"P": {"achieve": 0.5, "calls": [{"args": [], "fail": 0.6}]}}}',
     "add up to more than 1", '{"args": []'),
    ('{"defaults": {"calls": []}}', "unknown setting", "[]"),
]


@pytest.mark.parametrize("text, message, needle", BAD, ids=[b[1] for b in BAD])
def test_a_bad_model_is_one_message_at_its_line_and_column(text, message, needle, tmp_path):
    path = tmp_path / "model.json"
    path.write_text(text)
    mission = tmp_path / "m.mcl"
    mission.write_text(ONE_TASK.format(timeout=10))
    out = run_cli("odds", mission, "--vehicle-model", path)
    error = one_error(out, message)
    if needle is None:
        assert "model.json:1:" in error, error
    else:
        at = text.index(needle)
        line, column = text.count("\n", 0, at) + 1, at - (text.rfind("\n", 0, at) + 1) + 1
        assert f"model.json:{line}:{column}:" in error, error


def test_a_continuous_delay_is_for_campaigns_only(tmp_path):
    model = _model({"primitives": {"P": {"after": {"exponential": {"mean": 3}}}}})
    with pytest.raises(Mcl2PnmlError, match="no exact odds"):
        odds(_net(ONE_TASK.format(timeout=10)), model)


def test_the_chain_of_a_model_is_what_odds_of_reads(examples):
    model = VehicleModel.load(MODELS["sonar"])
    net = examples.net("sauce")
    chain = chain_of(net, model)
    for successors in chain.successors:
        assert not successors or sum(p for _, p in successors) == 1     # exactly
    assert odds_of(chain) == odds(net, model)


def test_continuous_delays_are_drawn_with_their_law():
    """An exponential report against a time-out T: the end time is min(D, T), whose mean
    is m (1 - e^(-T/m)); and P(OK) = 1 - e^(-T/m). 4,000 runs within their 99.9% bounds."""
    m, timeout, runs = 6.0, 10, 4000
    model = _model({"primitives": {"P": {"after": {"exponential": {"mean": m}}}}})
    checked = pipeline.check_source(ONE_TASK.format(timeout=timeout))
    ok, times = 0, []
    for seed in range(runs):
        r = run(ReferenceEngine(checked), ModelVehicle(model, Draw(random.Random(seed))))
        ok += r.outcome.value == "OK"
        times.append(r.time)
    low, high = _wilson(ok, runs)
    assert low <= 1 - math.exp(-timeout / m) <= high
    mean = sum(times) / runs
    se = math.sqrt(sum((t - mean) ** 2 for t in times) / (runs - 1) / runs)
    assert abs(mean - m * (1 - math.exp(-timeout / m))) <= 3.29 * se
