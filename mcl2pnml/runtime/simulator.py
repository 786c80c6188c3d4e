"""A kinematic AUV in a water tank: the vehicle missions run on before a real one.

The vehicle is a point with a heading: position x, y (metres, in the tank),
depth z (metres, down from the surface) and yaw (radians). Its speeds follow
their set points with first-order lags and within limits (surge speed,
heave speed, turn rate), integrated in steps of :attr:`World.dt` seconds of
virtual time. Optional noise (a seeded random walk on the position, as
currents and navigation drift do) makes runs differ; with the same seed
they are identical.

What it can do is in :mod:`mcl2pnml.runtime.simprims`: each primitive's
arguments, set points and reports, the paper's (GoToWayPoint, KeepDepth,
KeepHeading, DetectCross, ReleaseMarker: section 3, Fig. 5) and those the
examples declare, in one registry that a user's primitives join. Here is
the dynamics, and the world they act in (:class:`World`, docs/simulator.md):
the tank (from :attr:`World.origin`), and what is in the water (the cross,
a dock, obstacles, plumes). Each set point channel (a point to steer to, a
depth, a heading) follows the enabled primitive of highest priority that
sets it.

Enabling and disabling are acknowledged at once (``on``, ``off``).
"""
from __future__ import annotations

import copy
import json
import math
import random
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from mcl2pnml.runtime.aal import Action, ActionKind, Event, EventKind, Reported, Vehicle
from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import read_text
from mcl2pnml.core.jsontext import parse_located
from mcl2pnml.runtime.simprims import Context, SimulatedPrimitive, built_in, installed

#: The built-in simulated primitives' names (:mod:`mcl2pnml.runtime.simprims` has the table).
PRIMITIVES: tuple[str, ...] = tuple(sorted(built_in()))

#: The longest description a world file may give, in characters.
MAX_DESCRIPTION = 4000
#: The largest world file read, in bytes (its obstacles and plumes are lists).
MAX_WORLD = 1 << 20


