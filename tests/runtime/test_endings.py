"""Every ending of a run writes its outcome, its log and the vehicle's safe state.

``mcl2pnml run`` as a process of its own, stopped as people and their tools
stop it: SIGTERM (``kill``, ``timeout``, ``systemctl stop``), SIGHUP (a
dropped session) and SIGINT (Ctrl-C), on the simulator and on the fake
autopilot of tests/support/fake_autopilot.py (ArduSub itself: tests/runtime/test_ardusub.py).
Each run ends INTERRUPTED, naming the signal, with its safe stop (and an
autopilot held, surfaced and disarmed), its outcome printed and its
``--log`` written, with the exit status 128 + the signal's number; a second
signal while the safe state runs changes nothing, a third cuts it short and
says so. Beside them, what a run says of why it ended: the time-out that
failed a task, in the text and in ``--json``; a stalled run's diagnosis in
``--json`` and in the log.
"""
from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator

import pytest

import sitl
from helpers import ROOT, run_cli

#: Wall seconds: a run's start (a fresh interpreter), its end after a signal (the safe
#: state included), a state of the fake autopilot awaited, the test as a whole.
START_BOUND, END_BOUND, STATE_BOUND, TEST_BOUND = 60.0, 30.0, 60.0, 120
#: A mission that never ends on the simulator: each Hold is kept until its time-out
#: (OK), and the loop goes on; beside it a watch that stays enabled (no obstacle comes).
#: At a virtual time limit no machine reaches, it runs until it is stopped.
FOREVER = """\
primitive KeepDepth(depth);
primitive DetectObstacle(range);
task Hold(d) = KeepGoal(KeepDepth(d)) timeout 5;
task Watch() = AchieveGoal(DetectObstacle(1.0));
function Loop() {
    while (Hold(1.0)) do { Hold(2.0); }
}
mission {
    parallel(Watch(), Loop());
}
"""
NEVER_ENDS = "1e9"
SAUCE = ROOT / "examples" / "sauce.mcl"


@dataclass
class Ended:
    """A finished run: exit status, standard output and error, the ``--log``'s lines."""

    status: int
    out: str
    err: str
    log: list[dict]

    @property
    def last(self) -> dict:
        return self.log[-1]

    def diagnosis(self) -> list[str]:
        """The lines under ``outcome ...`` in the text."""
        lines = self.out.splitlines()
        start = max(i for i, line in enumerate(lines) if line.startswith("outcome "))
        return [line.strip() for line in lines[start + 1:] if line.startswith("  ")]

    def assert_interrupted_by(self, sig: signal.Signals) -> None:
        """INTERRUPTED by ``sig``: in the exit status, the text, and the log's last line."""
        assert "Traceback" not in self.err + self.out, self.err[-3000:]
        assert self.status == 128 + sig, (self.status, self.err[-2000:])
        assert f"outcome INTERRUPTED" in self.out, self.out[-2000:]
        assert self.diagnosis()[0] == f"interrupted by {sig.name}", self.diagnosis()
        assert self.last["outcome"] == "INTERRUPTED", self.last
        assert self.last["diagnosis"][0] == f"interrupted by {sig.name}", self.last


