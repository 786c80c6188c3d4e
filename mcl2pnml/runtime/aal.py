"""The Architecture Abstraction Layer: what passes between a mission and a vehicle.

Section 2.1 of the paper puts one layer between the Mission Control System
and the vehicle's architecture, so that the same mission runs on any vehicle
that offers its primitives. Across it go **actions** (enable or disable a
primitive, with its arguments) and **events** (the primitive is on, has
achieved or failed its goal, is off). This module holds both, and the one
interface every vehicle implements, whether scripted, simulated or real:
:class:`Vehicle`.

Vehicles here run in *virtual time*: the engine asks when the vehicle's
next event is due (:meth:`Vehicle.next_event_time`) and takes it
(:meth:`Vehicle.take_event`), so that a 20-minute mission runs in
milliseconds and a test is exactly reproducible.
"""
from __future__ import annotations

import json
import math
import re
from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

from mcl2pnml.core.errors import (Location, Mcl2PnmlError, line_of, source_lines,
                                  text_location)
from mcl2pnml.core.files import json_fault, read_text
from mcl2pnml.core.jsontext import without_bom
# The kinds of actions and events are what a compiled net's payloads say, so
# they are defined with the payload records in core (which may not import
# runtime) and re-exported here, where the vehicle's side of the layer uses them.
from mcl2pnml.core.payloads import ActionKind, EventKind  # noqa: F401 (re-exported)

#: The largest vehicle script read, in bytes: a reply is a few bytes, a run a few thousand.
MAX_SCRIPT = 16 << 20


@dataclass(frozen=True)
class Action:
    """An action at virtual time ``t``: enable (with arguments) or disable a primitive."""

    t: float
    kind: ActionKind
    primitive: str
    args: tuple = ()

    def as_json(self) -> dict[str, Any]:
        return {"t": _time(self.t), "action": self.kind.value, "primitive": self.primitive,
                "args": _plain(self.args)}


@dataclass(frozen=True)
class SafeStop(Action):
    """A ``disable`` sent by the run loop, not by the mission, when the run ends.

    Every ending (a result, a stall, the time limit, a failing vehicle, a
    lost link, an interrupt) disables the primitives still enabled, so that
    the vehicle does not go on driving for a mission that has stopped
    (docs/faults.md). Logged apart from the mission's own trace.
    """

    def as_json(self) -> dict[str, Any]:
        return {**super().as_json(), "safe_stop": True}


class VehicleInputError(Mcl2PnmlError):
    """Bad input from the vehicle's side (an unknown primitive or event, a garbled line).

    One message naming where it came from (the script's file:line:col, or
    the line received on a live link); the run ends with it, after its safe
    stop.
    """


class LinkLost(Exception):
    """The link to the vehicle closed or broke: nothing more can be sent or received."""


class VehicleFault(Exception):
    """The vehicle cannot go on (an autopilot that refuses to arm, that reboots...).

    Its message is the run's diagnosis, as it stands: the run ends STALLED,
    with its safe stop.
    """


@dataclass(frozen=True)
class Event:
    """An event at virtual time ``t`` from one primitive."""

    t: float
    kind: EventKind
    primitive: str

    def as_json(self) -> dict[str, Any]:
        return {"t": _time(self.t), "event": self.kind.value, "primitive": self.primitive}


@dataclass(frozen=True)
class Reported(Event):
    """An achieved or failed that says who judged it and why: the autopilot's telemetry
    or its acknowledgement (``source`` "autopilot"), a simulated sensor ("simulated"),
    or the simulator ("simulator": why the primitive failed).

    Its trace entry is an :class:`Event`'s (:func:`canonical_trace`); the run log
    adds ``source`` and ``why`` (:mod:`mcl2pnml.runtime.runlog`), and the run's
    ``--json`` lists the failures' reasons apart, as ``problems``.
    """

    source: str = "autopilot"
    why: str = ""


def _time(t: float) -> float | int:
    return int(t) if float(t).is_integer() else round(t, 6)


def _plain(value: Any) -> Any:
    if isinstance(value, (tuple, list)):
        return [_plain(v) for v in value]
    return value


def traced(entry: Action | Event) -> bool:
    """Whether an entry belongs in the run's trace (cli.md: actions, achieved, failed, off)."""
    return not (isinstance(entry, Event) and entry.kind is EventKind.ON)


def canonical_trace(entries: Iterable[Action | Event]) -> list[dict[str, Any]]:
    """The trace of cli.md, in causal order: the order the run loop recorded (docs/simulator.md).

    The run loop (:mod:`mcl2pnml.runtime.engine`) takes one stimulus at a
    time, in time order: the start, a vehicle event (in the order the vehicle
    delivers them) or a timer's expiry. After each it records the actions the
    stimulus caused at its instant, in zero time and transitively, and sends
    them to the vehicle in that recorded order: by primitive name, each
    primitive's own in the order they were caused (disable before enable).
    So an ``achieved`` comes before the ``disable`` and ``enable`` it causes,
    and the order depends on nothing an engine chooses: since both engines
    cause the same actions per stimulus, the vehicle sees the same actions
    in the same order and answers in the same order. The trace is those
    entries as recorded, without the ``on`` events (cli.md).
    """
    return [e.as_json() for e in entries if traced(e)]


