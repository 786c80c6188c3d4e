"""A vehicle's odds: how likely each primitive is to achieve or fail, and when it answers.

The proofs say what a mission does for *every* vehicle; a mission engineer
signing off a dive also asks how likely each ending is with *this* vehicle.
A vehicle model (a JSON file, docs/odds.md) says, per primitive, what one
enabling of it does:

* it is acknowledged (``on``) after the ``ack`` delay;
* then it reports ``achieved`` with probability ``achieve``, ``failed`` with
  probability ``fail``, or never reports (the rest, ``1 - achieve - fail``),
  after the ``achieved_after`` or ``failed_after`` delay (``after``: both);
* a goal achieved is later lost (reported ``failed``, as a kept goal's loss
  is: section 2.1) with probability ``lose``, ``lost_after`` after;
* a disable is acknowledged (``off``) after the ``ack`` delay, and silences
  every report still to come (as the scripted vehicle does, docs/running.md);
* the enablings with given arguments (a primitive's ``calls``) may have
  settings of their own: the vehicle tells a call by what it is asked.

Delays are distributions of seconds: ``{"fixed": 5}``, ``{"uniform": [20, 60]}``
(whole seconds, both ends included), ``{"table": {"30": 0.5, "40": 0.5}}``,
and, for simulated campaigns only, ``{"exponential": {"mean": 30}}`` and
``{"lognormal": {"mu": 3, "sigma": 0.5}}``. Probabilities are numbers or
exact fractions (``"2/3"``), read exactly (0.1 is 1/10).

One :class:`ModelVehicle` serves both uses of a model, so that they cannot
disagree on what it means: a simulated run draws each choice at random
(:class:`Draw`, seeded), and the exact odds (:mod:`mcl2pnml.odds`)
enumerate every choice with its probability (:class:`Replay`).
"""
from __future__ import annotations

import random
import re
from dataclasses import dataclass, field, replace
from fractions import Fraction
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence, TypeVar

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import read_text
from mcl2pnml.core.jsontext import check_schema, dotted, parse_located
from mcl2pnml.runtime.aal import Action, ActionKind, Event, EventKind, Vehicle

#: The largest vehicle model read, in bytes.
MAX_MODEL = 1 << 20
#: The longest delay a model may give, in seconds (a week).
MAX_DELAY = 7 * 24 * 3600
#: The most values a discrete delay may take (a uniform range, a table).
MAX_SUPPORT = 10_000
#: The most calls (argument lists with settings of their own) a primitive may give.
MAX_CALLS = 100

T = TypeVar("T")

#: a number, or a string of an exact one ("2/3", "0.1"): read by :func:`_probability`
_PROBABILITY = {"type": ["number", "string"], "minimum": 0, "maximum": 1, "maxLength": 40}
_EXACT = re.compile(r"\s*\d+(\.\d+)?\s*(/\s*\d+\s*)?")
_SECONDS = {"type": "number", "minimum": 0, "maximum": MAX_DELAY}
_WHOLE = {"type": "integer", "minimum": 0, "maximum": MAX_DELAY}
_DELAY = {
    "type": "object", "minProperties": 1, "maxProperties": 1,
    "properties": {
        "fixed": _SECONDS,
        "uniform": {"type": "array", "items": _WHOLE, "minItems": 2, "maxItems": 2},
        "table": {"type": "object", "minProperties": 1, "maxProperties": MAX_SUPPORT,
                  "propertyNames": {"pattern": r"^\d+(\.\d+)?$", "maxLength": 12},
                  "additionalProperties": _PROBABILITY},
        "exponential": {"type": "object", "required": ["mean"], "additionalProperties": False,
                        "properties": {"mean": {"type": "number", "exclusiveMinimum": 0,
                                                "maximum": MAX_DELAY}}},
        "lognormal": {"type": "object", "required": ["mu", "sigma"],
                      "additionalProperties": False,
                      "properties": {"mu": {"type": "number", "minimum": -50, "maximum": 50},
                                     "sigma": {"type": "number", "minimum": 0,
                                               "maximum": 10}}},
    },
    "additionalProperties": False,
}
_SETTINGS = {
    "achieve": _PROBABILITY, "fail": _PROBABILITY, "lose": _PROBABILITY,
    "after": _DELAY, "achieved_after": _DELAY, "failed_after": _DELAY, "lost_after": _DELAY,
    "ack": _DELAY,
}
_PRIMITIVE = {"type": "object", "additionalProperties": False, "properties": _SETTINGS}
#: A call's arguments as the trace writes them (numbers, strings, lists of them)
_ARGUMENT = {"type": ["number", "string", "boolean", "array"], "maxLength": 200,
             "maxItems": 32, "items": {"type": ["number", "string", "boolean"],
                                       "maxLength": 200}}
