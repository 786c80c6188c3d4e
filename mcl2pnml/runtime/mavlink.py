"""A MAVLink autopilot as the vehicle: missions flown on ArduSub (docs/ardusub.md).

The paper runs its missions on the real vehicle through the Architecture
Abstraction Layer (section 2.1, section 3). Here the vehicle is an
autopilot spoken to as a ground station speaks to it, over MAVLink (TCP,
UDP or a serial line, through ``pymavlink``, the ``mavlink`` extra):

* **Start** (:meth:`MavlinkVehicle.open`): a heartbeat from a submarine
  autopilot, ``SIM_SPEEDUP`` read where there is one (a simulated autopilot
  runs its failsafes on its own clock), the telemetry rates raised, the
  EKF's position and pre-arm checks awaited, GUIDED, armed. Every wait is
  bounded by the mapping (in the autopilot's seconds) and by the liveness
  (in wall seconds: a silent peer).
* **Time** is the autopilot's (``time_boot_ms``): a run at a simulator's
  speed-up of 100 is the same run as at 1, and its times come from the
  autopilot. The mission's clock starts when the vehicle is armed.
* **Actions and events** as :mod:`mcl2pnml.runtime.autopilot` maps them:
  one GUIDED position target composed from the flown primitives, servo
  and relay commands acknowledged by ``COMMAND_ACK``, simulated sensors on
  the autopilot's position. Each achieved or failed says where it came
  from (:class:`Reported`).
* **Liveness**: heartbeats sent at the speed-up's rate (or at its clock's
  as measured, when faster) from a thread of their own (the autopilot's GCS
  failsafe counts them on its clock: a busy run loop must not starve them);
  every write to the link goes under one lock, whole. The autopilot's own
  heartbeat awaited: none within the liveness, the link is lost, and the
  run stops with its safe stop. A heartbeat of another kind of vehicle, a
  clock that runs back, leaps or stands, a peer that sends only garbage:
  the same.
* **Fresh data**: every message already received is read before a decision
  (an acknowledgement's deadline passed, the armed flag, the liveness, the
  time an event is awaited until): a deadline on the autopilot's clock is
  judged on its messages up to now, not on a backlog read halfway. Each
  command is followed by a TIMESYNC request: the autopilot's answer says
  when it had the command, from which its deadline counts (a link that lags
  shows older times first), and which acknowledgement is the command's.
* **The vehicle's real state**: a vehicle armed already when we connect is
  refused (another ground station flies it); another ground station heard
  on the link while we fly ends the run when it has our system id (the one
  the autopilot obeys), and is warned of otherwise; the vehicle's own
  position (the mapping's ``home`` plus LOCAL_POSITION_NED) is held to the
  world's tank, :data:`TANK_MARGIN` beyond its walls: never armed outside
  it, and the run ends when it leaves it.
* **Safe state** (:meth:`MavlinkVehicle.secure`): after the run loop has
  disabled every primitive, the mapping's steps (hold, surface, disarm),
  each logged acknowledged or not; an autopilot that is silent (frozen, its
  link down for a while) is tried for the mapping's ``secure_within`` wall
  seconds, so that one that comes back is still brought to it.
"""
from __future__ import annotations

import math
import os
import select
import socket
import threading
import time
from collections import deque
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Mapping

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.settings import SettingError
from mcl2pnml.runtime import interrupts
from mcl2pnml.runtime.aal import (Action, ActionKind, Event, EventKind, LinkLost, LiveVehicle,
                                  Reported, VehicleFault)
from mcl2pnml.runtime.autopilot import AutopilotMapping, Binding
from mcl2pnml.runtime.link import LinkOptions
from mcl2pnml.runtime.simprims import Context, SimulatedPrimitive, Steer, installed
from mcl2pnml.runtime.simulator import State, World

#: ArduSub's modes (``HEARTBEAT.custom_mode``), as its documentation numbers them.
MODES = {0: "STABILIZE", 1: "ACRO", 2: "ALT_HOLD", 3: "AUTO", 4: "GUIDED", 7: "CIRCLE",
         9: "SURFACE", 16: "POSHOLD", 19: "MANUAL", 20: "MOTOR_DETECT", 21: "SURFTRAK"}
GUIDED, SURFACE, POSHOLD, ALT_HOLD = 4, 9, 16, 2
MAV_TYPE_SUBMARINE, MAV_TYPE_GCS, MAV_AUTOPILOT_INVALID = 12, 6, 8
#: MAV_CMD numbers used
SET_MODE, ARM_DISARM, SET_MESSAGE_INTERVAL, DO_SET_SERVO, DO_SET_RELAY = 176, 400, 511, 183, 181
#: SET_POSITION_TARGET_LOCAL_NED type masks: position only; position and yaw
POSITION, POSITION_YAW = 0x0DF8, 0x09F8
EKF_POS_HORIZ_ABS = 0x10
PREARM_OK = 0x10000000
ARMED_FLAG = 0x80
#: COMMAND_ACK results, in words
RESULTS = {0: "ACCEPTED", 1: "TEMPORARILY_REJECTED", 2: "DENIED", 3: "UNSUPPORTED",
           4: "FAILED", 5: "IN_PROGRESS", 6: "CANCELLED"}
#: The largest step of the autopilot's clock between two messages (s); more is a fault.
MAX_CLOCK_STEP = 60.0
#: Wall seconds one wait for a message lasts before the bounds are looked at again.
POLL = 0.05
#: Autopilot messages kept for the log (STATUSTEXT and the like); the rest counted.
KEPT_NOTES = 200
#: The track is logged once per this many seconds of the autopilot's clock.
TRACK_EVERY = 1.0
#: Metres beyond the tank's walls and floor the vehicle's position may be before it has
#: left the tank: the autopilot's position wanders a little (EKF, overshoot at a waypoint
#: by the wall), and a target is already held inside the tank itself.
TANK_MARGIN = 1.0
#: The most messages read at once to bring the state up to now (a flood is cut there).
MAX_DRAIN = 20_000
#: Wall seconds over which the autopilot's clock's speed is measured; the largest speed
#: taken (its SIM_SPEEDUP's bound); our heartbeats' shortest period (wall s), and how
#: often their thread looks at it again (wall s).
RATE_WINDOW, MAX_RATE, MIN_BEAT, BEAT_CHECK = 0.2, 10_000.0, 0.002, 0.05
#: Wall seconds a parameter's value is awaited once the autopilot has had the request
#: (its answer to the TIMESYNC request sent after it has come): ArduPilot answers
#: parameters from a queue of its own, a little after.
PARAMETER_WAIT = 1.0
#: The TIMESYNC requests whose answers are awaited at once (each command sends one).
KEPT_SYNCS = 256
#: Our MAVLink system id: a ground station's (ArduPilot obeys ``MAV_GCS_SYSID``, 255).
SYSTEM = 255
#: Our component ids, one per run from the user range (MAV_COMP_ID_USER1..75): ArduPilot
#: routes a ground station's heartbeats to its other links only when that system and
#: component has not been seen on them, so two runs with one id would not hear each other.
COMPONENTS = range(25, 100)


