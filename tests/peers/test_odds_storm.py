"""The exact odds agree with Storm's, on the chain ``to_prism`` exports.

``mcl2pnml odds`` builds a discrete-time Markov chain of a mission and its
vehicle model (:func:`mcl2pnml.odds.chain_of`), solves it with our own
sparse solver (:func:`~mcl2pnml.odds.odds_of`, :mod:`mcl2pnml.analysis.markov`),
and can export it in PRISM's language (:func:`~mcl2pnml.odds.to_prism`).
Storm is an independent model checker: it reads that export and solves the
chain in exact rational arithmetic. Agreement therefore checks two things of
ours at once, the solver (probabilities of OK, FAIL, ABORTED, of waiting for
ever and of looping for ever; the expected end time) and the export (Storm's
model is compared with our chain transition by transition, exactly). It says
nothing about whether the chain is the right one for the mission: the
simulation tests, which hold the odds to simulated runs of both engines, check
the chain's construction.

The cases: the example missions with the vehicle models shipped beside them
(examples/NAME.model.json, the paper's mission's among them);
every example mission with vehicle models drawn from a seeded ``random.Random``
(exact fractions, small discrete delays, sometimes acknowledgement delays,
goals lost, reports that never come); and generated missions (tests/support/missions.py),
each with a model seeded by its text. Our probabilities are floats from a
sparse solve, Storm's exact rationals: they must agree to ``TOLERANCE``.
"""
from __future__ import annotations

import json
import random
import zlib
from collections import Counter
from fractions import Fraction
from pathlib import Path

import pytest

stormpy = pytest.importorskip(
    "stormpy", reason="stormpy is not installed (make setup installs it where its wheel can be had)")

from hypothesis import HealthCheck, assume, given, seed, settings, strategies as st  # noqa: E402

from mcl2pnml.analysis.markov import CYCLES, solve  # noqa: E402
from mcl2pnml import pipeline  # noqa: E402
from mcl2pnml.runtime.executor import PetriEngine  # noqa: E402
from mcl2pnml.odds import (ENDS, WAITS, TooManyStates, chain_of, odds_of, owes_labels,  # noqa: E402
                           to_prism)
from mcl2pnml.runtime.vehicle_model import VehicleModel  # noqa: E402

from helpers import ROOT  # noqa: E402
from sampling import sample, variants  # noqa: E402
from missions import missions, shaped_missions  # noqa: E402

#: Ours (floats) against Storm's (exact rationals).
TOLERANCE = 1e-9
#: A chain larger than this is skipped: Storm's exact solve and our exploration of it
#: would take most of the file's time budget.
MAX_STATES = 2_000
#: Seeds of the models drawn for each example mission (the slow variant's: the third).
EXAMPLE_SEEDS = (0, 1)
SLOW_SEEDS = (2,)
#: Generated missions drawn, and how many of them must be checked (not skipped).
GENERATED_EXAMPLES = sample(20, 8)
MIN_CHECKED = GENERATED_EXAMPLES * 3 // 5

EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))
PROPERTIES = ('P=? [F "OK"]', 'P=? [F "FAIL"]', 'P=? [F "ABORTED"]', 'P=? [F "waits"]',
              'P=? [F "ended"]', 'R{"time"}=? [F "ended"]')


# -- vehicle models --------------------------------------------------------------------------

def _delay(rng: random.Random) -> dict:
    roll = rng.random()
    if roll < 0.4:
        return {"fixed": rng.randint(0, 6)}
    if roll < 0.7:
        low = rng.randint(0, 4)
        return {"uniform": [low, low + rng.randint(1, 2)]}
    a, b = rng.sample(range(1, 13), 2)
    return {"table": {str(a): "1/3", str(b): "2/3"}}