#: A named primitive: its settings, and optionally other settings for the enablings
#: with given arguments ("calls")
_NAMED = {"type": "object", "additionalProperties": False, "properties": {
    **_SETTINGS,
    "calls": {"type": "array", "maxItems": MAX_CALLS, "items": {
        "type": "object", "required": ["args"], "additionalProperties": False,
        "properties": {**_SETTINGS, "args": {"type": "array", "maxItems": 32,
                                             "items": _ARGUMENT}}}}}}

#: The file's JSON Schema (docs/odds.md); sums and ranges are checked after it.
SCHEMA: dict[str, Any] = {
    "type": "object", "additionalProperties": False,
    "properties": {
        "description": {"type": "string", "maxLength": 2000},
        "defaults": _PRIMITIVE,
        "primitives": {"type": "object", "maxProperties": 1000,
                       "propertyNames": {"pattern": "^[A-Za-z_][A-Za-z0-9_]*$",
                                         "maxLength": 200},
                       "additionalProperties": _NAMED},
    },
}


class NotDiscrete(Mcl2PnmlError):
    """A delay the exact odds cannot enumerate (exponential, log-normal)."""


@dataclass(frozen=True)
class Delay:
    """A distribution of delays in seconds: discrete (``support``) or continuous."""

    #: how the file gave it: fixed, uniform, table, exponential or lognormal
    kind: str
    #: the values and their probabilities, for the discrete kinds
    support: tuple[tuple[float, Fraction], ...] = ()
    #: the continuous kinds' parameters (mean; mu and sigma)
    parameters: tuple[float, ...] = ()
    #: where the file gave it, for the exact odds' refusal of a continuous one
    where: Location | None = field(default=None, compare=False)

    @classmethod
    def fixed(cls, seconds: float) -> "Delay":
        return cls("fixed", ((float(seconds), Fraction(1)),))

    def values(self) -> tuple[tuple[float, Fraction], ...]:
        """The delays with their probabilities; a continuous delay is refused."""
        if not self.support:
            raise NotDiscrete(f"a {self.kind} delay has no exact odds: give a fixed, uniform "
                              "or table delay (exponential and log-normal delays are for "
                              "simulated campaigns)", self.where)
        return self.support

    def draw(self, rng: random.Random) -> float:
        if self.kind == "exponential":
            return rng.expovariate(1.0 / self.parameters[0])
        if self.kind == "lognormal":
            return rng.lognormvariate(*self.parameters)
        return pick(self.support, rng)


@dataclass(frozen=True)
class PrimitiveModel:
    """What one enabling of a primitive does (the module's documentation)."""

    achieve: Fraction = Fraction(1)
    fail: Fraction = Fraction(0)
    achieved_after: Delay = Delay.fixed(1)
    failed_after: Delay = Delay.fixed(1)
    lose: Fraction = Fraction(0)
    lost_after: Delay = Delay.fixed(1)
    ack: Delay = Delay.fixed(0)
    #: the enablings with these arguments (as the trace writes them, lists as tuples)
    #: behave as their own settings say instead (the file's "calls", in its order)
    calls: tuple[tuple[tuple, "PrimitiveModel"], ...] = ()

    @property
    def never(self) -> Fraction:
        """The probability that it never reports."""
        return 1 - self.achieve - self.fail

    def call(self, args: tuple) -> int:
        """The index of the call whose arguments are ``args`` (-1: none, the primitive's
        own settings)."""
        key = _arguments(args)
        return next((k for k, (a, _) in enumerate(self.calls) if a == key), -1)

    def settings(self, call: int) -> "PrimitiveModel":
        """The settings of call ``call`` (-1: the primitive's own)."""
        return self if call < 0 else self.calls[call][1]


def _arguments(args: Any) -> Any:
    """Arguments compared as values: lists as tuples, recursively (1 equals 1.0)."""
    if isinstance(args, (list, tuple)):
        return tuple(_arguments(a) for a in args)
    return args


#: The model of a primitive a file does not name, and the settings a file leaves out:
#: acknowledged at once, achieved one second later, never failing or lost (docs/odds.md).
DEFAULT = PrimitiveModel()