@dataclass(frozen=True)
class _Sent:
    """A command sent: its TIMESYNC request's token, and the autopilot's clock (as last
    heard) and the wall clock when it went."""

    token: int
    boot: float | None
    wall: float


@dataclass
class _Active:
    """An enabled primitive: its arguments, its goal (Fig. 1: C, S2, S1), its state here."""

    binding: Binding
    prim: SimulatedPrimitive
    args: tuple
    since: float
    enabling: int
    achieved: int
    goal: str = "C"
    memory: dict = field(default_factory=dict)
    #: why it can no longer reach its goal (the autopilot left GUIDED...): it says nothing more
    dead: str | None = None
    #: an actuator: its command not yet acknowledged (False), accepted (True)
    accepted: bool = False


class MavlinkVehicle(LiveVehicle):
    """An autopilot over MAVLink, flying a mission's primitives (see the module's documentation)."""

    def __init__(self, address: str, mapping: AutopilotMapping, world: World | None = None,
                 link: LinkOptions | None = None,
                 table: Mapping[str, SimulatedPrimitive] | None = None):
        self.address, self.mapping = address, mapping
        self.url = _url(address)
        self.world = world or World()
        self.link = link or LinkOptions()
        home = mapping.home or self.world.start[:2]
        self.home = (float(home[0]), float(home[1]))
        self.offer(installed() if table is None else table)
        #: where the run's log lines about the autopilot go: ``log(t, kind, text, obj)``
        self.log: Callable[[float, str, str, dict], None] = lambda *entry: None
        self.conn = None
        #: every write to the link (our heartbeats' thread writes too); re-entrant, as a
        #: send already under it writes through the guarded connection
        self.lock = threading.RLock()
        self.component = COMPONENTS[os.getpid() % len(COMPONENTS)]
        self.stopping = threading.Event()
        self.beat: threading.Thread | None = None
        self.send_fault: str | None = None
        self.speedup = 1.0
        #: the autopilot's clock's speed as measured (its seconds per wall second, over
        #: :data:`RATE_WINDOW`), and where the measure started (wall, its clock)
        self.rate = 0.0
        self.rate_from: tuple[float, float] | None = None
        self.target = (1, 1)
        self.boot: float | None = None     # the autopilot's clock, s
        self.t0 = 0.0                      # its reading when the mission's clock started
        self.ned: tuple[float, float, float] | None = None
        self.speed = 0.0
        #: its depth (m, down): LOCAL_POSITION_NED's, or GLOBAL_POSITION_INT's, which it
        #: sends on (from its depth sensor) when its EKF has lost the horizontal position
        self.depth: float | None = None
        self.yaw = 0.0
        self.mode: int | None = None
        self.armed = False
        self.ekf = 0
        self.position_since: float | None = None   # when the EKF last had a position
        self.prearm = False
        self.last_heartbeat = 0.0                 # wall clock
        self.clock_moved = 0.0                    # wall clock; 0: its clock not yet awaited
        self.last_text = ""
        self.bad_data = 0
        self.notes_dropped = 0
        self.notes = 0
        self.acks: deque = deque(maxlen=64)       # (command, result, number) not yet taken
        self.ack_count = 0                        # COMMAND_ACKs received
        self.active: dict[str, _Active] = {}
        self.enablings: dict[str, int] = {}
        self.achievements: dict[str, int] = {}
        self.events: deque[Event] = deque()
        self.pending: list[tuple[str, int, _Sent]] = []   # actuator: (primitive, command, sent)
        #: the TIMESYNC requests sent with our commands, by token: the autopilot's time when
        #: it answered (it had the command by then) and the COMMAND_ACKs received by then,
        #: None until it has
        self.synced: dict[int, tuple[float, int] | None] = {}
        self.next_token = 1
        #: the autopilot answers TIMESYNC (then a command's deadline waits for its answer)
        self.sync_seen = False
        #: the wall time up to which an answer is awaited whatever the liveness (the safe
        #: state's end: a link that lags longer is still tried)
        self.answer_by = 0.0
        self.hold: list[float] = [0.0, 0.0, 0.0]  # NED where an unset channel holds
        self.owners: tuple = (None, None, None)
        self.sent_target: tuple | None = None
        self.next_track = 0.0
        self.unready: Exception | None = None
        self.opened = False
        #: the link itself broke (closed, reset): nothing can be sent, waiting will not help
        self.broken: str | None = None
        #: we asked the autopilot to arm: its safe state then always sends the disarm
        self.arm_asked = False
        #: why the vehicle left the tank (said once: the run ends on it)
        self.escaped: str | None = None
        #: other ground stations heard on the link, (system, component)
        self.stations: set[tuple[int, int]] = set()
        #: the safe state is being reached: what would end the run is only logged
        self.securing = False

    # -- the mission's side ---------------------------------------------------------------

    def offer(self, table: Mapping[str, SimulatedPrimitive]) -> None:
        """The simulated primitives that give each mapped primitive its meaning."""
        self.table = dict(table)
        self.primitives = frozenset(self.mapping.bindings)

    def check_primitives(self, used: set[str]) -> None:
        for name in sorted(used):
            if name in self.mapping.bindings and name not in self.table:
                raise Mcl2PnmlError(
                    f"the mapping binds '{name}', but no simulated primitive of that name says "
                    "what its set points and its goal are (docs/simulator.md: "
                    "--sim-primitives)", None)

    def clock(self) -> float:
        """The mission's clock: the autopilot's seconds since it was armed for the mission
        (0 until then: a run that never started ends at 0, not at the autopilot's uptime)."""
        return (self.boot or 0.0) - self.t0 if self.t0 else 0.0

    def act(self, action: Action) -> None:
        self._ready()
        name, t = action.primitive, action.t
        if action.kind is ActionKind.DISABLE:
            act = self.active.pop(name, None)
            if act is not None and act.binding.by in ("servo", "relay"):
                self._release(act)
            self._steer()
            self.events.append(Event(t, EventKind.OFF, name))
            return
        binding = self.mapping.bindings[name]
        self.enablings[name] = self.enablings.get(name, 0) + 1
        act = self.active[name] = _Active(binding, self.table[name], tuple(action.args), t,
                                          self.enablings[name], self.achievements.get(name, 0))
        self.events.append(Event(t, EventKind.ON, name))
        problem = act.prim.check(self._context(act))
        if problem is None and binding.by == "autopilot":
            self._drain()      # its mode and arming as it says them now, not as last read
            if not self._flying():
                problem = self._why_not_flying()
        if problem is not None:
            self._give_up(act, name, t, problem)
            return
        if binding.by == "servo":
            self.pending.append((name, DO_SET_SERVO,
                                 self._command(DO_SET_SERVO, binding.channel, binding.pwm)))
        elif binding.by == "relay":
            self.pending.append((name, DO_SET_RELAY,
                                 self._command(DO_SET_RELAY, binding.relay, 1)))
        self._steer()

    def wait_event(self, timeout: float | None, clock) -> Event | None:
        """The next event; None once the autopilot's clock has run ``timeout`` seconds."""
        self._ready()
        deadline = None if timeout is None else self.clock() + timeout
        while not self.events:
            if deadline is not None and self.clock() >= deadline:
                self._drain()       # what was received by now may still come first
                if not self.events:
                    return None
                break
            self._pump(POLL)
        return self.events.popleft()

    # -- connecting -----------------------------------------------------------------------

    def open(self) -> None:
        """Connect; then make ready (a failure there ends the run STALLED, with its reason)."""
        mavutil = _mavutil()
        previous = socket.getdefaulttimeout()
        socket.setdefaulttimeout(self.link.connect_timeout)   # pymavlink's connect has none
        scheme, _, rest = self.url.partition(":")
        try:
            if scheme == "serial":
                device, _, baud = rest.rpartition(":")
                self.conn = mavutil.mavlink_connection(device, baud=int(baud),
                                                       source_system=SYSTEM,
                                                       source_component=self.component)
            else:
                self.conn = mavutil.mavlink_connection(self.url, source_system=SYSTEM,
                                                       source_component=self.component,
                                                       retries=0)
        except Exception as e:   # refused, unreachable, no such device
            raise Mcl2PnmlError(f"cannot connect to the autopilot at {self.address}: "
                                f"{getattr(e, 'strerror', None) or e}") from None
        finally:
            socket.setdefaulttimeout(previous)
        self.opened = True
        for hook, why in (("handle_eof", "the autopilot closed the connection"),
                          ("handle_disconnect", "the connection was reset")):
            # pymavlink's TCP link prints these (on our standard output, at every read
            # after) and reads on from a closed socket: here either breaks the link
            if hasattr(self.conn, hook):
                setattr(self.conn, hook, _broken(why))
        self._guard_writes()
        try:
            self._prepare()
        except (VehicleFault, LinkLost) as e:
            self.unready = e
        except Mcl2PnmlError:     # refused before anything was sent: one message, exit 2
            self.close()
            self.conn = None
            raise

    def _guard_writes(self) -> None:
        """Every write to the link under :attr:`lock` and whole. pymavlink numbers a frame
        and writes it in two steps that two threads may interleave, and its TCP link
        writes to a non-blocking socket once (a full buffer drops the frame or its end,
        and the frames after it are misread); here the rest is written within the send
        time-out, after which the link counts as broken."""
        conn, write = self.conn, self.conn.write
        sock = getattr(conn, "port", None) if self.url.startswith("tcp:") else None
        bound = self.link.send_timeout

        def whole(buf) -> None:
            with self.lock:
                if sock is None:
                    write(buf)
                    return
                data, end = memoryview(bytes(buf)), time.monotonic() + bound
                while data:
                    try:
                        data = data[sock.send(data):]
                        continue
                    except BlockingIOError:
                        pass
                    left = end - time.monotonic()
                    if left <= 0:
                        raise ConnectionError(f"a write took over {bound:g} s")
                    select.select([], [sock], [], min(left, POLL))
        conn.write = whole

    def _prepare(self) -> None:
        self._await_heartbeat()
        # the speed-up first: it sets our heartbeats' period, and the autopilot's GCS
        # failsafe counts from the first one it sees
        self._read_speedup()
        self.beat = threading.Thread(target=self._heartbeats, name="mavlink-heartbeat",
                                     daemon=True)
        self.beat.start()
        mavlink = _mavutil().mavlink
        rate = 1e6 / self.mapping.telemetry_rate
        for message, interval in ((mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED, rate),
                                  (mavlink.MAVLINK_MSG_ID_ATTITUDE, rate),
                                  (mavlink.MAVLINK_MSG_ID_EKF_STATUS_REPORT, 5e5),
                                  (mavlink.MAVLINK_MSG_ID_SYS_STATUS, 5e5),
                                  (mavlink.MAVLINK_MSG_ID_SYSTEM_TIME, 5e5)):
            self._command(SET_MESSAGE_INTERVAL, message, interval)
        self.clock_moved = time.monotonic()
        self._log_note("connected: system %d, a submarine; speed-up %g" %
                       (self.target[0], self.speedup))
        ready = self._until(lambda: self.ekf & EKF_POS_HORIZ_ABS and self.prearm
                            and self.ned is not None, self.mapping.ready_within)
        if not ready:
            self._log_note(f"no position and pre-arm checks after {self.mapping.ready_within:g} "
                           "s; trying GUIDED all the same")
        self._drain()
        if self.ned is not None and self._outside(self._state()):
            raise VehicleFault(self._outside_words(self._state(), "is outside")
                               + ": not armed (the mapping's home is where its position's "
                               "origin is in the world)")
        self._set_mode(GUIDED, "GUIDED")
        self.arm_asked = True
        result = self._ask(ARM_DISARM, 1)
        if result != 0:
            raise VehicleFault(f"the autopilot refused to arm ({_result(result)})"
                               + self._said())
        if not self._until(lambda: self.armed, self.mapping.ack_within):
            raise VehicleFault("the autopilot acknowledged arming but does not say it is armed")
        self.t0 = self.boot
        self.hold = list(self.ned)
        self.owners = (None, None, None)
        self.next_track = 0.0
        self._log_note("armed in GUIDED: the mission's clock starts")
        self._steer(force=True)

    def _ready(self) -> None:
        if self.unready is not None:
            raise self.unready
        if self.send_fault is not None:
            raise LinkLost(self.send_fault)

    def _await_heartbeat(self) -> None:
        end = time.monotonic() + self.link.liveness
        while time.monotonic() < end:
            msg = self._recv(min(POLL, max(0.0, end - time.monotonic())))
            if msg is not None and msg.get_type() == "HEARTBEAT" \
                    and msg.type != MAV_TYPE_GCS and msg.autopilot != MAV_AUTOPILOT_INVALID:
                self.target = (msg.get_srcSystem(), msg.get_srcComponent())
                self._heartbeat(msg)
                if self.armed:
                    raise Mcl2PnmlError(
                        f"the autopilot at {self.address} is armed already (in "
                        f"{MODES.get(self.mode, self.mode)}): another ground station may be "
                        "flying it; nothing was sent. Disarm it first")
                return
        raise LinkLost(f"no autopilot heartbeat from {self.address} within "
                       f"{self.link.liveness:g} s")

    def _read_speedup(self) -> None:
        """A simulated autopilot's speed-up (its failsafes run on its clock); 1 where none.
        Its answer is awaited :data:`PARAMETER_WAIT` past the autopilot's answer to a
        TIMESYNC request sent after the parameter's (a link that lags delays both alike),
        and at most the liveness (an autopilot that answers neither: a real one, whose
        parameters have no SIM_SPEEDUP, and no TIMESYNC)."""
        with self._sending():
            self.conn.mav.param_request_read_send(*self.target, b"SIM_SPEEDUP", -1)
            token = self._request_sync()
        limit = end = time.monotonic() + self.link.liveness
        while time.monotonic() < end:
            msg = self._recv(POLL)
            if self.synced.get(token) is not None and end == limit:
                end = min(limit, time.monotonic() + PARAMETER_WAIT)
            if msg is not None and msg.get_type() == "PARAM_VALUE" \
                    and msg.param_id == "SIM_SPEEDUP":
                value = float(msg.param_value)
                if math.isfinite(value) and 0 < value <= 10_000:
                    self.speedup = value
                return
            if msg is not None:     # its heartbeats and the rest count meanwhile
                self._handle(msg)

    def _heartbeats(self) -> None:
        """Our heartbeat, ``heartbeat`` seconds of the autopilot's clock apart, the first at
        once (one wall second later would be 100 of a simulator's at a speed-up of 100).
        A thread of its own, so that a run loop busy with a flood, a slow log or a loaded
        machine does not starve the autopilot's GCS failsafe. The autopilot's clock runs
        at its ``SIM_SPEEDUP``, or faster as measured (:attr:`rate`: a speed-up not read
        in time, on a loaded machine, must not slow them to one a wall second); the
        period is looked at again every :data:`BEAT_CHECK` wall seconds."""
        mavlink = _mavutil().mavlink
        last = -math.inf
        while True:
            period = max(MIN_BEAT, self.link.heartbeat / max(1.0, self.speedup, self.rate))
            now = time.monotonic()
            if now - last >= period:
                try:
                    with self.lock:
                        self.conn.mav.heartbeat_send(mavlink.MAV_TYPE_GCS,
                                                     mavlink.MAV_AUTOPILOT_INVALID, 0, 0,
                                                     mavlink.MAV_STATE_ACTIVE)
                except Exception as e:   # the link is gone: the loop hears it as lost
                    self.send_fault = f"cannot send to the autopilot: {e}"
                    return
                last = now
            if self.stopping.wait(min(BEAT_CHECK, max(0.0, last + period - now))):
                return

    # -- receiving --------------------------------------------------------------------------

    def _recv(self, timeout: float):
        try:
            return self.conn.recv_match(blocking=True, timeout=timeout)
        except Exception as e:    # a socket error, a device gone
            self.broken = f"the link to the autopilot broke: {e}"
            raise LinkLost(self.broken) from None

    def _take(self):
        """The next message already received, without waiting (None: none)."""
        try:
            return self.conn.recv_msg()
        except Exception as e:
            self.broken = f"the link to the autopilot broke: {e}"
            raise LinkLost(self.broken) from None

    def _drain(self) -> None:
        """Handle every message already received (up to :data:`MAX_DRAIN`), waiting for
        none: what the autopilot said by now, before a decision is taken on its state."""
        for _ in range(MAX_DRAIN):
            msg = self._take()
            if msg is None:
                return
            self._handle(msg)

    def _pump(self, timeout: float) -> None:
        """Take what the autopilot sent within ``timeout`` wall seconds; check liveness."""
        end = time.monotonic() + timeout
        msg = self._recv(timeout)
        while msg is not None:
            self._handle(msg)
            if time.monotonic() > end:
                break    # a flood: look at the bounds, then read on
            msg = self._take()
        if any(self._passed(sent.boot, sent, self.mapping.ack_within)
               for _, _, sent in self.pending):
            self._drain()     # an acknowledgement may be among what is received, unread
        self._check_pending()
        if self._stale() is not None:
            self._drain()     # a run loop held up (a slow log, a loaded machine) reads first
        if time.monotonic() - self.last_heartbeat > self.link.liveness:
            raise LinkLost(f"no heartbeat from the autopilot for {self.link.liveness:g} s "
                           f"(bad MAVLink data: {self.bad_data} messages)")
        if self.send_fault is not None:
            raise LinkLost(self.send_fault)
        if self.clock_moved and time.monotonic() - self.clock_moved > self.link.liveness:
            at = "it has sent no time" if self.boot is None else f"at {self.boot:.3f} s"
            raise VehicleFault(f"the autopilot's clock has not moved for {self.link.liveness:g} s"
                               f" ({at}): no telemetry, or a clock that stands")

    def _until(self, done: Callable[[], Any], seconds: float, sent: _Sent | None = None) -> bool:
        """Pump until ``done()`` or ``seconds`` of the autopilot's clock have passed (since
        it had the command ``sent``, when one is waited for: :meth:`_passed`). The clock
        starts at the autopilot's time now (what was received is read first), and the
        deadline is judged passed only once every message received by then is read: a
        backlog read halfway has times past the deadline before the answer in it."""
        self._drain()
        start = self.boot
        while not done():
            if start is None:
                start = self.boot
            elif self._passed(start, sent, seconds):
                self._drain()
                return bool(done())
            self._pump(POLL)
        return True

    def _passed(self, start: float | None, sent: _Sent | None, seconds: float) -> bool:
        """Whether ``seconds`` of the autopilot's clock have passed since ``start``, or,
        for a command ``sent``, since the autopilot had it: its answer to the TIMESYNC
        request sent right after the command gives its time then. A link that lags (a
        backlog on the way, our command arriving late) shows times from before the
        command reached it, which must not count. An autopilot that answers TIMESYNC is
        waited for its answer up to the liveness (wall), or while its safe state is being
        reached, up to the end of ``secure_within``; one that never has, is not."""
        if sent is not None:
            answer = self.synced.get(sent.token)
            if answer is not None:
                start = answer[0] if start is None else max(start, answer[0])
            elif self._awaiting(sent):
                return False
        return start is not None and self.boot is not None and self.boot - start >= seconds

    def _awaiting(self, sent: _Sent) -> bool:
        """The answer to ``sent``'s TIMESYNC request is still to be waited for."""
        return self.sync_seen and self.synced.get(sent.token) is None \
            and time.monotonic() < max(sent.wall + self.link.liveness, self.answer_by)

    def _handle(self, msg) -> None:
        kind = msg.get_type()
        if kind == "BAD_DATA":
            self.bad_data += 1
            return
        if kind == "HEARTBEAT" and msg.type == MAV_TYPE_GCS:
            self._station(msg.get_srcSystem(), msg.get_srcComponent())
            return
        if (msg.get_srcSystem(), msg.get_srcComponent()) != self.target:
            return     # another component (a gimbal, a camera) or another ground station
        millis = getattr(msg, "time_boot_ms", None)
        if millis is not None:
            self._tick(millis / 1000.0)
        if kind == "HEARTBEAT":
            self._heartbeat(msg)
        elif kind == "LOCAL_POSITION_NED":
            values = (msg.x, msg.y, msg.z, msg.vx, msg.vy, msg.vz)
            if all(map(math.isfinite, values)) and max(map(abs, values)) < 1e6:
                self.ned = (msg.x, msg.y, msg.z)
                self.depth = msg.z
                self.speed = math.sqrt(msg.vx ** 2 + msg.vy ** 2 + msg.vz ** 2)
                self._sample()
        elif kind == "GLOBAL_POSITION_INT":
            self.depth = -msg.relative_alt / 1000.0
            self.speed = math.sqrt(msg.vx ** 2 + msg.vy ** 2 + msg.vz ** 2) / 100.0
        elif kind == "ATTITUDE":
            if math.isfinite(msg.yaw):
                self.yaw = msg.yaw
        elif kind == "EKF_STATUS_REPORT":
            self.ekf = msg.flags
            if self.ekf & EKF_POS_HORIZ_ABS:
                self.position_since = None
            elif self.position_since is None:
                self.position_since = self.boot
            self._position_lost()
        elif kind == "SYS_STATUS":
            self.prearm = bool(msg.onboard_control_sensors_health & PREARM_OK)
        elif kind == "TIMESYNC":
            if msg.tc1 > 0 and self.synced.get(msg.ts1, ()) is None:   # an answer to ours
                self.synced[msg.ts1] = (msg.tc1 / 1e9, self.ack_count)
                self.sync_seen = True
        elif kind == "COMMAND_ACK":
            self.ack_count += 1
            self.acks.append((msg.command, msg.result, self.ack_count))
            self._acknowledged(msg.command, msg.result)
        elif kind == "STATUSTEXT":
            text = "".join(ch for ch in str(msg.text) if ch.isprintable())[:120]
            if "yaw alignment" not in text:    # twenty of them after arming
                self.last_text = text
                self._log_note(f"says: {text}")

    def _tick(self, seconds: float) -> None:
        if not math.isfinite(seconds):
            return
        if self.boot is not None and (seconds < self.boot - 1.0
                                      or seconds > self.boot + MAX_CLOCK_STEP):
            was, self.boot = self.boot, seconds
            if self.t0:     # the mission's time goes on from where it was
                self.t0 += seconds - was
            # said once: the run ends on it, and its safe state reads the new clock
            raise VehicleFault(f"the autopilot's clock went from {was:.3f} s to "
                               f"{seconds:.3f} s: rebooted, or not one autopilot")
        if self.boot is None or seconds > self.boot:
            self.clock_moved = self.clock_moved and time.monotonic()
        self.boot = seconds if self.boot is None else max(self.boot, seconds)
        now = time.monotonic()
        if self.rate_from is None:
            self.rate_from = (now, self.boot)
        elif now - self.rate_from[0] >= RATE_WINDOW:
            wall, boot = self.rate_from
            self.rate = min(MAX_RATE, (self.boot - boot) / (now - wall))
            self.rate_from = (now, self.boot)

    def _station(self, system: int, component: int) -> None:
        """Another ground station's heartbeat, routed to us by the autopilot. One with our
        system id is one the autopilot obeys as it obeys us (another run, a ground station
        left at its default): two of them command one vehicle, and the run ends. Another
        may only watch: it is said once, loudly, in the log."""
        station = (system, component)
        if station == (SYSTEM, self.component) or station in self.stations:
            return
        self.stations.add(station)
        if system == SYSTEM and not self.securing:
            raise VehicleFault(f"another ground station (system {system}, component "
                               f"{component}) is on the autopilot's link with our system id: "
                               "it can command the vehicle as we do, and two stations flying "
                               "one vehicle is not safe")
        self._log_note(f"WARNING: another ground station (system {system}, component "
                       f"{component}) is on the link: it can command the vehicle too",
                       always=True)

    def _heartbeat(self, msg) -> None:
        if msg.type != MAV_TYPE_SUBMARINE:
            raise VehicleFault(f"the autopilot (system {msg.get_srcSystem()}) says it is a "
                               f"vehicle of MAV_TYPE {msg.type}, not a submarine "
                               f"({MAV_TYPE_SUBMARINE}): {self.mapping.autopilot} flies "
                               "submarines only")
        self.last_heartbeat = time.monotonic()
        armed = bool(msg.base_mode & ARMED_FLAG)
        mode = msg.custom_mode
        if self.opened and self.t0 and (mode != self.mode or armed != self.armed):
            what = f"mode {MODES.get(mode, mode)}, {'armed' if armed else 'disarmed'}"
            self._log_note(f"now {what}")
            if not (armed and mode == GUIDED):
                self._fail_flown(f"the autopilot is now in {what}")
        self.mode, self.armed = mode, armed

    # -- the primitives' goals --------------------------------------------------------------

    def _state(self) -> State:
        n, e, d = self.ned
        return State(self.clock(), self.home[0] + n, self.home[1] + e, d, self.yaw)

    def _outside(self, s: State) -> bool:
        """The vehicle is out of the world's tank by more than :data:`TANK_MARGIN` (above
        the surface is not out: it is where it surfaces)."""
        (ox, oy), (sx, sy, sz) = self.world.origin, self.world.tank
        return not (ox - TANK_MARGIN <= s.x <= ox + sx + TANK_MARGIN
                    and oy - TANK_MARGIN <= s.y <= oy + sy + TANK_MARGIN
                    and s.z <= sz + TANK_MARGIN)

    def _outside_words(self, s: State, verb: str) -> str:
        return (f"the vehicle {verb} the tank at ({s.x:.1f}, {s.y:.1f}) depth {s.z:.1f} m (the "
                f"world's {self.world.tank_words()}, {TANK_MARGIN:g} m beyond its walls)")

    def _context(self, act: _Active) -> Context:
        b = act.binding
        world = self.world
        changes = {k: v for k, v in (("settle_time", b.settle), ("lost_after", b.lost_after))
                   if v is not None}
        if b.tolerance is not None:
            changes.update(acceptance=b.tolerance, depth_band=b.tolerance,
                           heading_band=math.radians(b.tolerance))
        if changes:
            world = replace(world, **changes)
        state = self._state() if self.ned is not None else State(self.clock(), *self.home,
                                                                  0.0, 0.0)
        return Context(act.args, state, world, act.since, act.goal, act.enabling,
                       act.achieved, act.memory)

    def _sample(self) -> None:
        """A new position: each enabled primitive's goal judged, the target composed again."""
        if not self.t0:
            return
        t = self.clock()
        if t >= self.next_track:
            x, y, z, yaw = (s := self._state()).x, s.y, s.z, s.yaw
            self.log(t, "track", "", {"track": [round(x, 3), round(y, 3), round(z, 3),
                                                round(math.degrees(yaw), 1)]})
            self.next_track = t + TRACK_EVERY
        if self.escaped is None and not self.securing and self._outside(self._state()):
            # said once: the run ends on it, and its safe state reads on
            self.escaped = self._outside_words(self._state(), "left")
            raise VehicleFault(self.escaped)
        lost = self._no_position()
        for name in sorted(self.active):
            act = self.active[name]
            if act.dead is not None:
                continue
            by = act.binding.by
            if by == "autopilot" and lost is not None:
                self._give_up(act, name, t, lost)
                continue
            if by in ("servo", "relay") and not act.accepted:
                continue
            report = act.prim.sense(self._context(act))
            if report is not None and report is not self._goal_event(act):
                self._report(act, name, report, t,
                             "simulated" if by == "simulated" else "autopilot",
                             "sensed" if by == "simulated" else "telemetry")
        self._steer()

    def _no_position(self) -> str | None:
        """Why the flown primitives fail: no position for the mapping's while (None: not)."""
        if self.position_since is None \
                or self.boot - self.position_since < self.mapping.position_lost_after:
            return None
        return (f"the autopilot has had no position for "
                f"{self.mapping.position_lost_after:g} s (EKF flags {self.ekf:#x})")

    def _position_lost(self) -> None:
        """Without a position the autopilot may stop sending LOCAL_POSITION_NED (ArduSub
        does), so its EKF reports judge that too, as :meth:`_sample` does."""
        lost = self._no_position() if self.t0 else None
        if lost is not None:
            self._fail_flown(lost)

    def _fail_flown(self, why: str) -> None:
        """Every flown primitive still seeking fails, for ``why``, by name."""
        for name in sorted(self.active):
            act = self.active[name]
            if act.binding.by == "autopilot" and act.dead is None:
                self._give_up(act, name, self.clock(), why)

    def _give_up(self, act: _Active, name: str, t: float, why: str) -> None:
        """``act`` fails for ``why`` (the autopilot's doing) and says nothing more."""
        self._report(act, name, EventKind.FAILED, t, "autopilot", why)
        act.dead = why

    @staticmethod
    def _goal_event(act: _Active) -> EventKind | None:
        return {"S2": EventKind.ACHIEVED, "S1": EventKind.FAILED}.get(act.goal)

    def _report(self, act: _Active, name: str, kind: EventKind, t: float, source: str,
                why: str) -> None:
        act.goal = "S2" if kind is EventKind.ACHIEVED else "S1"
        if kind is EventKind.ACHIEVED:
            self.achievements[name] = self.achievements.get(name, 0) + 1
            if name == "ReleaseMarker" and self.ned is not None:
                s = self._state()
                self.log(t, "marker", "", {"marker": [round(s.x, 3), round(s.y, 3)]})
        self.events.append(Reported(t, kind, name, source, why))

    # -- actuators -------------------------------------------------------------------------

    def _acknowledged(self, command: int, result: int) -> None:
        for i, (name, cmd, _) in enumerate(self.pending):
            if cmd == command:
                del self.pending[i]
                act = self.active.get(name)
                if act is None or act.dead is not None:
                    return
                if result == 0:
                    act.accepted = True
                else:
                    self._give_up(act, name, self.clock(),
                                  f"the autopilot refused command {command}: "
                                  f"{_result(result)}{self._said()}")
                return

    def _check_pending(self) -> None:
        if self.boot is None:
            return
        for name, cmd, sent in list(self.pending):
            if self._passed(sent.boot, sent, self.mapping.ack_within):
                self.pending.remove((name, cmd, sent))
                act = self.active.get(name)
                if act is not None and act.dead is None:
                    self._give_up(act, name, self.clock(),
                                  f"no acknowledgement of command {cmd} within "
                                  f"{self.mapping.ack_within:g} s")

    def _release(self, act: _Active) -> None:
        b = act.binding
        if b.by == "servo" and b.release_pwm is not None:
            self._command(DO_SET_SERVO, b.channel, b.release_pwm)
        elif b.by == "relay":
            self._command(DO_SET_RELAY, b.relay, 0)

    # -- set points -------------------------------------------------------------------------

    def _flying(self) -> bool:
        return self.armed and self.mode == GUIDED

    def _why_not_flying(self) -> str:
        return (f"the autopilot is in {MODES.get(self.mode, self.mode)}, "
                f"{'armed' if self.armed else 'disarmed'}: flown primitives need GUIDED, armed")

    def _steer(self, force: bool = False) -> None:
        """Send the GUIDED target the flown primitives compose (the simulator's rule)."""
        if self.ned is None or not self._flying():
            return
        chosen: dict[str, tuple[int, str, Any]] = {}
        for name in sorted(self.active):
            act = self.active[name]
            if act.binding.by != "autopilot" or act.dead is not None:
                continue
            steer: Steer | None = act.prim.steer(self._context(act))
            if steer is None:
                continue
            for channel, value in (("point", steer.point), ("depth", steer.depth),
                                   ("heading", steer.heading)):
                if value is not None and act.prim.priority > chosen.get(channel, (-1,))[0]:
                    chosen[channel] = (act.prim.priority, name, value)
        owners = tuple(chosen.get(c, (0, None))[1] for c in ("point", "depth", "heading"))
        n, e, d = self.ned
        # a channel let go holds where the vehicle is now
        if owners[0] is None and self.owners[0] is not None:
            self.hold[0], self.hold[1] = n, e
        if owners[1] is None and self.owners[1] is not None:
            self.hold[2] = d
        self.owners = owners
        north, east = (chosen["point"][2][0] - self.home[0], chosen["point"][2][1] - self.home[1]) \
            if "point" in chosen else (self.hold[0], self.hold[1])
        down = chosen["depth"][2] if "depth" in chosen else self.hold[2]
        yaw = chosen["heading"][2] if "heading" in chosen else None
        target = (round(north, 3), round(east, 3), round(down, 3),
                  None if yaw is None else round(yaw, 4))
        if target == self.sent_target and not force:
            return
        self.sent_target = target
        with self._sending():
            self.conn.mav.set_position_target_local_ned_send(
                int(self.boot * 1000) & 0xFFFFFFFF, *self.target, 1,
                POSITION if yaw is None else POSITION_YAW, north, east, down,
                0, 0, 0, 0, 0, 0, yaw or 0.0, 0)
        x, y = self.home[0] + north, self.home[1] + east
        words = f"target ({x:.2f}, {y:.2f}) depth {down:.2f} m" + (
            "" if yaw is None else f" heading {math.degrees(yaw):.0f} deg")
        self.log(self.clock(), "autopilot", words,
                 {"setpoint": [round(x, 3), round(y, 3), round(down, 3)]})

    # -- commands ---------------------------------------------------------------------------

    @contextmanager
    def _sending(self):
        """One send at a time (the heartbeat thread sends too); a failure loses the link."""
        with self.lock:
            try:
                yield
            except (LinkLost, VehicleFault):
                raise
            except Exception as e:   # a socket error, a device gone
                raise LinkLost(f"cannot send to the autopilot: {e}") from None

    def _command(self, command: int, *params: float) -> _Sent:
        """Send a command, and a TIMESYNC request right after it: the autopilot answers
        the request once it has had the command (one link keeps the order)."""
        params = list(params) + [0.0] * (7 - len(params))
        self.last_text = ""     # what it says next may be why it refuses this one
        with self._sending():
            self.conn.mav.command_long_send(*self.target, command, 0, *params)
            token = self._request_sync()
        return _Sent(token, self.boot, time.monotonic())

    def _request_sync(self) -> int:
        """Send a TIMESYNC request (under the lock); its token, in :attr:`synced`."""
        token, self.next_token = self.next_token, self.next_token + 1
        self.synced[token] = None
        self.synced.pop(token - KEPT_SYNCS, None)
        self.conn.mav.timesync_send(0, token)
        return token

    def _ask(self, command: int, *params: float) -> int | None:
        """Send a command and wait for its acknowledgement; None when none came in time."""
        self.acks.clear()
        sent = self._command(command, *params)
        got: list[int] = []

        def acked():
            if self._awaiting(sent):
                return False    # its answer says which acknowledgement is this command's
            answer = self.synced.get(sent.token)
            results = [(n, result) for cmd, result, n in self.acks
                       if cmd == command and result != 5]   # IN_PROGRESS is not the answer
            if answer is not None and any(n <= answer[1] for n, _ in results):
                # the last before the TIMESYNC answer: one before it answered an earlier
                # command of ours that a lagging link brings only now
                got.append([r for n, r in results if n <= answer[1]][-1])
            elif results:
                got.append(results[0][1])
            return bool(got)
        return got[0] if self._until(acked, self.mapping.ack_within, sent) else None

    def _set_mode(self, mode: int, name: str) -> None:
        self.last_text = ""
        result = self._ask(SET_MODE, 1, mode)
        if result != 0:
            raise VehicleFault(f"the autopilot refused mode {name} ({_result(result)})"
                               + self._said())
        if not self._until(lambda: self.mode == mode, self.mapping.ack_within):
            raise VehicleFault(f"the autopilot acknowledged mode {name} but is in "
                               f"{MODES.get(self.mode, self.mode)}")

    def _said(self) -> str:
        return f": \"{self.last_text}\"" if self.last_text else ""

    def _log_note(self, text: str, always: bool = False) -> None:
        """Log what the autopilot said or did; past :data:`KEPT_NOTES` only what must be
        read (``always``: a warning, the safe state's waits) is kept."""
        if self.notes >= KEPT_NOTES and not always:
            self.notes_dropped += 1
            return
        self.notes += 1
        # before it is armed the mission's clock is 0: the autopilot's own time says when
        boot = {} if self.boot is None else {"boot": round(self.boot, 3)}
        self.log(self.clock(), "autopilot", text, {"autopilot": text, **boot})

    # -- the end ----------------------------------------------------------------------------

    def secure(self, t: float) -> list[str]:
        """Bring the vehicle to the mapping's safe state; each step said, acknowledged or not.

        What was received is read before each step (a stale armed flag must not leave an
        armed vehicle armed), and a vehicle we asked to arm is sent the disarm whatever
        its last heartbeat said. A step that the autopilot's silence stops (no heartbeat
        within the liveness, or a clock that stands: frozen, its link down for a while)
        is tried again once it is heard, for up to the mapping's ``secure_within`` wall
        seconds; a link that is broken, or a peer never heard, is not waited for."""
        # kept on the vehicle as they are done: a safe state cut short keeps its steps
        done: list[str] = []
        self.secured_steps = done
        if self.conn is None:
            return done
        self.securing = True
        deadline = self.answer_by = time.monotonic() + self.mapping.secure_within

        def step(name: str, text: str, ok: bool) -> None:
            line = f"{name}: {text}"
            with interrupts.current().recording():    # said on the console and in the log
                done.append(line)
                self.log(self.clock() if self.t0 else 0.0, "safe-state", line,
                         {"safe_state": name, "acknowledged": ok, "detail": text})

        steps = list(self.mapping.safe_state)
        while steps:
            try:
                gone = self._gone()
                if gone is not None:     # nothing can be sent, nor its state known
                    raise LinkLost(gone)
                self._drain()
                if self.armed or self.arm_asked:     # a step will send: it must be heard
                    self._await_live(deadline)
                self._secure_step(steps[0], step)
            except (LinkLost, VehicleFault) as e:
                if self._gone() is None and self._stale() is not None \
                        and time.monotonic() < deadline:
                    continue      # silent for now: waited for, then the step again
                step(steps[0], f"not done: {e}", False)
            steps.pop(0)
        return done

    def _gone(self) -> str | None:
        """Why waiting cannot bring the autopilot back: its link broke, or it was never
        heard (None: it may come back)."""
        if self.broken is not None or self.send_fault is not None:
            return self.broken or self.send_fault
        if not self.last_heartbeat:
            return str(self.unready or f"no autopilot heartbeat from {self.address}")
        return None

    def _stale(self) -> str | None:
        """Why the autopilot is not live now: no heartbeat, or a clock that stands, for the
        liveness (None: it is)."""
        now, liveness = time.monotonic(), self.link.liveness
        if now - self.last_heartbeat > liveness:
            return f"no heartbeat from the autopilot for {liveness:g} s"
        if self.clock_moved and now - self.clock_moved > liveness:
            return f"the autopilot's clock has not moved for {liveness:g} s"
        return None

    def _await_live(self, deadline: float) -> None:
        """Return once the autopilot is live; while it is silent, keep listening (said
        once in the log) up to ``deadline`` (wall), then raise why it is not."""
        gone = self._gone()
        if gone is not None:
            raise LinkLost(gone)
        why = self._stale()
        if why is None:
            return
        left = deadline - time.monotonic()
        if left > 0:
            self._log_note(f"the autopilot is silent ({why}): still trying to bring it to its "
                           f"safe state for {round(left, 1):g} s", always=True)
        while (why := self._stale()) is not None:
            if time.monotonic() >= deadline:
                raise LinkLost(f"{why}; its safe state was tried for "
                               f"{self.mapping.secure_within:g} s")
            try:
                self._pump(POLL)
            except (LinkLost, VehicleFault):
                gone = self._gone()
                if gone is not None:
                    raise LinkLost(gone) from None
        self._log_note("the autopilot is heard again: its safe state goes on", always=True)

    def _secure_step(self, name: str, step: Callable[[str, str, bool], None]) -> None:
        """One step of the safe state, said by ``step``."""
        if not self.armed and not (name == "disarm" and self.arm_asked):
            # motors off is the safe state a step would reach, and we never armed it:
            # nothing is sent (SURFACE or POSHOLD would only wait to be armed)
            where = f"(in {MODES.get(self.mode, self.mode)})"
            if name == "disarm":
                step(name, f"already disarmed {where}: nothing to send", True)
            else:
                step(name, f"not sent: the autopilot is disarmed {where}", False)
            return
        if name == "hold":
            mode, word = (POSHOLD, "POSHOLD") if self.ekf & EKF_POS_HORIZ_ABS \
                else (ALT_HOLD, "ALT_HOLD")
            result = self._ask(SET_MODE, 1, mode)
            if result == 0:
                slow = self._until(lambda: self.speed < 0.2, self.mapping.hold_within)
                step(name, f"{word} acknowledged; "
                     + ("the vehicle has stopped" if slow else
                        f"still moving after {self.mapping.hold_within:g} s"), True)
            else:
                step(name, f"{word} not acknowledged ({_result(result)}){self._said()}", False)
        elif name == "surface":
            result = self._ask(SET_MODE, 1, SURFACE)
            if result == 0:
                up = self._until(lambda: self.depth is not None
                                 and self.depth <= self.mapping.surface_depth,
                                 self.mapping.surface_within)
                depth = "unknown" if self.depth is None else f"{self.depth:.2f} m"
                step(name, "SURFACE acknowledged; " + (
                    f"at the surface (depth {depth})" if up else
                    f"depth {depth} after {self.mapping.surface_within:g} s"), True)
            else:
                step(name, f"SURFACE not acknowledged ({_result(result)}){self._said()}",
                     False)
        else:
            # sent even when its last heartbeat said disarmed: that heartbeat may predate
            # the arming we asked for (a backlog), and a disarmed vehicle accepts it
            result = self._ask(ARM_DISARM, 0)
            off = result == 0 and self._until(lambda: not self.armed, self.mapping.ack_within)
            step(name, "disarm acknowledged; disarmed" if off else
                 f"disarm not acknowledged ({_result(result)}){self._said()}", off)

    def close(self) -> None:
        self.stopping.set()
        if self.beat is not None:
            self.beat.join(timeout=2.0)
        if self.conn is not None:
            try:
                self.conn.close()
            except Exception:   # closing a broken link: nothing more to do with it
                pass


