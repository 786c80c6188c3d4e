"""Missions flown on the real autopilot: ArduSub in software-in-the-loop (tests/support/sitl.py).

``mcl2pnml run --vehicle mavlink`` flies a mission on ArduPilot's ArduSub: the
firmware itself, with a simulated submarine, spoken to over MAVLink as a
ground station speaks to it. Each test starts an autopilot of its own and
flies the mission with the command line, as a user does:

* the paper's mission on both engines: the cross found by the simulated
  camera on the autopilot's own position, the same actions in the same
  order, OK, and the vehicle left disarmed;
* the same without a cross: OK, and no marker dropped;
* faults made to happen to the firmware mid-mission (its GPS lost, its
  process killed, its ground-station failsafe, a mode and a servo it
  refuses): each run ends logged, with its safe state and no traceback,
  as the mission's semantics say it must for what the autopilot reported;
* (slow) every example whose primitives the default mapping binds, ending
  as it ends on the simulator in the same world.

"As the semantics say" is computed, not written down: the autopilot's
reports (each enabling answered achieved or failed after so long, or not
at all) are replayed on a vehicle script in virtual time, where both
engines must give the same actions and outcome as the flight did.
"""
from __future__ import annotations

import json
import subprocess
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Iterator

import pytest

import sitl
from helpers import ENGINES, ROOT, both, run_cli
from mcl2pnml.pipeline import check_file
from mcl2pnml.runtime.autopilot import AutopilotMapping
from mcl2pnml.runtime.engine import Outcome
from mcl2pnml.runtime.mavlink import DO_SET_SERVO
from mcl2pnml.runtime.reference import ReferenceEngine
from mcl2pnml.runtime.simulator import World
from test_show import marking, page_of  # noqa: F401 (fixtures)

EXAMPLES = ROOT / "examples"
SAUCE = EXAMPLES / "sauce.mcl"
#: Wall seconds: a run of the paper's mission (about 2 s alone), the autopilot
#: reaching a time of the mission, the test as a whole (past the autopilot's start and a
#: second station's connection, tests/support/sitl.py, so that a bound of theirs says what waited).
RUN_BOUND, MISSION_BOUND, TEST_BOUND = 30.0, 15.0, 120
#: Seconds of the autopilot's clock after arming when a fault is made to happen:
#: the vehicle is then on its way to the first waypoint.
FAULT_AT = 5.0
#: A ground station's system id that nobody on the link has (we are 255, the
#: second station 254): made the autopilot's own, its heartbeats stop for it.
NOBODY = 200
#: An output function that is not a plain servo (7: a camera mount's tilt):
#: ArduPilot refuses DO_SET_SERVO on an output that has it.
MOUNT_TILT = 7


@pytest.fixture
def ardusub() -> Path:
    """The firmware's folder; skipped, saying why, where it or pymavlink is not."""
    return sitl.need()


@pytest.fixture
def autopilot(ardusub, tmp_path) -> Iterator[sitl.Sitl]:
    """An ArduSub of the test's own, with ArduPilot's SITL defaults, stopped at the end."""
    with sitl.running(ardusub, tmp_path / "sitl") as running:
        yield running


@pytest.fixture
def faulted(ardusub, tmp_path) -> Iterator[sitl.Sitl]:
    """An ArduSub of the test's own, as ``autopilot``, at ``sitl.FAULT_SPEEDUP``: a second
    station faults it mid-mission."""
    with sitl.running(ardusub, tmp_path / "sitl", speedup=sitl.FAULT_SPEEDUP) as running:
        yield running


# -- a flight ---------------------------------------------------------------------------------