def refuse_unused(named: Iterable[str], used: set[str], where: Mapping[str, Location],
                  says: str) -> None:
    """One message at the first primitive a file names that the mission does not use:
    a typo would otherwise leave the primitive it meant as the defaults say."""
    for name in named:
        if name not in used:
            raise Mcl2PnmlError(f"{says} '{name}', which the mission does not use; it uses "
                                + ", ".join(sorted(used)), where.get(name))


@dataclass(frozen=True)
class VehicleModel:
    """A loaded vehicle model: each named primitive's, and the rest's (``default``)."""

    primitives: Mapping[str, PrimitiveModel]
    default: PrimitiveModel = DEFAULT
    description: str = ""
    filename: str = field(default="<model>", compare=False)
    #: where the file names each primitive (a name the mission does not use is refused)
    where: Mapping[str, Location] = field(default_factory=dict, compare=False)

    def of(self, primitive: str) -> PrimitiveModel:
        return self.primitives.get(primitive, self.default)

    def check_primitives(self, used: set[str]) -> None:
        """Refuse a model of a primitive the mission does not use (a typo)."""
        refuse_unused(self.primitives, used, self.where, "the vehicle model gives")

    def replaced(self, primitive: str, **changes) -> "VehicleModel":
        """The model with one primitive's settings changed (the sensitivity table's)."""
        m = self.of(primitive)
        calls = tuple((args, replace(c, **changes)) for args, c in m.calls)
        return replace(self, primitives={**self.primitives,
                                         primitive: replace(m, **changes, calls=calls)})

    # -- reading ------------------------------------------------------------------------

    @classmethod
    def from_json(cls, text: str, filename: str = "<model>") -> "VehicleModel":
        data, where = parse_located(text, filename, "a vehicle model")
        check_schema(data, SCHEMA, where, what="a vehicle model")
        default = _primitive(data.get("defaults", {}), DEFAULT, ("defaults",), where)
        primitives = {name: _named(spec, default, ("primitives", name), where)
                      for name, spec in data.get("primitives", {}).items()}
        return cls(primitives, default, data.get("description", ""), filename,
                   {name: where(("primitives", name)) for name in primitives})

    @classmethod
    def load(cls, path: str | Path) -> "VehicleModel":
        return cls.from_json(read_text(path, "vehicle model", MAX_MODEL), str(path))


def _probability(value: Any, path: tuple, where) -> Fraction:
    """A probability as written: 0.1 is 1/10 (not the nearest double), "2/3" two thirds."""
    if isinstance(value, str):
        if not _EXACT.fullmatch(value):
            raise Mcl2PnmlError(f'{dotted(path)}: "{value}" is not a probability: a number from '
                                '0 to 1, or a fraction such as "2/3"', where(path))
        top, _, bottom = value.replace(" ", "").partition("/")
        if bottom and int(bottom) == 0:
            raise Mcl2PnmlError(f"{dotted(path)}: {value} divides by zero", where(path))
        p = Fraction(top) / (int(bottom) if bottom else 1)
    else:
        p = Fraction(str(value))
    if p > 1:
        raise Mcl2PnmlError(f"{dotted(path)}: {value} is more than 1", where(path))
    return p


def _delay(spec: Mapping[str, Any], path: tuple, where) -> Delay:
    (kind, value), = spec.items()
    at = where(path)
    if kind == "fixed":
        return Delay("fixed", ((float(value), Fraction(1)),), where=at)
    if kind == "uniform":
        low, high = value
        if high < low:
            raise Mcl2PnmlError(f"{dotted(path)}.uniform: [{low}, {high}] is empty: the first "
                                "bound is the smaller", where((*path, "uniform")))
        if high - low + 1 > MAX_SUPPORT:
            raise Mcl2PnmlError(f"{dotted(path)}.uniform: {high - low + 1:,} values, more "
                                f"than {MAX_SUPPORT:,}", where((*path, "uniform")))
        n = high - low + 1
        return Delay("uniform", tuple((float(d), Fraction(1, n)) for d in range(low, high + 1)),
                     where=at)
    if kind == "table":
        support = []
        for key, p in value.items():
            seconds = float(key)
            if seconds > MAX_DELAY:
                raise Mcl2PnmlError(f"{dotted(path)}.table: {key} s is longer than "
                                    f"{MAX_DELAY:,} s", where((*path, "table", key)))
            support.append((seconds, _probability(p, (*path, "table", key), where)))
        total = sum(p for _, p in support)
        if total != 1:
            raise Mcl2PnmlError(f"{dotted(path)}.table: the probabilities add up to {total}, "
                                "not 1", where((*path, "table")))
        return Delay("table", tuple(sorted((s, p) for s, p in support if p)), where=at)
    if kind == "exponential":
        return Delay("exponential", parameters=(float(value["mean"]),), where=at)
    return Delay("lognormal", parameters=(float(value["mu"]), float(value["sigma"])), where=at)


