"""`mcl2pnml campaign`: simulated runs on Dask agree with the exact odds, and survive their
workers.

A campaign's outcome frequencies must hold the exact odds (`mcl2pnml odds`) within their
99% intervals; its runs are exactly its seeds, each once, whatever the cluster: the same
for a local cluster, a scheduler and workers started as separate processes on loopback,
and that cluster with a worker killed mid-campaign (Dask reschedules its batches).
"""
from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path

import pytest

from dask_cluster import free_port, started
from helpers import ROOT, one_error, run_cli
from sampling import variants
from mcl2pnml import pipeline
from mcl2pnml.commands.fly import CampaignOptions, campaign
from mcl2pnml.campaign import BATCH, TRACKS, Fleet, fly_batch
from mcl2pnml.core.progress import Notes
from mcl2pnml.odds import chain_of, odds, odds_of
from mcl2pnml.runtime.vehicle_model import VehicleModel

distributed = pytest.importorskip("distributed", reason="Dask's distributed is not installed "
                                  "(pip install -e '.[test]' installs it)")

SAUCE = ROOT / "examples" / "sauce.mcl"
MODEL = ROOT / "examples" / "sauce.model.json"


@pytest.fixture(scope="module")
def exact():
    return odds(pipeline.compile_checked(pipeline.check_file(SAUCE)), VehicleModel.load(MODEL))


@pytest.fixture(scope="module")
def local(tmp_path_factory):
    """800 runs on a local cluster of two workers, with their table."""
    table = tmp_path_factory.mktemp("campaign") / "runs.csv"
    out = run_cli("campaign", SAUCE, "--vehicle-model", MODEL, "--runs", 800, "--workers", 2,
                  "--json", "--table", table, "--seed", 100, "--progress", timeout=240)
    assert out.returncode == 0, out.stderr
    # the bar, and the note of the table written above it, on standard error only
    assert "800/800" in out.stderr and f"wrote {table}" in out.stderr, out.stderr
    return json.loads(out.stdout), table.read_text().splitlines()


def test_a_campaign_holds_the_exact_odds_within_its_intervals(local, exact):
    data, _ = local
    for outcome, d in data["outcomes"].items():
        low, high = d["interval"]
        assert low <= exact.outcomes[outcome] <= high, (outcome, d, exact.outcomes)
    t = data["end_time"]
    assert abs(t["mean"] - exact.mean) <= t["mean_interval_halfwidth"], (t, exact.mean)


def test_every_seed_is_flown_once_and_replays_alone(local):
    data, rows = local
    seeds = [int(r.split(",")[0]) for r in rows[1:]]
    assert seeds == list(range(100, 900)) and data["runs"] == 800
    # any run flown again alone, by its seed: the same end
    seed, outcome, t = rows[1 + 737].split(",")
    again = run_cli("run", SAUCE, "--vehicle", f"model:{MODEL}@{seed}", "--json")
    assert json.loads(again.stdout)["outcome"] == outcome
    assert float(json.loads(again.stdout)["time"]) == float(t)


@pytest.fixture(scope="module")
def shared():
    """One local cluster of two worker processes for the tests that need no cluster of
    their own (a campaign's default one is the command's test, above)."""
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=50)
    yield cluster.scheduler_address
    cluster.close()


def test_the_sequential_test_stops_as_soon_as_it_decides(exact, shared):
    target = exact.outcomes["OK"] - 0.1       # plainly true: decided early
    runs = 4 * BATCH        # decided in the first batch: the other three are never taken
    flown = campaign(SAUCE, CampaignOptions(MODEL, runs=runs, target=target,
                                            scheduler=shared)).flown
    data = flown.as_json()
    assert data["test"]["decided"] == f"P(OK) >= {target:g}"
    assert data["runs"] == data["test"]["after_runs"] < BATCH


@pytest.fixture
def cluster(tmp_path):
    """A scheduler and two workers, separate processes on loopback; killed at the end."""
    with started(tmp_path, workers=2) as running:
        yield running.address, running.workers