class Launched:
    """``mcl2pnml run`` in flight, its output going to files that the test reads."""

    def __init__(self, process: subprocess.Popen, folder: Path):
        self.process, self.folder = process, folder

    def out(self) -> str:
        return (self.folder / "run.out").read_text()

    def wait_for(self, done: Callable[[], object], what: str, bound: float = START_BOUND):
        """Until ``done()``; the run must still be going; at most ``bound`` wall seconds."""
        end = time.monotonic() + bound
        while not done():
            assert self.process.poll() is None, f"the run ended before {what}:\n" \
                + self.out()[-2000:] + (self.folder / "run.err").read_text()[-2000:]
            assert time.monotonic() < end, f"waited {bound:g} s for {what}"
            time.sleep(0.02)

    def said(self, text: str) -> bool:
        return text in self.out()

    def signal(self, sig: signal.Signals) -> None:
        self.process.send_signal(sig)

    def stop(self) -> None:
        """Killed by its process id, if it still runs (the test ended first)."""
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(10)

    def finish(self, bound: float = END_BOUND) -> Ended:
        try:
            status = self.process.wait(bound)
        except subprocess.TimeoutExpired:
            pytest.fail(f"the run did not end within {bound:g} s of its signal:\n"
                        + self.out()[-3000:])
        log = self.folder / "run.jsonl"
        assert log.is_file(), "no --log written"
        return Ended(status, self.out(), (self.folder / "run.err").read_text(),
                     [json.loads(line) for line in log.read_text().splitlines()])


@contextmanager
def launched(folder: Path, mission: Path, *options: str,
             ignoring: signal.Signals | None = None) -> Iterator[Launched]:
    """``python -m mcl2pnml run MISSION --log folder/run.jsonl OPTIONS`` (a fresh process, so
    that signals reach it alone; ``ignoring`` a signal, as ``nohup`` starts it); killed by
    its process id if the block ends first."""
    folder.mkdir(parents=True, exist_ok=True)
    command = [sys.executable, "-m", "mcl2pnml", "run", str(mission),
               "--log", str(folder / "run.jsonl"), *options]
    streams = {"stdout": (folder / "run.out").open("w"), "stderr": (folder / "run.err").open("w")}

    def as_a_shell_starts_it() -> None:
        # every signal tested at its default, whatever the test process ignores (an ignored
        # signal is inherited, and a run keeps ignoring it: in the whole suite, SIGINT was
        # ignored in a worker by the time these tests ran), but ``ignoring``
        for sig in SIGNALS:
            signal.signal(sig, signal.SIG_DFL)
        if ignoring is not None:
            signal.signal(ignoring, signal.SIG_IGN)
    try:
        process = subprocess.Popen(command, cwd=ROOT, stdin=subprocess.DEVNULL, **streams,
                                   preexec_fn=as_a_shell_starts_it)
    finally:
        for stream in streams.values():
            stream.close()      # the child has its own copies
    run = Launched(process, folder)
    try:
        yield run
    finally:
        run.stop()


SIGNALS = [signal.SIGTERM, signal.SIGHUP, signal.SIGINT]


# -- what each signal does, one after another ------------------------------------------------

def test_the_first_signal_stops_the_run_the_second_is_said_the_third_cuts_the_safe_state(
        capfd):
    from mcl2pnml.runtime.interrupts import Guard, Interrupted, Phase, SafeStateCut
    g = Guard()
    with pytest.raises(Interrupted) as stop:
        g.handle(signal.SIGTERM)
    assert stop.value.reason == "interrupted by SIGTERM" and g.signum == signal.SIGTERM
    with g.securing():
        g.handle(signal.SIGINT)                    # the second: said, nothing else
        with pytest.raises(SafeStateCut):
            g.handle(signal.SIGINT)                # the third
        g.handle(signal.SIGINT)                    # and after it, said again
    assert g.phase is Phase.ENDING
    for _ in range(3):
        g.handle(signal.SIGHUP)                    # the log is written whatever comes
    err = capfd.readouterr().err.splitlines()
    assert err[0] == "mcl2pnml: SIGINT: the safe state goes on (a third signal cuts it short)"
    assert err[1].startswith("mcl2pnml: SIGINT again: the safe state is cut short")
    assert err[-1] == "mcl2pnml: SIGHUP: the run is ending; its log and outcome are being written"
    # a cut that comes while a step is written down waits for the step to be written
    g = Guard()
    with g.securing():
        g.handle(signal.SIGTERM)
        g.handle(signal.SIGTERM)
        written = []
        with pytest.raises(SafeStateCut):
            with g.recording():
                g.handle(signal.SIGTERM)           # the third, in the middle of a step
                written.append("hold")             # the rest of the step still runs
        assert written == ["hold"] and g.cut
    # a signal after the mission's own result: said, until the third cuts its safe state
    g = Guard()
    with g.securing():
        g.handle(signal.SIGTERM)
        g.handle(signal.SIGTERM)
        with pytest.raises(SafeStateCut):
            g.handle(signal.SIGTERM)
    assert g.signum is None
    # printing the outcome: the third since it began stops it
    g = Guard(Phase.PRINTING)
    g.handle(signal.SIGTERM)
    g.handle(signal.SIGTERM)
    with pytest.raises(Interrupted):
        g.handle(signal.SIGTERM)


