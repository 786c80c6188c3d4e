"""A kinematic AUV in a water tank: the vehicle missions run on before a real one.

The vehicle is a point with a heading: position x, y (metres, in the tank),
depth z (metres, down from the surface) and yaw (radians). Its speeds follow
their set points with first-order lags and within limits (surge speed,
heave speed, turn rate), integrated in steps of :attr:`World.dt` seconds of
virtual time. Optional noise (a seeded random walk on the position, as
currents and navigation drift do) makes runs differ; with the same seed
they are identical.

It offers the primitives of the paper's experiment (section 3, Fig. 5):

* ``GoToWayPoint((x, y, z))``: steer there; achieved inside the acceptance
  sphere; failed at once if the point is outside the tank;
* ``KeepDepth(z)``: hold the depth; achieved inside the depth band, failed
  (lost) when it drifts out of twice the band, achieved again back inside;
* ``KeepHeading(degrees)``: hold the heading, with a heading band likewise;
* ``DetectCross()``: the down-looking camera; achieved when the cross on
  the tank floor is inside the camera's footprint;
* ``ReleaseMarker()``: drops a marker; achieved when it is away
  (:attr:`World.release_time` later), where it lands is recorded.

Enabling and disabling are acknowledged at once (``on``, ``off``).
"""
from __future__ import annotations

import json
import math
import random
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mcl2pnml.runtime.aal import Action, ActionKind, Event, EventKind, Vehicle
from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import json_fault, read_text

PRIMITIVES = ("GoToWayPoint", "KeepDepth", "KeepHeading", "DetectCross", "ReleaseMarker")


@dataclass(frozen=True)
class World:
    """The tank, the vehicle's limits and the target. Defaults: the paper's 16 x 8 x 5 m tank."""

    tank: tuple[float, float, float] = (16.0, 8.0, 5.0)   # x, y, depth extents from 0
    start: tuple[float, float, float] = (2.0, 4.0, 0.0)
    start_yaw: float = 0.0
    cross: tuple[float, float] | None = (10.0, 4.0)      # on the floor; None: no cross
    max_speed: float = 0.5          # m/s, surge
    max_heave: float = 0.3          # m/s
    max_turn: float = math.radians(30)   # rad/s
    tau: float = 1.5                # s, first-order lag of every speed
    acceptance: float = 0.5         # m, radius of the waypoint's sphere
    depth_band: float = 0.2         # m
    heading_band: float = math.radians(5)
    camera_half_angle: float = math.radians(30)
    release_time: float = 1.0       # s
    noise: float = 0.0              # m/sqrt(s): random walk of the position
    seed: int | None = 0
    dt: float = 0.1                 # s

    @classmethod
    def from_json(cls, text: str, filename: str = "<world>") -> "World":
        """A world file: any of the fields above, as JSON (``"cross": null`` for none).

        Every field is checked, each fault one message at the field's line and
        column: its type, that its numbers are finite and in range (:data:`RANGES`;
        the time step ``dt`` from :data:`MIN_DT` to :data:`MAX_DT` s, so that a
        run takes a bounded number of steps), the shapes of ``tank``, ``start``
        and ``cross``, and that the start and the cross are inside the tank.
        Angles are in degrees in the file, radians inside.
        """
        try:
            data = json.loads(text)
        except json.JSONDecodeError as e:
            raise Mcl2PnmlError(f"not a world file: {e.msg}",
                                Location(filename, e.lineno, e.colno)) from None
        except (ValueError, RecursionError) as e:   # a number past Python's digit limit
            raise Mcl2PnmlError(f"not a world file: {json_fault(e)}", Location(filename)) \
                from None
        valid = set(cls.__dataclass_fields__)
        if not isinstance(data, dict):
            raise Mcl2PnmlError("a world file is a JSON object with some of: "
                                + ", ".join(sorted(valid)), Location(filename))
        where = _field_locations(text, filename)
        unknown = sorted(set(data) - valid)
        if unknown:
            raise Mcl2PnmlError(f"unknown world setting '{unknown[0]}'; valid: "
                                + ", ".join(sorted(valid)), where(unknown[0]))
        return cls(**_checked_fields(data, where))

    @classmethod
    def load(cls, path: str | Path) -> "World":
        return cls.from_json(read_text(path, "world file"), str(path))


@dataclass
class State:
    t: float
    x: float
    y: float
    z: float
    yaw: float
    u: float = 0.0      # surge speed
    w: float = 0.0      # heave speed
    r: float = 0.0      # turn rate


@dataclass
class _Active:
    """A running primitive: its arguments, and where its goal stands."""

    name: str
    args: tuple
    since: float
    goal: str = "C"                 # C seeking, S1 failed or lost, S2 achieved
    bad: bool = False               # arguments it cannot use: it does nothing


