"""The simulator's primitives: what each one makes the vehicle do, and when it reports.

Section 2.1 of the paper puts the primitives on the vehicle's side of the
abstraction layer: the mission only enables and disables them and hears
whether each goal is achieved or failed. A simulated primitive is the same
thing for :class:`~mcl2pnml.runtime.simulator.AUVSimulator`: a
:class:`SimulatedPrimitive` says which arguments it takes, which set points
it imposes on the vehicle while enabled (a point to steer to, a depth, a
heading, a drift), and, from the vehicle's state and the world, when its goal
is achieved or failed (section 2.2, Fig. 1: C seeking, S2 achieved, S1
failed or lost). The simulator does the dynamics; this module the meaning.

The built-in primitives (angles in degrees, lengths in metres, times in
seconds; every time and place named is a world setting, docs/simulator.md):

* ``CheckLatch()``: achieved: latch_time after enabling, at the dock;
  failed: latch_time after enabling, away from the dock (or no dock).
* ``DetectCross()``: achieved: the floor's cross inside the down-looking
  camera's footprint; failed: never.
* ``DetectMisalignment(max_error)``: achieved: sideways off the homing's
  track (from where it is enabled to the dock) by more than max_error;
  failed: at once: no dock, or max_error not above 0.
* ``DetectObstacle(range)``: achieved: an obstacle or the tank's side within
  range, inside the sonar's cone; failed: at once: range not above 0.
* ``DetectPlume(threshold)``: achieved: the concentration rises through the
  threshold; failed: at once: threshold not above 0.
* ``FireBottle()``: achieved: bottle_time after enabling; failed: at once:
  every one of the world's bottles is fired.
* ``GoToPoint((x, y))``: achieved: within the acceptance radius of (x, y),
  at any depth; failed: at once: the point is outside the tank.
* ``GoToWayPoint((x, y, z))``: achieved: inside the acceptance sphere;
  failed: at once: the point is outside the tank.
* ``GpsFix()``: achieved: gps_time without a break above gps_depth; failed:
  never: under water it waits (the task's time-out decides).
* ``HomeToDock()``: achieved: within the acceptance radius of the dock;
  failed: at once: the world has no dock.
* ``KeepDepth(depth)``: achieved: settled: inside depth_band for settle_time
  (again after a loss); failed: lost: out of twice the band for lost_after
  seconds after achieving; at once: the depth is outside the tank.
* ``KeepHeading(heading)``: achieved: settled: inside heading_band for
  settle_time (again after a loss); failed: lost: out of twice the band for
  lost_after seconds after achieving.
* ``ReleaseMarker()``: achieved: release_time after enabling (where it lands
  is recorded); failed: never.
* ``SendAcoustic(message)``: achieved: acoustic_time after enabling; failed:
  at once: the message is not a string.

A keep-primitive reports as a real one does (section 2.2 treats a lost
goal as a transient state that can be regained): ``achieved`` only once the
vehicle has settled, ``failed`` only when the error has stayed outside the
wider band for ``lost_after`` seconds, and ``achieved`` again when it has
settled again. So an overshoot while turning is no loss; a depth that
cannot be held is. The vehicle decides what a loss is; the task patterns
keep mcl.md's meaning (KeepGoal fails when its primitive reports failure).

Adding one's own: subclass :class:`SimulatedPrimitive` and decorate it with
:func:`register` (the built-ins below are registered that way), in a file
given to ``mcl2pnml run --sim-primitives FILE.py`` or in a module named by
an entry point of the group ``mcl2pnml.simulated_primitives`` (loaded when a
simulator is made). A name taken twice is refused.
"""
from __future__ import annotations

import math
import runpy
import traceback
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.payloads import EventKind

# The simulator's ``State`` and ``World`` are named in annotations as text only:
# the simulator imports this module, and the layers allow no circle of imports.
#: The entry-point group through which an installed package adds simulated primitives.
ENTRY_POINTS = "mcl2pnml.simulated_primitives"


