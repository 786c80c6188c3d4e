"""The vehicle's real state over MAVLink, against the fake autopilot (tests/support/fake_autopilot.py).

What the run believes of the vehicle must be what the vehicle is, however
late the autopilot's words come and however busy the run is:

* a link that lags (our arming reaches the autopilot late, its answer comes
  behind the telemetry of that while) makes no false "refused to arm": the
  deadline counts from when the autopilot had the command (its answer to
  our TIMESYNC request); a vehicle whose "armed" was still on the way when
  the link fell silent is disarmed by the safe state once it speaks again;
* our heartbeats keep their rate while the run loop's thread is busy, and
  follow the autopilot's clock as measured when its speed-up is not read;
* a vehicle armed already is refused, and sent nothing;
* another ground station on the link: the run ends (our system id) or
  warns (another);
* the vehicle's own position leaves the tank: the run ends, the vehicle
  disarmed; a vehicle outside the tank from the start is never armed;
* an autopilot stopped for a while (SIGSTOP) is brought to its safe state
  when it resumes, within the mapping's ``secure_within``.
"""
from __future__ import annotations

import io
import re
import time

import pytest

pytest.importorskip("pymavlink")

from mcl2pnml.runtime.engine import Outcome  # noqa: E402
from mcl2pnml.runtime.mavlink import COMPONENTS, SYSTEM, TANK_MARGIN  # noqa: E402
from mcl2pnml.runtime.simulator import World  # noqa: E402

from fake_autopilot import ARM_DISARM, FakeAutopilot  # noqa: E402
from helpers import one_error, run_cli  # noqa: E402
from test_mavlink_peers import SAUCE, fly, mapping_file  # noqa: E402
from test_mavlink_peers import _mapping  # noqa: E402,F401 (its fixture: the runs' mapping)

#: Wall seconds the run loop's thread is kept busy: four times ArduSub's GCS failsafe
#: (FS_GCS_TIMEOUT, 5 s of its clock without our heartbeat) at the fake's speed-up of 10.
BUSY = 2.0
#: The longest pause of a thread a loaded machine makes, in wall seconds (0.61 s was seen
#: with two suites on 2 cores): at the fake's speed-up of 10, more than its failsafe. The
#: heartbeat tests tell heartbeats that are late by such a pause from heartbeats that are
#: not sent (the whole busy stretch) or follow the wall's clock (a wall second apart).
PAUSE = 0.8
DISARMED = "disarm: disarm acknowledged; disarmed"


def assert_left_disarmed(result, fake: FakeAutopilot) -> None:
    assert result.secured and result.secured[-1] == DISARMED, result.secured
    assert fake.armed_ever and not fake.armed


# -- case 5: stale data ------------------------------------------------------------------------

@pytest.mark.timeout(30)
def test_a_link_that_lags_after_guided_does_not_make_the_arming_look_refused():
    # from GUIDED on, every word each way is 0.5 s late (5 s of its clock, more than the
    # 3 s the arming's acknowledgement may take): our arming reaches it late, and its
    # answer comes behind the telemetry of that while
    with FakeAutopilot(lag=0.5) as fake:
        result, _, text = fly(fake, liveness=3.0, max_time=120)
    assert fake.lagged, "nothing was late"
    assert "refused" not in text, text
    assert "armed in GUIDED: the mission's clock starts" in text
    # flown to its end (the lag's 10 s of its clock a round trip may cost the marker's
    # time-out: OK or FAIL), then disarmed
    assert result.outcome in (Outcome.OK, Outcome.FAIL), result.report()
    assert fake.flown and not result.waiting
    assert_left_disarmed(result, fake)


