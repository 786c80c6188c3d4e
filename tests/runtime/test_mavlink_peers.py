"""A MAVLink autopilot that misbehaves, on loopback: each run ends in its bound, with its safe stop.

``mcl2pnml run --vehicle mavlink`` against the fake autopilot of
tests/support/fake_autopilot.py, through the real entry point (the pipeline's
``run_mission``, or the command line). A peer that behaves is flown: armed
in GUIDED, the waypoints sent as position targets, the marker's servo
commanded, then the safe state (hold, surface, disarm), each step
acknowledged. Then each way a peer can fail: it says nothing, sends
garbage, floods, is not a submarine, goes silent mid-mission, closes the
connection, its clock leaps, runs back or stands, it refuses GUIDED or
acknowledges nothing; and the addresses and options that cannot work. Each run
ends within the liveness (1 s here) and a few seconds, STALLED with the
reason first in its diagnosis, the primitives it had enabled disabled.
"""
from __future__ import annotations

import io
import json
import re
import socket
import time
from importlib import resources
from pathlib import Path

import pytest

pytest.importorskip("pymavlink")

from mcl2pnml.pipeline import RunOptions, run_mission  # noqa: E402
from mcl2pnml.runtime.aal import Action, ActionKind  # noqa: E402
from mcl2pnml.runtime.engine import Outcome, Run  # noqa: E402
from mcl2pnml.runtime.mavlink import Reported  # noqa: E402

from fake_autopilot import (ARM_DISARM, DO_SET_SERVO, GUIDED, POSHOLD, QUADROTOR,  # noqa: E402
                            SET_MODE, SURFACE, FakeAutopilot)
from helpers import ROOT, cli, one_error, run_cli  # noqa: E402

SAUCE = ROOT / "examples" / "sauce.mcl"
#: The liveness of every run here (s): a peer that says nothing for this long is lost.
LIVENESS = 1.0
#: What a run may take past its bound: connecting, the safe state's steps, a busy machine
#: (seconds where a quiet one takes tenths: a bound of 9 s was overrun by a run of 10.3 s
#: with three suites on 2 cores); still far short of the minute of wall clock the runs
#: here have before their time limit (600 s of the autopilot's clock at its speed-up of 10).
SLACK = 10.0
#: Wall seconds for a test as a whole: past every bound above, so that a bound says what
#: waited, not the test's time-out.
TEST_BOUND = 60
#: Wall seconds the safe state keeps trying a silent peer here (the mapping's
#: ``secure_within``): short, so that a run that ends on a silent peer ends soon after.
SECURE_WITHIN = 0.5
#: The first waypoint of sauce.mcl, (10, 0) at 2 m, from the world's start (2, 4): north,
#: east, down, as the autopilot's position target has it.
WAYPOINT_1 = (8.0, -4.0, 2.0)


def mapping_file(folder: Path, **settings) -> Path:
    """The package's ArduSub mapping with ``settings`` changed, written in ``folder``."""
    data = json.loads(resources.files("mcl2pnml.runtime").joinpath("ardusub.json")
                      .read_text("utf-8"))
    data.update(settings)
    path = folder / ("mapping-" + "-".join(f"{k}{v}" for k, v in sorted(settings.items()))
                     + ".json")
    path.write_text(json.dumps(data))
    return path


#: The mapping every run here uses unless told otherwise (written by :func:`_mapping`).
MAPPING: Path | None = None


@pytest.fixture(autouse=True, scope="module")
def _mapping(tmp_path_factory):
    """Every run here uses the package's mapping with a short ``secure_within``."""
    global MAPPING
    MAPPING = mapping_file(tmp_path_factory.mktemp("mapping"), secure_within=SECURE_WITHIN)
    yield


def fly(fake: FakeAutopilot, *, max_time: float = 600.0, log=None, mapping: Path | None = None,
        liveness: float = LIVENESS) -> tuple[Run, float, str]:
    """A run of sauce.mcl against ``fake``: the run, its wall time, its live log."""
    text = io.StringIO()
    start = time.monotonic()
    result = run_mission(SAUCE, RunOptions(vehicle=f"mavlink:{mapping or MAPPING}",
                                           connect=fake.address, liveness=liveness,
                                           max_time=max_time),
                         text=text, log_path=log)
    elapsed = time.monotonic() - start
    fake.check()
    return result, elapsed, text.getvalue()