def _primitive(spec: Mapping[str, Any], base: PrimitiveModel, path: tuple,
               where) -> PrimitiveModel:
    """One primitive's settings over ``base`` (the defaults)."""
    changes: dict[str, Any] = {}
    for key in ("achieve", "fail", "lose"):
        if key in spec:
            changes[key] = _probability(spec[key], (*path, key), where)
    for key in ("after", "achieved_after", "failed_after", "lost_after", "ack"):
        if key in spec:
            changes[key] = _delay(spec[key], (*path, key), where)
    after = changes.pop("after", None)
    if after is not None:
        changes.setdefault("achieved_after", after)
        changes.setdefault("failed_after", after)
    model = replace(base, **changes)
    if model.achieve + model.fail > 1:
        raise Mcl2PnmlError(f"{dotted(path)}: achieve {model.achieve} and fail {model.fail} "
                            "add up to more than 1 (the rest is the chance it never reports)",
                            where(path))
    return model


def _named(spec: Mapping[str, Any], base: PrimitiveModel, path: tuple,
           where) -> PrimitiveModel:
    """A named primitive's settings over the defaults, and its calls' over its own."""
    own = _primitive({k: v for k, v in spec.items() if k != "calls"}, base, path, where)
    calls: list[tuple[tuple, PrimitiveModel]] = []
    for k, call in enumerate(spec.get("calls", ())):
        args = _arguments(call["args"])
        same = next((j for j, (a, _) in enumerate(calls) if a == args), None)
        if same is not None:
            raise Mcl2PnmlError(f"{dotted((*path, 'calls', k, 'args'))}: the same arguments "
                                f"as calls[{same}]", where((*path, "calls", k, "args")))
        settings = {key: v for key, v in call.items() if key != "args"}
        calls.append((args, _primitive(settings, own, (*path, "calls", k), where)))
    return replace(own, calls=tuple(calls))


# -- choosing ---------------------------------------------------------------------------

def pick(options: Sequence[tuple[T, Fraction]], rng: random.Random) -> T:
    """One of ``options`` (value, probability), drawn with ``rng``."""
    u = rng.random()
    for value, p in options:
        u -= float(p)
        if u < 0:
            return value
    return options[-1][0]


class Chooser:
    """How a :class:`ModelVehicle` makes each of its choices: one among ``options``
    (value, probability; the probabilities add up to 1), and when a delay may end."""

    def choose(self, options: Sequence[tuple[T, Fraction]]) -> T:
        raise NotImplementedError

    def schedule(self, delay: Delay, t: float) -> tuple[tuple[float, Fraction], ...]:
        """The times an event ``delay`` after ``t`` may come at, with their probabilities."""
        return tuple((t + d, p) for d, p in delay.values())


class Draw(Chooser):
    """At random: a simulated run (``random.Random(seed)``, so that a run is replayed by
    its seed)."""

    def __init__(self, rng: random.Random):
        self.rng = rng

    def choose(self, options):
        return pick(options, self.rng)

    def schedule(self, delay: Delay, t: float) -> tuple[tuple[float, Fraction], ...]:
        return ((t + delay.draw(self.rng), Fraction(1)),)    # drawn at once: the same law


class Choice(Exception):
    """A :class:`Replay` has no more choices made: these are the options of the next one."""

    def __init__(self, options: Sequence[tuple[Any, Fraction]]):
        super().__init__("a choice to make")
        self.options = list(options)


class Replay(Chooser):
    """The choices made already, by their index; the next one raises :class:`Choice`,
    so that the caller tries each option in turn (the exact odds' enumeration)."""

    def __init__(self, made: Sequence[int]):
        self.made, self.k = made, 0

    def choose(self, options):
        if len(options) == 1:       # no choice at all
            return options[0][0]
        if self.k == len(self.made):
            raise Choice(options)
        self.k += 1
        return options[self.made[self.k - 1]][0]