@dataclass(frozen=True)
class World:
    """The tank, the vehicle's limits and what is in the water (docs/simulator.md).

    Defaults: the paper's 16 x 8 x 5 m tank with its cross; the settings of
    the other primitives' world (dock, obstacles, plumes, GPS, payloads) are
    there for every mission, so that any of them runs in the default world.
    """

    tank: tuple[float, float, float] = (16.0, 8.0, 5.0)   # x, y, depth extents from origin
    origin: tuple[float, float] = (0.0, 0.0)             # the tank's corner of least x, y
    start: tuple[float, float, float] = (2.0, 4.0, 0.0)
    start_yaw: float = 0.0
    cross: tuple[float, float] | None = (10.0, 4.0)      # on the floor; None: no cross
    max_speed: float = 0.5          # m/s, surge
    max_heave: float = 0.3          # m/s
    max_turn: float = math.radians(30)   # rad/s
    tau: float = 1.5                # s, first-order lag of every speed
    acceptance: float = 0.5         # m, radius of the waypoint's sphere
    hold_radius: float = 0.05       # m: this near a point across, only the depth is steered
    depth_band: float = 0.2         # m
    heading_band: float = math.radians(5)
    settle_time: float = 2.0        # s inside a keep-primitive's band before "achieved"
    lost_after: float = 5.0         # s outside twice the band before "failed" (lost)
    camera_half_angle: float = math.radians(30)
    release_time: float = 1.0       # s
    dock: tuple[float, float, float] | None = None   # where HomeToDock goes; None: no dock
    dock_heading: float = 0.0       # rad: the direction of the dock's axis, into the dock
    dock_drift: float = 0.0         # m/s sideways (to the axis's left) while homing ...
    dock_drifts: int = 0            # ... on this many first homings
    latch_time: float = 1.0         # s
    obstacles: tuple[tuple[float, float, float, float], ...] = ()   # x, y, z, radius
    sonar_half_angle: float = math.radians(30)
    plumes: tuple[tuple[float, float, float, float, float], ...] = ()  # x, y, z, radius, peak
    gps_depth: float = 0.3          # m: the antenna is out of the water above it
    gps_time: float = 10.0          # s at the surface for a fix
    acoustic_time: float = 5.0      # s to send a message
    bottle_time: float = 3.0        # s to fire a bottle
    bottles: int = 12
    noise: float = 0.0              # m/sqrt(s): random walk of the position
    seed: int | None = 0
    dt: float = 0.1                 # s

    @classmethod
    def from_json(cls, text: str, filename: str = "<world>") -> "World":
        """A world file: any of the fields above, as JSON (``"cross": null`` for none).

        Every field is checked, each fault one message at the field's line and
        column: its type, that its numbers are finite and in range (:data:`RANGES`;
        the time step ``dt`` from :data:`MIN_DT` to :data:`MAX_DT` s, so that a
        run takes a bounded number of steps), the shapes of the points and
        lists, and that the start, the cross, the dock, the obstacles and the
        plumes are inside the tank. Angles are in degrees in the file, radians
        inside.
        """
        data, at = parse_located(text, filename, "a world file")
        # "description": words for the reader, as a vehicle model's and a fault file's
        valid = set(cls.__dataclass_fields__) | {"description"}
        if not isinstance(data, dict):
            raise Mcl2PnmlError("a world file is a JSON object with some of: "
                                + ", ".join(sorted(valid)), Location(filename))

        def where(key: str) -> Location:
            return at((key,))
        unknown = sorted(set(data) - valid)
        if unknown:
            raise Mcl2PnmlError(f"unknown world setting '{unknown[0]}'; valid: "
                                + ", ".join(sorted(valid)), where(unknown[0]))
        described = data.pop("description", "")
        if not isinstance(described, str) or len(described) > MAX_DESCRIPTION:
            raise Mcl2PnmlError(f"description: a string of at most {MAX_DESCRIPTION:,} "
                                "characters", where("description"))
        return cls(**_checked_fields(data, where))

    @classmethod
    def load(cls, path: str | Path) -> "World":
        return cls.from_json(read_text(path, "world file", MAX_WORLD), str(path))

    # -- what the primitives ask of the world -------------------------------------

    def inside(self, point: tuple[float, ...]) -> bool:
        """Whether a point (x, y) or (x, y, depth) is in the tank."""
        lows = (*self.origin, 0.0)
        return all(lo <= v <= lo + size for v, lo, size in zip(point, lows, self.tank))

    def tank_words(self) -> str:
        words = " x ".join(f"{v:g}" for v in self.tank) + " m tank"
        return words if self.origin == (0.0, 0.0) else \
            words + f" from ({self.origin[0]:g}, {self.origin[1]:g})"

    def concentration(self, s: "State") -> float:
        """The plumes' concentration at the vehicle: each a Gaussian of its radius."""
        return sum(peak * math.exp(-math.dist((s.x, s.y, s.z), (x, y, z)) ** 2 / (2 * r * r))
                   for x, y, z, r, peak in self.plumes)

    def sonar_range(self, s: "State") -> float:
        """How far ahead the forward sonar sees something: an obstacle or the tank's side.

        An obstacle counts inside the cone of :attr:`sonar_half_angle` about
        the heading, at the distance to its surface; the side at the distance
        along the heading to where it leaves the tank.
        """
        best = math.inf
        for x, y, z, r in self.obstacles:
            dx, dy = x - s.x, y - s.y
            if abs(_angle(math.atan2(dy, dx) - s.yaw)) <= self.sonar_half_angle or \
                    math.hypot(dx, dy) <= r:
                best = min(best, max(0.0, math.dist((s.x, s.y, s.z), (x, y, z)) - r))
        c, si = math.cos(s.yaw), math.sin(s.yaw)
        for pos, lo, size, d in ((s.x, self.origin[0], self.tank[0], c),
                                 (s.y, self.origin[1], self.tank[1], si)):
            if d > 1e-12:
                best = min(best, (lo + size - pos) / d)
            elif d < -1e-12:
                best = min(best, (lo - pos) / d)
        return best


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
    enabling: int = 1
    achieved: int = 0
    memory: dict = field(default_factory=dict)