@dataclass
class Flight:
    """A finished ``mcl2pnml run``: its exit status, output, and JSON-lines log."""

    status: int
    out: str
    err: str
    log: list[dict]

    @property
    def outcome(self) -> str:
        return [e["outcome"] for e in self.log if "outcome" in e][-1]

    def actions(self) -> list[tuple]:
        """The mission's actions in order, as (action, primitive, args): the safe stop's not."""
        return [(e["action"], e["primitive"], e["args"]) for e in self.log
                if "action" in e and not e.get("safe_stop")]

    def reports(self, kind: str, primitive: str | None = None) -> list[dict]:
        return [e for e in self.log if e.get("event") == kind
                and primitive in (None, e["primitive"])]

    def secured(self) -> list[tuple[str, bool, str]]:
        """The safe state's steps: (step, acknowledged, what was seen)."""
        return [(e["safe_state"], e["acknowledged"], e["detail"]) for e in self.log
                if "safe_state" in e]

    def said(self) -> list[str]:
        """What the autopilot said (its STATUSTEXT), in order."""
        return [e["autopilot"] for e in self.log if str(e.get("autopilot", "")).startswith("says:")]

    def diagnosis(self) -> list[str]:
        """The lines under ``outcome ...`` in the report: why a run stalled, its safe state."""
        lines = self.out.splitlines()
        start = max(i for i, line in enumerate(lines) if line.startswith("outcome "))
        return [line.strip() for line in lines[start + 1:] if line.startswith("  ")]

    def assert_clean(self) -> None:
        """No traceback anywhere; the exit status is the outcome's."""
        assert "Traceback" not in self.err + self.out, self.err[-3000:]
        assert self.status == Outcome.from_json(self.outcome).exit_status, (self.status,
                                                                             self.outcome)

    def assert_left_disarmed(self) -> None:
        """The safe state's last step: the autopilot acknowledged the disarm, and is."""
        steps = self.secured()
        assert steps, "no safe state logged"
        assert steps[-1][:2] == ("disarm", True), steps


class Launched:
    """A run in flight: finished within a bound, killed if the test ends first."""

    def __init__(self, process: subprocess.Popen, folder: Path):
        self.process, self.folder = process, folder

    def finish(self, bound: float = RUN_BOUND) -> Flight:
        try:
            status = self.process.wait(bound)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(5)
            pytest.fail(f"the run did not end within {bound:g} s:\n"
                        + (self.folder / "run.out").read_text()[-3000:])
        log = self.folder / "run.jsonl"
        lines = log.read_text().splitlines() if log.is_file() else []
        return Flight(status, (self.folder / "run.out").read_text(),
                      (self.folder / "run.err").read_text(), [json.loads(line) for line in lines])


@contextmanager
def flying(autopilot: sitl.Sitl, folder: Path, *options: str, mission: Path = SAUCE,
           vehicle: str = "mavlink") -> Iterator[Launched]:
    """``mcl2pnml run MISSION --vehicle mavlink --connect`` the autopilot, logged in
    ``folder``; a run still going when the block ends is killed."""
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "run.out", "w") as out, open(folder / "run.err", "w") as err:
        process = subprocess.Popen(
            [sys.executable, "-m", "mcl2pnml", "run", str(mission), "--vehicle", vehicle,
             "--connect", autopilot.address, "--log", str(folder / "run.jsonl"), *options],
            cwd=ROOT, stdin=subprocess.DEVNULL, stdout=out, stderr=err)
    try:
        yield Launched(process, folder)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(5)


def fly(autopilot: sitl.Sitl, folder: Path, *options: str, bound: float = RUN_BOUND,
        **how) -> Flight:
    with flying(autopilot, folder, *options, **how) as run:
        return run.finish(bound)


def assert_disarmed(ground: sitl.Second) -> None:
    """The autopilot's next heartbeat says it is disarmed."""
    ground.armed = None
    ground.until(lambda: ground.armed is not None, MISSION_BOUND, "a heartbeat")
    assert ground.armed is False, "the autopilot is still armed"


def assert_autopilot_disarmed(autopilot: sitl.Sitl) -> None:
    """Asked on its second port after the run: the autopilot says it is disarmed."""
    with sitl.second(autopilot) as ground:
        assert_disarmed(ground)


# -- what the mission's semantics say ---------------------------------------------------------

def script_of(flight: Flight) -> dict[str, list[str]]:
    """A vehicle script answering each enabling as the autopilot did: its first report
    while enabled, that long after the enabling (``ok@S``, ``fail@S``), else ``never``."""
    script: dict[str, list[str]] = {}
    since: dict[str, float] = {}
    for e in flight.log:
        name = e.get("primitive")
        if "action" in e and not e.get("safe_stop"):
            if e["action"] == "enable":
                script.setdefault(name, []).append("never")
                since[name] = e["t"]
            else:
                since.pop(name, None)
        elif e.get("event") in ("achieved", "failed") and name in since:
            word = "ok" if e["event"] == "achieved" else "fail"
            script[name][-1] = f"{word}@{round(e['t'] - since.pop(name), 6)}"
    return script


