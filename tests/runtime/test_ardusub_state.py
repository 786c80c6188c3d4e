"""The vehicle's real state on ArduSub in software-in-the-loop (tests/support/sitl.py).

Each case a user met on the real autopilot, flown as they flew it:

* a second ground station: a second ``mcl2pnml run`` on another port of an
  armed, flying sub is refused (exit 2, nothing sent), and a ground station
  with our system id heard on the link ends the flying run safely;
* the tank held on the vehicle's own position: a mapping whose ``home``
  puts the vehicle 1 km outside the tank never arms it; a vehicle that a
  watching station sends away (a target of its own) is stopped and
  disarmed as it crosses the tank's wall;
* a link that lags (each way, more than an acknowledgement may take on the
  autopilot's clock): GUIDED and the arming are not taken for refused, the
  mission flies, and the vehicle is left disarmed;
* the autopilot's process stopped (SIGSTOP) for about 10 s mid-mission and
  resumed: the run, stalled on its silence, brings it to its safe state
  (disarmed) once it speaks again, within the mapping's ``secure_within``.
"""
from __future__ import annotations

import json
import os
import re
import signal
import socket
import threading
import time
from contextlib import contextmanager
from importlib import resources
from pathlib import Path
from typing import Iterator

import pytest

import sitl
from mcl2pnml.runtime.mavlink import POSITION, TANK_MARGIN
from mcl2pnml.runtime.simulator import World
from test_ardusub import (FAULT_AT, MISSION_BOUND, RUN_BOUND, TEST_BOUND,  # noqa: F401
                          ardusub, assert_autopilot_disarmed, assert_disarmed, autopilot,
                          faulted, fly, flying)  # (fixtures too)

#: Wall seconds the autopilot's process is stopped (SIGSTOP) mid-mission.
STOPPED = 10.0
#: A mission that holds a depth for 2000 s of the autopilot's clock (20 s of wall clock at
#: its speed-up of 100): still flying while a second run starts, on a loaded machine too.
HOLD = """
primitive KeepDepth(depth);
task Hold(d) = KeepGoal(KeepDepth(d)) timeout 2000;
mission { Hold(2.0); }
"""
#: Wall seconds a lagging link holds each way, and the autopilot's speed-up then: 5 s of
#: its clock, more than the 3 s an acknowledgement may take.
LAG, LAGGED_SPEEDUP = 0.25, 20
#: The third MAVLink port of an instance (SERIAL2), beside the mission's and the watcher's.
THIRD = 5763


def mapping_file(folder: Path, **settings) -> Path:
    data = json.loads(resources.files("mcl2pnml.runtime").joinpath("ardusub.json")
                      .read_text("utf-8"))
    data.update(settings)
    path = folder / "mapping.json"
    path.write_text(json.dumps(data))
    return path


def third_port(autopilot: sitl.Sitl) -> int:
    return THIRD + 10 * autopilot.instance


@contextmanager
def lagging(address: tuple[str, int], lag: float) -> Iterator[str]:
    """A TCP proxy on loopback to ``address`` whose every byte, each way, is ``lag`` wall
    seconds late, in order; its ``tcp:`` address. Closed, its threads ended, at the end."""
    listener = socket.create_server(("127.0.0.1", 0))
    listener.settimeout(sitl.CONNECT_BOUND)
    stop, threads, sockets = threading.Event(), [], [listener]

    def carry(source: socket.socket, target: socket.socket) -> None:
        queue: list[tuple[float, bytes]] = []
        source.settimeout(0.01)
        while not stop.is_set():
            try:
                data = source.recv(65536)
                if not data:
                    break
                queue.append((time.monotonic() + lag, data))
            except socket.timeout:
                pass
            except OSError:
                break
            due = [data for at, data in queue if at <= time.monotonic()]
            del queue[:len(due)]
            try:
                target.sendall(b"".join(due))
            except OSError:
                break

    def serve() -> None:
        try:
            client, _ = listener.accept()
            upstream = socket.create_connection(address, timeout=sitl.CONNECT_BOUND)
        except OSError:
            return
        sockets.extend((client, upstream))
        for source, target in ((client, upstream), (upstream, client)):
            threads.append(threading.Thread(target=carry, args=(source, target), daemon=True))
            threads[-1].start()

    threads.append(threading.Thread(target=serve, daemon=True))
    threads[0].start()
    try:
        yield f"tcp:127.0.0.1:{listener.getsockname()[1]}"
    finally:
        stop.set()
        for s in sockets:
            s.close()
        for t in list(threads):
            t.join(sitl.STOP_BOUND)


