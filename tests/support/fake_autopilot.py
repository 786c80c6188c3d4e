"""A fake MAVLink autopilot on loopback: a submarine that can be flown, and that misbehaves on cue.

``mcl2pnml run --vehicle mavlink --connect tcp:127.0.0.1:PORT`` connects to
it as to ArduSub's simulator. It listens on a TCP port, takes the first
connection, and speaks MAVLink as system 1 component 1, encoding its
frames with pymavlink's own encoder (``mavutil.mavlink.MAVLink``):

* its heartbeat (type 12, a submarine; autopilot 3, ArduPilot) says its
  mode and whether it is armed, once a second of its clock and at once
  after a change;
* it answers ``COMMAND_ACK`` to SET_MODE, ARM_DISARM, SET_MESSAGE_INTERVAL,
  DO_SET_SERVO and DO_SET_RELAY, and ``PARAM_VALUE`` to SIM_SPEEDUP;
* it streams LOCAL_POSITION_NED, ATTITUDE, EKF_STATUS_REPORT (a
  horizontal position, 0x10) and SYS_STATUS (pre-arm checks passed,
  0x10000000) with a ``time_boot_ms`` that runs ``speedup`` times the wall
  clock;
* armed in GUIDED it moves toward the last SET_POSITION_TARGET_LOCAL_NED
  at ``speed`` m/s of its clock; in SURFACE it rises; in POSHOLD or
  ALT_HOLD it stops.

How it behaves is its ``behaviour``: ``"fly"`` (the above), ``"silent"``
(it reads and says nothing), ``"garbage"`` (random bytes only),
``"flood"`` (thousands of STATUSTEXT and PARAM_VALUE a second, no
heartbeat), ``"flood+fly"`` (the flood on top of flying), ``"leap"`` (its
clock jumps three hours ahead, and flies on from there), ``"backwards"``
(its clock jumps 50 s back), ``"frozen"`` (its clock stands, the rest goes
on), ``"heartbeats"`` (its heartbeats and its answers, and no telemetry),
``"deaf"`` (it flies on, and answers no command nor parameter), ``"close"``
(it closes the connection), ``"drift"`` (in GUIDED it flies north at its
speed whatever its target: a vehicle that leaves the tank), ``"paused"``
(the process stopped, as by SIGSTOP: it says nothing and answers nothing
for ``pause`` wall seconds, its clock standing; then it flies on,
answering what it was sent meanwhile), ``"crowded"`` (it flies on, and
passes on the heartbeats of another ground station, ``station`` (system,
component), as ArduPilot routes one heard on another of its links).
``then`` is the behaviour it turns to once it is armed and has had a
position target away from where it is (a primitive the mission flies),
``after`` wall seconds later. Its heartbeats and slow messages are timed
on the wall clock, as often as its clock would have them running: a clock
that stands or leaps does not stop them.

Other ways it can be: ``armed`` at the start (another ground station flies
it); ``lag`` wall seconds by which, once it has accepted GUIDED (or once
armed: ``lag_from="arming"``), everything it says and everything it is
sent is late, in order (a link that lags: our arming reaches it late, and
its answer comes behind the telemetry of that while). It answers TIMESYNC
requests with its clock, as ArduPilot does. It keeps when it heard each of
our heartbeats (:meth:`FakeAutopilot.heartbeat_gap`: the longest gap, on
its clock) and the ground stations' heartbeats it was sent
(:attr:`FakeAutopilot.stations`).
"""
from __future__ import annotations

import math
import random
import socket
import threading
import time

from pymavlink import mavutil

mavlink = mavutil.mavlink