@pytest.mark.timeout(30)
def test_an_armed_vehicle_whose_armed_was_not_yet_read_is_disarmed(tmp_path):
    # the link lags past the liveness as it arms: the run stops on its silence while its
    # "armed" is still on the way, and the last word it read was "disarmed"
    mapping = mapping_file(tmp_path, secure_within=10)
    with FakeAutopilot(lag=1.0, lag_from="arming") as fake:
        result, elapsed, text = fly(fake, liveness=0.5, mapping=mapping)
    assert result.outcome is Outcome.STALLED, result.report()
    # the lag holds heartbeats and time alike: which silence is seen first is whichever
    # message the loaded machine read last before it (a second suite beside saw the clock's)
    assert any(silence in result.waiting[0] for silence in (
        "no heartbeat from the autopilot for 0.5 s",
        "the autopilot's clock has not moved for 0.5 s")), result.waiting
    assert "the autopilot is silent" in text and "still trying" in text, text
    # armed once, then disarmed: again while the lagging link has not acknowledged it
    arming = [p[0] for p in fake.commanded(ARM_DISARM)]
    assert arming[0] == 1 and len(arming) > 1 and set(arming[1:]) == {0}, arming
    assert_left_disarmed(result, fake)
    assert elapsed < 10 + 5, elapsed


# -- case 6: our heartbeats while the run is busy --------------------------------------------

class Busy(io.StringIO):
    """The run's text output; the line saying the vehicle is armed keeps the run loop's
    thread computing for :data:`BUSY` wall seconds (the interpreter's lock held, as a
    busy run on a loaded machine holds it)."""

    def __init__(self):
        super().__init__()
        self.busy_for = 0.0

    def write(self, text: str) -> int:
        if "armed in GUIDED" in text:
            start = time.monotonic()
            while time.monotonic() - start < BUSY:
                sum(i * i for i in range(1000))
            self.busy_for = time.monotonic() - start
        return super().write(text)


@pytest.mark.timeout(30)
def test_our_heartbeats_keep_their_rate_while_the_run_loop_is_busy():
    from mcl2pnml.pipeline import RunOptions, run_mission
    text = Busy()
    with FakeAutopilot() as fake:
        result = run_mission(SAUCE, RunOptions(vehicle="mavlink", connect=fake.address,
                                               liveness=3.0, max_time=120), text=text)
        fake.check()
    assert text.busy_for >= BUSY
    # BUSY wall seconds are 20 s of the fake's clock: without heartbeats of their own,
    # ArduSub's failsafe would have disarmed it four times over; with them, the longest
    # gap is a loaded machine's pause at most
    assert 0 < fake.heartbeat_gap() < PAUSE * fake.speedup < BUSY * fake.speedup, \
        fake.heartbeat_gap()
    # from one ground station: our system id, a component of the run's own
    [(system, component)] = fake.stations
    assert system == SYSTEM and component in COMPONENTS
    assert result.outcome is Outcome.OK, result.report()
    assert_left_disarmed(result, fake)


@pytest.mark.timeout(30)
def test_our_heartbeats_follow_the_autopilots_clock_when_its_speed_up_is_not_read():
    # a simulator at a speed-up of 10 whose SIM_SPEEDUP is not answered (on a loaded
    # machine, not in time): one heartbeat a wall second would be 10 s of its clock, twice
    # its failsafe; heartbeats on its clock are apart by a loaded machine's pause at most
    with FakeAutopilot(answer_speedup=False, speedup=10) as fake:
        result, _, text = fly(fake, liveness=3.0, max_time=120)
    assert "speed-up 1" in text
    assert 0 < fake.heartbeat_gap() < PAUSE * fake.speedup < 1.0 * fake.speedup, \
        fake.heartbeat_gap()
    assert result.outcome is Outcome.OK, result.report()
    assert_left_disarmed(result, fake)


# -- case 3: another ground station ----------------------------------------------------------

@pytest.mark.timeout(30)
def test_a_vehicle_armed_already_is_refused_and_sent_nothing():
    with FakeAutopilot(armed=True) as fake:
        out = run_cli("run", SAUCE, "--vehicle", "mavlink", "--connect", fake.address,
                      "--liveness", 1, timeout=20)
        time.sleep(0.2)      # anything sent would have arrived
        fake.check()
    text = one_error(out, f"the autopilot at {fake.address} is armed already (in GUIDED)")
    assert "another ground station may be flying it; nothing was sent" in text
    assert out.stdout == ""
    assert fake.commands == [] and fake.targets == [] and fake.heartbeats_heard == 0
    assert fake.armed