# -- on the simulator ------------------------------------------------------------------------

@pytest.mark.timeout(TEST_BOUND)
@pytest.mark.parametrize("sig", SIGNALS, ids=lambda s: s.name)
def test_a_signal_ends_a_simulated_run_interrupted_with_its_safe_stop(tmp_path, sig):
    mission = tmp_path / "forever.mcl"
    mission.write_text(FOREVER)
    with launched(tmp_path / "run", mission, "--max-time", NEVER_ENDS) as run:
        run.wait_for(lambda: run.said("enable    KeepDepth"), "the mission's first action")
        run.signal(sig)
        ended = run.finish()
    ended.assert_interrupted_by(sig)
    # the watch, enabled all along, is disabled by the safe stop, said and logged
    assert any(line.startswith("safe stop: disabled DetectObstacle")
               for line in ended.diagnosis())
    assert "DetectObstacle" in [e["primitive"] for e in ended.log if e.get("safe_stop")]
    assert "safe-stop  disable   DetectObstacle" in ended.out
    # and what the mission waited for when it was stopped
    assert "DetectObstacle: enabled at t=0 s, still enabled" in ended.last["diagnosis"]


@pytest.mark.timeout(TEST_BOUND)
def test_a_journaled_run_stopped_by_a_signal_can_be_resumed(tmp_path):
    # the journal ends where the run was stopped: its safe stop and outcome are not the
    # mission's, and a resume replays it, then runs on past it
    mission, journal = tmp_path / "forever.mcl", tmp_path / "run.journal"
    mission.write_text(FOREVER)
    with launched(tmp_path / "run", mission, "--max-time", NEVER_ENDS,
                  "--journal", str(journal)) as run:
        run.wait_for(lambda: run.said("enable    KeepDepth(2.0)"), "the loop's body")
        run.signal(signal.SIGTERM)
        ended = run.finish()
    ended.assert_interrupted_by(signal.SIGTERM)
    lines = [json.loads(line) for line in journal.read_text().splitlines()]
    assert not any("outcome" in e or e.get("safe_stop") for e in lines)
    stopped_at = lines[-1]["t"]
    with launched(tmp_path / "resumed", mission, "--resume", str(journal)) as run:
        run.wait_for(lambda: last_time(run.out()) > stopped_at, "the run past the journal")
        run.signal(signal.SIGTERM)
        resumed = run.finish()
    resumed.assert_interrupted_by(signal.SIGTERM)
    assert len(journal.read_text().splitlines()) > len(lines)


def last_time(out: str) -> float:
    """The time of the live log's last whole line (-1 before any)."""
    times = re.findall(r"^t=\s*([0-9.]+) ", out.rsplit("\n", 1)[0], re.M)
    return float(times[-1]) if times else -1.0


@pytest.mark.timeout(TEST_BOUND)
def test_a_signal_ignored_when_the_run_starts_stays_ignored(tmp_path):
    # nohup's SIGHUP: the run goes on past it, and the next signal stops it
    mission = tmp_path / "forever.mcl"
    mission.write_text(FOREVER)
    with launched(tmp_path / "run", mission, "--max-time", NEVER_ENDS,
                  ignoring=signal.SIGHUP) as run:
        run.wait_for(lambda: run.said("enable    KeepDepth"), "the mission's first action")
        run.signal(signal.SIGHUP)
        at = len(run.out())
        run.wait_for(lambda: len(run.out()) > at + 10_000, "the run going on past SIGHUP")
        run.signal(signal.SIGTERM)
        ended = run.finish()
    ended.assert_interrupted_by(signal.SIGTERM)


