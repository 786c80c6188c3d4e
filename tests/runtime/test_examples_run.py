"""Every example runs: on the vehicle script beside it, and on the simulator in its world.

``examples/NAME.vehicle.json`` scripts a plausible run of a mission and
``examples/NAME.world.json`` is the place it is written for, which the
simulator takes by default (tests/runtime/test_simprims.py runs them there); both
engines must give the same run, and the default vehicle's refusal of a
primitive it does not simulate must say what to give instead.
"""
from __future__ import annotations

import json

import pytest

from helpers import ROOT, run_cli

EXAMPLES = ROOT / "examples"
MISSIONS = sorted(EXAMPLES.glob("*.mcl"))


@pytest.mark.timeout(120)
@pytest.mark.parametrize("mission", MISSIONS, ids=lambda p: p.stem)
def test_every_example_runs_to_a_result_and_the_engines_agree(mission):
    script = mission.with_name(mission.stem + ".vehicle.json")
    vehicle = ["--vehicle", script] if script.is_file() else []
    runs = []
    for engine in ("petri", "reference"):
        out = run_cli("run", mission, "--engine", engine, "--json", *vehicle)
        assert out.returncode == 0, out.stderr
        runs.append(json.loads(out.stdout))
    assert runs[0] == runs[1]
    assert runs[0]["outcome"] == "OK" and "safe_stop" not in runs[0]


def test_every_example_the_simulator_cannot_fly_has_a_script():
    from mcl2pnml.pipeline import check_file
    from mcl2pnml.runtime.simulator import PRIMITIVES
    for mission in MISSIONS:
        used = set(check_file(mission).primitives)
        script = mission.with_name(mission.stem + ".vehicle.json")
        assert used <= set(PRIMITIVES) or script.is_file(), mission.name


def test_the_default_vehicle_says_it_is_the_simulator_and_names_the_script(tmp_path):
    # a primitive no simulated one answers to: the refusal names the script beside it
    mission = tmp_path / "winch.mcl"
    mission.write_text("primitive Winch(metres);\ntask Reel() = AchieveGoal(Winch(3.0));\n"
                       "mission { Reel(); }\n")
    script = tmp_path / "winch.vehicle.json"
    script.write_text('{"Winch": ["ok@5"]}')
    out = run_cli("run", mission)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "'Winch', which the simulator (the default vehicle) does not offer" in out.stderr
    assert f"--vehicle {script}" in out.stderr
    chosen = run_cli("run", mission, "--vehicle", "sim")
    assert chosen.returncode == 2 and "which this vehicle does not offer" in chosen.stderr


def test_the_world_beside_a_mission_is_named_when_it_is_taken():
    out = run_cli("run", EXAMPLES / "docking.mcl", "--json")
    assert out.returncode == 0, out.stderr
    beside = EXAMPLES / "docking.world.json"
    assert f"world: {beside}, the one beside the mission" in out.stderr
    given = run_cli("run", EXAMPLES / "docking.mcl", "--json", "--world", beside)
    assert given.returncode == 0 and "world:" not in given.stderr
    assert json.loads(given.stdout) == json.loads(out.stdout)
