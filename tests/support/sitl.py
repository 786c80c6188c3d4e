"""ArduSub in software-in-the-loop for the tests: found, started on ports of its own, stopped.

The real autopilot (ArduPilot's ArduSub firmware built as a SITL program,
with its ``vectored`` submarine physics) is looked for in ``$MCL2PNML_ARDUSUB``,
then in ``../shared/peers/ardusub`` beside the repository. A test that
needs it takes :func:`need`, which skips with the reason when the program
or pymavlink is absent.

* **One instance per test.** :func:`running` claims an instance number N
  (``-I N``: every port moves by 10*N, MAVLink on TCP 5760+10N, a second
  MAVLink port on 5762+10N) under a lock file per N in the temporary
  folder, so that parallel test workers never share one, and starts the
  program in a folder of the test's own with the arguments its
  ``start_sitl.sh`` uses.
* **Its parent is the test.** SITL exits when its parent process does, so
  it is started with :class:`subprocess.Popen` from the test's own process,
  and stopped by its process id when the test ends, whatever the ending
  (terminated, then killed after a bound).
* **A second ground station** (:class:`Second`) on the second port watches
  the autopilot's clock and state, and sets parameters mid-run: how a test
  makes a fault happen to a mission in flight (GPS lost, the ground
  station's failsafe).
* **Every wait is bounded**, in wall seconds; what the autopilot does is
  timed on its own clock (``time_boot_ms``), as its failsafes are.
"""
from __future__ import annotations

import fcntl
import os
import platform
import signal
import socket
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator

import pytest

ENV = "MCL2PNML_ARDUSUB"
#: The firmware's folder beside the repository (../shared/peers/ardusub).
BESIDE = Path(__file__).resolve().parents[3] / "shared" / "peers" / "ardusub"
PROGRAM = "ardusub"
DEFAULTS = "sub.parm"
#: Simulated seconds per wall second asked for (about 100 is what two cores keep up).
SPEEDUP = 100
#: The speed-up of an autopilot whose test makes something happen mid-mission (a fault, a
#: signal) from a second station: at 100 the mission runs on for 100 of its seconds in
#: each second the station waits for a core, and two suites side by side on 2 cores had
#: the mission end before the fault came (at 20, the GPS's loss once came after the
#: survey's last waypoint).
FAULT_SPEEDUP = 10
HOME = "43.6,-8.8,0,0"
#: What every test's autopilot has besides ArduPilot's SITL defaults (a test's own file
#: comes after it). The ground-station failsafe waits 60 s of the autopilot's clock for our
#: heartbeat, not ArduSub's 5: at the speed-up of 100 those 5 s are 50 ms of wall time,
#: less than a machine loaded by a second suite keeps our heartbeat thread waiting for a
#: core, and the failsafe then ended flights that test something else. The failsafe's own
#: test sets ArduSub's 5 s back.
HARNESS = {"FS_GCS_TIMEOUT": 60}
#: ArduSub's own ground-station failsafe time-out, in seconds of its clock.
FS_GCS_TIMEOUT = 5
#: The instance numbers the tests use (0, the program's default, is left to people).
INSTANCES = range(1, 61)
#: The first MAVLink port (SERIAL0, the mission's), the second (SERIAL1), the RC input.
MAVLINK, SECOND, RC_INPUT = 5760, 5762, 5501
#: Wall seconds: the program's start, its stop, a connection, a parameter's answer. Each is
#: a wait that ends as soon as the thing happens, so generous bounds cost nothing: a
#: loaded machine (two suites on 2 cores) took over 10 s to have the mission's run connect
#: and the second port open.
START_BOUND, STOP_BOUND, CONNECT_BOUND, ANSWER_BOUND = 30.0, 5.0, 30.0, 10.0
#: ArduPilot's system and component ids of the vehicle (its README).
VEHICLE = (1, 1)
ARMED_FLAG = 0x80
LOCKS = Path(tempfile.gettempdir())


def find() -> tuple[Path | None, str]:
    """The firmware's folder, or None and why it is not usable."""
    places = ([(f"${ENV}", Path(os.environ[ENV]))] if os.environ.get(ENV) else []) \
        + [("../shared/peers/ardusub", BESIDE)]
    for _, folder in places:
        if (folder / PROGRAM).is_file() and (folder / DEFAULTS).is_file():
            if not os.access(folder / PROGRAM, os.X_OK):
                return None, f"{folder / PROGRAM} is not executable"
            return folder, ""
    where = ", ".join(f"{label} ({folder})" for label, folder in places)
    return None, f"ArduSub SITL ({PROGRAM} and {DEFAULTS}) not found in {where}"