@dataclass(frozen=True)
class Steer:
    """What a primitive asks of the vehicle's controllers; None leaves a channel alone.

    ``point`` (x, y) is steered to (heading and surge speed follow);
    ``heading`` is in radians; ``drift`` (m/s, x and y) is a current the
    vehicle is carried by while the primitive is enabled.
    """

    point: tuple[float, float] | None = None
    depth: float | None = None
    heading: float | None = None
    drift: tuple[float, float] = (0.0, 0.0)


@dataclass
class Context:
    """What a primitive sees: its enabling, the vehicle's state and the world.

    ``goal`` is what it last reported ("C" seeking, "S2" achieved, "S1"
    failed or lost: Fig. 1's places); ``memory`` is its own, kept for this
    enabling (the simulator copies it when it looks ahead, so that looking
    ahead changes nothing); ``enabling`` counts its enablings in the run from
    1; ``achieved`` counts its ``achieved`` reports before this enabling.
    """

    args: tuple
    state: "State"
    world: "World"
    since: float
    goal: str = "C"
    enabling: int = 1
    achieved: int = 0
    memory: dict[str, Any] = field(default_factory=dict)


class SimulatedPrimitive(ABC):
    """One primitive the simulator offers (see the module's documentation)."""

    #: its name, as missions declare it
    name: str = ""
    #: its arguments, in words (``run --help`` and docs/simulator.md)
    arguments: str = "none"
    #: when it reports ``achieved`` and ``failed``, in words
    achieves: str = ""
    fails: str = "never"
    #: whose set points win where two primitives set the same channel (higher wins)
    priority: int = 0

    def check(self, ctx: Context) -> str | None:
        """Why the vehicle cannot do it with ``ctx.args`` (it then fails at once), or None."""
        return f"{self.name} takes no arguments" if ctx.args else None

    def steer(self, ctx: Context) -> Steer | None:
        """The set points it imposes now (default: none, a sensor)."""
        return None

    @abstractmethod
    def sense(self, ctx: Context) -> EventKind | None:
        """The report its goal calls for in this state (None: as it was).

        Called at every time step while it is enabled, the look-ahead's and
        the real run's alike, so it may keep notes in ``ctx.memory``; a report
        equal to the last one is not sent again.
        """

    def reported(self, ctx: Context, kind: EventKind, vehicle: Any) -> None:
        """After a report was sent (a marker dropped is recorded here); default nothing."""


Registry = dict[str, SimulatedPrimitive]

_BUILT_IN: Registry = {}
#: where the primitives being registered go (a user's file registers into its own)
_target: list[Registry] = [_BUILT_IN]


def register(cls: type[SimulatedPrimitive]) -> type[SimulatedPrimitive]:
    """Class decorator: offer this primitive in the simulator (a name only once)."""
    if not (isinstance(cls, type) and issubclass(cls, SimulatedPrimitive)) or not cls.name:
        raise TypeError("register() takes a SimulatedPrimitive subclass with a name")
    table = _target[-1]
    if cls.name in table or cls.name in _BUILT_IN:
        raise ValueError(f"a simulated primitive '{cls.name}' is registered already")
    table[cls.name] = cls()
    return cls


def built_in() -> Registry:
    """The built-in primitives, by name."""
    return dict(_BUILT_IN)


def installed() -> Registry:
    """The built-ins and those of the installed packages' entry points."""
    # importlib.metadata, 22 ms (python -X importtime): only when the primitives are looked
    # up, not on the CLI's start, which imports this module
    from importlib.metadata import entry_points
    table = built_in()
    for ep in sorted(entry_points(group=ENTRY_POINTS), key=lambda e: e.name):
        table.update(_collect(lambda ep=ep: ep.load(), f"entry point '{ep.name}' ({ep.value})",
                              Location(ep.value), table))
    return table


def load_file(path: str | Path, table: Registry | None = None) -> Registry:
    """``table`` (default: :func:`installed`) with the primitives a Python file registers."""
    path = Path(path)
    table = installed() if table is None else dict(table)
    if not path.is_file():
        raise Mcl2PnmlError("no such file of simulated primitives", Location(str(path)))
    added = _collect(lambda: runpy.run_path(str(path), run_name="mcl2pnml_sim_primitives"),
                     str(path), Location(str(path)), table)
    if not added:
        raise Mcl2PnmlError("the file registers no simulated primitive (decorate a "
                            "SimulatedPrimitive subclass with @register)", Location(str(path)))
    table.update(added)
    return table