def test_a_run_puts_back_the_handlers_it_found_and_runs_in_a_thread_too(tmp_path):
    from mcl2pnml.pipeline import RunOptions, run_mission
    mission, script = tmp_path / "m.mcl", tmp_path / "v.json"
    mission.write_text(TIMED_OUT)
    script.write_text(json.dumps({"GoToWayPoint": ["ok@5"]}))
    before = {sig: signal.getsignal(sig) for sig in SIGNALS}
    assert run_mission(mission, RunOptions(vehicle=str(script))).outcome.value == "OK"
    assert {sig: signal.getsignal(sig) for sig in SIGNALS} == before
    # outside the main thread no handler can be set: the run goes on without
    results = []
    worker = threading.Thread(target=lambda: results.append(
        run_mission(mission, RunOptions(vehicle=str(script)))))
    worker.start()
    worker.join(END_BOUND)
    assert [r.outcome.value for r in results] == ["OK"]


# -- on an autopilot -------------------------------------------------------------------------

@pytest.fixture
def fake_autopilot():
    pytest.importorskip("pymavlink")
    from fake_autopilot import FakeAutopilot
    made = []

    def make(**how) -> "FakeAutopilot":
        made.append(FakeAutopilot(**how))
        return made[-1]
    yield make
    for fake in made:
        fake.close()


#: The runs' liveness on the fake autopilot: these tests are of signals, not of the link,
#: and a loaded machine can hold the fake's thread (in the test's process) for seconds
LIVENESS = "15"
#: ... but a command a deaf autopilot does not answer is waited for up to the liveness
#: (each step of its safe state): less there, or that test waits it out at every step
DEAF_LIVENESS = "8"


def flying(folder: Path, fake, *options: str):
    return launched(folder, SAUCE, "--vehicle", "mavlink", "--connect", fake.address,
                    "--liveness", LIVENESS, *options)


def safe_state(ended: Ended) -> list[tuple[str, bool]]:
    return [(e["safe_state"], e["acknowledged"]) for e in ended.log if "safe_state" in e]


@pytest.mark.timeout(TEST_BOUND)
@pytest.mark.parametrize("sig", SIGNALS, ids=lambda s: s.name)
def test_a_signal_brings_the_autopilot_to_its_safe_state_and_ends_logged(tmp_path,
                                                                          fake_autopilot, sig):
    from fake_autopilot import ARM_DISARM, POSHOLD, SET_MODE, SURFACE
    fake = fake_autopilot()
    with flying(tmp_path / "run", fake) as run:
        run.wait_for(lambda: fake.armed and fake.flown, "the sub armed and on its way")
        run.signal(sig)
        ended = run.finish()
    ended.assert_interrupted_by(sig)
    assert not fake.armed
    assert [int(p[1]) for p in fake.commanded(SET_MODE)][-2:] == [POSHOLD, SURFACE]
    assert [p[0] for p in fake.commanded(ARM_DISARM)] == [1, 0]
    assert safe_state(ended) == [("hold", True), ("surface", True), ("disarm", True)]
    assert "safe state: disarm: disarm acknowledged; disarmed" in ended.diagnosis()
    # the waypoint it was flying to was disabled first
    assert "GoToWayPoint" in [e["primitive"] for e in ended.log if e.get("safe_stop")]


