"""Running a mission: the interface of an engine, and the loop that drives it against a vehicle.

Two engines run missions, and must agree (the tests hold them to it): the
Petri-net executor of :mod:`mcl2pnml.runtime.executor`, the paper's Mission Control
System, and the reference interpreter of :mod:`mcl2pnml.runtime.reference`, which
reads the MCL directly. Both implement :class:`Engine`; :func:`run` drives
either one against a :class:`~mcl2pnml.runtime.aal.Vehicle`.

The rules that make a run deterministic, for both engines alike:

* one stimulus at a time: a vehicle event or an expired timer, then
  everything it causes at that instant, before the next stimulus;
* stimuli in time order; at one instant, vehicle events before timers,
  events by primitive name, timers by the name of their task;
* a vehicle answers an action at once if it can (the scripted vehicle's
  ``on`` and ``off``), and those answers are stimuli of the same instant;
* the actions one stimulus causes are recorded and sent by primitive name,
  each primitive's in the order they were caused
  (:func:`~mcl2pnml.runtime.aal.causal_order`), so that the trace is in
  causal order and the same for both engines
  (:func:`~mcl2pnml.runtime.aal.canonical_trace`).
"""
from __future__ import annotations

import enum
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, Callable

from mcl2pnml.runtime.aal import (Action, ActionKind, Event, EventKind, LinkLost, Reported, SafeStop, Vehicle, VehicleFault, VehicleInputError,
                  _time, canonical_trace, causal_order)


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
    event) and no result was reached; or the vehicle or its link failed
    (the diagnosis says which)."""

    TIMELIMIT = "TIMELIMIT"
    """The time limit (``run --max-time``) came first: something was still
    due (a vehicle event, a time-out) when the run was stopped at the limit,
    with its safe stop. The mission did not stall: it was cut short."""

    # The member values are the words of cli.md's JSON and of the run log:
    # these two methods are the only mapping between the two, both ways.
    def as_json(self) -> str:
        """The outcome as ``mcl2pnml run --json`` and the run log write it."""
        return self.value

    @classmethod
    def from_json(cls, word: str) -> "Outcome":
        """The outcome a JSON object names (the inverse of :meth:`as_json`)."""
        return cls(word)

    @property
    def exit_status(self) -> int:
        """The exit status of ``mcl2pnml run`` that ends this way.

        One per outcome, so that a test harness or a vehicle's supervisor can
        act on it without parsing the output. 2 is bad input (every command),
        3 a partial analysis (``analyze``), 130 an interrupt: not used here.
        """
        return _EXIT_STATUS[self]


#: ``mcl2pnml run``'s exit status per outcome (README.md, "Running a mission").
_EXIT_STATUS = {Outcome.OK: 0, Outcome.FAIL: 1, Outcome.ABORTED: 4, Outcome.STALLED: 5,
                Outcome.TIMELIMIT: 6}


FireListener = Callable[[float, str], None]


class Engine(ABC):
    """One way of running a mission. Every method returns the actions it caused, in order.

    Besides running the mission, an engine answers what the run loop and
    the command line ask of it: the primitives the vehicle must offer
    (:meth:`primitives_used`), the events it ignored and why
    (:attr:`ignored`), and, where the engine has transitions, each firing as
    it happens (:attr:`on_fire`).
    """

    #: The result, once the mission has one: the run loop stops the moment
    #: it is set (the vehicle is then safe-stopped, :func:`run`).
    outcome: Outcome | None

    #: Every vehicle event that changed nothing, with the reason, in the
    #: order they came: a report the mission did not wait for (a primitive
    #: not enabled, a second ``achieved``) or from a primitive it does not
    #: use. The robot went on as if the event had not come; the live log
    #: shows each one, and the run's result lists them all.
    ignored: list[tuple[Event, str]]

    #: Called with (time, transition id) at each firing, where the engine
    #: has transitions (the Petri-net executor): the live log's ``fire``
    #: lines, which say why the robot did what it did. None: nobody listens.
    #: An engine without transitions (the reference engine) never calls it.
    on_fire: FireListener | None

    def __init__(self) -> None:
        self.outcome = None
        self.ignored = []
        self.on_fire = None

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

    def enable_arguments(self) -> dict[str, list[tuple]] | None:
        """Every argument tuple each primitive may be enabled with, known before the run.

        A real vehicle's mapping is checked against them before anything is
        sent (:meth:`~mcl2pnml.runtime.aal.LiveVehicle.check_enables`). None:
        this engine cannot tell (each command is then checked as it is made).
        """
        return None

    @abstractmethod
    def primitives_used(self) -> set[str]:
        """The primitives the mission may enable: the vehicle must offer every one.

        Checked before the run starts, so that a mission never drives the
        robot half-way and then needs a primitive it does not have.
        """


@dataclass
class Run:
    """What a run did: its outcome, when it ended, every action and event, and its safe stop."""

    outcome: Outcome
    time: float
    entries: list[Action | Event] = field(default_factory=list)
    ignored: list[tuple[Event, str]] = field(default_factory=list)
    waiting: list[str] = field(default_factory=list)
    #: the disables the run loop sent at the end to primitives still enabled
    safe_stop: list[SafeStop] = field(default_factory=list)
    #: then the vehicle's safe state, step by step (an autopilot's hold, surface, disarm)
    secured: list[str] = field(default_factory=list)

    def as_json(self) -> dict[str, Any]:
        """The object of ``mcl2pnml run --json`` (cli.md), with ``safe_stop`` when there was one."""
        out = {"outcome": self.outcome.as_json(), "time": _time(self.time),
               "trace": canonical_trace(self.entries)}
        if self.safe_stop:
            out["safe_stop"] = [a.as_json() for a in self.safe_stop]
        if self.secured:
            out["safe_state"] = list(self.secured)
        problems = self.problems()
        if problems:
            out["problems"] = problems
        return out

    def problems(self) -> list[dict[str, Any]]:
        """Why primitives failed, as the vehicle said (a :class:`Reported` failure): each
        ``{"t", "primitive", "why", "source"}``, in the trace's order (cli.md)."""
        return [{"t": _time(e.t), "primitive": e.primitive, "why": e.why, "source": e.source}
                for e in self.entries
                if isinstance(e, Reported) and e.kind is EventKind.FAILED and e.why]

    def report(self) -> list[str]:
        """The end of ``mcl2pnml run``'s text: the outcome, what it waits for, the safe stop."""
        lines = [f"outcome {self.outcome.value} at t={self.time:g} s"]
        lines += [f"  {line}" for line in self.waiting]
        if self.safe_stop:
            lines.append("  safe stop: disabled " + ", ".join(a.primitive for a in self.safe_stop))
        lines += [f"  safe state: {line}" for line in self.secured]
        return lines