# -- case 5: a link that lags -----------------------------------------------------------------

@pytest.mark.slow      # the fake autopilot's lag (test_mavlink_state.py) runs in every suite
@pytest.mark.timeout(TEST_BOUND)
def test_a_link_that_lags_takes_no_acknowledgement_for_refused(ardusub, tmp_path):
    with sitl.running(ardusub, tmp_path / "sitl", speedup=LAGGED_SPEEDUP) as autopilot, \
            lagging(("127.0.0.1", autopilot.port), LAG) as address:
        flight = fly(autopilot, tmp_path / "run", "--connect", address)
        assert_autopilot_disarmed(autopilot)
    flight.assert_clean()
    said = [e["autopilot"] for e in flight.log if "autopilot" in e]
    assert "armed in GUIDED: the mission's clock starts" in said, flight.out[-3000:]
    assert not any("refused" in line for line in flight.diagnosis()), flight.diagnosis()
    # flown to an end of the mission's own (the lag may cost it a time-out: OK or FAIL)
    assert flight.outcome in ("OK", "FAIL"), flight.out[-3000:]
    assert flight.reports("achieved", "GoToWayPoint")
    flight.assert_left_disarmed()


# -- case 3: a second ground station -----------------------------------------------------------

@pytest.mark.timeout(TEST_BOUND)
def test_a_second_ground_station_is_refused_then_heard_and_the_run_ends_safely(autopilot,
                                                                               tmp_path):
    from pymavlink import mavutil
    hold = tmp_path / "hold.mcl"
    hold.write_text(HOLD)
    with flying(autopilot, tmp_path / "first", mission=hold) as run, \
            sitl.second(autopilot) as ground:
        ground.mission_time(FAULT_AT, MISSION_BOUND)
        # a second run on another port of the flying sub: refused, nothing sent
        autopilot.wait_listening(third_port(autopilot), MISSION_BOUND)
        second = fly(autopilot, tmp_path / "second", "--connect",
                     f"tcp:127.0.0.1:{third_port(autopilot)}", bound=RUN_BOUND)
        assert second.status == 2, second.out + second.err
        assert "is armed already (in GUIDED): another ground station may be flying it; " \
               "nothing was sent" in second.err, second.err
        assert "Traceback" not in second.err
        assert [set(e) for e in second.log] == [{"t", "error"}], second.log   # nothing flown
        assert run.process.poll() is None, "the first run ended when the second was refused"
        # a ground station left at its default ids (255, 190) on that port: the flying run
        # hears its heartbeats, routed by the autopilot, and ends
        station = mavutil.mavlink_connection(f"tcp:127.0.0.1:{third_port(autopilot)}",
                                             source_system=255, source_component=190,
                                             retries=0)
        try:
            end = time.monotonic() + RUN_BOUND
            while run.process.poll() is None and time.monotonic() < end:
                station.mav.heartbeat_send(6, 8, 0, 0, 4)
                station.recv_match(blocking=True, timeout=0.05)
        finally:
            station.close()
        flight = run.finish()
        assert_disarmed(ground)
    flight.assert_clean()
    assert flight.outcome == "STALLED", flight.out[-3000:]
    assert flight.diagnosis()[0].startswith("another ground station (system 255, component "
                                            "190) is on the autopilot's link with our system "
                                            "id"), flight.diagnosis()
    assert any(e.get("safe_stop") for e in flight.log)
    flight.assert_left_disarmed()