@pytest.mark.timeout(TEST_BOUND)
def test_a_second_signal_while_the_safe_state_runs_changes_nothing(tmp_path, fake_autopilot):
    # at twice the speed of the wall clock, surfacing from a metre takes most of a second
    fake = fake_autopilot(speedup=2.0, speed=0.5)
    with flying(tmp_path / "run", fake) as run:
        run.wait_for(lambda: fake.ned[2] > 1.0, "the sub a metre down", STATE_BOUND)
        run.signal(signal.SIGINT)
        run.wait_for(lambda: run.said("safe-state  hold:"), "the safe state's first step")
        run.signal(signal.SIGINT)
        ended = run.finish()
    ended.assert_interrupted_by(signal.SIGINT)
    assert "mcl2pnml: SIGINT: the safe state goes on" in ended.err
    assert safe_state(ended) == [("hold", True), ("surface", True), ("disarm", True)]
    assert not fake.armed and fake.ned[2] <= 0.3


@pytest.mark.timeout(TEST_BOUND)
def test_a_third_signal_cuts_the_safe_state_short_and_says_so(tmp_path, fake_autopilot):
    # an autopilot that turns deaf once flying: each step of the safe state waits its
    # acknowledgement for seconds, which the third signal does not
    fake = fake_autopilot(speedup=1.0, then="deaf")
    # a deaf autopilot is waited for up to secure_within: a few seconds here
    mapping = tmp_path / "mapping.json"
    settings = json.loads((ROOT / "mcl2pnml" / "runtime" / "ardusub.json").read_text())
    mapping.write_text(json.dumps({**settings, "secure_within": 4}))
    with launched(tmp_path / "run", SAUCE, "--vehicle", f"mavlink:{mapping}", "--connect",
                  fake.address, "--liveness", DEAF_LIVENESS) as run:
        run.wait_for(lambda: fake.armed and fake.flown and fake.behaviour == "deaf",
                     "the sub flying, deaf")
        for _ in range(2):
            run.signal(signal.SIGTERM)
            time.sleep(0.2)
        # the third once a step is done (hold, unacknowledged): it is kept, the rest cut
        run.wait_for(lambda: run.said("hold: "), "the safe state's first step")
        run.signal(signal.SIGTERM)
        ended = run.finish()
    ended.assert_interrupted_by(signal.SIGTERM)
    assert "mcl2pnml: SIGTERM again: the safe state is cut short" in ended.err
    cut = ("the safe state was cut short by SIGTERM, the run's third signal: the vehicle "
           "may not be in its safe state")
    assert cut in ended.diagnosis() and cut in ended.last["diagnosis"]
    # cut before the disarm's step; the steps done before it kept in the outcome
    assert ("disarm", True) not in safe_state(ended)
    assert [step for step, _ in safe_state(ended)][:1] == ["hold"]
    assert ended.out.count("safe state: hold: ") == 1, ended.out[-2000:]


@pytest.mark.timeout(TEST_BOUND)
def test_a_signal_stops_a_bridged_vehicle_with_its_safe_stop(tmp_path):
    # the example bridge server's fake middleware, answering nothing within the test: the
    # primitives the mission enabled are stopped through the bridge when the run is
    from test_bridge_safety import SIM_MAPPING, bridge_server
    server = bridge_server.serve(0, "fake", delay=600.0)
    host, port = server.server_address[:2]
    try:
        with launched(tmp_path / "run", SAUCE, "--vehicle", f"bridge:{SIM_MAPPING}",
                      "--connect", f"{host}:{port}") as run:
            run.wait_for(lambda: run.said("enable    GoToWayPoint"), "the first waypoint")
            run.signal(signal.SIGTERM)
            ended = run.finish()
        commands = [c.get("command") for mw in server.served for c in mw.commands]
    finally:
        server.shutdown()
        server.server_close()
    ended.assert_interrupted_by(signal.SIGTERM)
    stopped = sorted(e["primitive"] for e in ended.log if e.get("safe_stop"))
    assert stopped == ["DetectCross", "GoToWayPoint"]
    assert {"stop_DetectCross", "stop_GoToWayPoint"} <= set(commands), commands