def _broken(why: str) -> Callable[[], None]:
    def hook() -> None:
        raise ConnectionError(why)
    return hook


def _result(result: int | None) -> str:
    return "no acknowledgement" if result is None else RESULTS.get(result, f"result {result}")


def _mavutil():
    try:
        # pymavlink, 0.28 s (python -X importtime), and optional: only when an autopilot
        # is connected
        from pymavlink import mavutil
    except ImportError:
        raise SettingError("vehicle", "a MAVLink autopilot needs pymavlink: pip install "
                           "'mcl2pnml[mavlink]'") from None
    return mavutil


def _url(address: str) -> str:
    """``tcp:HOST:PORT``, ``udp:HOST:PORT`` (listen) or ``serial:DEVICE[:BAUD]`` as pymavlink's."""
    scheme, _, rest = address.partition(":")
    if scheme in ("tcp", "udp"):
        host, sep, port = rest.rpartition(":")
        # pymavlink's links take a host name or an IPv4 address (no IPv6)
        if not sep or not host or ":" in host or not port.isdigit() \
                or not 0 < int(port) < 65536:
            raise SettingError("connect", f"'{address}': write {scheme}:HOST:PORT, as "
                               f"{scheme}:127.0.0.1:{5760 if scheme == 'tcp' else 14550}")
        return f"{scheme}:{host}:{port}"
    if scheme == "serial":
        device, _, baud = rest.partition(":")
        if not device or (baud and not baud.isdigit()):
            raise SettingError("connect", f"'{address}': write serial:DEVICE[:BAUD], as "
                               "serial:/dev/ttyACM0:115200")
        return f"serial:{device}:{baud or 115200}"
    raise SettingError("connect", f"'{address}': an autopilot is reached at tcp:HOST:PORT, "
                       "udp:HOST:PORT or serial:DEVICE[:BAUD]")