def _angle(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


class AUVSimulator(Vehicle):
    """The kinematic AUV as a :class:`~mcl2pnml.runtime.aal.Vehicle` (see the module's documentation).

    ``primitives``: the simulated primitives it offers, by name (default: the
    built-ins and those installed through the entry-point group,
    :func:`mcl2pnml.runtime.simprims.installed`).
    """

    def __init__(self, world: World | None = None,
                 primitives: Mapping[str, SimulatedPrimitive] | None = None):
        self.world = world or World()
        self.offer(installed() if primitives is None else primitives)
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
        self.enablings: dict[str, int] = {}
        self.achievements: dict[str, int] = {}
        self._lookahead: tuple[float, Event, dict[str, dict]] | None = None

    def fork(self) -> "AUVSimulator":
        """A copy that runs on alone from here, to look ahead at its events (a fault
        injector does, :mod:`mcl2pnml.runtime.faults`): all of it copied but the track
        drawn so far (the trajectory and the set points: their last points only), which
        no event depends on and which grows with the run."""
        kept = self.trajectory, self.setpoints
        self.trajectory, self.setpoints = kept[0][-1:], kept[1][-1:]
        # the generator copied as a whole (its state, an immutable tuple, shared): a deep
        # copy went through its 625 numbers one by one, most of a fork's time
        memo = {id(self.world): self.world, id(self.rng): copy.copy(self.rng)}
        try:
            return copy.deepcopy(self, memo)
        finally:
            self.trajectory, self.setpoints = kept

    def offer(self, primitives: Mapping[str, SimulatedPrimitive]) -> None:
        """Offer these simulated primitives instead (before the run: a user's added)."""
        self.table = dict(primitives)
        self.primitives = frozenset(self.table)

    # -- actions ------------------------------------------------------------------

    def act(self, action: Action) -> None:
        self._lookahead = None
        name, t = action.primitive, action.t
        if action.kind is ActionKind.DISABLE:
            self.active.pop(name, None)
            self.acks.append(Event(t, EventKind.OFF, name))
            return
        self.enablings[name] = self.enablings.get(name, 0) + 1
        act = self.active[name] = _Active(name, action.args, t, enabling=self.enablings[name],
                                          achieved=self.achievements.get(name, 0))
        self.acks.append(Event(t, EventKind.ON, name))
        prim = self.table.get(name)
        # a run checks the primitives before it starts (session.py); called
        # directly with one it does not offer, the vehicle says it cannot
        problem = (f"the simulator does not offer {name}" if prim is None else
                   prim.check(self._context(act, self.state)))
        if problem:
            # the vehicle cannot do it: it says so at once, and does nothing
            act.goal, act.bad = "S1", True
            self.acks.append(Reported(t, EventKind.FAILED, name, "simulator", problem))
            self.problems.append((t, name, problem))
            return
        steer = prim.steer(self._context(act, self.state))
        if steer is not None and (steer.point is not None or steer.depth is not None):
            s = self.state
            x, y = steer.point or (s.x, s.y)
            self.setpoints.append((t, x, y, s.z if steer.depth is None else steer.depth))

    def _context(self, act: _Active, s: State, memory: dict | None = None) -> Context:
        return Context(act.args, s, self.world, act.since, act.goal, act.enabling,
                       act.achieved, act.memory if memory is None else memory)

    # -- dynamics -----------------------------------------------------------------

    def _targets(self, s: State) -> tuple[float, float, float, tuple[float, float]]:
        """Set points: surge speed, depth, heading and drift, from the active primitives.

        Each channel is set by the primitive of highest priority that sets it
        (ties by name); a point to steer to sets the heading and the speed.
        """
        w = self.world
        speed, depth, heading = 0.0, s.z, s.yaw
        drift = [0.0, 0.0]
        chosen: dict[str, tuple[int, float]] = {}
        for name in sorted(self.active):
            act = self.active[name]
            if act.bad:
                continue
            prim = self.table[name]
            steer = prim.steer(self._context(act, s))
            if steer is None:
                continue
            drift[0] += steer.drift[0]
            drift[1] += steer.drift[1]
            if steer.point is not None and prim.priority > chosen.get("point", (-1, 0))[0]:
                dx, dy = steer.point[0] - s.x, steer.point[1] - s.y
                dist = math.hypot(dx, dy)
                near = dist <= w.hold_radius   # above the point: hold the heading, heave
                aim = s.yaw if near else math.atan2(dy, dx)
                # slow down near the point, and turn before speeding up
                go = 0.0 if near else \
                    min(w.max_speed, 0.5 * dist) * max(0.0, math.cos(_angle(aim - s.yaw)))
                chosen["point"] = (prim.priority, go)
                chosen["heading"] = max(chosen.get("heading", (-1, 0)), (prim.priority, aim),
                                        key=lambda c: c[0])
            for channel, value in (("depth", steer.depth), ("heading", steer.heading)):
                if value is not None and prim.priority > chosen.get(channel, (-1, 0))[0]:
                    chosen[channel] = (prim.priority, value)
        speed = chosen["point"][1] if "point" in chosen else speed
        depth = chosen["depth"][1] if "depth" in chosen else depth
        heading = chosen["heading"][1] if "heading" in chosen else heading
        return speed, depth, heading, (drift[0], drift[1])

    def _step(self, s: State, dt: float, rng: random.Random) -> State:
        w = self.world
        speed, depth, heading, drift = self._targets(s)
        k = 1 - math.exp(-dt / w.tau)
        heave = max(-w.max_heave, min(w.max_heave, (depth - s.z) / max(w.tau, dt)))
        turn = max(-w.max_turn, min(w.max_turn, _angle(heading - s.yaw) / max(w.tau, dt)))
        u = s.u + (speed - s.u) * k
        wv = s.w + (heave - s.w) * k
        r = s.r + (turn - s.r) * k
        yaw = _angle(s.yaw + r * dt)
        x = s.x + (u * math.cos(yaw) + drift[0]) * dt
        y = s.y + (u * math.sin(yaw) + drift[1]) * dt
        z = s.z + wv * dt
        if w.noise:
            sigma = w.noise * math.sqrt(dt)
            x += rng.gauss(0, sigma)
            y += rng.gauss(0, sigma)
            z += rng.gauss(0, sigma * 0.3)
        (ox, oy), (sx, sy, sz) = w.origin, w.tank
        x = min(max(x, ox), ox + sx)
        y = min(max(y, oy), oy + sy)
        z = min(max(z, 0.0), sz)
        return State(s.t + dt, x, y, z, yaw, u, wv, r)

    def _sensed(self, s: State, memories: dict[str, dict]) -> list[tuple[str, EventKind]]:
        """The primitives whose goal changes in state ``s``: (name, achieved|failed), by name.

        Every primitive is asked at every step, whether or not another
        reports, so that the notes it keeps in ``memories`` are the same in
        the look-ahead as in the real run.
        """
        out = []
        for name in sorted(self.active):
            act = self.active[name]
            if act.bad:
                continue
            kind = self.table[name].sense(self._context(act, s, memories[name]))
            if kind is not None and kind is not _REPORTED[act.goal]:
                out.append((name, kind))
        return out

    # -- the vehicle interface -------------------------------------------------------

    #: How far ahead to look for the next event before saying there is none.
    HORIZON = 3600.0

    def next_event_time(self) -> float | None:
        if self.acks:
            return self.acks[0].t
        nxt = self._next_sensed()
        return None if nxt is None else nxt[0]

    def _next_sensed(self) -> tuple[float, Event, dict[str, dict]] | None:
        if self._lookahead is not None:
            return self._lookahead
        if not self.active:
            return None
        s, rng = self.state, random.Random()
        rng.setstate(self.rng.getstate())
        memories = {n: dict(a.memory) for n, a in self.active.items()}
        end = s.t + self.HORIZON
        while s.t < end:
            s = self._step(s, self.world.dt, rng)
            sensed = self._sensed(s, memories)
            if sensed:
                name, kind = sensed[0]
                event = Event(s.t, kind, name) if kind is not EventKind.FAILED else \
                    Reported(s.t, kind, name, "simulator", _sensed_why(self.table[name]))
                self._lookahead = (s.t, event, memories)
                return self._lookahead
        return None

    def take_event(self) -> Event:
        if self.acks:
            return self.acks.pop(0)
        nxt = self._next_sensed()
        assert nxt is not None, "no event is pending"
        t, event, memories = nxt
        self.advance(t)
        for name, memory in memories.items():   # the notes as of the event's step
            self.active[name].memory = memory
        act = self.active[event.primitive]
        act.goal = "S2" if event.kind is EventKind.ACHIEVED else "S1"
        if event.kind is EventKind.ACHIEVED:
            self.achievements[event.primitive] = self.achievements.get(event.primitive, 0) + 1
        if isinstance(event, Reported):
            self.problems.append((t, event.primitive, event.why))
        self.table[event.primitive].reported(self._context(act, self.state), event.kind, self)
        self._lookahead = None
        return event

    def advance(self, t: float) -> None:
        """Integrate the real state up to time ``t`` (the look-ahead replays exactly).

        The primitives' notes follow the real run step by step, as in the
        look-ahead; at an event's instant :meth:`take_event` takes the
        look-ahead's, which are the same.
        """
        dt = self.world.dt
        if self._lookahead is not None and abs(self._lookahead[0] - t) > 1e-9:
            self._lookahead = None    # stopping off its grid: look again from there
        memories = {n: a.memory for n, a in self.active.items()}
        while self.state.t < t - 1e-9:
            step = min(dt, t - self.state.t)
            self.state = self._step(self.state, step, self.rng)
            self._sensed(self.state, memories)
            self.trajectory.append((self.state.t, self.state.x, self.state.y, self.state.z))


def _sensed_why(prim: SimulatedPrimitive) -> str:
    """Why a primitive failed after it started: its ``fails`` words, the at-once ones aside
    (those are :meth:`~mcl2pnml.runtime.simprims.SimulatedPrimitive.check`'s, said then)."""
    later = [part for part in prim.fails.split("; ")
             if part and not part.startswith(("at once", "never"))]
    return "; ".join(later) or f"{prim.name} reported its goal failed"


#: The report that leaves each goal state as it is (Fig. 1: S2 achieved, S1 failed).
_REPORTED = {"C": None, "S2": EventKind.ACHIEVED, "S1": EventKind.FAILED}


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
    "hold_radius": ("the distance across to a point within which only the depth is steered, "
                    "in metres", 0.0, True, MAX_LENGTH),
    "depth_band": ("the depth band in metres", 0.0, False, MAX_LENGTH),
    "heading_band": ("the heading band in degrees", 0.0, False, 180.0),
    "camera_half_angle": ("the camera's half angle in degrees", 0.0, False, 89.0),
    "release_time": ("the time a marker takes to go in seconds", 0.0, True, 3600.0),
    "settle_time": ("the time inside a keep-primitive's band before it is achieved, in "
                    "seconds", 0.0, True, 3600.0),
    "lost_after": ("the time outside twice a keep-primitive's band before it is lost, in "
                   "seconds", 0.0, True, 3600.0),
    "dock_heading": ("the direction of the dock's axis in degrees", -360.0, True, 360.0),
    "dock_drift": ("the sideways drift while homing in m/s", -100.0, True, 100.0),
    "latch_time": ("the time the latch takes to report in seconds", 0.0, True, 3600.0),
    "sonar_half_angle": ("the sonar's half angle in degrees", 0.0, False, 180.0),
    "gps_depth": ("the depth above which GPS is received in metres", 0.0, True, MAX_LENGTH),
    "gps_time": ("the time at the surface for a GPS fix in seconds", 0.0, True, 3600.0),
    "acoustic_time": ("the time an acoustic message takes in seconds", 0.0, True, 3600.0),
    "bottle_time": ("the time a bottle takes to fire in seconds", 0.0, True, 3600.0),
    "noise": ("the random walk of the position in m/sqrt(s)", 0.0, True, 100.0),
    "dt": ("the time step in seconds", MIN_DT, True, MAX_DT),
}
_DEGREES = ("start_yaw", "max_turn", "heading_band", "camera_half_angle", "dock_heading",
            "sonar_half_angle")