def assert_stalled(result: Run, elapsed: float, why: str, bound: float = LIVENESS + SLACK):
    """STALLED within ``bound`` wall seconds, ``why`` first in the diagnosis."""
    assert result.outcome is Outcome.STALLED, result.report()
    assert why in result.waiting[0], result.waiting
    assert elapsed < bound, elapsed


def safe_stopped(result: Run) -> list[str]:
    return [action.primitive for action in result.safe_stop]


def left_enabled(result: Run) -> set[str]:
    """The primitives enabled and disabled neither by the mission nor by the safe stop."""
    enabled: set[str] = set()
    for entry in result.entries:
        if isinstance(entry, Action):
            (enabled.add if entry.kind is ActionKind.ENABLE else enabled.discard)(
                entry.primitive)
    return enabled - set(safe_stopped(result))


def free_port() -> int:
    with socket.create_server(("127.0.0.1", 0)) as s:
        return s.getsockname()[1]


# -- a peer that behaves ------------------------------------------------------------------------

@pytest.mark.timeout(TEST_BOUND)
def test_every_position_streamed_is_judged_not_only_the_latest():
    # an autopilot ticking twice a wall second streams ten positions each time (a link
    # that batches, a loaded machine): the last of them is metres past the cross under
    # the second leg, one in between is over it
    with FakeAutopilot(tick=0.5) as fake:
        result, _, _ = fly(fake)
    assert result.outcome is Outcome.OK, result.report()
    assert [p[:2] for p in fake.commanded(DO_SET_SERVO)] == [(9, 1900), (9, 1100)], \
        "the cross was flown over and not seen"


@pytest.mark.timeout(TEST_BOUND)
def test_a_peer_that_behaves_flies_the_mission_and_is_left_disarmed(tmp_path):
    log = tmp_path / "run.jsonl"
    with FakeAutopilot() as fake:
        result, elapsed, text = fly(fake, log=log)
    assert result.outcome is Outcome.OK, result.report()
    assert elapsed < 20, elapsed        # at the fake's speed-up, not the autopilot's clock
    assert left_enabled(result) == set() and result.safe_stop == []
    # GUIDED and armed; at the end POSHOLD, SURFACE, disarmed
    assert [int(p[1]) for p in fake.commanded(SET_MODE)] == [GUIDED, POSHOLD, SURFACE]
    assert [p[0] for p in fake.commanded(ARM_DISARM)] == [1, 0]
    assert fake.armed_ever and not fake.armed
    # the waypoint flown as a GUIDED target; the marker's servo set, then released
    assert WAYPOINT_1 in fake.targets
    assert [p[:2] for p in fake.commanded(DO_SET_SERVO)] == [(9, 1900), (9, 1100)]
    achieved = [e for e in result.entries if isinstance(e, Reported)
                and e.primitive == "GoToWayPoint"]
    assert achieved and achieved[0].source == "autopilot" and achieved[0].why == "telemetry"
    # the safe state, every step acknowledged
    assert result.secured[0] == "hold: POSHOLD acknowledged; the vehicle has stopped"
    assert result.secured[1].startswith("surface: SURFACE acknowledged; at the surface")
    assert result.secured[2] == "disarm: disarm acknowledged; disarmed"
    assert result.as_json()["safe_state"] == result.secured
    lines = [json.loads(line) for line in log.read_text().splitlines()]
    steps = [(line["safe_state"], line["acknowledged"]) for line in lines if "safe_state" in line]
    assert steps == [("hold", True), ("surface", True), ("disarm", True)]
    assert "armed in GUIDED: the mission's clock starts" in text


