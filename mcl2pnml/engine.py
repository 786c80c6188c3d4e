"""Running a mission: the interface of an engine, and the loop that drives it against a vehicle.

Two engines run missions, and must agree (the tests hold them to it): the
Petri-net executor of :mod:`mcl2pnml.executor`, the paper's Mission Control
System, and the reference interpreter of :mod:`mcl2pnml.reference`, which
reads the MCL directly. Both implement :class:`Engine`; :func:`run` drives
either one against a :class:`~mcl2pnml.aal.Vehicle`.

The rules that make a run deterministic, for both engines alike:

* one stimulus at a time: a vehicle event or an expired timer, then
  everything it causes at that instant, before the next stimulus;
* stimuli in time order; at one instant, vehicle events before timers,
  events by primitive name, timers by the name of their task;
* a vehicle answers an action at once if it can (the scripted vehicle's
  ``on`` and ``off``), and those answers are stimuli of the same instant.
"""
from __future__ import annotations

import enum
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, Callable

from .aal import Action, Event, Vehicle, _time, canonical_trace


class Outcome(enum.Enum):
    """How a run ends."""

    OK = "OK"
    """The mission ended OK."""

    FAIL = "FAIL"
    """The mission ended FAIL."""

    ABORTED = "ABORTED"
    """The mission was aborted and has stopped."""

    STALLED = "STALLED"
    """Nothing can happen any more (no enabled transition, timer or pending
    event) and no result was reached."""


class Engine(ABC):
    """One way of running a mission. Every method returns the actions it caused, in order."""

    #: the result, once the mission has one
    outcome: Outcome | None = None

    @abstractmethod
    def start(self, t: float) -> list[Action]:
        """Start the mission at time ``t``."""

    @abstractmethod
    def on_event(self, event: Event) -> list[Action]:
        """A vehicle event, and everything it causes at its instant.

        An event nothing waits for (an unknown primitive, a primitive that is
        not enabled, a second report) changes nothing: it is recorded in
        :attr:`ignored` with the reason.
        """

    @abstractmethod
    def next_timer(self) -> tuple[float, str] | None:
        """The next timer to expire, as (time, name of its task), or None."""

    @abstractmethod
    def fire_timer(self, t: float, name: str) -> list[Action]:
        """Expire the timer ``name`` (announced by :meth:`next_timer`), and what follows."""

    @abstractmethod
    def waiting(self) -> list[str]:
        """What the mission waits for now, in words (for a run that stalls)."""

    ignored: list[tuple[Event, str]]


@dataclass
class Run:
    """What a run did: its outcome, when it ended, and every action and event."""

    outcome: Outcome
    time: float
    entries: list[Action | Event] = field(default_factory=list)
    ignored: list[tuple[Event, str]] = field(default_factory=list)
    waiting: list[str] = field(default_factory=list)

    def as_json(self) -> dict[str, Any]:
        """The object of ``mcl2pnml run --json`` (cli.md)."""
        return {"outcome": self.outcome.value, "time": _time(self.time),
                "trace": canonical_trace(self.entries)}


Listener = Callable[[Action | Event], None]


def _deliverer(entries: list, vehicle, listener: Listener | None) -> Callable[[list], None]:
    """Send actions to the vehicle, recording them and showing them to the listener."""
    def deliver(actions: list[Action]) -> None:
        for action in actions:
            entries.append(action)
            if listener:
                listener(action)
            vehicle.act(action)
    return deliver


def run(engine: Engine, vehicle: Vehicle, *, listener: Listener | None = None,
        max_time: float | None = None) -> Run:
    """Drive ``engine`` against ``vehicle`` in virtual time until a result or a stall.

    ``listener`` sees every action and event as it happens (the live log);
    ``max_time`` stops a mission that would run for ever (a loop whose
    vehicle keeps answering) with the outcome STALLED.
    """
    entries: list[Action | Event] = []
    deliver = _deliverer(entries, vehicle, listener)
    t = 0.0
    deliver(engine.start(t))
    while engine.outcome is None:
        te, timer = vehicle.next_event_time(), engine.next_timer()
        if te is None and timer is None:
            return Run(Outcome.STALLED, t, entries, list(engine.ignored), engine.waiting())
        at = te if timer is None or (te is not None and te <= timer[0]) else timer[0]
        if max_time is not None and at > max_time:
            return Run(Outcome.STALLED, t, entries, list(engine.ignored),
                       [f"stopped at the time limit of {max_time:g} s"] + engine.waiting())
        t = at
        vehicle.advance(t)
        if timer is None or (te is not None and te <= timer[0]):
            event = vehicle.take_event()
            entries.append(event)
            if listener:
                listener(event)
            deliver(engine.on_event(event))
        else:
            deliver(engine.fire_timer(t, timer[1]))
    return Run(engine.outcome, t, entries, list(engine.ignored))


def run_realtime(engine: Engine, vehicle, *, clock: Callable[[], float] | None = None,
                 listener: Listener | None = None, max_time: float | None = None) -> Run:
    """Drive ``engine`` against a real vehicle (a :class:`~mcl2pnml.bridge.MappedVehicle`).

    Time is the wall clock from the start; time-outs fire when it reaches
    them, and events count from when they arrive. A real vehicle can always
    still answer, so a run ends with a result, at ``max_time`` (STALLED), or
    when the operator interrupts it.
    """
    import time

    clock = clock or time.monotonic
    start = clock()
    now = lambda: clock() - start    # noqa: E731
    entries: list[Action | Event] = []
    deliver = _deliverer(entries, vehicle, listener)
    deliver(engine.start(0.0))
    while engine.outcome is None:
        timer = engine.next_timer()
        limit = [x for x in (timer[0] if timer else None, max_time) if x is not None]
        wait = max(0.0, min(limit) - now()) if limit else None
        event = vehicle.wait_event(wait, now)
        if event is not None:
            entries.append(event)
            if listener:
                listener(event)
            deliver(engine.on_event(event))
            continue
        if timer is not None and now() >= timer[0]:
            deliver(engine.fire_timer(timer[0], timer[1]))
        elif max_time is not None and now() >= max_time:
            return Run(Outcome.STALLED, now(), entries, list(engine.ignored),
                       [f"stopped at the time limit of {max_time:g} s"] + engine.waiting())
    return Run(engine.outcome, now(), entries, list(engine.ignored))
