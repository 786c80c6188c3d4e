"""The simulator's primitives (runtime/simprims.py, docs/simulator.md).

Every example flies on the simulator in the world beside it and both engines
give the same run; a keep-primitive rides out an overshoot (section 2.2: a
lost goal is a state that can be regained) but a real loss still fails the
KeepGoal task; a user's primitive file is loaded the way the built-ins are
registered, and its faults are our errors at its line.
"""
from __future__ import annotations

import pytest

from helpers import ROOT, run_cli
from sampling import variants
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.pipeline import check_source, run_mission
from mcl2pnml.runtime.aal import canonical_trace
from mcl2pnml.runtime.engine import Outcome, run
from mcl2pnml.runtime.session import RunOptions
from mcl2pnml.runtime import simprims
from mcl2pnml.runtime.simprims import built_in, load_file, table_rows
from mcl2pnml.runtime.simulator import AUVSimulator, World

from helpers import engines

EXAMPLES = ROOT / "examples"
DATA = ROOT / "tests" / "data" / "simprims"
MISSIONS = sorted(p.stem for p in EXAMPLES.glob("*.mcl"))


def _both(mission, **options) -> list[dict]:
    return [run_mission(mission, RunOptions(engine=engine, **options)).as_json()
            for engine in ("petri", "reference")]


# multi_leg reaches no line or branch of ours that the others do not (make test-slow flies it)
@pytest.mark.parametrize("name", variants(MISSIONS, [m for m in MISSIONS if m != "multi_leg"],
                                          ids=MISSIONS))
def test_every_example_flies_on_the_simulator_and_the_engines_agree(name):
    petri, reference = _both(EXAMPLES / f"{name}.mcl")
    assert petri == reference
    assert petri["outcome"] == "OK" and "safe_stop" not in petri


def test_every_primitive_an_example_declares_is_simulated_and_documented():
    used = set()
    for mission in EXAMPLES.glob("*.mcl"):
        used |= set(check_source(mission.read_text(), str(mission)).primitives)
    assert used <= set(built_in())
    doc = (ROOT / "docs" / "simulator.md").read_text()
    for name, arguments, achieves, fails in table_rows(built_in()):
        assert f"| {name} | {arguments} | {achieves} | {fails} |" in doc, name
        assert f"``{name}(" in simprims.__doc__, name


KEEP = """primitive KeepHeading(h);
primitive KeepDepth(d);
task H(h) = KeepGoal(KeepHeading(h)) timeout 60;
task D(d) = KeepGoal(KeepDepth(d)) timeout 60;
mission {{ {body} }}
"""


def _run_both(body: str, world: World) -> list:
    checked = check_source(KEEP.format(body=body))
    return [run(engine, AUVSimulator(world), max_time=600) for engine in engines(checked)]


@pytest.mark.parametrize("body", ["H(90.0);", "D(3.0);"])
def test_a_kept_goal_survives_the_overshoot_and_ends_ok_at_its_time_out(body):
    runs = _run_both(body, World())
    assert [r.outcome for r in runs] == [Outcome.OK, Outcome.OK]
    assert runs[0].time == 60 and runs[0].as_json() == runs[1].as_json()


def test_a_real_loss_still_fails_the_kept_goal():
    # a sea a weak depth controller cannot hold against: out of twice the band for 5 s
    runs = _run_both("D(2.5);", World(noise=1.0, max_heave=0.05, seed=1, cross=None))
    assert [r.outcome for r in runs] == [Outcome.FAIL, Outcome.FAIL]
    assert runs[0].as_json() == runs[1].as_json()
    events = [e["event"] for e in runs[0].as_json()["trace"] if "event" in e]
    assert events[:2] == ["achieved", "failed"]
    # a depth the tank cannot give fails at once
    assert [r.outcome for r in _run_both("D(9.0);", World())] == [Outcome.FAIL] * 2