@pytest.mark.timeout(TEST_BOUND)
def test_a_run_ended_by_bad_input_writes_its_log_to_the_error(tmp_path):
    # a bridge that answers the first command with a line that is not JSON: one message,
    # exit 2, after the safe stop; the log written whole, its last line the error
    from test_bridge_safety import GOTO, SIM_MAPPING, Peer, send_after_first_command
    mission, log = tmp_path / "goto.mcl", tmp_path / "run.jsonl"
    mission.write_text(GOTO)
    peer = Peer(send_after_first_command(b"this is not json\n"))
    out = run_cli("run", mission, "--vehicle", f"bridge:{SIM_MAPPING}", "--connect",
                  peer.address, "--log", log, timeout=END_BOUND)
    peer.finish()
    assert out.returncode == 2 and "Traceback" not in out.stderr, out.stderr
    lines = [json.loads(line) for line in log.read_text().splitlines()]
    assert [e["primitive"] for e in lines if e.get("safe_stop")] == ["GoToWayPoint"]
    assert lines[-1]["error"] == out.stderr.strip()
    assert lines[-1]["error"].startswith("the vehicle's bridge sent a line that is not a JSON")


# -- on ArduSub (tests/support/sitl.py) ----------------------------------------------------------------

#: Wall seconds: a SITL test as a whole (its start, the dive, the end; two suites side by
#: side on 2 cores took over 30 s to have the run arm the sub).
SITL_TEST_BOUND = 150
#: Metres: the sub is diving (the paper's first waypoint is at 2 m), then surfaced (the
#: mapping's surface depth, 0.3 m, and what the simulator's waves add).
DIVING, SURFACED = 0.5, 0.5
GUIDED = 4


def watching_depth(ground) -> None:
    """The second ground station also follows the sub's depth (its LOCAL_POSITION_NED's z,
    ten times a second of the autopilot's clock), in ``ground.depth``."""
    from pymavlink import mavutil
    ground.depth = None
    receive = ground.conn.recv_match

    def recv_match(*args, **kwargs):
        msg = receive(*args, **kwargs)
        if msg is not None and msg.get_type() == "LOCAL_POSITION_NED":
            ground.depth = msg.z
        return msg
    ground.conn.recv_match = recv_match
    ground.command(511, mavutil.mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 100_000)


@pytest.mark.timeout(SITL_TEST_BOUND)
@pytest.mark.parametrize("signals", [
    # SIGHUP takes SIGTERM's path (each signal is sent to the fake autopilot's runs above):
    # on ArduSub, a variant of the slow suite
    (signal.SIGTERM,), pytest.param((signal.SIGHUP,), marks=pytest.mark.slow),
    (signal.SIGINT, signal.SIGINT)], ids=["SIGTERM", "SIGHUP", "SIGINT-twice"])