@pytest.mark.timeout(TEST_BOUND)
def test_an_autopilot_without_sim_speedup_keeps_its_heartbeats_counted():
    # a real autopilot has no SIM_SPEEDUP: the second spent waiting for one counted none of
    # its heartbeats, and a liveness of 1 s lost the link as soon as it was made
    with FakeAutopilot(answer_speedup=False) as fake:
        result, elapsed, _ = fly(fake, max_time=3)
    assert result.outcome is Outcome.TIMELIMIT, result.report()
    assert elapsed < LIVENESS + SLACK + 1, elapsed
    assert result.secured[-1] == "disarm: disarm acknowledged; disarmed"


# -- a peer that is no autopilot -----------------------------------------------------------------

@pytest.mark.timeout(TEST_BOUND)
def test_a_peer_that_says_nothing_is_no_autopilot_after_the_liveness():
    with FakeAutopilot("silent") as fake:
        result, elapsed, _ = fly(fake)
    assert_stalled(result, elapsed, f"no autopilot heartbeat from {fake.address} within 1 s")
    assert elapsed >= LIVENESS
    assert result.time == 0
    assert fake.commands == []      # nothing commanded to what never said it is an autopilot
    assert [line.split(":")[0] for line in result.secured] == ["hold", "surface", "disarm"]
    assert all(": not done: " in line for line in result.secured)


@pytest.mark.timeout(TEST_BOUND)
def test_a_peer_that_sends_garbage_is_no_autopilot_and_no_traceback():
    with FakeAutopilot("garbage") as fake:
        start = time.monotonic()
        out = run_cli("run", SAUCE, "--vehicle", "mavlink", "--connect", fake.address,
                      "--liveness", LIVENESS, timeout=20)
        elapsed = time.monotonic() - start
        fake.check()
    assert "Traceback" not in out.stderr and out.stderr == "", out.stderr
    assert out.returncode == Outcome.STALLED.exit_status, out.stdout
    assert f"no autopilot heartbeat from {fake.address} within 1 s" in out.stdout
    # and the interpreter's start, which a loaded machine (the whole suite at once) makes slow
    assert elapsed < LIVENESS + SLACK + 6, elapsed


@pytest.mark.timeout(TEST_BOUND)
def test_a_flood_without_a_heartbeat_is_no_autopilot():
    with FakeAutopilot("flood", flood_rate=20_000) as fake:
        result, elapsed, _ = fly(fake)
    assert_stalled(result, elapsed, f"no autopilot heartbeat from {fake.address} within 1 s")
    # it flooded all along (how many it sent depends on the machine's load, not checked)
    assert fake.sent_messages > 0


@pytest.mark.timeout(TEST_BOUND)
def test_a_vehicle_that_is_not_a_submarine_is_refused_before_anything_is_sent():
    with FakeAutopilot(kind=QUADROTOR) as fake:
        result, elapsed, _ = fly(fake)
    assert_stalled(result, elapsed, "the autopilot (system 1) says it is a vehicle of "
                                    "MAV_TYPE 2, not a submarine (12)")
    assert "flies submarines only" in result.waiting[0]
    assert fake.commands == []


@pytest.mark.timeout(TEST_BOUND)
def test_a_peer_that_sends_only_heartbeats_has_no_clock():
    with FakeAutopilot("heartbeats") as fake:
        result, elapsed, _ = fly(fake)
    assert_stalled(result, elapsed, "the autopilot's clock has not moved for 1 s (it has sent "
                                    "no time): no telemetry, or a clock that stands")
    assert not fake.armed_ever


# -- a peer that refuses ---------------------------------------------------------------------------

@pytest.mark.timeout(TEST_BOUND)
def test_a_refused_guided_says_the_refusal_and_the_autopilots_words():
    with FakeAutopilot(refuse_guided=True) as fake:
        result, elapsed, _ = fly(fake)
    assert_stalled(result, elapsed, 'the autopilot refused mode GUIDED (FAILED): "Mode change '
                                    'failed: GUIDED requires position"')
    assert fake.commanded(ARM_DISARM) == [] and not fake.armed_ever
    assert result.time == 0      # the mission's clock never started