def causal_order(actions: Iterable[Action]) -> list[Action]:
    """The actions one stimulus caused, as they are recorded and sent: by primitive name.

    A stable sort: the actions of one primitive keep the order in which they
    were caused (see :func:`canonical_trace`).
    """
    return sorted(actions, key=lambda a: a.primitive)


class Vehicle(ABC):
    """One vehicle behind the abstraction layer.

    The engine sends every action through :meth:`act` and takes events, one
    at a time, in the order of :meth:`next_event_time` (ties by primitive
    name). A vehicle may answer an action at once (an event at the same
    instant), later, or never.
    """

    #: the primitives this vehicle offers (None: any, as a scripted vehicle)
    primitives: frozenset[str] | None = None

    @abstractmethod
    def act(self, action: Action) -> None:
        """Carry out an action (at ``action.t``)."""

    @abstractmethod
    def next_event_time(self) -> float | None:
        """When the next event is due (None: none is pending)."""

    @abstractmethod
    def take_event(self) -> Event:
        """Remove and return the next event (the one :meth:`next_event_time` announced)."""

    def advance(self, t: float) -> None:
        """Let the vehicle's own time reach ``t`` (simulators move; others need not)."""

    def check_primitives(self, used: set[str]) -> None:
        """Refuse a mission this vehicle cannot serve, before it starts (default: any)."""


class LiveVehicle(ABC):
    """A vehicle in real time: its events come when they come (see :mod:`mcl2pnml.runtime.bridge`).

    The same actions and events as :class:`Vehicle`; only the clock differs,
    so the engine waits for an event (or for its next timer) instead of
    asking when the next one is due.
    """

    primitives: frozenset[str] | None = None

    @abstractmethod
    def act(self, action: Action) -> None:
        """Send an action to the vehicle."""

    def check_primitives(self, used: set[str]) -> None:
        """Refuse a mission this vehicle cannot serve, before it starts (default: any)."""

    def check_enables(self, enables: Mapping[str, Iterable[tuple]] | None) -> None:
        """Refuse, before anything is sent, arguments this vehicle cannot take (default: any).

        ``enables``: every argument tuple each primitive may be enabled with,
        or None when the engine cannot tell before the run.
        """

    def open(self) -> None:
        """Connect to the vehicle, once the mission is checked (default: nothing to do)."""

    def close(self) -> None:
        """Let go of the vehicle, after the run and its safe stop (default: nothing to do)."""

    @abstractmethod
    def wait_event(self, timeout: float | None, clock) -> Event | None:
        """The next event, stamped ``clock()`` on arrival; None after ``timeout`` seconds."""

    #: The vehicle's own clock, where it keeps one (an autopilot's): the run's time
    #: is then its seconds, not the wall clock's (None: the wall clock).
    clock: Callable[[], float] | None = None

    #: The steps of :meth:`secure` said so far, as it says them: what a safe state cut
    #: short (the run's third signal) had done.
    secured_steps: list[str] = []

    def secure(self, t: float) -> list[str]:
        """After the safe stop's disables: bring the vehicle to a safe state (hold,
        surface, disarm...), each step in words, acknowledged or not (default: none);
        each also in :attr:`secured_steps` as it is done."""
        return []


# ---------------------------------------------------------------------------
# The scripted vehicle of cli.md


@dataclass(frozen=True)
class Reply:
    """One scripted answer to an enabling: achieved or failed after a delay, or never."""

    kind: EventKind | None      # None: no report at all
    delay: float = 0.0

    @classmethod
    def parse(cls, text: str, where: str) -> "Reply":
        if text == "never":
            return cls(None)
        word, at, delay = text.partition("@")
        kinds = {"ok": EventKind.ACHIEVED, "fail": EventKind.FAILED}
        if not at or word not in kinds:
            raise ValueError(f"{where}: '{text}' is not a reply; one of ok@SECONDS, "
                             "fail@SECONDS, never")
        try:
            seconds = float(delay)
        except ValueError:
            seconds = math.nan
        if not math.isfinite(seconds) or seconds < 0:
            raise ValueError(f"{where}: '{delay}' in '{text}' is not a number of seconds >= 0")
        return cls(kinds[word], seconds)


class QueuedVehicle(Vehicle):
    """A simulated vehicle that schedules its events when it is told to act: each
    primitive's events in time order, given one at a time in the order of
    :class:`Vehicle` (by time, ties by primitive name)."""

    def __init__(self) -> None:
        self.pending: dict[str, list[Event]] = {}   # primitive -> events in time order

    def _next(self) -> tuple[float, str] | None:
        due = [(events[0].t, name) for name, events in self.pending.items() if events]
        return min(due) if due else None

    def next_event_time(self) -> float | None:
        nxt = self._next()
        return None if nxt is None else nxt[0]

    def take_event(self) -> Event:
        nxt = self._next()
        assert nxt is not None, "no event is pending"
        return self.pending[nxt[1]].pop(0)


