"""Binding a mission's primitives to an autopilot: the autopilot mapping file.

A MAVLink autopilot (ArduSub: docs/ardusub.md) does not know MCL's
primitives; it holds a mode, a position target, servo outputs. The mapping
file says, per primitive, who carries it out (section 2.1: the primitives
live on the vehicle's side of the abstraction layer):

* ``"by": "autopilot"``: flown. The primitive's set points (a point, a depth,
  a heading: what the simulated primitive of the same name asks,
  :mod:`mcl2pnml.runtime.simprims`) become one GUIDED position target,
  composed from every enabled primitive by the simulator's rule: each channel
  follows the enabled primitive of highest priority that sets it, ties by
  name; a channel nobody sets holds where the vehicle was when it was let go.
  Its goal is judged as the simulator judges it, on the autopilot's own
  position (a tolerance band held for a settle time, lost when out of it for
  longer than a loss time); it fails when the autopilot leaves GUIDED,
  disarms, or has had no position for ``position_lost_after`` seconds.
* ``"by": "servo"``: an actuator, ``MAV_CMD_DO_SET_SERVO`` to ``pwm`` on
  ``channel`` (``release_pwm`` when disabled); ``"by": "relay"``:
  ``MAV_CMD_DO_SET_RELAY``. Failed when the autopilot refuses the command
  or does not acknowledge it within ``ack_within``; once accepted, achieved
  as the simulated primitive says (after its world delay).
* ``"by": "simulated"``: a payload sensor the autopilot does not have
  (a camera that sees the cross, a plume detector...), simulated from the
  world file against the autopilot's own position. The log says so.

Only a primitive that moves the vehicle (its simulated counterpart sets a
point, a depth or a heading) may be flown: a built-in sensor or actuator
(DetectCross, CheckLatch, ReleaseMarker...) bound ``"by": "autopilot"``
would send no target and wait for a goal nothing reaches, and is refused.

The safe state is a list of steps, or ``"none"`` for a run that leaves the
vehicle as it is when it ends; an empty list is refused, since it reads as
an oversight (and leaves an armed vehicle armed).

Every bound (how long to wait for a position, an acknowledgement, the
surface) and the safe state a run ends in are settings of the file,
checked as the world file's are: one message at the setting's line and
column (the file read as every JSON input is, :mod:`mcl2pnml.core.jsontext`:
a key given twice, NaN, bytes that are not UTF-8 refused). The package's own mapping, for ArduSub, is ``ardusub.json`` beside
this module (``--vehicle mavlink``).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

from mcl2pnml.core.bounds import MAX_ACK_WITHIN
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.files import read_text
from mcl2pnml.core.jsontext import check_schema, parse_located
from mcl2pnml.runtime.simprims import SimulatedPrimitive, built_in

#: The largest mapping file read, in bytes.
MAX_MAPPING = 1 << 20
#: The steps of the safe state, in the only order they make sense in.
SAFE_STEPS = ("hold", "surface", "disarm")
#: Who carries out a primitive.
BY = ("autopilot", "servo", "relay", "simulated")
#: ``"safe_state"``'s spelling of a safe state of no step, said on purpose.
NO_SAFE_STATE = "none"


def _seconds(low: float, high: float) -> dict[str, Any]:
    return {"type": "number", "minimum": low, "maximum": high}


_BINDING = {
    "autopilot": {"settle": _seconds(0, 600), "lost_after": _seconds(0, 3600),
                  "tolerance": {"type": "number", "exclusiveMinimum": 0, "maximum": 1000}},
    "servo": {"channel": {"type": "integer", "minimum": 1, "maximum": 32},
              "pwm": {"type": "integer", "minimum": 500, "maximum": 2500},
              "release_pwm": {"type": "integer", "minimum": 500, "maximum": 2500}},
    "relay": {"relay": {"type": "integer", "minimum": 0, "maximum": 15}},
    "simulated": {},
}
_REQUIRED = {"servo": ["channel", "pwm"], "relay": ["relay"]}

#: The file's JSON Schema; each binding is checked against its kind's after.
SCHEMA: dict[str, Any] = {
    "type": "object",
    "required": ["primitives"],
    "additionalProperties": False,
    "properties": {
        "autopilot": {"type": "string", "maxLength": 200},
        "home": {"type": "array", "minItems": 2, "maxItems": 2,
                 "items": {"type": "number", "minimum": -1e6, "maximum": 1e6}},
        "ready_within": _seconds(1, 3600),
        "ack_within": _seconds(0.1, MAX_ACK_WITHIN),
        "position_lost_after": _seconds(0, 3600),
        "telemetry_rate": {"type": "number", "minimum": 1, "maximum": 50},
        "safe_state": {"anyOf": [{"type": "array", "minItems": 1, "maxItems": 3,
                                  "uniqueItems": True, "items": {"enum": list(SAFE_STEPS)}},
                                 {"const": NO_SAFE_STATE}]},
        "hold_within": _seconds(0, 600),
        "surface_depth": {"type": "number", "minimum": 0, "maximum": 100},
        "surface_within": _seconds(0, 3600),
        "secure_within": _seconds(0, 3600),
        "primitives": {
            "type": "object", "maxProperties": 1000,
            "propertyNames": {"pattern": "^[A-Za-z_][A-Za-z0-9_]*$", "maxLength": 200},
            "additionalProperties": {"type": "object", "required": ["by"],
                                     "properties": {"by": {"enum": list(BY)}}},
        },
    },
}


@functools.cache
def not_flown() -> frozenset[str]:
    """The built-in primitives the autopilot cannot fly: the sensors and actuators, whose
    simulated counterparts steer nothing. (A user's primitive, registered later, is not
    known when the mapping is read.)"""
    return frozenset(name for name, prim in built_in().items()
                     if type(prim).steer is SimulatedPrimitive.steer)


@dataclass(frozen=True)
class Binding:
    """One primitive: who carries it out, and that kind's settings (None: the world's)."""

    primitive: str
    by: str
    settle: float | None = None
    lost_after: float | None = None
    tolerance: float | None = None
    channel: int | None = None
    pwm: int | None = None
    release_pwm: int | None = None
    relay: int | None = None


@dataclass(frozen=True)
class AutopilotMapping:
    """A loaded autopilot mapping (see the module's documentation); times in the autopilot's s."""

    bindings: Mapping[str, Binding]
    autopilot: str = "ArduSub"
    #: the world point (x, y) of the autopilot's EKF origin; None: the world's start
    home: tuple[float, float] | None = None
    #: how long the autopilot may take to have a position and pass its pre-arm checks
    ready_within: float = 180.0
    #: how long a command (mode, arm, servo) may wait for its COMMAND_ACK
    ack_within: float = 3.0
    #: a flown primitive fails after this long without the autopilot's position
    position_lost_after: float = 5.0
    #: LOCAL_POSITION_NED and ATTITUDE per second of the autopilot's clock
    telemetry_rate: float = 10.0
    safe_state: tuple[str, ...] = SAFE_STEPS
    hold_within: float = 10.0
    surface_depth: float = 0.3
    surface_within: float = 120.0
    #: wall seconds the safe state keeps trying to reach a silent autopilot (frozen, or its
    #: link down for a while) before its steps are given up as not done
    secure_within: float = 30.0
    filename: str = field(default="<mapping>", compare=False)

    @classmethod
    def from_json(cls, text: str, filename: str = "<mapping>") -> "AutopilotMapping":
        data, where = parse_located(text, filename, "an autopilot mapping")
        if isinstance(data, dict) and data.get("safe_state") == []:
            raise Mcl2PnmlError(
                'safe_state: an empty list would leave the vehicle as it is when the run '
                f'ends (armed, wherever it is); to mean that, write "safe_state": '
                f'"{NO_SAFE_STATE}"', where(("safe_state",)))
        check_schema(data, SCHEMA, where, what="an autopilot mapping")
        bindings = {}
        for name, spec in data["primitives"].items():
            kind = spec["by"]
            schema = {"type": "object", "additionalProperties": False,
                      "required": ["by"] + _REQUIRED.get(kind, []),
                      "properties": {"by": {}, **_BINDING[kind]}}
            check_schema(spec, schema, lambda path, n=name: where(("primitives", n, *path)),
                         ("primitives", name), what="an autopilot mapping")
            if kind == "autopilot" and name in not_flown():
                raise Mcl2PnmlError(
                    f'primitives.{name}.by: the autopilot cannot fly {name}: it steers '
                    'nothing (no point, depth or heading); bind a sensor "by": "simulated", '
                    'an actuator "by": "servo" or "relay"', where(("primitives", name, "by")))
            bindings[name] = Binding(name, **spec)
        safe_state = data.get("safe_state", SAFE_STEPS)
        steps = () if safe_state == NO_SAFE_STATE else tuple(safe_state)
        if list(steps) != sorted(steps, key=SAFE_STEPS.index):
            raise Mcl2PnmlError("safe_state: the steps go in the order hold, surface, disarm "
                                "(any of them may be left out)", where(("safe_state",)))
        settings = {k: v for k, v in data.items() if k not in ("primitives", "safe_state")}
        if "home" in settings:
            settings["home"] = tuple(float(v) for v in settings["home"])
        return cls(bindings, safe_state=steps, filename=filename, **settings)

    @classmethod
    def load(cls, path: str | Path) -> "AutopilotMapping":
        """The mapping file at ``path`` (at most :data:`MAX_MAPPING` bytes, UTF-8)."""
        return cls.from_json(read_text(path, "autopilot mapping", MAX_MAPPING), str(path))

    @classmethod
    def ardusub(cls) -> "AutopilotMapping":
        """The package's own mapping for ArduSub (``ardusub.json``)."""
        source = resources.files("mcl2pnml.runtime").joinpath("ardusub.json")
        return cls.from_json(source.read_text("utf-8"), "ardusub.json (mcl2pnml's own)")