@pytest.mark.timeout(TEST_BOUND)
def test_a_peer_that_acknowledges_nothing_is_refused_within_the_acknowledgement_time():
    with FakeAutopilot("deaf") as fake:
        result, elapsed, _ = fly(fake)
    # a second for SIM_SPEEDUP, then 3 s of its clock (0.3 s at its speed-up) for GUIDED
    assert_stalled(result, elapsed, "the autopilot refused mode GUIDED (no acknowledgement)")
    assert [int(p[1]) for p in fake.commanded(SET_MODE)] == [GUIDED]
    assert not fake.armed_ever


@pytest.mark.timeout(TEST_BOUND)
def test_a_peer_deaf_mid_mission_has_each_safe_state_step_said_unacknowledged_in_time():
    with FakeAutopilot(then="deaf", after=0.1) as fake:
        result, elapsed, _ = fly(fake, max_time=3)
    assert result.outcome is Outcome.TIMELIMIT, result.report()
    # each step waits for the answer to its TIMESYNC request up to the liveness (it has
    # answered them before: a link that lags), then 3 s of the autopilot's clock; no longer
    assert elapsed < 3 * LIVENESS + SLACK, elapsed
    assert result.secured == ["hold: POSHOLD not acknowledged (no acknowledgement)",
                              "surface: SURFACE not acknowledged (no acknowledgement)",
                              "disarm: disarm not acknowledged (no acknowledgement)"]
    assert fake.armed      # its own failsafes are all that is left
    assert left_enabled(result) == set()


# -- a peer that fails mid-mission ----------------------------------------------------------------

@pytest.mark.timeout(TEST_BOUND)
def test_a_peer_silent_mid_mission_is_a_lost_link_with_the_safe_stop(tmp_path):
    log = tmp_path / "run.jsonl"
    with FakeAutopilot(then="silent", after=0.3) as fake:
        result, elapsed, text = fly(fake, log=log)
        end = time.monotonic()
    silent_for = end - fake.turned_at - 0.3
    assert_stalled(result, elapsed, "the link to the vehicle was lost (waiting): no heartbeat "
                                    "from the autopilot for 1 s")
    assert LIVENESS - 0.2 <= silent_for < LIVENESS + SLACK, silent_for
    # it was armed and flying to the first waypoint when it fell silent
    assert fake.armed_ever and WAYPOINT_1 in fake.targets
    assert "GoToWayPoint" in safe_stopped(result) and left_enabled(result) == set()
    stops = result.as_json()["safe_stop"]       # what --json prints
    assert {"action": "disable", "primitive": "GoToWayPoint", "safe_stop": True}.items() <= \
        next(s for s in stops if s["primitive"] == "GoToWayPoint").items()
    lines = [json.loads(line) for line in log.read_text().splitlines()]
    assert any(line.get("safe_stop") and line["primitive"] == "GoToWayPoint" for line in lines)
    # the safe state was tried, and each step said not done: nobody answers
    steps = [line for line in lines if "safe_state" in line]
    assert [(s["safe_state"], s["acknowledged"]) for s in steps] == [
        ("hold", False), ("surface", False), ("disarm", False)]
    assert all("not done: no heartbeat from the autopilot for 1 s" in line
               for line in result.secured)
    assert "safe-stop" in text


@pytest.mark.timeout(TEST_BOUND)
def test_a_peer_that_closes_mid_mission_ends_the_run_at_once_and_prints_nothing(capfd):
    with FakeAutopilot(then="close", after=0.3) as fake:
        result, elapsed, _ = fly(fake)
        end = time.monotonic()
    assert result.outcome is Outcome.STALLED, result.report()
    assert re.search(r"the link to the vehicle was lost \(.*\): .*(the autopilot closed the "
                     r"connection|the connection was reset)", result.waiting[0]), result.waiting
    # heard at once, not after the liveness
    assert end - fake.turned_at - 0.3 < LIVENESS, end - fake.turned_at
    assert "GoToWayPoint" in safe_stopped(result) and left_enabled(result) == set()
    assert all(": not done: " in line for line in result.secured)
    # pymavlink's own words on a closed socket, once per read, used to fill standard output
    out, err = capfd.readouterr()
    assert "TCP socket" not in out + err