def random_model(primitives: set[str], rng: random.Random) -> str:
    """A vehicle model's JSON text for ``primitives``: mostly achieving, sometimes
    failing, now and then never reporting; sometimes slow to acknowledge, or losing
    a goal achieved."""
    out = {}
    for name in sorted(primitives):
        k = rng.choice([3, 4, 5, 10])
        fail = rng.randint(0, k // 3)
        never = rng.choice([0, 0, 0, 1]) if fail < k else 0
        spec: dict = {"achieve": f"{k - fail - never}/{k}", "fail": f"{fail}/{k}"}
        if rng.random() < 0.25:
            spec["achieved_after"], spec["failed_after"] = _delay(rng), _delay(rng)
        else:
            spec["after"] = _delay(rng)
        if rng.random() < 0.3:
            spec["ack"] = {"fixed": rng.randint(0, 2)}
        if rng.random() < 0.3:
            spec["lose"] = f"1/{rng.randint(2, 5)}"
            spec["lost_after"] = _delay(rng)
        out[name] = spec
    return json.dumps({"description": "drawn by tests/peers/test_odds_storm.py", "primitives": out},
                      indent=1)


# -- the comparison --------------------------------------------------------------------------

def _exact(value) -> Fraction:
    return Fraction(str(value))


def storm_agrees(chain, title: str, pm: Path, context: str) -> dict:
    """Export ``chain``, have Storm build it exactly and solve it, and hold our model and
    our odds to Storm's; returns Storm's values (exact) for the caller's tally."""
    pm.write_text(to_prism(chain, title))
    program = stormpy.parse_prism_program(str(pm))
    props = stormpy.parse_properties("; ".join(PROPERTIES), program)
    options = stormpy.BuilderOptions(props)
    options.set_build_state_valuations()
    options.set_build_all_labels()
    options.set_build_all_reward_models()
    model = stormpy.build_model[stormpy.Rational](program, options=options)

    # the export, exactly: Storm's states are ours (each named by its valuation of s)
    assert model.nr_states == chain.size, context
    var = program.modules[0].integer_variables[0].expression_variable
    ours_of = [model.state_valuations.get_int64_value(i, var) for i in range(model.nr_states)]
    assert sorted(ours_of) == list(range(chain.size)), context
    rewards = model.reward_models["time"].state_rewards
    for state in model.states:
        s = ours_of[state.id]
        row = {ours_of[t.column]: _exact(t.value) for t in state.actions[0].transitions}
        expected = dict(chain.successors[s]) or {s: Fraction(1)}   # absorbing: a self-loop
        assert row == expected, f"{context}: state {s}: Storm has {row}, we have {expected}"
        assert abs(_exact(rewards[state.id]) - Fraction(chain.duration[s])) <= TOLERANCE, \
            f"{context}: state {s} lasts {chain.duration[s]}, Storm's reward {rewards[state.id]}"
    for name in (*ENDS, WAITS, "ended"):
        stormed = {ours_of[i] for i in model.labeling.get_states(name)}
        ours = {s for s, x in enumerate(chain.label)
                if x == name or (name == "ended" and x in ENDS)}
        assert stormed == ours, f"{context}: label {name}: Storm {sorted(stormed)}, ours {sorted(ours)}"

    # the odds
    init = model.initial_states[0]
    assert ours_of[init] == 0, context
    value = {}
    for text, prop in zip(PROPERTIES, props):
        result = stormpy.model_checking(model, prop, only_initial_states=True)
        value[text] = result.get_value(init)
    p = {name: _exact(value[f'P=? [F "{name}"]']) for name in (*ENDS, WAITS, "ended")}
    odds = odds_of(chain)
    absorption = solve(chain.as_analysis(), ENDS)

    def close(ours: float, storm: Fraction, what: str) -> None:
        assert abs(Fraction(ours) - storm) <= TOLERANCE, (
            f"{context}: {what}: ours {ours!r}, Storm's {storm} = {float(storm)!r}")

    for name in ENDS:
        close(odds.outcomes[name], p[name], f"P({name})")
    if odds.exact is not None:      # ours over the rationals too: exactly Storm's
        assert {name: odds.exact[name] for name in ENDS} == {name: p[name] for name in ENDS}, \
            f"{context}: exact outcomes: ours {odds.exact}, Storm's {p}"
        assert odds.exact["never"] == 1 - p["ended"], context
    close(odds.outcomes["never"], 1 - p["ended"], "P(never) against 1 - P(F ended)")
    close(absorption.probability.get(WAITS, 0.0), p[WAITS], "P(waits)")
    close(absorption.probability.get(CYCLES, 0.0), 1 - p["ended"] - p[WAITS],
          "P(cycles) against 1 - P(F ended) - P(F waits)")
    assert p["ended"] + p[WAITS] <= 1, context
    # the properties: Storm's LTL model checking of "eventually always owed" (a finite
    # run ends in an absorbing state, its self-loop for ever) is their failure
    for prop, label, held in zip(chain.properties, owes_labels(chain.properties),
                                 odds.properties):
        formula = f'P=? [F G "{label}"]'
        parsed = stormpy.parse_properties(formula, program)[0]
        fails = _exact(stormpy.model_checking(model, parsed, only_initial_states=True)
                       .get_value(init))
        close(held.holds, 1 - fails, f"P({prop.name} holds) against 1 - {formula}")
        if held.exact is not None:
            assert held.exact == 1 - fails, \
                f"{context}: {prop.name}: ours {held.exact}, Storm's {1 - fails}"
    if p["ended"] == 1:
        storm_mean = _exact(value['R{"time"}=? [F "ended"]'])
        assert odds.mean is not None, f"{context}: it surely ends, yet we give no mean"
        assert abs(Fraction(odds.mean) - storm_mean) <= TOLERANCE * max(1, storm_mean), (
            f"{context}: mean end time: ours {odds.mean!r}, Storm's {storm_mean} "
            f"= {float(storm_mean)!r}")
    elif p["ended"] > 0:
        # a mission that may never end: the mean end time of the runs that end, Storm's
        # conditional expected reward
        formula = 'R{"time"}=? [F "ended" || F "ended"]'
        parsed = stormpy.parse_properties(formula, program)[0]
        storm_mean = _exact(stormpy.model_checking(model, parsed, only_initial_states=True)
                            .get_value(init))
        assert odds.mean is not None, f"{context}: it may end, yet we give no mean"
        assert abs(Fraction(odds.mean) - storm_mean) <= TOLERANCE * max(1, storm_mean), (
            f"{context}: mean end time of the runs that end: ours {odds.mean!r}, Storm's "
            f"{storm_mean} = {float(storm_mean)!r}")
    return p


def lasts_no_time(chain) -> bool:
    """Every step of ``chain`` takes no time (the mission ends at its start): its export
    has a reward structure of one zero (the test below: Storm refused an empty one)."""
    return not any(chain.duration)


def _net(path: Path):
    return pipeline.compile_checked(pipeline.check_file(path))


def _watched(mission: Path) -> tuple:
    """The mission's properties: its own, then those of MISSION.props and
    MISSION.false.props (which hold or fail on the untimed net; with a vehicle, each
    has its probability)."""
    own = pipeline.properties_of(mission)[1]
    out = list(own)
    for side in (mission.with_suffix(".props"), mission.with_suffix(".false.props")):
        if side.is_file():
            out += pipeline.properties_of(mission, extra=side)[1][len(own):]
    return tuple(out)


# -- the cases -------------------------------------------------------------------------------

MODELLED = sorted((ROOT / "examples").glob("*.model.json"))


def test_the_papers_mission_has_a_vehicle_model():
    assert ROOT / "examples" / "sauce.model.json" in MODELLED


# the quick suite hands Storm the paper's mission with its model and one example with drawn
# vehicles; the others reach no line or branch of ours that these do not (make test-slow)
@pytest.mark.parametrize("model_path", variants(
    MODELLED, [ROOT / "examples" / "sauce.model.json"],
    ids=[p.name.split(".")[0] for p in MODELLED]))
def test_every_example_with_its_own_vehicle_model(model_path, tmp_path):
    """The vehicle models shipped beside their missions (the paper's: examples/sauce.*)."""
    mission = model_path.with_name(model_path.name.split(".")[0] + ".mcl")
    net = _net(mission)
    model = VehicleModel.load(model_path)
    model.check_primitives(PetriEngine(net).primitives_used())
    chain = chain_of(net, model, MAX_STATES, _watched(mission))
    assert chain.properties, f"{mission.name} has no properties to weigh"
    p = storm_agrees(chain, mission.stem, tmp_path / f"{mission.stem}.pm",
                     f"{mission.name} with {model_path.name}")
    assert sum(p[name] for name in ENDS) == p["ended"]


@pytest.mark.parametrize("path", variants(EXAMPLES, [ROOT / "examples" / "multi_leg.mcl"],
                                          ids=[p.stem for p in EXAMPLES]))
def test_every_example_with_drawn_vehicles(path, tmp_path):
    _drawn_vehicles(path, tmp_path, EXAMPLE_SEEDS)


@pytest.mark.slow
@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_every_example_with_more_drawn_vehicles(path, tmp_path):
    _drawn_vehicles(path, tmp_path, SLOW_SEEDS)


def _drawn_vehicles(path: Path, tmp_path: Path, seeds) -> None:
    net = _net(path)
    used = PetriEngine(net).primitives_used()
    checked = 0
    for s in seeds:
        rng = random.Random(zlib.crc32(f"{path.name}:{s}".encode()))
        text = random_model(used, rng)
        model = VehicleModel.from_json(text, f"<drawn for {path.name}, seed {s}>")
        try:
            chain = chain_of(net, model, MAX_STATES, _watched(path))
        except TooManyStates:
            continue
        storm_agrees(chain, f"{path.stem} seed {s}", tmp_path / f"{path.stem}-{s}.pm",
                     f"{path.name} with the model\n{text}\n")
        checked += 1
    if not checked:
        pytest.skip(f"every drawn model makes {path.name}'s chain larger than {MAX_STATES:,} states")


GENERATED = st.one_of(missions(depth=2, width=2), shaped_missions(depth=2))


def test_generated_missions_with_drawn_vehicles(tmp_path):
    tally: Counter = Counter()

    @settings(max_examples=GENERATED_EXAMPLES, deadline=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
    @given(GENERATED)
    def one(source):
        tally["drawn"] += 1
        net = pipeline.compile_checked(pipeline.check_source(source, "generated.mcl"))
        used = PetriEngine(net).primitives_used()
        assume(used)
        crc = zlib.crc32(source.encode())
        text = random_model(used, random.Random(crc))
        model = VehicleModel.from_json(text, "<drawn>")
        try:
            chain = chain_of(net, model, MAX_STATES)
        except TooManyStates:
            tally["too large"] += 1
            assume(False)
        tally["takes no time"] += lasts_no_time(chain)
        p = storm_agrees(chain, "generated", tmp_path / f"generated-{crc:08x}.pm",
                         f"the mission\n{source}\nwith the model\n{text}\n")
        tally["checked"] += 1
        tally["never ends, sometimes"] += p["ended"] < 1
        tally["ends, sometimes"] += 0 < p["ended"] < 1
        tally["waits, sometimes"] += p[WAITS] > 0

    seed(20240611)(one)()
    assert tally["checked"] >= MIN_CHECKED, f"too few generated missions checked: {dict(tally)}"
    # the conditional mean end time (Storm's R{"time"}=? [F "ended" || F "ended"]) checked
    assert tally["ends, sometimes"] >= 1, dict(tally)


def test_a_mission_that_takes_no_time_exports_a_chain_storm_reads(tmp_path):
    source = ("primitive P();\ntask T() = AchieveGoal(P()) timeout 10;\n"
              "mission { T(); }\n")
    net = pipeline.compile_checked(pipeline.check_source(source, "at_once.mcl"))
    model = VehicleModel.from_json(
        '{"primitives": {"P": {"achieve": "1/2", "fail": "1/2", "after": {"fixed": 0}}}}')
    chain = chain_of(net, model, MAX_STATES)
    assert lasts_no_time(chain)
    storm_agrees(chain, "at once", tmp_path / "at_once.pm", f"the mission\n{source}")