def need() -> Path:
    """The firmware's folder; the test is skipped, saying why, when it or pymavlink is absent."""
    if not sys.platform.startswith("linux") or platform.machine() not in ("x86_64", "AMD64"):
        pytest.skip("the ArduSub SITL program here is built for x86-64 Linux")
    try:
        import pymavlink.mavutil  # noqa: F401
    except ImportError:
        pytest.skip("pymavlink is not installed (pip install 'mcl2pnml[mavlink]')")
    folder, why = find()
    if folder is None:
        pytest.skip(why)
    return folder


# -- instances ------------------------------------------------------------------------------

def _free(port: int, kind: int) -> bool:
    """Nobody on this machine has the port (a listening socket, a bound UDP one)."""
    with socket.socket(socket.AF_INET, kind) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind(("0.0.0.0", port))
        except OSError:
            return False
    return True


def ports_free(n: int) -> bool:
    return all(_free(MAVLINK + 10 * n + k, socket.SOCK_STREAM) for k in (0, 2, 3)) \
        and _free(RC_INPUT + 10 * n, socket.SOCK_DGRAM)


@contextmanager
def instance() -> Iterator[int]:
    """An instance number no other test holds (a lock file per number) whose ports are free."""
    for n in INSTANCES:
        handle = open(LOCKS / f"mcl2pnml-ardusub-{n}.lock", "a")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            continue
        if not ports_free(n):
            handle.close()
            continue
        try:
            yield n
        finally:
            handle.close()     # the lock goes with it
        return
    raise RuntimeError(f"no free ArduSub SITL instance in {INSTANCES.start}.."
                       f"{INSTANCES.stop - 1} (every lock held or port taken)")


def listening(port: int) -> bool:
    """A TCP socket listens on ``port`` (read from /proc: no connection is made, which
    would start the simulation)."""
    want = f":{port:04X}"
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            lines = Path(table).read_text().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            parts = line.split()
            if len(parts) > 3 and parts[1].endswith(want) and parts[3] == "0A":
                return True
    return False


@dataclass
class Sitl:
    """One running ArduSub: its instance, folder, process and ports."""

    instance: int
    folder: Path
    process: subprocess.Popen
    output: Path

    @property
    def port(self) -> int:
        return MAVLINK + 10 * self.instance

    @property
    def second_port(self) -> int:
        return SECOND + 10 * self.instance

    @property
    def address(self) -> str:
        """``mcl2pnml run --connect``'s address of the mission's MAVLink port."""
        return f"tcp:127.0.0.1:{self.port}"

    def alive(self) -> bool:
        return self.process.poll() is None

    def said(self) -> str:
        """What the program wrote (its console), for a failure's message."""
        try:
            return self.output.read_text(errors="replace")[-2000:]
        except OSError:
            return ""

    def wait_listening(self, port: int, bound: float) -> None:
        end = time.monotonic() + bound
        while not listening(port):
            if not self.alive():
                raise RuntimeError(f"ArduSub SITL (instance {self.instance}) exited with "
                                   f"status {self.process.returncode}:\n{self.said()}")
            if time.monotonic() > end:
                raise RuntimeError(f"ArduSub SITL (instance {self.instance}) does not listen "
                                   f"on TCP {port} after {bound:g} s:\n{self.said()}")
            time.sleep(0.02)

    def kill(self) -> None:
        """The autopilot dies at once (SIGKILL), as a vehicle's computer that loses power."""
        if self.alive():
            self.process.send_signal(signal.SIGKILL)
        self.process.wait(STOP_BOUND)

    def stop(self) -> None:
        """End it by its process id: terminated, killed if it has not exited within a bound."""
        if self.alive():
            self.process.terminate()
            try:
                self.process.wait(STOP_BOUND)
                return
            except subprocess.TimeoutExpired:
                self.process.kill()
        self.process.wait(STOP_BOUND)


@contextmanager
def running(folder: Path, work: Path, extra: Path | None = None,
            speedup: float = SPEEDUP) -> Iterator[Sitl]:
    """ArduSub from ``folder`` running in ``work`` (its eeprom and logs go there) on an
    instance of its own, waiting for its first client; ``extra``: a parameter file loaded
    after ArduPilot's SITL defaults. Stopped at the end, however the block ends."""
    work.mkdir(parents=True, exist_ok=True)
    harness = work / "harness.parm"
    harness.write_text("".join(f"{name} {value:g}\n" for name, value in HARNESS.items()))
    defaults = ",".join([str(folder / DEFAULTS), str(harness.resolve()),
                         *([str(Path(extra).resolve())] if extra else [])])
    with instance() as n:
        output = work / "sitl.log"
        with open(output, "w") as console:
            process = subprocess.Popen(
                [str(folder / PROGRAM), "-w", "--model", "vectored", "--speedup", f"{speedup:g}",
                 f"-I{n}", "--home", HOME, "--defaults", defaults],
                cwd=work, stdin=subprocess.DEVNULL, stdout=console, stderr=subprocess.STDOUT)
        sitl = Sitl(n, work, process, output)
        try:
            sitl.wait_listening(sitl.port, START_BOUND)
            yield sitl
        finally:
            sitl.stop()