def test_a_scheduler_of_the_users_gives_the_same_runs_and_survives_a_killed_worker(cluster):
    address, procs = cluster
    # four batches: when the first is in, the others are being flown or wait, on both
    # workers; one of them killed then leaves batches to fly again on the other
    runs = 4 * BATCH
    done, result = [], {}

    def fly():
        try:
            result["campaign"] = campaign(
                SAUCE, CampaignOptions(MODEL, runs=runs, seed=5, scheduler=address),
                progress=lambda n, total: done.append(n)).flown
        except BaseException as e:     # noqa: BLE001 (said by the test, below)
            result["error"] = e
    # a daemon: a campaign that never ends fails this test, not the session's exit
    thread = threading.Thread(target=fly, daemon=True)
    thread.start()
    deadline = time.monotonic() + 60
    while not done and time.monotonic() < deadline and thread.is_alive():
        time.sleep(0.05)
    assert done, f"no batch came back within 60 s: {result.get('error')!r}"
    os.killpg(procs[0].pid, signal.SIGKILL)       # one worker gone mid-campaign
    thread.join(240)
    # the runs taken by then tell a stuck campaign from a slow one
    assert not thread.is_alive(), f"the campaign had not ended 240 s after the kill, " \
                                  f"{done[-1]:,} of {runs:,} runs taken"
    assert "error" not in result, repr(result.get("error"))
    flown = result["campaign"]
    assert [r.seed for r in flown.runs] == list(range(5, 5 + runs))
    # the same runs as flown here, batch by batch, without Dask
    alone = [r for k in range(0, runs, BATCH)
             for r in fly_batch(str(SAUCE), Fleet(model=str(MODEL)), "petri",
                                list(range(5 + k, 5 + min(k + BATCH, runs))), 24 * 3600.0)]
    assert flown.runs == alone


def test_a_scheduler_that_is_not_there_is_one_message():
    out = run_cli("campaign", SAUCE, "--vehicle-model", MODEL, "--runs", 10,
                  "--scheduler", f"tcp://127.0.0.1:{free_port()}", timeout=120)
    one_error(out, "cannot reach the Dask scheduler")


def test_a_bad_model_is_refused_before_any_run(tmp_path):
    bad = tmp_path / "m.json"
    bad.write_text('{"primitives": {"DetectCross": {"achieve": 2}}}')
    out = run_cli("campaign", SAUCE, "--vehicle-model", bad, "--runs", 10)
    one_error(out, "m.json:1:44:", "greater than the maximum")


def test_a_campaign_on_the_simulator_with_faults(shared, tmp_path):
    """The kinematic simulator in a noisy world, with KeepDepth's goal reports turned
    into failures one time in five: the paper's mission, which fails when a depth
    change fails, ends OK when none of its depth changes' reports is turned,
    (4/5)^k for its k calls of AchieveDepth. Every property the untimed net proves
    holds on every run (a run of an engine is a run of the net); the first runs'
    tracks are kept for the map; and any run flies again alone, by its seed."""
    from mcl2pnml.analysis.checking.observers import Status
    world = tmp_path / "noisy.world.json"
    world.write_text('{"noise": 0.05}')
    faults = tmp_path / "depth.faults.json"
    faults.write_text(json.dumps({"faults": {"KeepDepth": {"fail": "1/5"}}}))
    table, plot = tmp_path / "runs.csv", tmp_path / "runs.png"
    runs = 120
    flown = campaign(SAUCE, CampaignOptions(runs=runs, world=world, faults=faults, seed=40,
                                            properties="", scheduler=shared, table=table,
                                            plot=plot)).flown
    data = flown.as_json()
    calls = sum(line.count("AchieveDepth(") for line in SAUCE.read_text().splitlines()
                if not line.lstrip().startswith(("task", "//")))
    assert calls == 2
    low, high = data["outcomes"]["OK"]["interval"]
    assert low <= (4 / 5) ** calls <= high, data["outcomes"]
    assert set(data["outcomes"]) == {"OK", "FAIL"}

    net, props = pipeline.properties_of(SAUCE, extra=SAUCE.with_suffix(".props"))
    proven = {v.property.name for v in pipeline.check_properties(net, props)
              if v.status is Status.HOLDS}
    assert proven
    for p in data["properties"]:
        assert p["runs_judged"] == runs, p
        if p["property"] in proven:
            assert p["holds"] == 1.0, p

    assert [bool(r.track) for r in flown.runs] == [k < TRACKS for k in range(runs)]
    assert plot.read_bytes().startswith(b"\x89PNG")
    rows = table.read_text().splitlines()
    assert rows[0].startswith("seed,outcome,time,fails_")
    for outcome in ("OK", "FAIL"):
        seed, _, t = next(r for r in rows[1:] if r.split(",")[1] == outcome).split(",")[:3]
        again = run_cli("run", SAUCE, "--vehicle", f"sim@{seed}", "--world", world,
                        "--faults", faults, "--json")
        assert again.returncode in (0, 1), again.stderr
        assert (json.loads(again.stdout)["outcome"], float(json.loads(again.stdout)["time"])) \
            == (outcome, float(t))