Listener = Callable[[Action | Event], None]


class _Driver:
    """What both run loops share: sending actions, taking events, and the safe stop.

    It keeps the set of primitives the mission has enabled and not disabled,
    so that however the run ends (a result, a stall, the time limit, a
    vehicle that fails, a link that drops, the operator's Ctrl-C) every
    primitive still enabled is sent ``disable``: the vehicle is never left
    holding a depth or driving to a waypoint for a mission that has stopped.
    """

    def __init__(self, engine: Engine, vehicle, listener: Listener | None):
        self.engine, self.vehicle, self.listener = engine, vehicle, listener
        self.entries: list[Action | Event] = []
        self.enabled: dict[str, None] = {}      # insertion-ordered set
        self.fault: str | None = None           # what the vehicle or its link did wrong
        self.secured: list[str] = []            # the vehicle's safe state, step by step

    def deliver(self, actions: list[Action]) -> None:
        """Record and send the actions one stimulus caused, in causal order (the trace's)."""
        for action in causal_order(actions):
            self.entries.append(action)
            if self.listener:
                self.listener(action)
            # counted enabled before it is sent: a failed send may have half-happened
            if action.kind is ActionKind.ENABLE:
                self.enabled[action.primitive] = None
            else:
                self.enabled.pop(action.primitive, None)
            self.vehicle_call(self.vehicle.act, action, f"{action.kind.value} "
                              f"{action.primitive} at t={_time(action.t)} s")

    def event(self, event: Event) -> None:
        self.entries.append(event)
        if self.listener:
            self.listener(event)
        self.deliver(self.engine.on_event(event))

    def vehicle_call(self, call: Callable, arg: Any, what: str) -> Any:
        """Call the vehicle; a failure of the vehicle (not bad input) ends the run as a fault."""
        try:
            return call(arg)
        except VehicleInputError:
            raise
        except Exception as e:      # an adapter's own error, whatever its type
            if isinstance(e, LinkLost):
                self.fault = f"the link to the vehicle was lost ({what}): {e}"
            elif isinstance(e, VehicleFault):
                self.fault = str(e)
            else:
                self.fault = f"the vehicle failed to carry out {what}: {type(e).__name__}: {e}"
            raise _Fault from None

    def end(self, outcome: Outcome | None, t: float, note: list[str] | None = None) -> Run:
        """The run's result, after the safe stop.

        No outcome is a stall; :attr:`Outcome.TIMELIMIT` is given with
        ``note`` saying what was still due. Either way the diagnosis lists
        the fault first, then the note, then what the mission waits for.
        """
        stopped, failed = self.safe_stop(t)
        waiting: list[str] = []
        if outcome in (None, Outcome.TIMELIMIT):   # no result: say why the mission stopped
            outcome = outcome or Outcome.STALLED
            waiting = ([self.fault] if self.fault else []) + (note or []) \
                + self.engine.waiting()
        return Run(outcome, t, self.entries, list(self.engine.ignored), waiting + failed,
                   stopped, self.secured)

    def safe_stop(self, t: float) -> tuple[list[SafeStop], list[str]]:
        """Disable every primitive still enabled; the ones that could not be, in words."""
        stopped, failed = [], []
        for name in list(self.enabled):
            action = SafeStop(t, ActionKind.DISABLE, name)
            del self.enabled[name]
            stopped.append(action)
            try:
                self.vehicle.act(action)
            except Exception as e:   # the link is gone, or the adapter fails again
                failed.append(f"safe stop: could not disable {name}: {type(e).__name__}: {e}")
        for action in stopped:      # logged after: a failing log must not keep the vehicle going
            if self.listener:
                self.listener(action)
        secure = getattr(self.vehicle, "secure", None)
        if secure is not None and not self.secured:
            try:
                self.secured = secure(t)
            except Exception as e:   # an adapter's own failure: say it, the run still ends
                self.secured = [f"could not be reached: {type(e).__name__}: {e}"]
        return stopped, failed