def _angle(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


class AUVSimulator(Vehicle):
    """The kinematic AUV as a :class:`~mcl2pnml.runtime.aal.Vehicle` (see the module's documentation)."""

    primitives = frozenset(PRIMITIVES)

    def __init__(self, world: World | None = None):
        self.world = world or World()
        w = self.world
        self.state = State(0.0, *w.start, w.start_yaw)
        self.rng = random.Random(w.seed)
        self.active: dict[str, _Active] = {}
        self.acks: list[Event] = []               # on/off and at-once replies, in order
        self.trajectory: list[tuple[float, float, float, float]] = [
            (0.0, self.state.x, self.state.y, self.state.z)]
        self.setpoints: list[tuple[float, float, float, float]] = [
            (0.0, self.state.x, self.state.y, self.state.z)]
        self.markers: list[tuple[float, float]] = []
        self.problems: list[tuple[float, str, str]] = []   # (t, primitive, why it failed)
        self._lookahead: tuple[float, Event] | None = None

    # -- actions ------------------------------------------------------------------

    def act(self, action: Action) -> None:
        self._lookahead = None
        name, t = action.primitive, action.t
        if action.kind is ActionKind.DISABLE:
            self.active.pop(name, None)
            self.acks.append(Event(t, EventKind.OFF, name))
            return
        self.active[name] = _Active(name, action.args, t)
        self.acks.append(Event(t, EventKind.ON, name))
        problem = self._check_args(name, action.args)
        if problem:
            # the vehicle cannot do it: it says so at once, and does nothing
            self.active[name].goal, self.active[name].bad = "S1", True
            self.acks.append(Event(t, EventKind.FAILED, name))
            self.problems.append((t, name, problem))
        elif name == "GoToWayPoint":
            self.setpoints.append((t, *map(float, action.args[0])))
        elif name == "KeepDepth":
            s = self.state
            self.setpoints.append((t, s.x, s.y, float(action.args[0])))

    def _check_args(self, name: str, args: tuple) -> str | None:
        w = self.world
        number = lambda v: isinstance(v, (int, float)) and not isinstance(v, bool)
        if name == "GoToWayPoint":
            if len(args) != 1 or not isinstance(args[0], tuple) or len(args[0]) != 3 \
                    or not all(map(number, args[0])):
                return "GoToWayPoint takes one point (x, y, z)"
            x, y, z = args[0]
            if not (0 <= x <= w.tank[0] and 0 <= y <= w.tank[1] and 0 <= z <= w.tank[2]):
                return f"({x}, {y}, {z}) is outside the {w.tank[0]:g} x {w.tank[1]:g} x " \
                       f"{w.tank[2]:g} m tank"
        elif name in ("KeepDepth", "KeepHeading"):
            if len(args) != 1 or not number(args[0]):
                return f"{name} takes one number"
            if name == "KeepDepth" and not 0 <= args[0] <= w.tank[2]:
                return f"depth {args[0]} is outside the tank (0 to {w.tank[2]:g} m)"
        elif args:
            return f"{name} takes no arguments"
        return None

    # -- dynamics -----------------------------------------------------------------

    def _targets(self, s: State) -> tuple[float, float, float]:
        """Set points: surge speed, depth and heading, from the active primitives."""
        w = self.world
        speed, depth, heading = 0.0, s.z, s.yaw
        usable = {n: a for n, a in self.active.items() if not a.bad}
        go = usable.get("GoToWayPoint")
        if go is not None:
            x, y, z = go.args[0]
            dx, dy = x - s.x, y - s.y
            dist = math.hypot(dx, dy)
            if dist > 0.05:
                heading = math.atan2(dy, dx)
                # slow down near the point, and turn before speeding up
                speed = min(w.max_speed, 0.5 * dist) * max(0.0, math.cos(_angle(heading - s.yaw)))
            depth = z
        keep = usable.get("KeepDepth")
        if keep is not None:
            depth = float(keep.args[0])
        head = usable.get("KeepHeading")
        if head is not None and go is None:
            heading = math.radians(float(head.args[0]))
        return speed, depth, heading

    def _step(self, s: State, dt: float, rng: random.Random) -> State:
        w = self.world
        speed, depth, heading = self._targets(s)
        k = 1 - math.exp(-dt / w.tau)
        heave = max(-w.max_heave, min(w.max_heave, (depth - s.z) / max(w.tau, dt)))
        turn = max(-w.max_turn, min(w.max_turn, _angle(heading - s.yaw) / max(w.tau, dt)))
        u = s.u + (speed - s.u) * k
        wv = s.w + (heave - s.w) * k
        r = s.r + (turn - s.r) * k
        yaw = _angle(s.yaw + r * dt)
        x = s.x + u * math.cos(yaw) * dt
        y = s.y + u * math.sin(yaw) * dt
        z = s.z + wv * dt
        if w.noise:
            sigma = w.noise * math.sqrt(dt)
            x += rng.gauss(0, sigma)
            y += rng.gauss(0, sigma)
            z += rng.gauss(0, sigma * 0.3)
        x = min(max(x, 0.0), w.tank[0])
        y = min(max(y, 0.0), w.tank[1])
        z = min(max(z, 0.0), w.tank[2])
        return State(s.t + dt, x, y, z, yaw, u, wv, r)

    def _sensed(self, s: State, goals: dict[str, str]) -> list[tuple[str, EventKind]]:
        """The primitives whose goal changes in state ``s``: (name, achieved|failed)."""
        w = self.world
        out = []
        for name, act in self.active.items():
            if act.bad:
                continue
            goal = goals[name]
            if name == "GoToWayPoint":
                x, y, z = act.args[0]
                if goal == "C" and math.dist((s.x, s.y, s.z), (x, y, z)) <= w.acceptance:
                    out.append((name, EventKind.ACHIEVED))
            elif name in ("KeepDepth", "KeepHeading"):
                if name == "KeepDepth":
                    error, band = abs(s.z - float(act.args[0])), w.depth_band
                else:
                    error = abs(_angle(s.yaw - math.radians(float(act.args[0]))))
                    band = w.heading_band
                if goal in ("C", "S1") and error <= band:
                    out.append((name, EventKind.ACHIEVED))
                elif goal == "S2" and error > 2 * band:
                    out.append((name, EventKind.FAILED))
            elif name == "DetectCross":
                if goal == "C" and w.cross is not None:
                    footprint = (w.tank[2] - s.z) * math.tan(w.camera_half_angle)
                    if math.hypot(s.x - w.cross[0], s.y - w.cross[1]) <= footprint:
                        out.append((name, EventKind.ACHIEVED))
            elif name == "ReleaseMarker":
                if goal == "C" and s.t >= act.since + w.release_time - 1e-9:
                    out.append((name, EventKind.ACHIEVED))
        return sorted(out)

    # -- the vehicle interface -------------------------------------------------------

    #: How far ahead to look for the next event before saying there is none.
    HORIZON = 3600.0

    def next_event_time(self) -> float | None:
        if self.acks:
            return self.acks[0].t
        nxt = self._next_sensed()
        return None if nxt is None else nxt[0]

    def _next_sensed(self) -> tuple[float, Event] | None:
        if self._lookahead is not None:
            return self._lookahead
        if not self.active:
            return None
        s, rng = self.state, random.Random()
        rng.setstate(self.rng.getstate())
        goals = {n: a.goal for n, a in self.active.items()}
        end = s.t + self.HORIZON
        while s.t < end:
            s = self._step(s, self.world.dt, rng)
            sensed = self._sensed(s, goals)
            if sensed:
                name, kind = sensed[0]
                self._lookahead = (s.t, Event(s.t, kind, name))
                return self._lookahead
        return None

    def take_event(self) -> Event:
        if self.acks:
            return self.acks.pop(0)
        nxt = self._next_sensed()
        assert nxt is not None, "no event is pending"
        t, event = nxt
        self.advance(t)
        act = self.active[event.primitive]
        act.goal = "S2" if event.kind is EventKind.ACHIEVED else "S1"
        if event.primitive == "ReleaseMarker" and event.kind is EventKind.ACHIEVED:
            self.markers.append((self.state.x, self.state.y))
        self._lookahead = None
        return event

    def advance(self, t: float) -> None:
        """Integrate the real state up to time ``t`` (the look-ahead replays exactly)."""
        dt = self.world.dt
        if self._lookahead is not None and abs(self._lookahead[0] - t) > 1e-9:
            self._lookahead = None    # stopping off its grid: look again from there
        while self.state.t < t - 1e-9:
            step = min(dt, t - self.state.t)
            self.state = self._step(self.state, step, self.rng)
            self.trajectory.append((self.state.t, self.state.x, self.state.y, self.state.z))


#: The time step's range, in seconds: the simulator integrates in steps of ``dt``
#: and looks ahead :attr:`AUVSimulator.HORIZON` seconds for the next event, so
#: that a look-ahead takes at most HORIZON / MIN_DT steps (360,000).
MIN_DT, MAX_DT = 0.01, 10.0
#: How large a length, in metres, may be (tank extents, bands, radii).
MAX_LENGTH = 1e6
#: The numbers of a world file: what each is, its lowest and highest value, and
#: whether the lowest is allowed (False: only values above it). Angles in degrees.
RANGES: dict[str, tuple[str, float, bool, float]] = {
    "start_yaw": ("the heading at the start in degrees", -360.0, True, 360.0),
    "max_speed": ("the top surge speed in m/s", 0.0, False, 100.0),
    "max_heave": ("the top heave speed in m/s", 0.0, False, 100.0),
    "max_turn": ("the top turn rate in degrees/s", 0.0, False, 3600.0),
    "tau": ("the time constant of the speeds in seconds", 0.0, False, 3600.0),
    "acceptance": ("the radius of a waypoint's sphere in metres", 0.0, False, MAX_LENGTH),
    "depth_band": ("the depth band in metres", 0.0, False, MAX_LENGTH),
    "heading_band": ("the heading band in degrees", 0.0, False, 180.0),
    "camera_half_angle": ("the camera's half angle in degrees", 0.0, False, 89.0),
    "release_time": ("the time a marker takes to go in seconds", 0.0, True, 3600.0),
    "noise": ("the random walk of the position in m/sqrt(s)", 0.0, True, 100.0),
    "dt": ("the time step in seconds", MIN_DT, True, MAX_DT),
}
_DEGREES = ("start_yaw", "max_turn", "heading_band", "camera_half_angle")
_SEED_LIMIT = 2 ** 63


def _number(value: Any) -> bool:
    """A JSON number that is finite (JSON's ``true`` is no number here)."""
    return (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value))