def assert_as_the_semantics_say(flight: Flight, mission: Path = SAUCE) -> None:
    """Replayed on a vehicle script in virtual time, the autopilot's reports give, on both
    engines, the actions and the outcome the flight had."""
    petri, reference = both(check_file(mission), script_of(flight))
    assert petri == reference
    replayed = [(e["action"], e["primitive"], e["args"]) for e in reference["trace"]
                if "action" in e]
    assert replayed == flight.actions()
    assert reference["outcome"] == flight.outcome


def world_without_the_cross(folder: Path) -> Path:
    path = folder / "no_cross.world.json"
    path.write_text(json.dumps({"cross": None}))
    return path


# -- the paper's mission ------------------------------------------------------------------------

@pytest.mark.timeout(TEST_BOUND)
def test_the_papers_mission_finds_the_cross_on_both_engines_alike(ardusub, tmp_path):
    flights = {}
    for engine in ENGINES:
        with sitl.running(ardusub, tmp_path / engine / "sitl") as autopilot:
            flights[engine] = fly(autopilot, tmp_path / engine, "--engine", engine)
            assert_autopilot_disarmed(autopilot)
    for engine, flight in flights.items():
        flight.assert_clean()
        assert flight.outcome == "OK", (engine, flight.out[-3000:])
        found = flight.reports("achieved", "DetectCross")
        assert found and all(e["source"] == "simulated" for e in found), engine
        assert flight.reports("achieved", "ReleaseMarker"), engine
        assert any("marker" in e for e in flight.log), engine
        assert not flight.reports("failed"), engine
        flight.assert_left_disarmed()
        assert_as_the_semantics_say(flight)
    # the times are the autopilot's and differ a little from run to run; the actions do not
    assert flights["petri"].actions() == flights["reference"].actions()


@pytest.mark.timeout(TEST_BOUND)
def test_without_the_cross_the_survey_ends_ok_and_drops_no_marker(autopilot, tmp_path):
    flight = fly(autopilot, tmp_path, "--world", str(world_without_the_cross(tmp_path)))
    assert_autopilot_disarmed(autopilot)
    flight.assert_clean()
    assert flight.outcome == "OK", flight.out[-3000:]
    assert not flight.reports("achieved", "DetectCross")
    assert all(primitive != "ReleaseMarker" for _, primitive, _ in flight.actions())
    assert not any("marker" in e for e in flight.log)
    # every waypoint flown to the end: the survey, not the cross, ended the monitor
    legs = [args for action, primitive, args in flight.actions()
            if (action, primitive) == ("enable", "GoToWayPoint")]
    assert legs and len(flight.reports("achieved", "GoToWayPoint")) == len(legs)
    flight.assert_left_disarmed()
    assert_as_the_semantics_say(flight)


@pytest.mark.timeout(TEST_BOUND)
def test_a_flight_is_replayed_on_the_page_and_drawn_as_fig_5(faulted, tmp_path, page_of):
    """``show --run`` plays a flight's log on the net; Fig. 5 is drawn from its own track."""
    from paper_repro.ardusub import main as fig5, trial_from_log
    # at the fault speed-up: at 100, DropMarker's 10 s are a tenth of a wall second, and
    # beside a second suite the servo's answer came later (the mission FAILed)
    flight = fly(faulted, tmp_path)
    assert flight.outcome == "OK", flight.out[-3000:]
    log = tmp_path / "run.jsonl"
    out = run_cli("show", SAUCE, "--run", log, "-o", tmp_path / "flight.html", cwd=ROOT)
    assert out.returncode == 0, out.stderr
    page = page_of(tmp_path / "flight.html")
    page.click("#run-end")
    assert "mission.OK" in marking(page)
    fired = [e["fire"] for e in flight.log if "fire" in e]
    assert page.locator("#history li").all_text_contents() == fired
    # the log's own lines are told in words, the track is not played
    shown = page.locator("#run-entries li").all_text_contents()
    assert any("(simulated)" in line and "DetectCross" in line for line in shown)
    assert any("safe state disarm" in line for line in shown)
    assert not any('"track"' in line for line in shown)
    # Fig. 5 from the log alone: the track, the set points, the marker, the outcome
    trial = trial_from_log(log, "flown", None)
    assert trial.outcome is Outcome.OK
    assert len(trial.trajectory) == sum("track" in e for e in flight.log) > 10
    assert trial.markers == [tuple(e["marker"]) for e in flight.log if "marker" in e]
    deepest = max(args[0] for action, primitive, args in flight.actions()
                  if (action, primitive) == ("enable", "KeepDepth"))
    assert max(z for _, _, _, z in trial.trajectory) >= deepest - 2 * World().depth_band
    assert fig5([str(log), "-o", str(tmp_path / "fig5.png")]) == 0
    assert (tmp_path / "fig5.png").stat().st_size > 10_000