class _Fault(Exception):
    """The vehicle failed (its :attr:`_Driver.fault` says how): the run ends STALLED."""


def run(engine: Engine, vehicle: Vehicle, *, listener: Listener | None = None,
        max_time: float | None = None) -> Run:
    """Drive ``engine`` against ``vehicle`` in virtual time until a result or a stall.

    ``listener`` sees every action and event as it happens (the live log);
    ``max_time`` stops a mission that would run for ever (a loop whose
    vehicle keeps answering) at that time, with the outcome TIMELIMIT. Whatever the ending,
    primitives still enabled are disabled (:class:`~mcl2pnml.runtime.aal.SafeStop`),
    also before an error or an interrupt is passed on (docs/faults.md).
    """
    d = _Driver(engine, vehicle, listener)
    t = 0.0
    try:
        d.deliver(engine.start(t))
        while engine.outcome is None:
            te = d.vehicle_call(lambda _: vehicle.next_event_time(), None,
                                "its next event")
            timer = engine.next_timer()
            if te is None and timer is None:
                return d.end(None, t)
            by_vehicle = timer is None or (te is not None and te <= timer[0])
            at = te if by_vehicle else timer[0]
            if max_time is not None and at > max_time:
                # cut short, not stalled: the stop (and its safe stop) is at the limit
                due = "a vehicle event" if by_vehicle else f"the time-out of {timer[1]}"
                return d.end(Outcome.TIMELIMIT, max_time,
                             [f"stopped at the time limit of {max_time:g} s; {due} was due "
                              f"at t={at:g} s"])
            t = at
            vehicle.advance(t)
            if by_vehicle:
                d.event(d.vehicle_call(lambda _: vehicle.take_event(), None, "its next event"))
            else:
                d.deliver(engine.fire_timer(t, timer[1]))
    except _Fault:
        return d.end(None, t)
    except BaseException:
        d.safe_stop(t)      # an error of the mission or Ctrl-C: stop the vehicle, then say it
        raise
    return d.end(engine.outcome, t)


def run_realtime(engine: Engine, vehicle, *, clock: Callable[[], float] | None = None,
                 listener: Listener | None = None, max_time: float | None = None) -> Run:
    """Drive ``engine`` against a real vehicle (a :class:`~mcl2pnml.runtime.bridge.MappedVehicle`).

    Time is the wall clock from the start, or the vehicle's own clock where
    it keeps one (an autopilot's, so that a simulator sped up 100 times
    gives the same run); time-outs fire when it reaches them, and events
    count from when they arrive. A real vehicle can always
    still answer, so a run ends with a result, at ``max_time`` (TIMELIMIT), when
    the link drops (STALLED, saying so), or when the operator interrupts it;
    each way with the safe stop of :func:`run`, then the vehicle's own safe
    state (:meth:`~mcl2pnml.runtime.aal.LiveVehicle.secure`).
    """
    import time

    own = getattr(vehicle, "clock", None)
    if clock is None and own is not None:
        now = own       # the vehicle's own clock (an autopilot's): its seconds are the run's
    else:
        clock = clock or time.monotonic
        start = clock()
        now = lambda: clock() - start    # noqa: E731
    d = _Driver(engine, vehicle, listener)
    try:
        d.deliver(engine.start(0.0))
        while engine.outcome is None:
            timer = engine.next_timer()
            limit = [x for x in (timer[0] if timer else None, max_time) if x is not None]
            wait = max(0.0, min(limit) - now()) if limit else None
            event = d.vehicle_call(lambda w: vehicle.wait_event(w, now), wait, "waiting")
            if event is not None:
                d.event(event)
                continue
            if timer is not None and now() >= timer[0]:
                d.deliver(engine.fire_timer(timer[0], timer[1]))
            elif max_time is not None and now() >= max_time:
                # a real vehicle can always still answer: the limit cuts the run short
                return d.end(Outcome.TIMELIMIT, max_time,
                             [f"stopped at the time limit of {max_time:g} s"])
    except _Fault:
        return d.end(None, now())
    except BaseException:
        d.safe_stop(now())
        raise
    return d.end(engine.outcome, now())