class ScriptedVehicle(QueuedVehicle):
    """The vehicle script of cli.md: ``{"PRIMITIVE": ["ok@5", "fail@3", "never"], ...}``.

    Each enabling of a primitive takes the next reply of its list: achieved
    (``ok``) or failed (``fail``) that many seconds after the enabling, or no
    report at all (``never``); past the end of its list a primitive says
    ``never``. Enabling and disabling are acknowledged at once (``on``,
    ``off``); disabling cancels a report not yet sent.
    """

    def __init__(self, script: Mapping[str, Iterable[Reply]]):
        super().__init__()
        self.replies = {name: list(replies) for name, replies in script.items()}
        self.used: dict[str, int] = {}
        self.enabled: set[str] = set()
        self.where: dict[str, Location] = {}         # where the script names each primitive

    @classmethod
    def from_json(cls, text: str, filename: str = "<script>") -> "ScriptedVehicle":
        text = without_bom(text)     # as every JSON input (mcl2pnml.core.jsontext)

        def fail(message: str, line: int | None = None, column: int | None = None):
            return VehicleInputError(message, text_location(filename, text, line, column)
                                     if line else Location(filename))
        try:
            data = json.loads(text, object_pairs_hook=_no_duplicates)
        except json.JSONDecodeError as e:
            raise fail(f"not a vehicle script: {e.msg}", e.lineno, e.colno) from None
        except (ValueError, RecursionError) as e:   # a number of 5,000 digits, deep nesting
            raise fail(f"not a vehicle script: {json_fault(e)}") from None
        except _Duplicate as e:
            raise fail(f"'{e.args[0]}' is scripted twice", *_string_at(text, e.args[0], 2)) \
                from None
        if not isinstance(data, dict):
            raise fail("a vehicle script is a JSON object: "
                       '{"PRIMITIVE": ["ok@5", "fail@3", "never"], ...}', 1, 1)
        script, where = {}, {}
        strings = iter(_strings(text))   # the script's strings in order: a name, its replies...
        for name, replies in data.items():
            at = next(strings, (None, None, None))[1:]
            where[name] = at
            if not isinstance(replies, list) or not all(isinstance(r, str) for r in replies):
                raise fail(f"'{name}': a list of replies such as [\"ok@5\", \"never\"]", *at)
            script[name] = []
            for i, r in enumerate(replies):
                at = next(strings, (None, None, None))[1:]
                try:
                    script[name].append(Reply.parse(r, f"'{name}' reply {i + 1}"))
                except ValueError as e:
                    raise fail(str(e), *at) from None
        vehicle = cls(script)
        lines = source_lines(text)     # once, and cut at "\n" only, as the lines are counted
        vehicle.where = {name: Location(filename, line, col, line_of(lines, line))
                         for name, (line, col) in where.items() if line}
        return vehicle

    def check_primitives(self, used: set[str]) -> None:
        """Refuse a script that scripts a primitive the mission does not use (a typo)."""
        for name in self.replies:
            if name not in used:
                raise VehicleInputError(
                    f"the script scripts '{name}', which the mission does not use; it uses "
                    + ", ".join(sorted(used)), self.where.get(name))

    @classmethod
    def load(cls, path: str | Path) -> "ScriptedVehicle":
        return cls.from_json(read_text(path, "vehicle script", MAX_SCRIPT), str(path))

    def act(self, action: Action) -> None:
        name = action.primitive
        if action.kind is ActionKind.ENABLE:
            k = self.used.get(name, 0)
            self.used[name] = k + 1
            replies = self.replies.get(name, [])
            reply = replies[k] if k < len(replies) else Reply(None)
            events = [Event(action.t, EventKind.ON, name)]
            if reply.kind is not None:
                events.append(Event(action.t + reply.delay, reply.kind, name))
            self.pending[name] = events
            self.enabled.add(name)
        else:
            # disabling is acknowledged at once, and silences what was to come
            self.pending[name] = [Event(action.t, EventKind.OFF, name)]
            self.enabled.discard(name)


class _Duplicate(Exception):
    pass


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    seen: dict[str, Any] = {}
    for k, v in pairs:
        if k in seen:
            raise _Duplicate(k)
        seen[k] = v
    return seen


_STRING = re.compile(r'"(?:[^"\\]|\\.)*"')


def _strings(text: str) -> Iterable[tuple[str, int, int]]:
    """Each JSON string of ``text`` with its line and column (from 1), in order."""
    for m in _STRING.finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        yield json.loads(m.group()), line, m.start() - (text.rfind("\n", 0, m.start()) + 1) + 1


def _string_at(text: str, value: str, nth: int) -> tuple[int | None, int | None]:
    found = [(line, col) for s, line, col in _strings(text) if s == value]
    return found[nth - 1] if len(found) >= nth else (None, None)