@pytest.mark.timeout(TEST_BOUND)
def test_a_flood_mid_mission_with_heartbeats_does_not_hold_the_run_up():
    with FakeAutopilot(then="flood+fly", after=0.1, flood_rate=5000) as fake:
        result, elapsed, text = fly(fake, max_time=10)
    # 10 s of the autopilot's clock at its speed-up of 10, then the safe state
    assert result.outcome is Outcome.TIMELIMIT, result.report()
    assert elapsed < LIVENESS + SLACK + 1, elapsed
    assert safe_stopped(result) and left_enabled(result) == set()
    # the flood reached the run (how many the fake sends in its second depends on the
    # machine's load: 2,302 with two suites side by side on 2 cores, over 3,000 alone)
    assert "says: flood" in text
    assert result.secured[-1] == "disarm: disarm acknowledged; disarmed"
    assert not fake.armed
    # its words are kept to a bound, not one log line each
    assert text.count("says: flood") <= 200


@pytest.mark.timeout(TEST_BOUND)
@pytest.mark.parametrize("behaviour, why", [
    ("leap", r"the autopilot's clock went from ([\d.]+) s to ([\d.]+) s: rebooted, or not "
             r"one autopilot"),
    ("backwards", r"the autopilot's clock went from ([\d.]+) s to ([\d.]+) s: rebooted, or "
                  r"not one autopilot"),
    ("frozen", r"the autopilot's clock has not moved for 1 s \(at ([\d.]+) s\): no telemetry, "
               r"or a clock that stands"),
])
def test_a_clock_that_leaps_runs_back_or_stands_stops_the_run(behaviour, why):
    with FakeAutopilot(then=behaviour, after=0.3) as fake:
        result, elapsed, _ = fly(fake)
        end = time.monotonic()
    assert result.outcome is Outcome.STALLED, result.report()
    found = re.match(why, result.waiting[0])
    assert found, result.waiting
    if behaviour == "leap":
        before, after = map(float, found.groups())
        assert after - before > 3 * 3600 - 60
    elif behaviour == "backwards":
        before, after = map(float, found.groups())
        assert after < before - 1
    assert end - fake.turned_at - 0.3 < LIVENESS + SLACK
    # the primitives enabled then (a waypoint, or a depth: the vehicle moved on while
    # its clock stood) were disabled
    assert safe_stopped(result) and left_enabled(result) == set()
    assert [line.split(":")[0] for line in result.secured] == ["hold", "surface", "disarm"]


# -- addresses and options that cannot work --------------------------------------------------------

@pytest.mark.timeout(TEST_BOUND)
def test_an_address_nobody_listens_on_is_one_message():
    port = free_port()
    start = time.monotonic()
    out = run_cli("run", SAUCE, "--vehicle", "mavlink", "--connect", f"tcp:127.0.0.1:{port}",
                  "--liveness", LIVENESS, timeout=20)
    assert time.monotonic() - start < 15        # a refused connection, not a wait
    text = one_error(out, f"cannot connect to the autopilot at tcp:127.0.0.1:{port}: "
                          "Connection refused")
    assert len(text.strip().splitlines()) == 1, text
    assert out.stdout == ""


@pytest.mark.timeout(TEST_BOUND)
@pytest.mark.parametrize("address", ["tcp:nohost", "ftp:x", "tcp:127.0.0.1:0",
                                     "tcp:127.0.0.1:http", "tcp::5760", "udp:127.0.0.1",
                                     "serial:", None],
                         ids=lambda a: str(a))
def test_a_malformed_address_is_one_message_naming_connect(address):
    args = ["run", SAUCE, "--vehicle", "mavlink"]
    out = cli(*args, *(["--connect", address] if address is not None else []))
    one_error(out, "--connect")


@pytest.mark.timeout(TEST_BOUND)
@pytest.mark.parametrize("option", ["--secret", "--tls-ca"])
def test_the_bridges_security_options_are_refused(tmp_path, option):
    key = tmp_path / "key"
    key.write_text("k" * 32 + "\n")
    key.chmod(0o600)
    out = cli("run", SAUCE, "--vehicle", "mavlink", "--connect", "tcp:127.0.0.1:1", option, key)
    one_error(out, option, "MAVLink does not")