# -- faults ------------------------------------------------------------------------------------

@pytest.mark.timeout(TEST_BOUND)
def test_gps_lost_on_the_way_fails_the_waypoint_and_the_mission(faulted, tmp_path):
    # without the cross nothing but the waypoints can end the survey
    world = world_without_the_cross(tmp_path)
    # the GPS must be off well before the survey's last waypoint (about 20 s of the
    # autopilot's clock after the fault's time): at a speed-up of 100 that is 0.2 s of
    # wall clock for the second station to see the time and set the parameter, which two
    # suites side by side on 2 cores have exceeded; at sitl.FAULT_SPEEDUP, 2 s
    with flying(faulted, tmp_path, "--world", str(world)) as run, \
            sitl.second(faulted) as ground:
        ground.mission_time(FAULT_AT, MISSION_BOUND)
        assert ground.set_param("SIM_GPS1_ENABLE", 0) == 0
        flight = run.finish()
        assert_disarmed(ground)
    flight.assert_clean()
    failed = flight.reports("failed")
    assert failed, flight.out[-3000:]
    first = failed[0]
    assert (first["primitive"], first["source"]) == ("GoToWayPoint", "autopilot"), first
    assert "no position" in first["why"], first
    # AchieveWayPoint FAIL -> Survey FAIL ends the monitor without the cross: no marker;
    # then the surface depth is asked of an autopilot without a position: FAIL
    assert flight.outcome == "FAIL"
    assert_as_the_semantics_say(flight)
    flight.assert_left_disarmed()


@pytest.mark.timeout(TEST_BOUND)
def test_the_autopilot_killed_mid_mission_stalls_the_run_with_the_link_lost(faulted,
                                                                            tmp_path):
    with flying(faulted, tmp_path, "--liveness", "2") as run, \
            sitl.second(faulted) as ground:
        ground.mission_time(FAULT_AT, MISSION_BOUND)
        faulted.kill()
        flight = run.finish()
    flight.assert_clean()
    assert flight.outcome == "STALLED" and flight.status == 5
    assert "the link to the vehicle was lost" in flight.diagnosis()[0], flight.diagnosis()
    # the flown primitives were enabled: the safe stop disabled them, logged
    assert any(e.get("safe_stop") for e in flight.log)
    steps = flight.secured()
    assert [step for step, _, _ in steps] == list(AutopilotMapping.ardusub().safe_state)
    assert all(not acknowledged and "not done" in detail for _, acknowledged, detail in steps)


@pytest.mark.timeout(TEST_BOUND)
def test_the_ground_station_failsafe_disarms_and_the_flown_primitives_fail(faulted,
                                                                           tmp_path):
    with flying(faulted, tmp_path) as run, sitl.second(faulted) as ground:
        assert ground.param("FS_GCS_ENABLE") == 2      # ArduSub's default: disarm
        # the time-out ArduSub has (the harness gives the other flights more, sitl.HARNESS)
        assert ground.set_param("FS_GCS_TIMEOUT", sitl.FS_GCS_TIMEOUT) == sitl.FS_GCS_TIMEOUT
        ground.mission_time(FAULT_AT, MISSION_BOUND)
        assert ground.set_param("MAV_GCS_SYSID", NOBODY) == NOBODY
        flight = run.finish()
        assert_disarmed(ground)
    flight.assert_clean()
    assert any("heartbeat lost" in text for text in flight.said()), flight.said()
    failed = flight.reports("failed")
    assert failed, flight.out[-3000:]
    assert all(e["source"] == "autopilot" and "disarmed" in e["why"] for e in failed), failed
    # which of the flown primitives the disarm reaches first depends on where the mission
    # was when the failsafe came (on a loaded machine, between two legs): one of them
    assert failed[0]["primitive"] in ("GoToWayPoint", "KeepDepth"), failed
    assert flight.outcome == "FAIL"
    assert_as_the_semantics_say(flight)
    flight.assert_left_disarmed()