# -- case 4: the tank, on the vehicle's own position -----------------------------------------

@pytest.mark.timeout(TEST_BOUND)
def test_a_home_that_puts_the_vehicle_outside_the_tank_never_arms_it(autopilot, tmp_path):
    mapping = mapping_file(tmp_path, home=[1000, 0])
    with flying(autopilot, tmp_path, vehicle=f"mavlink:{mapping}") as run, \
            sitl.second(autopilot) as ground:
        flight = run.finish()
        assert_disarmed(ground)
        assert ground.armed_at is None, "armed outside the tank"
    flight.assert_clean()
    assert flight.outcome == "STALLED", flight.out[-3000:]
    assert flight.diagnosis()[0].startswith("the vehicle is outside the tank at (1000.0, "), \
        flight.diagnosis()
    assert not any("setpoint" in e for e in flight.log)


@pytest.mark.timeout(TEST_BOUND)
def test_a_vehicle_sent_out_of_the_tank_is_stopped_at_its_wall(faulted, tmp_path):
    world = World()
    # at the fault speed-up (sitl.FAULT_SPEEDUP): at 100 a loaded machine had the
    # mission ended before the second station sent the sub out
    with flying(faulted, tmp_path) as run, sitl.second(faulted) as ground:
        ground.mission_time(FAULT_AT, MISSION_BOUND)
        # the watching station (no heartbeat: not heard as one) sends the sub 30 m south
        # of the tank's wall, in the autopilot's frame (its origin: the world's start)
        north, east = 10.0 - world.start[0], -30.0 - world.start[1]
        ground.conn.mav.set_position_target_local_ned_send(
            0, *sitl.VEHICLE, 1, POSITION, north, east, 2.0, 0, 0, 0, 0, 0, 0, 0, 0)
        flight = run.finish()
        assert_disarmed(ground)
    flight.assert_clean()
    assert flight.outcome == "STALLED", flight.out[-3000:]
    left = re.match(r"the vehicle left the tank at \(([-\d.]+), ([-\d.]+)\)",
                    flight.diagnosis()[0])
    assert left, flight.diagnosis()
    # caught as it crossed the wall's margin (said to a tenth of a metre), not far beyond
    assert -TANK_MARGIN - 2.0 < float(left.group(2)) <= -TANK_MARGIN + 0.05, left.group(0)
    flight.assert_left_disarmed()


# -- case 7: the autopilot stopped for a while ------------------------------------------------

@pytest.mark.timeout(TEST_BOUND + 30)
def test_an_autopilot_stopped_mid_mission_is_disarmed_once_it_resumes(faulted, tmp_path):
    # at the fault speed-up: at 100, a second suite beside this one had the mission ended
    # between the station's reading of its time and the stop
    autopilot = faulted
    with flying(autopilot, tmp_path, "--liveness", "2") as run, \
            sitl.second(autopilot) as ground:
        ground.mission_time(FAULT_AT, MISSION_BOUND)
        os.kill(autopilot.process.pid, signal.SIGSTOP)
        try:
            time.sleep(STOPPED)
            # the run has stalled on its silence, and is still trying its safe state
            assert run.process.poll() is None, "the run gave up on a silent autopilot"
        finally:
            os.kill(autopilot.process.pid, signal.SIGCONT)
        flight = run.finish()
        assert_disarmed(ground)
    flight.assert_clean()
    assert flight.outcome == "STALLED", flight.out[-3000:]
    assert "no heartbeat from the autopilot for 2 s" in flight.diagnosis()[0], \
        flight.diagnosis()
    said = [e["autopilot"] for e in flight.log if "autopilot" in e]
    assert any(s.startswith("the autopilot is silent") and "still trying to bring it to its "
               "safe state for" in s for s in said), said
    assert "the autopilot is heard again: its safe state goes on" in said
    flight.assert_left_disarmed()