# -- a second ground station ----------------------------------------------------------------

@dataclass
class Second:
    """A second ground station on the autopilot's second port: it watches and sets
    parameters. It sends no heartbeat (it is nobody's ground station for the failsafe)."""

    sitl: Sitl
    system: int = 254
    conn: object = None
    boot: float | None = None            # the autopilot's clock, s
    armed: bool | None = None
    mode: int | None = None
    armed_at: float | None = None        # its clock when it was first seen armed
    params: dict = field(default_factory=dict)

    def connect(self, bound: float = CONNECT_BOUND) -> "Second":
        """Connect once the port listens (the simulation opens it when it starts: when the
        mission's run has connected to the first port), and hear the autopilot."""
        from pymavlink import mavutil
        self.sitl.wait_listening(self.sitl.second_port, bound)
        self.conn = mavutil.mavlink_connection(f"tcp:127.0.0.1:{self.sitl.second_port}",
                                               source_system=self.system,
                                               source_component=190, retries=0)
        # pymavlink's TCP link prints a closed socket at every read and reads on: fail instead
        self.conn.handle_eof = self.conn.handle_disconnect = _closed
        # the autopilot's clock on this link, 20 times a second of its own
        self.command(511, mavutil.mavlink.MAVLINK_MSG_ID_SYSTEM_TIME, 50_000)
        self.until(lambda: self.boot is not None and self.armed is not None, bound,
                   "the autopilot's clock and heartbeat on the second port")
        return self

    def command(self, command: int, *params: float) -> None:
        params = list(params) + [0.0] * (7 - len(params))
        self.conn.mav.command_long_send(*VEHICLE, command, 0, *params)

    def pump(self, timeout: float = 0.05) -> None:
        msg = self.conn.recv_match(blocking=True, timeout=timeout)
        while msg is not None:
            if (msg.get_srcSystem(), msg.get_srcComponent()) == VEHICLE:
                millis = getattr(msg, "time_boot_ms", None)
                if millis is not None:
                    self.boot = millis / 1000.0
                kind = msg.get_type()
                if kind == "HEARTBEAT":
                    self.armed = bool(msg.base_mode & ARMED_FLAG)
                    self.mode = msg.custom_mode
                    if self.armed and self.armed_at is None and self.boot is not None:
                        self.armed_at = self.boot
                elif kind == "PARAM_VALUE":
                    self.params[msg.param_id] = msg.param_value
            msg = self.conn.recv_match(blocking=False)

    def until(self, done: Callable[[], object], bound: float, what: str) -> None:
        """Pump until ``done()``; at most ``bound`` wall seconds, else the test fails."""
        end = time.monotonic() + bound
        while not done():
            if time.monotonic() > end:
                raise AssertionError(f"waited {bound:g} s for {what} (autopilot clock "
                                     f"{self.boot}, armed {self.armed}, mode {self.mode})")
            self.pump()

    def mission_time(self, seconds: float, bound: float) -> float:
        """Wait until the autopilot has been armed ``seconds`` of its own clock; its clock."""
        self.until(lambda: self.armed_at is not None, bound, "the autopilot to be armed")
        self.until(lambda: self.boot >= self.armed_at + seconds, bound,
                   f"{seconds:g} s of the autopilot's clock after arming")
        return self.boot

    def param(self, name: str, bound: float = ANSWER_BOUND) -> float:
        self.params.pop(name, None)
        self.conn.mav.param_request_read_send(*VEHICLE, name.encode(), -1)
        self.until(lambda: name in self.params, bound, f"parameter {name}")
        return self.params[name]

    def set_param(self, name: str, value: float, bound: float = ANSWER_BOUND) -> float:
        """Set a parameter; the value the autopilot answers it now has."""
        from pymavlink import mavutil
        self.params.pop(name, None)
        self.conn.mav.param_set_send(*VEHICLE, name.encode(), float(value),
                                     mavutil.mavlink.MAV_PARAM_TYPE_REAL32)
        self.until(lambda: name in self.params, bound, f"the answer to setting {name}")
        return self.params[name]

    def close(self) -> None:
        if self.conn is not None:
            try:
                self.conn.close()
            except OSError:
                pass


def _closed() -> None:
    raise ConnectionError("the autopilot closed its second port")


@contextmanager
def second(sitl: Sitl, bound: float = CONNECT_BOUND) -> Iterator[Second]:
    """A :class:`Second` ground station on ``sitl``, connected (once the mission's run has
    started the simulation), closed at the end."""
    ground = Second(sitl)
    try:
        yield ground.connect(bound)
    finally:
        ground.close()