def test_on_ardusub_a_signal_surfaces_and_disarms_the_sub(tmp_path, signals):
    # at the fault speed-up: at 100 the whole mission is a third of a wall second, and
    # beside a second suite the station never saw the sub diving before it had ended; and
    # the safe state's two or three seconds of the autopilot's are a fifth of a second of
    # the wall clock for the second signal to come in
    ardusub = sitl.need()
    with sitl.running(ardusub, tmp_path / "sitl", speedup=sitl.FAULT_SPEEDUP) as autopilot, \
            launched(tmp_path / "run", SAUCE, "--vehicle", "mavlink", "--connect",
                     autopilot.address, "--json") as run, \
            sitl.second(autopilot) as ground:
        # no failsafe of its own: whatever disarms the sub is the run's safe state
        assert ground.set_param("FS_GCS_ENABLE", 0) == 0
        watching_depth(ground)
        ground.until(lambda: ground.armed and (ground.depth or 0.0) > DIVING, STATE_BOUND,
                     "the sub armed and diving")
        run.signal(signals[0])
        if len(signals) > 1:     # the second once the safe state has taken the sub
            ground.until(lambda: ground.mode != GUIDED, STATE_BOUND, "the safe state")
            run.signal(signals[1])
        ended = run.finish()
        ground.armed = ground.depth = None      # what the autopilot says after the run
        ground.until(lambda: ground.armed is not None and ground.depth is not None,
                     STATE_BOUND, "a heartbeat and a depth after the run")
        assert ground.armed is False, "the sub is still armed"
        assert ground.depth < SURFACED, ground.depth
    sig = signals[0]
    assert "Traceback" not in ended.err, ended.err[-3000:]
    # the second signal is sent once the autopilot has left GUIDED; a loaded machine can
    # deliver it after the run has ended, its outcome written and its handlers given back:
    # the interpreter then ends by SIGINT, which a shell sees as 130 all the same
    # (test_a_second_signal_while_the_safe_state_runs_changes_nothing holds the run to
    # the second signal within the safe state without racing it)
    in_time = f"mcl2pnml: {sig.name}: the safe state goes on" in ended.err
    late = len(signals) > 1 and not in_time
    assert ended.status == 128 + sig or (late and ended.status == -sig), \
        (ended.status, ended.err[-2000:])
    result = json.loads(ended.out)
    assert result["outcome"] == "INTERRUPTED"
    assert result["diagnosis"][0] == f"interrupted by {sig.name}"
    assert result["safe_state"][-1] == "disarm: disarm acknowledged; disarmed", result
    assert safe_state(ended) == [("hold", True), ("surface", True), ("disarm", True)]
    assert ended.last["outcome"] == "INTERRUPTED"
    assert ended.last["diagnosis"][0] == f"interrupted by {sig.name}"


# -- why a run ended -------------------------------------------------------------------------

TIMED_OUT = """\
primitive GoToWayPoint(wp);
task Goto(wp) = AchieveGoal(GoToWayPoint(wp)) timeout 300;
mission {
    Goto((1.0, 2.0, 3.0));
}
"""


@pytest.mark.parametrize("engine", ["petri", "reference"])
def test_a_task_failed_by_its_time_out_is_named_in_the_text_and_the_json(tmp_path, engine):
    mission, script = tmp_path / "m.mcl", tmp_path / "v.json"
    mission.write_text(TIMED_OUT)
    script.write_text(json.dumps({"GoToWayPoint": ["never"]}))
    text = run_cli("run", mission, "--engine", engine, "--vehicle", script)
    assert text.returncode == 1, text.stderr
    assert "t=  300.000  time-out  Goto (300 s) expired" in text.stdout
    assert "  the last time-out: Goto (300 s), expired at t=300 s" in text.stdout
    out = run_cli("run", mission, "--engine", engine, "--vehicle", script, "--json",
                  "--log", tmp_path / "run.jsonl")
    result = json.loads(out.stdout)
    assert result["outcome"] == "FAIL"
    assert result["timeouts"] == [{"t": 300, "timeout": "Goto", "seconds": 300}]
    log = [json.loads(line) for line in (tmp_path / "run.jsonl").read_text().splitlines()]
    assert {"t": 300, "timeout": "Goto", "seconds": 300} in log


def test_a_stalled_run_says_why_in_its_json_and_its_log(tmp_path):
    mission, script = tmp_path / "m.mcl", tmp_path / "v.json"
    mission.write_text(TIMED_OUT.replace(" timeout 300", ""))
    script.write_text(json.dumps({"GoToWayPoint": ["never"]}))
    out = run_cli("run", mission, "--vehicle", script, "--json", "--log", tmp_path / "run.jsonl")
    assert out.returncode == 5, out.stderr
    result = json.loads(out.stdout)
    assert result["outcome"] == "STALLED"
    assert result["diagnosis"] == ["GoToWayPoint: enabled at t=0 s, still enabled"]
    last = json.loads((tmp_path / "run.jsonl").read_text().splitlines()[-1])
    assert last["outcome"] == "STALLED" and last["diagnosis"] == result["diagnosis"]
