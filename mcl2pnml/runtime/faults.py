"""Fault injection for simulated vehicles: the faults of a fault file, and the vehicle
that applies them.

A campaign of simulated missions asks what changes when the vehicle misbehaves
("what if the GPS fix fails one time in five?"). Rather than teach every
simulated vehicle to misbehave, a fault file (docs/faults.md, "Injecting faults
in simulated runs") says, per primitive, how its events are corrupted on their
way out of the vehicle, and :class:`FaultyVehicle` wraps any virtual-time
:class:`~mcl2pnml.runtime.aal.Vehicle` (the kinematic simulator, a vehicle model,
a script) and applies them:

* ``fail``: an ``achieved`` becomes a ``failed`` (source "fault", why "injected: ...");
* ``lose``: per event kind, the event is dropped;
* ``duplicate``: an ``achieved`` or ``failed`` is delivered twice;
* ``delay``: the event comes that many seconds late, and the later events of
  its primitive wait behind it (one primitive's events keep their order).

This module owns the fault file's format and checks (read as a vehicle model
is: bounded in size, one message at the fault's line and column) and the
wrapper. Draws come from the ``random.Random`` it is given, in the order the
inner vehicle's events come out, so that a run is replayed by its seed.
"""
from __future__ import annotations

import copy
import heapq
import random
from dataclasses import dataclass, field, replace
from fractions import Fraction
from pathlib import Path
from typing import Any, Mapping

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import read_text
from mcl2pnml.core.jsontext import check_schema, parse_located
from mcl2pnml.runtime.aal import (Action, Event, EventKind, Reported, SafeStop, Vehicle,
                                  VehicleFault)
from mcl2pnml.runtime.vehicle_model import _PROBABILITY, MAX_DELAY, _probability, refuse_unused

#: The largest fault file read, in bytes.
MAX_FAULTS = 1 << 20
#: The most events of the inner vehicle a look-ahead goes through without finding one
#: that reaches the mission (all lost or delayed): past it the run ends, stalled.
MAX_LOOKAHEAD = 10_000
#: The name that stands for every primitive the file does not name.
ANY = "*"

_KINDS = tuple(kind.value for kind in EventKind)
_FAULT = {
    "type": "object", "additionalProperties": False,
    "properties": {
        "fail": _PROBABILITY,
        "lose": {"type": "object", "additionalProperties": False,
                 "properties": {kind: _PROBABILITY for kind in _KINDS}},
        "duplicate": _PROBABILITY,
        "delay": {"type": "object", "additionalProperties": False,
                  "required": ["p", "seconds"],
                  "properties": {"p": _PROBABILITY,
                                 "seconds": {"type": "number", "minimum": 0,
                                             "maximum": MAX_DELAY}}},
    },
}

#: The fault file's JSON Schema; the exact probabilities are read after it.
SCHEMA: dict[str, Any] = {
    "type": "object", "additionalProperties": False, "required": ["faults"],
    "properties": {
        "description": {"type": "string", "maxLength": 2000},
        "faults": {"type": "object", "maxProperties": 1000,
                   "propertyNames": {"pattern": r"^([A-Za-z_][A-Za-z0-9_]*|\*)$",
                                     "maxLength": 200},
                   "additionalProperties": _FAULT},
    },
}

_NONE = Fraction(0)


@dataclass(frozen=True)
class PrimitiveFaults:
    """The faults of one primitive's events (each a probability, read exactly)."""

    fail: Fraction = _NONE
    #: per event kind, the probability it is lost
    lose: tuple[tuple[EventKind, Fraction], ...] = ()
    duplicate: Fraction = _NONE
    delay: Fraction = _NONE
    delay_seconds: float = 0.0

    def lost(self, kind: EventKind) -> Fraction:
        return dict(self.lose).get(kind, _NONE)


#: The faults of a primitive neither named nor covered by "*": none.
NO_FAULTS = PrimitiveFaults()


@dataclass(frozen=True)
class Faults:
    """A loaded fault file: each named primitive's faults, and the rest's (``default``,
    the file's "*"). A named primitive takes its own entry only, not "*"'s."""

    primitives: Mapping[str, PrimitiveFaults] = field(default_factory=dict)
    default: PrimitiveFaults = NO_FAULTS
    description: str = ""
    filename: str = field(default="<faults>", compare=False)
    #: where the file names each primitive (a name the mission does not use is refused)
    where: Mapping[str, Location] = field(default_factory=dict, compare=False)

    def of(self, primitive: str) -> PrimitiveFaults:
        return self.primitives.get(primitive, self.default)

    def check_primitives(self, used: set[str]) -> None:
        """Refuse faults of a primitive the mission does not use (a typo would inject nothing)."""
        refuse_unused(self.primitives, used, self.where, "the fault file names")

    @classmethod
    def from_json(cls, text: str, filename: str = "<faults>") -> "Faults":
        data, where = parse_located(text, filename, "a fault file")
        check_schema(data, SCHEMA, where, what="a fault file")
        specs = {name: _primitive(spec, ("faults", name), where)
                 for name, spec in data["faults"].items()}
        default = specs.pop(ANY, NO_FAULTS)
        return cls(specs, default, data.get("description", ""), filename,
                   {name: where(("faults", name)) for name in specs})

    @classmethod
    def load(cls, path: str | Path) -> "Faults":
        return cls.from_json(read_text(path, "fault file", MAX_FAULTS), str(path))