def _range_text(low: float, low_allowed: bool, high: float) -> str:
    return f"from {low:g} to {high:g}" if low_allowed else f"above {low:g}, up to {high:g}"


def _field_locations(text: str, filename: str):
    """``where(key)``: the location of a top-level field's value in a world file's text.

    Walks the object as JSON does (the text has parsed already), noting where
    each value starts; a key given twice is located where JSON takes it, the
    last time.
    """
    decoder = json.JSONDecoder()
    lines = text.split("\n")
    starts: dict[str, int] = {}
    i = text.index("{") + 1
    blank = " \t\r\n"
    while True:
        while text[i] in blank:
            i += 1
        if text[i] == "}":
            break
        key, i = json.decoder.scanstring(text, i + 1)
        while text[i] in blank + ":":
            i += 1
        starts[key] = i
        _, i = decoder.raw_decode(text, i)
        while text[i] in blank + ",":
            i += 1
        if text[i] == "}":
            break

    def where(key: str) -> Location:
        if key not in starts:
            return Location(filename)
        line = text.count("\n", 0, starts[key])
        column = starts[key] - (text.rfind("\n", 0, starts[key]) + 1) + 1
        return Location(filename, line + 1, column, lines[line][:400])
    return where


def _checked_fields(data: dict[str, Any], where) -> dict[str, Any]:
    """The world's fields from a file's object, each checked (see :meth:`World.from_json`)."""
    def bad(key: str, message: str) -> Mcl2PnmlError:
        return Mcl2PnmlError(f'world setting "{key}" is {message}, not '
                             f"{json.dumps(data[key])[:80]}", where(key))

    def point(key: str, size: int, what: str, inside: tuple[float, ...] | None) -> tuple:
        value = data[key]
        if not isinstance(value, list) or len(value) != size or not all(map(_number, value)):
            raise bad(key, f"{what}: a list of {size} finite numbers")
        if inside is None:
            if not all(0 < v <= MAX_LENGTH for v in value):
                raise bad(key, f"{what}: each above 0, up to {MAX_LENGTH:,.0f}")
        elif not all(0 <= v <= limit for v, limit in zip(value, inside)):
            sizes = " x ".join(f"{v:g}" for v in inside)
            raise bad(key, f"{what}: inside the {sizes} m tank (each from 0 to its extent)")
        return tuple(float(v) for v in value)

    fields: dict[str, Any] = {}
    if "tank" in data:
        fields["tank"] = point("tank", 3, "the tank's extents x, y and depth in metres", None)
    tank = fields.get("tank", World.tank)
    if "start" in data:
        fields["start"] = point("start", 3, "where the vehicle starts, x, y and depth", tank)
    elif not all(0 <= v <= limit for v, limit in zip(World.start, tank)):
        raise Mcl2PnmlError(f"the default start {World.start} is outside this tank: give "
                            '"start" too', where("tank"))
    if "cross" in data:
        fields["cross"] = None if data["cross"] is None else point(
            "cross", 2, "where the cross is on the floor, x and y (or null)", tank[:2])
    if "seed" in data:
        seed = data["seed"]
        if seed is not None and (not isinstance(seed, int) or isinstance(seed, bool)
                                 or abs(seed) >= _SEED_LIMIT):
            raise bad("seed", "the seed of the noise: an integer below 2^63 in size, or null")
        fields["seed"] = seed
    for key, (what, low, low_allowed, high) in RANGES.items():
        if key not in data:
            continue
        value = data[key]
        if not _number(value) or not (low <= value if low_allowed else low < value) \
                or value > high:
            raise bad(key, f"{what}: a number {_range_text(low, low_allowed, high)}")
        fields[key] = math.radians(value) if key in _DEGREES else float(value)
    return fields