def test_the_lost_rule_is_the_worlds():
    # no dwell: the overshoot of the turn is a loss again
    runs = _run_both("H(90.0);", World(lost_after=0.0, settle_time=0.0))
    assert [r.outcome for r in runs] == [Outcome.FAIL, Outcome.FAIL]


def test_a_users_primitive_file_adds_to_the_simulator(tmp_path):
    mission = tmp_path / "winch.mcl"
    mission.write_text("primitive Winch(metres);\ntask Reel(m) = AchieveGoal(Winch(m)) "
                       "timeout 30;\nmission { Reel(5.0); }\n")
    petri, reference = _both(mission, sim_primitives=(DATA / "winch.py",))
    assert petri == reference and petri["outcome"] == "OK" and petri["time"] == 10
    assert "Winch" not in built_in()      # the user's table is the run's, not the module's
    with pytest.raises(Mcl2PnmlError) as info:
        load_file(DATA / "broken.py")
    assert info.value.location.line == 4 and "'KeepDepth' is registered already" in str(
        info.value)


def test_a_users_primitive_file_on_the_command_line(tmp_path):
    mission = tmp_path / "winch.mcl"
    mission.write_text("primitive Winch(metres);\ntask Reel(m) = AchieveGoal(Winch(m));\n"
                       "mission { Reel(-1.0); }\n")
    out = run_cli("run", mission, "--sim-primitives", DATA / "winch.py", "--json")
    assert out.returncode == 1 and '"failed"' in out.stdout, out.stderr
    bad = tmp_path / "syntax.py"
    bad.write_text("x = 1\ndef (:\n")
    out = run_cli("run", mission, "--sim-primitives", bad)
    assert out.returncode == 2 and f"{bad}:2:" in out.stderr and "Traceback" not in out.stderr


def test_the_causal_order_of_one_instant():
    # the depth is achieved at t, which disables it and enables the waypoint at t:
    # the trace lists the cause first, on both engines
    checked = check_source("""primitive KeepDepth(d);
primitive GoToWayPoint(p);
task D(d) = AchieveGoal(KeepDepth(d)) timeout 60;
task G(p) = AchieveGoal(GoToWayPoint(p)) timeout 120;
mission { D(1.0); G((6.0, 4.0, 1.0)); }
""")
    traces = [canonical_trace(run(engine, AUVSimulator()).entries)
              for engine in engines(checked)]
    assert traces[0] == traces[1]
    kinds = [(e.get("event") or e["action"], e["primitive"]) for e in traces[0]]
    achieved = kinds.index(("achieved", "KeepDepth"))
    assert kinds[achieved:achieved + 4] == [("achieved", "KeepDepth"),
                                            ("disable", "KeepDepth"), ("off", "KeepDepth"),
                                            ("enable", "GoToWayPoint")]


def test_an_installed_packages_primitives_come_through_the_entry_point_group(monkeypatch):
    import importlib.metadata as metadata

    class Point:    # an installed package's entry point, naming the user's module
        name, value = "winch", "winch_package:primitives"

        def load(self):
            return load_file.__globals__["runpy"].run_path(str(DATA / "winch.py"))

    monkeypatch.setattr(metadata, "entry_points",
                        lambda group: [Point()] if group == simprims.ENTRY_POINTS else [])
    assert "Winch" in AUVSimulator().primitives and "Winch" not in built_in()


def test_a_resumed_run_uses_the_journals_primitive_files(tmp_path):
    mission = tmp_path / "winch.mcl"
    mission.write_text("primitive Winch(metres);\ntask Reel(m) = AchieveGoal(Winch(m));\n"
                       "mission { Reel(5.0); }\n")
    journal = tmp_path / "run.journal"
    first = run_mission(mission, RunOptions(journal=journal,
                                            sim_primitives=(DATA / "winch.py",)))
    lines = journal.read_text().splitlines(keepends=True)
    journal.write_text("".join(lines[:len(lines) // 2]))     # killed half-way
    again = run_mission(mission, RunOptions(resume=journal))
    assert first.as_json() == again.as_json() and first.outcome is Outcome.OK
