"""The executor and the reference engine: the same mission and vehicle, the same run.

The reference engine reads MCL by the rules of mcl.md; the executor plays
the compiled net. Each judges the other: on every example with several
scripts, and on generated missions with generated scripts, both must give
the same outcome, time and trace (cli.md's ``--json`` object).
"""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings

from mcl2pnml.pipeline import check_source, compile_checked

from helpers import ROOT, both
from missions import missions, scripts
from sampling import sample

EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))


def example_scripts(checked) -> list[dict]:
    """Every primitive answering ok, fail or never, at a few delays, with ties."""
    used = sorted({p.name for t in checked.tasks.values() for p in t.primitives})
    shapes = [["ok@5"] * 12, ["fail@5"] * 12, ["never"], ["ok@0", "fail@3", "ok@10"] * 4]
    out = [{p: shapes[(i + k) % len(shapes)] for i, p in enumerate(used)}
           for k in range(len(shapes))]
    out.append({p: ["ok@2"] * 12 for p in used})   # everything at once: ties everywhere
    return out


@pytest.mark.parametrize("mission", EXAMPLES, ids=lambda p: p.stem)
def test_every_example_runs_the_same_on_both_engines(mission, examples):
    checked, net = examples.checked(mission.stem), examples.net(mission.stem)
    for script in example_scripts(checked):     # the net compiled once, for every script
        petri, reference = both(checked, script, net)
        assert petri == reference, f"{mission.name} with {script}"


def test_the_papers_mission_ends_as_the_paper_says(examples):
    checked, net = examples.checked("sauce"), examples.net("sauce")
    # the cross is found during the survey: dive, drop the marker, surface
    found = {"GoToWayPoint": ["ok@30", "ok@40"], "DetectCross": ["ok@50"],
             "KeepDepth": ["ok@5", "ok@6"], "ReleaseMarker": ["ok@1"]}
    petri, reference = both(checked, found, net)
    assert petri == reference and petri["outcome"] == "OK"
    enabled = [e["primitive"] for e in petri["trace"] if e.get("action") == "enable"]
    assert enabled[-3:] == ["KeepDepth", "ReleaseMarker", "KeepDepth"]
    assert [e["args"] for e in petri["trace"] if e.get("action") == "enable"
            and e["primitive"] == "KeepDepth"] == [[4.0], [0.0]]
    # no cross: the survey ends, the detector is stopped, the vehicle surfaces
    missed = {"GoToWayPoint": ["ok@30", "ok@40"], "DetectCross": ["never"],
              "KeepDepth": ["ok@5"]}
    petri, reference = both(checked, missed, net)
    assert petri == reference and petri["outcome"] == "OK" and petri["time"] == 75
    assert "ReleaseMarker" not in {e["primitive"] for e in petri["trace"]}


@settings(max_examples=sample(80, 25), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(missions(), scripts)
def test_generated_missions_run_the_same_on_both_engines(source, script):
    checked = check_source(source, "generated.mcl")
    petri, reference = both(checked, script)
    assert petri == reference, source


@pytest.mark.slow
@settings(max_examples=3000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(missions(), scripts)
def test_many_generated_missions_run_the_same_on_both_engines(source, script):
    checked = check_source(source, "generated.mcl")
    petri, reference = both(checked, script)
    assert petri == reference, source


@pytest.mark.parametrize("body", [
    # found by the 10,000-mission campaign: the watcher (an empty block) ends at once
    # and aborts the watched sequence between its first statement's end and the
    # call that follows; the call must end ABORTED without starting
    "monitor({ {  } T0(1); }, { {  } });",
    # the same race between a loop's body and its next test
    "monitor({ while (T0(1)) { {  } } }, { {  } });",
    "monitor({ while (T0(1)) { {  } } T0(2); }, { { } });",
])
def test_an_abort_between_two_steps_of_a_structure(body):
    source = ("primitive Pa(v);\ntask T0(x) = AchieveGoal(Pa(x));\n"
              f"mission {{ {body} }}\n")
    checked = check_source(source, "race.mcl")
    net = compile_checked(checked)      # once, for the three scripts
    for script in ({"Pa": []}, {"Pa": ["ok@0"] * 3}, {"Pa": ["fail@0"]}):
        petri, reference = both(checked, script, net)
        assert petri == reference, (body, script)