def _outcomes(model: PrimitiveModel) -> list[tuple[EventKind | None, Fraction]]:
    out = [(EventKind.ACHIEVED, model.achieve), (EventKind.FAILED, model.fail),
           (None, model.never)]
    return [(kind, p) for kind, p in out if p]


@dataclass(frozen=True)
class Due:
    """A primitive's next event: its kind, and the times it may come at with their
    probabilities (not normalised: what is left of its delay's distribution once the
    earlier times have passed without it)."""

    kind: EventKind
    support: tuple[tuple[float, Fraction], ...]
    #: whose settings it follows: the call of the enabling (-1: the primitive's own)
    call: int = -1


class ModelVehicle(Vehicle):
    """A vehicle that answers as its model says, each choice made by ``chooser``.

    Each primitive has at most one event due (:class:`Due`): its acknowledgement,
    then its report, then the loss of a goal achieved. Where a delay may end at
    several times, whether the event comes at the earliest of them is chosen
    when that time comes, with the probability that it comes then given that it
    has not come before (its hazard): a run draws the same delays as it would by
    drawing them at once, and the exact odds branch two ways at an instant instead
    of once per value of every delay at the enabling.
    """

    def __init__(self, model: VehicleModel, chooser: Chooser | None):
        self.model, self.chooser = model, chooser
        self.pending: dict[str, Due] = {}

    def copy(self, chooser: Chooser) -> "ModelVehicle":
        other = ModelVehicle(self.model, chooser)
        other.pending = dict(self.pending)
        return other

    def state(self, now: float) -> tuple:
        """What the vehicle will still do, relative to ``now``: equal states, equal futures."""
        return tuple(sorted((name, due.kind.value, due.call,
                             tuple((t - now, p) for t, p in due.support))
                            for name, due in self.pending.items()))

    def check_primitives(self, used: set[str]) -> None:
        self.model.check_primitives(used)

    def _due(self, kind: EventKind, delay: Delay, t: float, call: int) -> Due:
        return Due(kind, self.chooser.schedule(delay, t), call)

    def act(self, action: Action) -> None:
        m = self.model.of(action.primitive)
        if action.kind is ActionKind.ENABLE:
            # the enabling's arguments choose its settings: its ack, report and loss
            call = m.call(action.args)
            self.pending[action.primitive] = self._due(EventKind.ON, m.settings(call).ack,
                                                       action.t, call)
        else:       # a disable silences whatever was still to come; the primitive's ack
            self.pending[action.primitive] = self._due(EventKind.OFF, m.ack, action.t, -1)

    def earliest(self) -> float | None:
        """The earliest time an event may come at (no choice made)."""
        return min((due.support[0][0] for due in self.pending.values()), default=None)

    def _head(self) -> tuple[float, str] | None:
        return min(((due.support[0][0], name) for name, due in self.pending.items()),
                   default=None)

    def next_event_time(self, until: float | None = None) -> float | None:
        """When the next event comes; whether one comes at a time up to ``until`` only is
        chosen (past it, the earliest time one may come at), so that the exact odds
        make the choices of one instant at that instant."""
        while True:
            head = self._head()
            if head is None:
                return None
            t, name = head
            due = self.pending[name]
            if len(due.support) == 1 or (until is not None and t > until):
                return t
            now = due.support[0][1] / sum(p for _, p in due.support)
            if self.chooser.choose([(True, now), (False, 1 - now)]):
                self.pending[name] = Due(due.kind, due.support[:1], due.call)
            else:
                self.pending[name] = Due(due.kind, due.support[1:], due.call)

    def take_event(self) -> Event:
        t, name = self._head()
        due = self.pending.pop(name)
        assert len(due.support) == 1, "take_event before next_event_time"
        m = self.model.of(name).settings(due.call)
        if due.kind is EventKind.ON:
            outcome = self.chooser.choose(_outcomes(m))
            if outcome is EventKind.ACHIEVED:
                self.pending[name] = self._due(outcome, m.achieved_after, t, due.call)
            elif outcome is EventKind.FAILED:
                self.pending[name] = self._due(outcome, m.failed_after, t, due.call)
        elif due.kind is EventKind.ACHIEVED and m.lose:
            if self.chooser.choose([(True, m.lose), (False, 1 - m.lose)]):
                self.pending[name] = self._due(EventKind.FAILED, m.lost_after, t, due.call)
        return Event(t, due.kind, name)