#: The whole numbers of a world file: what each is and its highest value (the lowest is 0).
COUNTS: dict[str, tuple[str, int]] = {
    "dock_drifts": ("how many first homings drift", 1_000_000),
    "bottles": ("how many bottles there are", 1_000_000),
}
#: The lists of a world file: what each item is, in words, and its numbers' count.
LISTS: dict[str, tuple[str, int]] = {
    "obstacles": ("an obstacle [x, y, depth, radius]", 4),
    "plumes": ("a plume [x, y, depth, radius, peak concentration]", 5),
}
#: How many items a list of a world file may have (each is looked at every time step).
MAX_ITEMS = 1000
_SEED_LIMIT = 2 ** 63


def _number(value: Any) -> bool:
    """A JSON number that is finite (JSON's ``true`` is no number here)."""
    return (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value))


def _range_text(low: float, low_allowed: bool, high: float) -> str:
    return f"from {low:g} to {high:g}" if low_allowed else f"above {low:g}, up to {high:g}"


def _checked_fields(data: dict[str, Any], where) -> dict[str, Any]:
    """The world's fields from a file's object, each checked (see :meth:`World.from_json`)."""
    fields = _Fields(data, where)
    fields.tank()
    fields.places()
    fields.numbers_and_counts()
    return fields.checked