def _primitive(spec: Mapping[str, Any], path: tuple, where) -> PrimitiveFaults:
    """One primitive's faults, its probabilities read exactly (0.1 is 1/10)."""
    def p(key: str, value: Any) -> Fraction:
        return _probability(value, (*path, *key.split(".")), where)

    lose = tuple((EventKind(kind), p(f"lose.{kind}", value))
                 for kind, value in spec.get("lose", {}).items())
    delay = spec.get("delay", {"p": 0, "seconds": 0})
    return PrimitiveFaults(
        fail=p("fail", spec["fail"]) if "fail" in spec else _NONE,
        lose=tuple((kind, q) for kind, q in lose if q),
        duplicate=p("duplicate", spec["duplicate"]) if "duplicate" in spec else _NONE,
        delay=p("delay.p", delay["p"]),
        delay_seconds=float(delay["seconds"]))


# -- the vehicle ----------------------------------------------------------------------

@dataclass
class _Step:
    """One event of the inner vehicle, with what the mission gets from it."""

    event: Event
    outputs: list[tuple[int, Event]]          # (order of issue, the event delivered)
    injected: list[tuple[float, str, str]]


class FaultyVehicle(Vehicle):
    """``inner`` with the faults of ``faults`` applied to its events, drawn with ``rng``.

    Actions, :meth:`advance` and :meth:`check_primitives` go to ``inner``
    unchanged; its events come out corrupted. :attr:`injected` lists each fault
    applied, as (t, primitive, what), at the time of the inner vehicle's event:
    the faults of the events the run reached, and, when a run stalls because
    nothing more reaches it, those that silenced the vehicle. Give it a
    ``random.Random`` of its own, not the inner vehicle's.

    The run loop asks when the next event is due before it knows whether a
    time-out comes first, and the inner vehicle may be asked to take an event
    only once the run has reached it (an action before then changes what the
    vehicle does). So an event that is lost or delayed cannot be taken out to
    look past it: the wrapper looks ahead in a copy of the inner vehicle
    (its ``fork()`` if it has one, else :func:`copy.deepcopy`; a virtual-time
    vehicle is a deterministic state),
    decides each event's fate there, and takes the real events only when the
    run's time reaches them. An action makes the look-ahead stale: it is made
    again, and the fates of events not yet reached are drawn again; those
    fates could not have changed what the run did so far, since every event
    they concern lies after the run's time.
    """

    def __init__(self, inner: Vehicle, faults: Faults, rng: random.Random):
        self.inner, self.faults, self.rng = inner, faults, rng
        self.injected: list[tuple[float, str, str]] = []
        # events taken from the inner vehicle, to deliver: (t, primitive, order, event);
        # ties by primitive name (Vehicle's rule), then in the order issued
        self.queue: list[tuple[float, str, int, Event]] = []
        self.issued = 0
        # per primitive, the time of its latest event given to the queue: the later
        # ones of that primitive are not delivered before it
        self.last: dict[str, float] = {}
        self.plan: list[_Step] | None = None     # the look-ahead, None when stale
        self.ahead: Vehicle | None = None        # the copy it was made in
        self.ahead_last: dict[str, float] = {}
        self.ahead_done = False                  # the copy has no more events
        self.due: tuple[float, str, int] | None = None   # the event advance() reached
        self.silent = False                      # nothing more was announced

    # -- forwarded -----------------------------------------------------------------------

    @property
    def primitives(self) -> frozenset[str] | None:     # type: ignore[override]
        return self.inner.primitives

    def check_primitives(self, used: set[str]) -> None:
        """The inner vehicle's check, then the fault file's (no faults of an unused name)."""
        self.inner.check_primitives(used)
        self.faults.check_primitives(used)

    def act(self, action: Action) -> None:
        if isinstance(action, SafeStop) and self.silent and self.plan:
            # the run ends because nothing more reaches it: the faults it looked
            # through (each inner event lost or delayed past the end) are why
            self.injected.extend(inj for step in self.plan for inj in step.injected)
            self.silent = False
        self.inner.act(action)
        self.plan, self.due = None, None

    def advance(self, t: float) -> None:
        head = self._head()
        if head is not None and head[0] == t:
            # the run takes this event next (an event goes before a time-out of its
            # instant): the inner events after it, at this instant too, wait for the
            # run's answer to it, as they would without the wrapper
            self._commit(lambda key: key <= head[:2])
            self.due = head
        else:
            self._commit(lambda key: key[0] <= t)
        self.inner.advance(t)
        # moving the inner vehicle (off its own step, for a simulator) may change
        # what comes next: look again, but not before the run has answered the event
        # it takes now (the vehicle is not asked in a state the run never leaves it in)
        self.plan = None

    # -- the events --------------------------------------------------------------------

    def next_event_time(self) -> float | None:
        head = self._head()
        self.silent = head is None
        return None if head is None else head[0]

    def take_event(self) -> Event:
        head, self.due = self.due, None
        if head is None or not self.queue or self.queue[0][:3] != head:
            head = self._head()
            assert head is not None, "no event is pending"
            self._commit(lambda key: key <= head[:2])
        entry = heapq.heappop(self.queue)
        assert entry[:3] == head, "the look-ahead and the vehicle disagree"
        return entry[3]

    def _head(self) -> tuple[float, str, int] | None:
        """The next event to deliver, as (t, primitive, order of issue).

        The look-ahead goes through the inner vehicle's events until none that
        is left can come before the best found: a vehicle gives its events by
        time, ties by primitive name, and a fault only makes an event later.
        """
        if self.plan is None:
            self.plan, self.ahead, self.ahead_last = [], None, dict(self.last)
            # the vehicle itself is asked first: a simulator keeps what it found, so
            # that its copy need not look for it again, and one with nothing due
            # needs no copy at all
            self.ahead_done = self.inner.next_event_time() is None
            if not self.ahead_done:
                fork = getattr(self.inner, "fork", None)
                self.ahead = fork() if fork is not None else copy.deepcopy(self.inner)
        best = self.queue[0][:3] if self.queue else None
        for step in self.plan:
            best = _least(best, step)
        looked = 0
        while not self.ahead_done:
            if self.plan and best is not None and best[:2] <= _key(self.plan[-1].event):
                break
            te = self.ahead.next_event_time()
            if te is None:
                self.ahead_done = True
                break
            if best is not None and te > best[0]:
                break
            looked += 1
            if looked > MAX_LOOKAHEAD:
                raise VehicleFault(f"the injected faults lost or delayed {MAX_LOOKAHEAD:,} "
                                   "events of the vehicle in a row")
            self.ahead.advance(te)
            step = self._fate(self.ahead.take_event(), self.ahead_last)
            self.plan.append(step)
            best = _least(best, step)
        return best

    def _commit(self, due) -> None:
        """Take from the inner vehicle its events whose (t, primitive) is ``due``: the run
        has reached them."""
        self._head()
        while self.plan and due(_key(self.plan[0].event)):
            step = self.plan.pop(0)
            # as the run loop drives a vehicle, and as the copy was driven
            self.inner.next_event_time()
            self.inner.advance(step.event.t)
            got = self.inner.take_event()
            if got != step.event:
                # the vehicle did not replay its copy (it is not deterministic): decide
                # the fate of what it did send, and look ahead again
                step = self._fate(got, self.last)
                self.plan = None
            for k, event in step.outputs:
                heapq.heappush(self.queue, (event.t, event.primitive, k, event))
                self.last[event.primitive] = max(self.last.get(event.primitive, event.t),
                                                 event.t)
            self.injected.extend(step.injected)
            if self.plan is None:
                self._head()

    def _draw(self, p: Fraction) -> bool:
        # no draw for a certainty: a fault of probability 0 or 1 leaves the stream as it is
        if p <= 0:
            return False
        if p >= 1:
            return True
        return self.rng.random() < p

    def _fate(self, event: Event, last: dict[str, float]) -> _Step:
        """What the mission gets from ``event``; ``last`` (per primitive, its latest
        delivery) is updated. Draws in this order: fail, lose, duplicate, delay."""
        name, t = event.primitive, event.t
        spec = self.faults.of(name)
        injected: list[tuple[float, str, str]] = []
        out = event
        if event.kind is EventKind.ACHIEVED and self._draw(spec.fail):
            out = Reported(t, EventKind.FAILED, name, "fault",
                           f"injected: achieved turned into failed (fail {spec.fail})")
            injected.append((t, name, "failed instead of achieved"))
        kind = out.kind.value
        if self._draw(spec.lost(out.kind)):
            injected.append((t, name, f"lost {kind}"))
            return _Step(event, [], injected)
        copies = 1
        if out.kind in (EventKind.ACHIEVED, EventKind.FAILED) and self._draw(spec.duplicate):
            copies = 2
            injected.append((t, name, f"duplicated {kind}"))
        at = t
        if self._draw(spec.delay):
            at += spec.delay_seconds
            injected.append((t, name, f"delayed {kind} by {spec.delay_seconds:g} s"))
        if last.get(name, at) > at:
            # one primitive's events keep their order: behind its delayed one
            at = last[name]
            injected.append((t, name, f"held {kind} back to t={at:g} s behind a delayed "
                                      "event"))
        last[name] = at
        outputs = []
        for _ in range(copies):
            self.issued += 1
            outputs.append((self.issued, out if at == out.t else replace(out, t=at)))
        return _Step(event, outputs, injected)


def _key(event: Event) -> tuple[float, str]:
    return event.t, event.primitive


def _least(best: tuple | None, step: _Step) -> tuple | None:
    """The earlier of ``best`` and the outputs of ``step`` (None: nothing to deliver)."""
    keys = [(e.t, e.primitive, k) for k, e in step.outputs]
    if best is not None:
        keys.append(best)
    return min(keys, default=None)