def test_a_campaign_flies_either_a_model_or_the_simulator(tmp_path):
    world = tmp_path / "w.world.json"
    world.write_text("{}")
    out = run_cli("campaign", SAUCE, "--vehicle-model", MODEL, "--world", world, "--runs", 10)
    one_error(out, "--world", "a vehicle model answers without one")
    bad = tmp_path / "f.json"
    bad.write_text('{"faults": {"Thruster": {"fail": 0.5}}}')
    one_error(run_cli("campaign", SAUCE, "--faults", bad, "--runs", 10), "f.json:1:")
    one_error(run_cli("run", SAUCE, "--vehicle", "sim@x"), "the seed after sim@ is a whole number")


def test_a_campaign_whose_runs_are_all_alike_says_so(shared):
    notes = Notes()
    flown = campaign(SAUCE, CampaignOptions(runs=5, scheduler=shared), notes=notes).flown
    assert any("every run flies alike" in line for line in notes.said), notes.said
    assert len({(r.outcome, r.time) for r in flown.runs}) == 1


EXAMPLE_MODELS = sorted((ROOT / "examples").glob("*.model.json"))


def _holds_the_exact_odds(model: Path, runs: int, scheduler: str) -> None:
    """The campaign's frequencies of each outcome and of each property holding (the
    mission's .props and .false.props) hold the exact odds within their intervals."""
    mission = model.with_name(model.name.replace(".model.json", ".mcl"))
    props = mission.with_suffix(".false.props")
    net, watched = pipeline.properties_of(mission, extra=props)
    exact = odds_of(chain_of(pipeline.compile_checked(pipeline.check_file(mission)),
                             VehicleModel.load(model), properties=watched))
    data = campaign(mission, CampaignOptions(model, runs=runs, scheduler=scheduler,
                                             properties=str(props))).as_json()
    for outcome in ("OK", "FAIL", "ABORTED"):
        d = data["outcomes"].get(outcome)
        if d is None:   # never seen: the exact odds make that likely at this many runs
            assert (1 - exact.outcomes[outcome]) ** runs > 0.001, (outcome, exact.outcomes)
            continue
        low, high = d["interval"]
        assert low <= exact.outcomes[outcome] <= high, (model.name, outcome, d, exact.outcomes)
    t = data["end_time"]
    assert abs(t["mean"] - exact.mean) <= t["mean_interval_halfwidth"], (model.name, t, exact.mean)
    assert [p["property"] for p in data["properties"]] == [p.name for p in exact.properties]
    for flown, weighed in zip(data["properties"], exact.properties):
        assert flown["runs_judged"] == runs, flown
        low, high = flown["interval"]
        assert low <= weighed.holds <= high, (model.name, flown, weighed)
    assert any(0 < p.holds < 1 for p in exact.properties), exact.properties


# the paper's mission's model in the quick suite; the others reach no line or branch of ours
# that it does not (``make test-slow`` flies them)
@pytest.mark.parametrize("model", variants(
    EXAMPLE_MODELS, [ROOT / "examples" / "sauce.model.json"], ids=[p.name for p in EXAMPLE_MODELS]))
def test_every_example_model_s_campaign_holds_its_exact_odds(model, shared):
    _holds_the_exact_odds(model, 500, shared)


@pytest.mark.slow
@pytest.mark.parametrize("model", EXAMPLE_MODELS, ids=lambda p: p.name)
def test_ten_thousand_runs_of_every_example_model_hold_its_exact_odds(model, shared):
    _holds_the_exact_odds(model, 10_000, shared)