class _Fields:
    """A world file's fields as they are checked, each fault one message at its key."""

    def __init__(self, data: dict[str, Any], where) -> None:
        self.data, self.where = data, where
        self.checked: dict[str, Any] = {}
        self.world = World()     # the tank the places are checked in, once it is read

    def bad(self, key: str, message: str) -> Mcl2PnmlError:
        return Mcl2PnmlError(f'world setting "{key}" is {message}, not '
                             f"{json.dumps(self.data[key])[:80]}", self.where(key))

    def numbers(self, key: str, value: Any, size: int, what: str) -> tuple[float, ...]:
        if not isinstance(value, list) or len(value) != size or not all(map(_number, value)):
            raise self.bad(key, f"{what}: a list of {size} finite numbers")
        return tuple(float(v) for v in value)

    def inside(self, key: str, point: tuple[float, ...], what: str) -> None:
        tank = self.world
        if not tank.inside(point):
            sizes = " x ".join(f"{v:g}" for v in tank.tank[:len(point)])
            start = "0" if tank.origin == (0.0, 0.0) else \
                "the origin ({:g}, {:g}, 0)".format(*tank.origin)
            raise self.bad(key, f"{what}: inside the {sizes} m tank (each from {start} to its "
                           "extent)")

    def tank(self) -> None:
        """The tank's extents and origin, which the places are then checked in."""
        data, fields = self.data, self.checked
        if "tank" in data:
            fields["tank"] = self.numbers("tank", data["tank"], 3,
                                          "the tank's extents x, y and depth in metres")
            if not all(0 < v <= MAX_LENGTH for v in fields["tank"]):
                raise self.bad("tank", f"the tank's extents x, y and depth in metres: each "
                               f"above 0, up to {MAX_LENGTH:,.0f}")
        if "origin" in data:
            fields["origin"] = self.numbers("origin", data["origin"], 2,
                                            "the tank's corner of least x and y in metres")
            if not all(abs(v) <= MAX_LENGTH for v in fields["origin"]):
                raise self.bad("origin", f"the tank's corner of least x and y in metres: each "
                               f"from {-MAX_LENGTH:,.0f} to {MAX_LENGTH:,.0f}")
        self.world = World(tank=fields.get("tank", World.tank),
                           origin=fields.get("origin", World.origin))

    def places(self) -> None:
        """The start, the cross, the dock and the lists of items, each inside the tank."""
        data, fields = self.data, self.checked
        if "start" in data:
            fields["start"] = self.numbers("start", data["start"], 3, "where the vehicle "
                                           "starts, x, y and depth")
            self.inside("start", fields["start"], "where the vehicle starts, x, y and depth")
        elif not self.world.inside(World.start):
            raise Mcl2PnmlError(f"the default start {World.start} is outside this tank: give "
                                '"start" too', self.where("tank" if "tank" in data else "origin"))
        for key, size, what in (("cross", 2, "where the cross is on the floor, x and y (or null)"),
                                ("dock", 3, "where the dock is, x, y and depth (or null)")):
            if key in data:
                fields[key] = (None if data[key] is None
                               else self.numbers(key, data[key], size, what))
                if fields[key] is not None:
                    self.inside(key, fields[key], what)
        for key, (what, size) in LISTS.items():
            if key in data:
                fields[key] = self.items(key, data[key], what, size)

    def items(self, key: str, items: Any, what: str, size: int) -> tuple[tuple[float, ...], ...]:
        if not isinstance(items, list) or len(items) > MAX_ITEMS:
            raise self.bad(key, f"a list of up to {MAX_ITEMS} items, each {what}")
        checked = []
        for item in items:
            values = self.numbers(key, item, size, f"a list of items, each {what}")
            self.inside(key, values[:3], f"a list of items, each {what}")
            if not all(0 < v <= MAX_LENGTH for v in values[3:]):
                raise self.bad(key, f"a list of items, each {what}, the radius (and peak) "
                               "above 0")
            checked.append(values)
        return tuple(checked)

    def numbers_and_counts(self) -> None:
        """The seed, the counts and the numbers in their ranges (angles read in degrees)."""
        data, fields = self.data, self.checked
        if "seed" in data:
            seed = data["seed"]
            if seed is not None and (not isinstance(seed, int) or isinstance(seed, bool)
                                     or abs(seed) >= _SEED_LIMIT):
                raise self.bad("seed", "the seed of the noise: an integer below 2^63 in size, "
                               "or null")
            fields["seed"] = seed
        for key, (what, high) in COUNTS.items():
            if key in data:
                value = data[key]
                if not isinstance(value, int) or isinstance(value, bool) \
                        or not 0 <= value <= high:
                    raise self.bad(key, f"{what}: a whole number from 0 to {high:,}")
                fields[key] = value
        for key, (what, low, low_allowed, high) in RANGES.items():
            if key not in data:
                continue
            value = data[key]
            if not _number(value) or not (low <= value if low_allowed else low < value) \
                    or value > high:
                raise self.bad(key, f"{what}: a number {_range_text(low, low_allowed, high)}")
            fields[key] = math.radians(value) if key in _DEGREES else float(value)