@pytest.mark.timeout(30)
def test_another_station_with_our_system_id_ends_the_run_safely():
    # at the first target flown, not a wall-clock while after it: a loaded machine can let
    # the fake's clock run the whole mission in that while
    with FakeAutopilot(then="crowded", station=(255, 42)) as fake:
        result, _, _ = fly(fake)
    assert result.outcome is Outcome.STALLED, result.report()
    assert result.waiting[0].startswith("another ground station (system 255, component 42) "
                                        "is on the autopilot's link with our system id"), \
        result.waiting
    # what was on when the other station came depends on how far the mission had got (on
    # a loaded machine, past the waypoint): something was, and the safe stop disabled it
    assert result.safe_stop, "the safe stop disabled nothing"
    assert_left_disarmed(result, fake)


@pytest.mark.timeout(30)
def test_another_station_watching_is_warned_of_and_the_mission_goes_on():
    with FakeAutopilot(then="crowded", after=0.2, station=(254, 190)) as fake:
        result, _, text = fly(fake)
    assert result.outcome is Outcome.OK, result.report()
    assert text.count("WARNING: another ground station (system 254, component 190) is on "
                      "the link") == 1, text
    assert_left_disarmed(result, fake)


# -- case 4: the tank, on the vehicle's own position ----------------------------------------

@pytest.mark.timeout(30)
def test_a_vehicle_that_leaves_the_tank_ends_the_run_and_is_disarmed():
    with FakeAutopilot(then="drift", after=0.1) as fake:
        result, _, _ = fly(fake)
    assert result.outcome is Outcome.STALLED, result.report()
    assert result.waiting[0].startswith("the vehicle left the tank at ("), result.waiting
    assert_left_disarmed(result, fake)
    # the position named is past the wall by the margin, and the vehicle was stopped there:
    # how far it drifted before the run noticed depends on the machine's load, so it is not
    # bounded here (the fake moves only while armed, and it was disarmed)
    named = float(result.waiting[0].split("at (", 1)[1].split(",", 1)[0])
    x = World().start[0] + fake.ned[0]
    wall = World().tank[0] + TANK_MARGIN
    assert wall - 0.05 <= named <= x + 0.05, (named, x)  # named to 0.1 m


@pytest.mark.timeout(30)
def test_a_vehicle_outside_the_tank_is_never_armed(tmp_path):
    with FakeAutopilot() as fake:
        result, _, _ = fly(fake, mapping=mapping_file(tmp_path, home=[1000, 0]))
    assert result.outcome is Outcome.STALLED, result.report()
    assert result.waiting[0].startswith("the vehicle is outside the tank at (1000.0, 0.0)"), \
        result.waiting
    assert fake.commanded(ARM_DISARM) == [] and not fake.armed_ever and fake.targets == []


# -- case 7: an autopilot stopped for a while -------------------------------------------------

@pytest.mark.timeout(30)
def test_an_autopilot_stopped_for_a_while_is_disarmed_when_it_resumes(tmp_path):
    mapping = mapping_file(tmp_path, secure_within=10)
    with FakeAutopilot(then="paused", after=0.2, pause=2.0) as fake:
        result, elapsed, text = fly(fake, mapping=mapping)
    assert result.outcome is Outcome.STALLED, result.report()
    assert "no heartbeat from the autopilot for 1 s" in result.waiting[0], result.waiting
    said = re.search(r"the autopilot is silent \(no heartbeat from the autopilot for 1 s\): "
                     r"still trying to bring it to its safe state for ([\d.]+) s", text)
    assert said and 0 < float(said.group(1)) <= 10, text
    assert "the autopilot is heard again" in text
    assert_left_disarmed(result, fake)
    assert elapsed < 10 + 5, elapsed