SUBMARINE, QUADROTOR, ARDUPILOT = 12, 2, 3
MANUAL, GUIDED, SURFACE, POSHOLD, ALT_HOLD = 19, 4, 9, 16, 2
SET_MODE, ARM_DISARM, SET_MESSAGE_INTERVAL, DO_SET_SERVO, DO_SET_RELAY = 176, 400, 511, 183, 181
ACCEPTED, FAILED, UNSUPPORTED = 0, 4, 3
EKF_OK = 0x1F7          # attitude, velocities, positions: 0x10 (horizontal absolute) among them
PREARM_OK = 0x10000000
CUSTOM_MODE_ENABLED, ARMED = 0x01, 0x80
#: The longest step of its clock (s) between two positions it sends (half a metre at its
#: default speed, within the camera's footprint on the cross), and the most steps
#: one tick sends (a tick held longer than that takes longer steps).
STEP, MAX_STEPS = 0.25, 400
BEHAVIOURS = ("fly", "silent", "garbage", "flood", "flood+fly", "leap", "backwards", "frozen",
              "heartbeats", "deaf", "close", "drift", "paused", "crowded")


class FakeAutopilot:
    """A fake submarine autopilot serving one connection on 127.0.0.1 (see the module)."""

    def __init__(self, behaviour: str = "fly", *, then: str | None = None, after: float = 0.0,
                 kind: int = SUBMARINE, speedup: float = 10.0, speed: float = 2.0,
                 answer_speedup: bool = True, refuse_guided: bool = False,
                 tick: float = 0.01, flood_rate: int = 5000, armed: bool = False,
                 lag: float = 0.0, lag_from: str = "GUIDED", pause: float = 0.0,
                 station: tuple[int, int] = (255, 42)):
        assert behaviour in BEHAVIOURS and then in BEHAVIOURS + (None,)
        self.behaviour, self.then, self.after = behaviour, then, after
        self.kind, self.speedup, self.speed = kind, speedup, speed
        self.answer_speedup, self.refuse_guided = answer_speedup, refuse_guided
        self.tick, self.flood_rate = tick, flood_rate
        assert lag_from in ("GUIDED", "arming")
        self.lag_after, self.lag_from, self.pause = lag, lag_from, pause
        self.station = mavlink.MAVLink(None, srcSystem=station[0], srcComponent=station[1])
        self.encoder = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self.parser = mavlink.MAVLink(None)
        self.parser.robust_parsing = True
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.listener.settimeout(10)
        self.port = self.listener.getsockname()[1]
        self.address = f"tcp:127.0.0.1:{self.port}"
        self.conn: socket.socket | None = None
        self.send_lock = threading.Lock()
        # reentrant: the tick turns, under it, to what is due (which takes it again)
        self.state = threading.RLock()
        self.stop = threading.Event()
        self.connected = threading.Event()
        self.random = random.Random(1)
        # the vehicle
        self.mode, self.armed = (GUIDED, True) if armed else (MANUAL, False)
        self.ned = [0.0, 0.0, 0.0]
        self.velocity = [0.0, 0.0, 0.0]
        self.yaw = 0.0
        self.target: tuple[float, float, float] | None = None
        self.offset = 100.0         # added to its clock: booted 100 s ago; a leap, a step back
        self.frozen_at: float | None = None
        #: the time its last tick's positions were stamped up to (its clock)
        self.stamped: float | None = None
        # what it was sent and did
        self.commands: list[tuple[int, tuple[float, ...]]] = []
        self.targets: list[tuple[float, float, float]] = []
        #: targets away from where it was when it got them (not a hold where it is)
        self.flown = 0
        self.heartbeats_heard = 0
        #: our heartbeats: when the last was heard (its clock), the longest gap between two
        self.last_beat: float | None = None
        self.longest_gap = 0.0
        #: the ground stations (system, component) whose heartbeats it was sent
        self.stations: set[tuple[int, int]] = set()
        #: the lag once it has begun (wall s; 0: none yet), and what is late: what
        #: it says and what it was sent, each with when it is due (wall)
        self.lag = 0.0
        self.late_out: list[tuple[float, bytes]] = []
        self.late_in: list[tuple[float, object]] = []
        self.lagged = 0
        #: while paused (wall time it resumes), what it was sent meanwhile
        self.paused_until: float | None = None
        self.unread: list = []
        self.armed_ever = False
        self.turned_at: float | None = None
        self.sent_messages = 0
        self.error: BaseException | None = None
        self.threads = [threading.Thread(target=self._serve, daemon=True)]
        self.threads[0].start()

    # -- the test's side --------------------------------------------------------------------

    def __enter__(self) -> "FakeAutopilot":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        self.stop.set()
        for s in (self.conn, self.listener):
            if s is not None:
                try:     # a shutdown wakes a thread blocked in recv or accept; a close does not
                    s.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
                s.close()
        for t in self.threads:
            t.join(timeout=5)

    def check(self) -> None:
        """Raise what went wrong in the fake itself (not in what it was told to do)."""
        if self.error is not None:
            raise self.error

    def commanded(self, command: int) -> list[tuple[float, ...]]:
        """The parameters of every COMMAND_LONG ``command`` received, in order."""
        return [params for cmd, params in list(self.commands) if cmd == command]

    def heartbeat_gap(self) -> float:
        """The longest time between two of the heartbeats it heard, on its clock (s)."""
        return self.longest_gap

    def boot(self) -> float:
        """Its clock, in seconds since it started."""
        if self.frozen_at is not None:
            return self.frozen_at
        return (time.monotonic() - self.started) * self.speedup + self.offset

    # -- serving ----------------------------------------------------------------------------

    def _serve(self) -> None:
        try:
            conn, _ = self.listener.accept()
        except OSError:
            return
        conn.settimeout(5)
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.conn = conn
        self.started = time.monotonic()
        self.last_step = self.started
        self.next_heartbeat = 0.0
        self.next_slow = 0.0
        self.connected.set()
        reader = threading.Thread(target=self._read, daemon=True)
        self.threads.append(reader)
        reader.start()
        try:
            while not self.stop.wait(self.tick):
                if self._turn():
                    return
                self._tick()
        except OSError:
            pass            # the other end went away
        except BaseException as e:     # a fault of the fake itself: the test shows it
            self.error = e

    def _due(self) -> None:
        """Turn to ``then`` once due: counted from the first target flown."""
        if self.then and self.turned_at is None and self.armed and self.flown:
            self.turned_at = time.monotonic()
        if self.turned_at is not None and self.then and \
                time.monotonic() - self.turned_at >= self.after:
            self._become(self.then)
            self.then = None

    def _turn(self) -> bool:
        """Turn to ``then`` once due; True when the connection is to end now."""
        self._due()
        if self.behaviour == "close":
            self.conn.close()
            return True
        if self.behaviour == "paused" and time.monotonic() >= self.paused_until:
            with self.state:     # its clock stood while it was stopped
                self.offset -= self.pause * self.speedup
                self.frozen_at = None
                self.behaviour = "fly"
                self.last_step = time.monotonic()
            for msg in self.unread:
                self._answer(msg)
            self.unread.clear()
        return False

    def _become(self, behaviour: str) -> None:
        with self.state:
            if behaviour == "leap":
                self.offset += 3 * 3600.0
            elif behaviour == "backwards":
                self.offset -= 50.0
            elif behaviour in ("frozen", "paused"):
                self.frozen_at = self.boot()
            if behaviour == "paused":
                self.paused_until = time.monotonic() + self.pause
            if behaviour == "crowded":      # the other station is heard at once
                self.next_heartbeat = 0.0
            self.behaviour = behaviour

    def _tick(self) -> None:
        now = time.monotonic()
        dt = (now - self.last_step) * self.speedup
        self.last_step = now
        b = self.behaviour
        if self.lag:
            self._late(now)
        if b in ("silent", "paused"):
            self.last_step = now
            return
        if b == "garbage":
            self._send_raw(self.random.randbytes(2048))
            return
        if b in ("flood", "flood+fly"):
            self._flood()
            if b == "flood":
                return
        if b == "heartbeats":
            if now >= self.next_heartbeat:
                self.next_heartbeat = now + 1.0 / self.speedup
                self._send(self._heartbeat_message())
            return
        with self.state:
            # under the lock the reader takes a target in: a turn due at a target is made
            # before the vehicle flies one tick toward it (a tick a loaded machine can make
            # long enough to fly the whole mission)
            self._due()
            b = self.behaviour
            boot = self.boot()
            # a tick a loaded machine held long is flown in steps, each position sent, as an
            # autopilot streams them: one jump would carry the vehicle past what the run
            # senses on its way (the cross under the second leg)
            steps = min(MAX_STEPS, max(1, math.ceil(dt / STEP)))
            track = []
            # stamped from the last time sent to this one, never back (a tick can compute
            # its time long after it started, behind a flood or the lock); a clock that
            # leaps or stands is stamped at its time
            last = self.stamped if self.stamped is not None and \
                boot - STEP * MAX_STEPS <= self.stamped <= boot else boot
            for k in range(steps):
                self._move(dt / steps)
                at = int((last + (boot - last) * (k + 1) / steps) * 1000) & 0xFFFFFFFF
                track.append(self.encoder.local_position_ned_encode(at, *self.ned,
                                                                    *self.velocity))
            self.stamped = boot
        millis = int(boot * 1000) & 0xFFFFFFFF
        messages = [*track,
                    self.encoder.attitude_encode(millis, 0.0, 0.0, self.yaw, 0.0, 0.0, 0.0)]
        if now >= self.next_slow:
            self.next_slow = now + 0.5 / self.speedup
            messages.append(self.encoder.ekf_status_report_encode(EKF_OK, 0.1, 0.1, 0.1, 0.1, 0))
            messages.append(self.encoder.sys_status_encode(0, 0, PREARM_OK, 0, 12000, 100, 90,
                                                           0, 0, 0, 0, 0, 0))
            messages.append(self.encoder.system_time_encode(int(time.time() * 1e6), millis))
        if now >= self.next_heartbeat:
            self.next_heartbeat = now + 1.0 / self.speedup
            messages.append(self._heartbeat_message())
            if b == "crowded":     # packed by the other station's own encoder, and sent
                # first: heard before the telemetry of the tick it came in
                other = self.station.heartbeat_encode(6, 8, 0, 0, 4).pack(self.station)
                with self.send_lock:
                    self.conn.sendall(other)
        self._send(*messages)

    def _late(self, now: float) -> None:
        """What lags and is due: sent, and handled, in order."""
        with self.send_lock:
            due = [data for at, data in self.late_out if at <= now]
            del self.late_out[:len(due)]
            self.conn.sendall(b"".join(due))
        while self.late_in and self.late_in[0][0] <= now:
            self._answer(self.late_in.pop(0)[1])

    def _move(self, dt: float) -> None:
        before = list(self.ned)
        step = self.speed * dt
        if not self.armed:
            pass
        elif self.mode == GUIDED and self.behaviour == "drift":
            self.ned[0] += step
        elif self.mode == GUIDED and self.target is not None:
            delta = [t - p for t, p in zip(self.target, self.ned)]
            distance = math.sqrt(sum(d * d for d in delta))
            if distance <= step:
                self.ned = list(self.target)
            else:
                self.ned = [p + d * step / distance for p, d in zip(self.ned, delta)]
        elif self.mode == SURFACE:
            self.ned[2] = max(0.0, self.ned[2] - step)
        self.velocity = [(a - b) / dt if dt > 0 else 0.0 for a, b in zip(self.ned, before)]

    def _flood(self) -> None:
        count = max(1, int(self.flood_rate * self.tick))
        messages = []
        for i in range(count):
            if i % 2:
                messages.append(self.encoder.statustext_encode(6, b"flood %d" % i))
            else:
                messages.append(self.encoder.param_value_encode(b"FLOOD_%d" % (i % 1000),
                                                                float(i), 9, 1000, i % 1000))
        self._send(*messages)

    def _heartbeat_message(self):
        base = CUSTOM_MODE_ENABLED | (ARMED if self.armed else 0)
        return self.encoder.heartbeat_encode(self.kind, ARDUPILOT, base, self.mode, 4)

    def _send(self, *messages) -> None:
        with self.send_lock:
            data = b"".join(m.pack(self.encoder) for m in messages)
            self.sent_messages += len(messages)
            if self.lag:
                self.late_out.append((time.monotonic() + self.lag, data))
                self.lagged += len(messages)
                return
            self.conn.sendall(data)

    def _send_raw(self, data: bytes) -> None:
        with self.send_lock:
            self.conn.sendall(data)

    # -- reading ----------------------------------------------------------------------------

    def _read(self) -> None:
        try:
            while not self.stop.is_set():
                try:
                    data = self.conn.recv(65536)
                except socket.timeout:
                    continue
                if not data:
                    return
                for msg in self.parser.parse_buffer(data) or []:
                    self._handle(msg)
        except OSError:
            pass
        except BaseException as e:
            self.error = e

    def _answering(self) -> bool:
        return self.behaviour in ("fly", "flood+fly", "leap", "backwards", "frozen", "heartbeats",
                                  "drift", "crowded")

    def _handle(self, msg) -> None:
        if self.behaviour == "paused":
            self.unread.append(msg)      # read when it resumes, as a stopped process would
        elif self.lag:
            self.late_in.append((time.monotonic() + self.lag, msg))
        else:
            self._answer(msg)

    def _answer(self, msg) -> None:
        kind = msg.get_type()
        if kind == "HEARTBEAT":
            self.heartbeats_heard += 1
            self.stations.add((msg.get_srcSystem(), msg.get_srcComponent()))
            now = self.boot()
            if self.last_beat is not None:
                self.longest_gap = max(self.longest_gap, now - self.last_beat)
            self.last_beat = now
        elif kind == "COMMAND_LONG":
            params = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6,
                      msg.param7)
            self.commands.append((msg.command, params))
            if self._answering():
                self._command(msg.command, params)
        elif kind == "PARAM_REQUEST_READ":
            if self.answer_speedup and self._answering() and msg.param_id == "SIM_SPEEDUP":
                self._send(self.encoder.param_value_encode(b"SIM_SPEEDUP", self.speedup, 9,
                                                           1, 0))
        elif kind == "TIMESYNC":
            if msg.tc1 == 0 and self._answering():
                self._send(self.encoder.timesync_encode(int(self.boot() * 1e9), msg.ts1))
        elif kind == "SET_POSITION_TARGET_LOCAL_NED":
            with self.state:
                self.target = (msg.x, msg.y, msg.z)
                if math.dist(self.target, self.ned) > 0.1:
                    self.flown += 1
                if msg.type_mask & 0x400 == 0:
                    self.yaw = msg.yaw
            self.targets.append(self.target)

    def _command(self, command: int, params: tuple[float, ...]) -> None:
        if command == SET_MODE:
            mode = int(params[1])
            if mode == GUIDED and self.refuse_guided:
                self._send(self.encoder.statustext_encode(
                    4, b"Mode change failed: GUIDED requires position"),
                    self.encoder.command_ack_encode(command, FAILED))
                return
            with self.state:
                self.mode = mode
            self._send(self.encoder.command_ack_encode(command, ACCEPTED),
                       self._heartbeat_message())
            if mode == GUIDED and self.lag_from == "GUIDED":
                self.lag = self.lag_after
        elif command == ARM_DISARM:
            with self.state:
                self.armed = params[0] == 1
                self.armed_ever |= self.armed
            if self.armed and self.lag_from == "arming":
                self.lag = self.lag_after      # its answer is late already
            self._send(self.encoder.command_ack_encode(command, ACCEPTED),
                       self._heartbeat_message())
        elif command in (SET_MESSAGE_INTERVAL, DO_SET_SERVO, DO_SET_RELAY):
            self._send(self.encoder.command_ack_encode(command, ACCEPTED))
        else:
            self._send(self.encoder.command_ack_encode(command, UNSUPPORTED))