@pytest.mark.timeout(TEST_BOUND)
def test_guided_refused_without_a_position_stalls_the_run_saying_so(ardusub, tmp_path):
    parm = tmp_path / "no_gps.parm"
    parm.write_text("SIM_GPS1_ENABLE 0\n")
    mapping = json.loads(resources.files("mcl2pnml.runtime").joinpath("ardusub.json")
                         .read_text("utf-8"))
    mapping["ready_within"] = 5
    mapping_file = tmp_path / "impatient.json"
    mapping_file.write_text(json.dumps(mapping))
    with sitl.running(ardusub, tmp_path / "sitl", parm) as autopilot:
        flight = fly(autopilot, tmp_path / "run", vehicle=f"mavlink:{mapping_file}")
        assert_autopilot_disarmed(autopilot)
    flight.assert_clean()
    assert flight.outcome == "STALLED" and flight.status == 5
    assert "refused mode GUIDED" in flight.diagnosis()[0], flight.diagnosis()
    assert not flight.reports("achieved") and not flight.reports("failed")
    # never armed: the safe state is logged; nothing is sent to a disarmed vehicle
    steps = {name: (acknowledged, detail) for name, acknowledged, detail in flight.secured()}
    assert set(steps) == {"hold", "surface", "disarm"}, steps
    assert all(not steps[name][0] and "disarmed" in steps[name][1]
               for name in ("hold", "surface")), steps
    assert steps["disarm"][0] and "already disarmed" in steps["disarm"][1], steps


@pytest.mark.timeout(TEST_BOUND)
def test_a_servo_the_autopilot_refuses_fails_the_marker(ardusub, tmp_path):
    channel = AutopilotMapping.ardusub().bindings["ReleaseMarker"].channel
    parm = tmp_path / "servo_in_use.parm"
    parm.write_text(f"SERVO{channel}_FUNCTION {MOUNT_TILT}\n")
    with sitl.running(ardusub, tmp_path / "sitl", parm) as autopilot:
        flight = fly(autopilot, tmp_path / "run")
        assert_autopilot_disarmed(autopilot)
    flight.assert_clean()
    failed = flight.reports("failed")
    assert [e["primitive"] for e in failed] == ["ReleaseMarker"], failed
    assert failed[0]["source"] == "autopilot"
    assert f"refused command {DO_SET_SERVO}" in failed[0]["why"], failed
    assert any("in use" in text for text in flight.said()), flight.said()
    # the cross was found all the same: DropMarker FAIL ends the mission FAIL
    assert flight.reports("achieved", "DetectCross")
    assert flight.outcome == "FAIL"
    assert_as_the_semantics_say(flight)
    flight.assert_left_disarmed()


# -- every example --------------------------------------------------------------------------

def flown_examples() -> list[Path]:
    """The examples whose primitives the default mapping binds, every one."""
    bound = set(AutopilotMapping.ardusub().bindings)
    return [m for m in sorted(EXAMPLES.glob("*.mcl"))
            if ReferenceEngine(check_file(m)).primitives_used() <= bound]


@pytest.mark.slow
@pytest.mark.timeout(300)
@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("mission", flown_examples(), ids=lambda p: p.stem)
def test_every_example_ends_on_the_autopilot_as_on_the_simulator(autopilot, tmp_path,
                                                                 mission, engine):
    simulated = run_cli("run", mission, "--json", "--engine", engine, cwd=ROOT, timeout=120)
    assert simulated.returncode in (0, 1, 4), simulated.stderr
    expected = json.loads(simulated.stdout)
    flight = fly(autopilot, tmp_path / "run", "--engine", engine, mission=mission, bound=240)
    assert_autopilot_disarmed(autopilot)
    flight.assert_clean()
    world = mission.with_name(mission.stem + ".world.json")
    if world.is_file():     # the world beside the mission is flown, and said to be
        assert str(world.relative_to(ROOT)) in flight.err or str(world) in flight.err
    assert flight.outcome == expected["outcome"], flight.out[-3000:]
    flight.assert_left_disarmed()
    here = {e["primitive"] for e in flight.reports("failed")}
    there = {e["primitive"] for e in expected["trace"] if e.get("event") == "failed"}
    assert here == there, (here, there)
    assert_as_the_semantics_say(flight, mission)