def _collect(load: Callable[[], Any], what: str, where: Location, table: Registry) -> Registry:
    """Run ``load`` with registrations going to a fresh table; its faults as our errors."""
    added: Registry = {}
    _target.append(added)
    try:
        load()
    except Exception as e:  # the user's code: whatever it raises is reported where it was
        raise Mcl2PnmlError(f"{what}: {type(e).__name__}: {e}", _fault_location(e, where)) \
            from None
    finally:
        _target.pop()
    for name in added:
        if name in table:
            raise Mcl2PnmlError(f"{what}: a simulated primitive '{name}' is registered "
                                "already", where)
    return added


def _fault_location(e: BaseException, where: Location) -> Location:
    """The line of the user's file where ``e`` happened (a syntax error's own position)."""
    if isinstance(e, SyntaxError) and e.filename == where.file:
        return Location(where.file, e.lineno, e.offset, e.text)
    frames = [f for f in traceback.extract_tb(e.__traceback__) if f.filename == where.file]
    if frames:
        return Location(where.file, frames[-1].lineno, 1, frames[-1].line)
    return where


# ---------------------------------------------------------------------------
# helpers the built-ins share

def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _angle(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def _one_number(name: str, args: tuple, what: str) -> str | None:
    if len(args) != 1 or not _number(args[0]):
        return f"{name} takes one number, {what}"
    return None


def _positive(name: str, args: tuple, what: str) -> str | None:
    return _one_number(name, args, what) or (
        None if args[0] > 0 else f"{name}'s {what} must be above 0, not {args[0]}")


def _point(name: str, args: tuple, size: int, world: "World") -> str | None:
    words = "(x, y, z)" if size == 3 else "(x, y)"
    if len(args) != 1 or not isinstance(args[0], tuple) or len(args[0]) != size \
            or not all(map(_number, args[0])):
        return f"{name} takes one point {words}"
    if not world.inside(args[0]):
        return f"{tuple(args[0])} is outside the {world.tank_words()}"
    return None


def _no_dock(world: "World") -> str | None:
    return None if world.dock is not None else "this world has no dock"


def _after(ctx: Context, seconds: float) -> bool:
    """Whether ``seconds`` have passed since the enabling (on the time step's grid)."""
    return ctx.state.t >= ctx.since + seconds - 1e-9


def _held(ctx: Context, key: str, holds: bool) -> float:
    """For how long ``holds`` has been true without a break (0 when it is false now)."""
    if not holds:
        ctx.memory.pop(key, None)
        return 0.0
    start = ctx.memory.setdefault(key, ctx.state.t)
    return ctx.state.t - start


def _reached(ctx: Context, point: tuple[float, ...]) -> bool:
    s = ctx.state
    here = (s.x, s.y, s.z)[:len(point)]
    return math.dist(here, point) <= ctx.world.acceptance


# ---------------------------------------------------------------------------
# the built-in primitives: moving

class _Above(SimulatedPrimitive):
    """A sensor whose one argument is a number above 0 (a range, a threshold)."""

    def check(self, ctx):
        return _positive(self.name, ctx.args, self.arguments)


class _GoTo(SimulatedPrimitive):
    """Steer to a point of ``size`` coordinates (x, y and, with three, the depth)."""

    priority, size = 1, 3
    fails = "at once: the point is outside the tank"

    def check(self, ctx):
        return _point(self.name, ctx.args, self.size, ctx.world)

    def steer(self, ctx):
        point = ctx.args[0]
        return Steer(point=(point[0], point[1]), depth=point[2] if self.size == 3 else None)

    def sense(self, ctx):
        return EventKind.ACHIEVED if _reached(ctx, ctx.args[0]) else None


@register
class GoToWayPoint(_GoTo):
    name, arguments = "GoToWayPoint", "(x, y, z)"
    achieves = "inside the acceptance sphere"


@register
class GoToPoint(_GoTo):
    name, arguments, size = "GoToPoint", "(x, y)", 2
    achieves = "within the acceptance radius of (x, y), at any depth"


class _Keep(SimulatedPrimitive):
    """Hold a value: achieved once settled, lost only after ``lost_after`` outside twice the band.

    Section 2.2: a lost goal is a transient state (S2 to S1 and back), which
    the vehicle, not the mission, tells from a passing error.
    """

    fails = "lost: out of twice the band for lost_after seconds after achieving"

    @abstractmethod
    def error(self, ctx: Context) -> tuple[float, float]:
        """The error now and the band, in the same unit."""

    def sense(self, ctx):
        error, band = self.error(ctx)
        inside = _held(ctx, "inside", error <= band)
        outside = _held(ctx, "outside", error > 2 * band)
        if ctx.goal != "S2" and error <= band and inside >= ctx.world.settle_time - 1e-9:
            return EventKind.ACHIEVED
        if ctx.goal == "S2" and error > 2 * band and outside >= ctx.world.lost_after - 1e-9:
            return EventKind.FAILED
        return None


@register
class KeepDepth(_Keep):
    name, arguments, priority = "KeepDepth", "depth", 2
    achieves = "settled: inside depth_band for settle_time (again after a loss)"
    fails = _Keep.fails + "; at once: the depth is outside the tank"

    def check(self, ctx):
        args, world = ctx.args, ctx.world
        problem = _one_number(self.name, args, "the depth")
        if problem is None and not 0 <= args[0] <= world.tank[2]:
            return f"depth {args[0]} is outside the tank (0 to {world.tank[2]:g} m)"
        return problem

    def steer(self, ctx):
        return Steer(depth=float(ctx.args[0]))

    def error(self, ctx):
        return abs(ctx.state.z - float(ctx.args[0])), ctx.world.depth_band


@register
class KeepHeading(_Keep):
    name, arguments = "KeepHeading", "heading"
    achieves = "settled: inside heading_band for settle_time (again after a loss)"

    def check(self, ctx):
        return _one_number(self.name, ctx.args, "the heading in degrees")

    def steer(self, ctx):
        return Steer(heading=math.radians(float(ctx.args[0])))

    def error(self, ctx):
        target = math.radians(float(ctx.args[0]))
        return abs(_angle(ctx.state.yaw - target)), ctx.world.heading_band


@register
class HomeToDock(SimulatedPrimitive):
    name, priority = "HomeToDock", 1
    achieves = "within the acceptance radius of the dock"
    fails = "at once: the world has no dock"

    def check(self, ctx):
        return super().check(ctx) or _no_dock(ctx.world)

    def steer(self, ctx):
        w = ctx.world
        x, y, z = w.dock
        drift = (0.0, 0.0)
        if ctx.enabling <= w.dock_drifts:
            # a cross-current on the first homings pushes the vehicle off the axis
            left = w.dock_heading + math.pi / 2
            drift = (w.dock_drift * math.cos(left), w.dock_drift * math.sin(left))
        return Steer(point=(x, y), depth=z, drift=drift)

    def sense(self, ctx):
        return EventKind.ACHIEVED if _reached(ctx, ctx.world.dock) else None


@register
class DetectMisalignment(_Above):
    name, arguments = "DetectMisalignment", "max_error"
    achieves = "sideways off the homing's track (from where it is enabled to the dock) by " \
        "more than max_error"
    fails = "at once: no dock, or max_error not above 0"

    def check(self, ctx):
        return super().check(ctx) or _no_dock(ctx.world)

    def sense(self, ctx):
        # the cross-track error of the homing: sideways from the straight line
        # from where the detector was enabled to the dock (where the homing
        # starts), not from the dock's axis, which a waypoint's acceptance
        # sphere may leave by more than the largest error allowed
        w, s = ctx.world, ctx.state
        x0, y0 = ctx.memory.setdefault("from", (s.x, s.y))
        track = math.atan2(w.dock[1] - y0, w.dock[0] - x0)
        dx, dy = s.x - x0, s.y - y0
        sideways = abs(-dx * math.sin(track) + dy * math.cos(track))
        return EventKind.ACHIEVED if sideways > float(ctx.args[0]) else None


@register
class CheckLatch(SimulatedPrimitive):
    name = "CheckLatch"
    achieves = "latch_time after enabling, at the dock"
    fails = "latch_time after enabling, away from the dock (or no dock)"

    def sense(self, ctx):
        if not _after(ctx, ctx.world.latch_time):
            return None
        docked = ctx.world.dock is not None and _reached(ctx, ctx.world.dock)
        return EventKind.ACHIEVED if docked else EventKind.FAILED


# ---------------------------------------------------------------------------
# sensors and payloads

@register
class DetectCross(SimulatedPrimitive):
    name = "DetectCross"
    achieves = "the floor's cross inside the down-looking camera's footprint"

    def sense(self, ctx):
        w, s = ctx.world, ctx.state
        if ctx.goal != "C" or w.cross is None:
            return None
        footprint = (w.tank[2] - s.z) * math.tan(w.camera_half_angle)
        seen = math.hypot(s.x - w.cross[0], s.y - w.cross[1]) <= footprint
        return EventKind.ACHIEVED if seen else None


class _Timed(SimulatedPrimitive):
    """Achieved once the world's ``delay`` (the name of a setting in seconds) has passed."""

    delay = ""

    def sense(self, ctx):
        return EventKind.ACHIEVED if ctx.goal == "C" and \
            _after(ctx, getattr(ctx.world, self.delay)) else None


@register
class ReleaseMarker(_Timed):
    name, delay = "ReleaseMarker", "release_time"
    achieves = "release_time after enabling (where it lands is recorded)"

    def reported(self, ctx, kind, vehicle):
        if kind is EventKind.ACHIEVED:
            vehicle.markers.append((ctx.state.x, ctx.state.y))


@register
class DetectObstacle(_Above):
    name, arguments = "DetectObstacle", "range"
    achieves = "an obstacle or the tank's side within range, inside the sonar's cone"
    fails = "at once: range not above 0"

    def sense(self, ctx):
        return EventKind.ACHIEVED if ctx.world.sonar_range(ctx.state) <= float(ctx.args[0]) \
            else None


@register
class GpsFix(SimulatedPrimitive):
    name = "GpsFix"
    achieves = "gps_time without a break above gps_depth"
    fails = "never: under water it waits (the task's time-out decides)"

    def sense(self, ctx):
        w = ctx.world
        up = _held(ctx, "surfaced", ctx.state.z <= w.gps_depth)
        return EventKind.ACHIEVED if ctx.goal == "C" and ctx.state.z <= w.gps_depth \
            and up >= w.gps_time - 1e-9 else None


@register
class SendAcoustic(_Timed):
    name, arguments, delay = "SendAcoustic", "message", "acoustic_time"
    achieves = "acoustic_time after enabling"
    fails = "at once: the message is not a string"

    def check(self, ctx):
        args = ctx.args
        if len(args) != 1 or not isinstance(args[0], str):
            return f"{self.name} takes one message, a string"
        return None


@register
class DetectPlume(_Above):
    name, arguments = "DetectPlume", "threshold"
    achieves = "the concentration rises through the threshold"
    fails = "at once: threshold not above 0"

    def sense(self, ctx):
        # a rise through the threshold, as a detector that is re-armed does:
        # enabled inside a plume, it waits for the vehicle to leave and meet one
        above = ctx.world.concentration(ctx.state) >= float(ctx.args[0])
        if not above:
            ctx.memory["armed"] = True
        return EventKind.ACHIEVED if above and ctx.memory.get("armed") and ctx.goal == "C" \
            else None


@register
class FireBottle(_Timed):
    name, delay = "FireBottle", "bottle_time"
    achieves = "bottle_time after enabling"
    fails = "at once: every one of the world's bottles is fired"

    def check(self, ctx):
        bottles = ctx.world.bottles
        return super().check(ctx) or (None if ctx.achieved < bottles else
                                       f"all {bottles} bottles are fired")


def table_rows(table: Mapping[str, SimulatedPrimitive]) -> list[tuple[str, str, str, str]]:
    """(name, arguments, achieved, failed) of each primitive, by name: the documented table."""
    return [(p.name, p.arguments, p.achieves, p.fails) for _, p in sorted(table.items())]
