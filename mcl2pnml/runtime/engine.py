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
import signal
import time
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, Callable

from mcl2pnml.core.timing import Assumptions
from mcl2pnml.runtime import interrupts
from mcl2pnml.runtime.aal import (Action, ActionKind, Event, EventKind, LinkLost, Reported, SafeStop, Vehicle, VehicleFault, VehicleInputError,
                  _time, canonical_trace, causal_order)
from mcl2pnml.runtime.interrupts import Interrupted, SafeStateCut
from mcl2pnml.runtime.watch import Breach, Watch


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

    INTERRUPTED = "INTERRUPTED"
    """A signal stopped the run (SIGINT, SIGTERM, SIGHUP: Ctrl-C, ``kill``, a
    dropped session), with its safe stop and the vehicle's safe state; the
    diagnosis names the signal (:mod:`mcl2pnml.runtime.interrupts`)."""

    BREACH = "BREACH"
    """The vehicle broke an assumption of the timed verdicts (``run --stop-on-breach``,
    :mod:`mcl2pnml.runtime.watch`): the run stopped at the breach, with its safe stop and
    the vehicle's safe state; the diagnosis says the breach."""

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
        3 a partial analysis (``analyze``): never an outcome's. INTERRUPTED's
        is 128 + SIGINT, 130, as a shell has it; a run stopped by another
        signal exits 128 + its number (:attr:`Run.exit_status`).
        """
        return _EXIT_STATUS[self]


#: ``mcl2pnml run``'s exit status per outcome (README.md, "Running a mission").
_EXIT_STATUS = {Outcome.OK: 0, Outcome.FAIL: 1, Outcome.ABORTED: 4, Outcome.STALLED: 5,
                Outcome.TIMELIMIT: 6, Outcome.BREACH: 7,
                Outcome.INTERRUPTED: interrupts.exit_status(signal.SIGINT)}

#: The outcomes that are not the mission's result: the run says why it stopped.
NO_RESULT = (Outcome.STALLED, Outcome.TIMELIMIT, Outcome.INTERRUPTED, Outcome.BREACH)


@dataclass(frozen=True)
class TimedOut:
    """A task's time-out expired at ``t``: the task ``task``'s declared ``seconds``
    (None where the engine cannot tell), which ends it as its pattern says (FAIL for
    AchieveGoal, OK for the Keep patterns; docs/mcl.md)."""

    t: float
    task: str
    seconds: float | None = None

    def as_json(self) -> dict[str, Any]:
        """As the run's ``--json`` lists it under ``timeouts``, and its log line."""
        return {"t": _time(self.t), "timeout": self.task,
                **({"seconds": _time(self.seconds)} if self.seconds is not None else {})}

    def named(self) -> str:
        """"Goto (900 s)": the task, and its time-out where known."""
        return self.task + (f" ({self.seconds:g} s)" if self.seconds is not None else "")

    def words(self) -> str:
        """"Goto (900 s), expired at t=901 s"."""
        return f"{self.named()}, expired at t={self.t:g} s"


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
    def waits_for(self, event: Event) -> bool:
        """Whether :meth:`on_event` would take ``event`` now (False: it would ignore it),
        changing nothing: the run loop watches the assumptions on the events a mission
        takes (:mod:`mcl2pnml.runtime.watch`), before it takes them."""

    @abstractmethod
    def next_timer(self) -> tuple[float, str] | None:
        """The next timer to expire, as (time, name of its task), or None."""

    @abstractmethod
    def fire_timer(self, t: float, name: str) -> list[Action]:
        """Expire the timer ``name`` (announced by :meth:`next_timer`), and what follows."""

    def timeout_of(self, task: str) -> float | None:
        """The seconds of ``task``'s declared time-out (its timers' name), or None: this
        engine cannot tell. Said when the time-out expires (:class:`TimedOut`)."""
        return None

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
    #: why a run without a result stopped (STALLED, TIMELIMIT, INTERRUPTED, BREACH), first the
    #: fault or the signal, then what the mission waited for in the engine's words; and
    #: what the safe stop could not do (the text's lines under the outcome)
    waiting: list[str] = field(default_factory=list)
    #: the disables the run loop sent at the end to primitives still enabled
    safe_stop: list[SafeStop] = field(default_factory=list)
    #: then the vehicle's safe state, step by step (an autopilot's hold, surface, disarm)
    secured: list[str] = field(default_factory=list)
    #: every time-out that expired, in order
    timeouts: list[TimedOut] = field(default_factory=list)
    #: the signal that stopped the run (INTERRUPTED), None otherwise
    signum: int | None = None
    #: :attr:`waiting` in the run loop's words, the same for both engines (``--json``'s
    #: and the log's ``diagnosis``): the fault or the signal, the primitives still enabled
    #: or awaited off, the next time-out; what the safe stop could not do
    diagnosis: list[str] = field(default_factory=list)
    #: every assumption of the timed verdicts the vehicle broke, in order (docs/time.md)
    breaches: list[Breach] = field(default_factory=list)

    @property
    def exit_status(self) -> int:
        """``mcl2pnml run``'s exit status: the outcome's, 128 + the signal's number for a
        run a signal stopped (130 SIGINT, 143 SIGTERM, 129 SIGHUP)."""
        if self.outcome is Outcome.INTERRUPTED and self.signum is not None:
            return interrupts.exit_status(self.signum)
        return self.outcome.exit_status

    def as_json(self) -> dict[str, Any]:
        """The object of ``mcl2pnml run --json`` (cli.md): ``diagnosis`` (why a run without
        a result stopped), ``timeouts``, ``safe_stop``, ``safe_state``, ``breaches`` and
        ``problems`` when there are any."""
        out = {"outcome": self.outcome.as_json(), "time": _time(self.time),
               "trace": canonical_trace(self.entries)}
        if self.diagnosis:
            out["diagnosis"] = list(self.diagnosis)
        if self.timeouts:
            out["timeouts"] = [x.as_json() for x in self.timeouts]
        if self.safe_stop:
            out["safe_stop"] = [a.as_json() for a in self.safe_stop]
        if self.secured:
            out["safe_state"] = list(self.secured)
        if self.breaches:
            out["breaches"] = [b.as_json() for b in self.breaches]
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
        """The end of ``mcl2pnml run``'s text: the outcome, the assumptions the vehicle
        broke, why (what it waits for, the signal, the last time-out of a run that
        failed), the safe stop."""
        lines = [f"outcome {self.outcome.value} at t={self.time:g} s"]
        lines += [f"  {b.words()}" for b in self.breaches]
        if self.outcome is Outcome.FAIL and self.timeouts:
            lines.append(f"  the last time-out: {self.timeouts[-1].words()}")
        lines += [f"  {line}" for line in self.waiting]
        if self.safe_stop:
            lines.append("  safe stop: disabled " + ", ".join(a.primitive for a in self.safe_stop))
        lines += [f"  safe state: {line}" for line in self.secured]
        return lines


Listener = Callable[[Action | Event | TimedOut | Breach], None]


class _Driver:
    """What both run loops share: sending actions, taking events, and the safe stop.

    It keeps the set of primitives the mission has enabled and not disabled,
    so that however the run ends (a result, a stall, the time limit, a
    vehicle that fails, a link that drops, a signal) every primitive still
    enabled is sent ``disable``: the vehicle is never left holding a depth or
    driving to a waypoint for a mission that has stopped.
    """

    def __init__(self, engine: Engine, vehicle, listener: Listener | None,
                 assumptions: Assumptions = Assumptions(), stop_on_breach: bool = False):
        self.engine, self.vehicle, self.listener = engine, vehicle, listener
        self.watch, self.stop_on_breach = Watch(assumptions), stop_on_breach
        self.entries: list[Action | Event] = []
        self.enabled: dict[str, float] = {}     # since when, in the order they were enabled
        self.disabling: dict[str, float] = {}   # disabled at, its 'off' not yet come
        self.fault: str | None = None           # what the vehicle or its link did wrong
        self.secured: list[str] = []            # the vehicle's safe state, step by step
        self.timeouts: list[TimedOut] = []
        self.stopped_safe = False                # the safe stop and safe state are done
        self.t = 0.0                             # the time of the last stimulus (virtual time)

    def drive(self, loop: Callable[[], Run], now: Callable[[], float]) -> Run:
        """Run ``loop`` (a run loop, which ends with :meth:`end`); a signal ends the run
        INTERRUPTED, an error is passed on after the safe stop.

        A signal can come at any instruction up to the safe stop's start, even in
        :meth:`end` before it: the safe stop is then made here, as it was not yet."""
        try:
            return loop()
        except Interrupted as stop:
            return self.interrupted(stop, now())
        except BaseException:
            self.safe_stop(now())      # an error of the mission: stop the vehicle, then say it
            raise

    def deliver(self, actions: list[Action]) -> None:
        """Record and send the actions one stimulus caused, in causal order (the trace's)."""
        for action in causal_order(actions):
            self.entries.append(action)
            if self.listener:
                self.listener(action)
            # counted enabled before it is sent: a failed send may have half-happened
            if action.kind is ActionKind.ENABLE:
                self.enabled[action.primitive] = action.t
            else:
                self.enabled.pop(action.primitive, None)
                self.disabling[action.primitive] = action.t
            self.watch.request(action)
            self.vehicle_call(self.vehicle.act, action, f"{action.kind.value} "
                              f"{action.primitive} at t={_time(action.t)} s")

    def event(self, event: Event) -> None:
        """A vehicle event: recorded, watched (:meth:`breached`), then taken by the engine."""
        taken = self.engine.waits_for(event)
        if event.kind is EventKind.OFF:
            self.disabling.pop(event.primitive, None)
        self.entries.append(event)
        if self.listener:
            self.listener(event)
        self.breached(self.watch.event(event, taken))
        self.deliver(self.engine.on_event(event))

    def due(self, now: float) -> None:
        """Time is about to reach ``now``: the acknowledgements due before it that have
        not come are breaches."""
        self.breached(self.watch.overdue(now))

    def breached(self, breaches: list[Breach], stop: bool = True) -> None:
        """Say each breach (the live log, the run's ``breaches``); the first stops the run
        with ``stop_on_breach``, before the mission takes what broke the assumption
        (``stop`` False: the run is ending anyway)."""
        for breach in breaches:
            if self.listener:
                self.listener(breach)
        if breaches and stop and self.stop_on_breach:
            raise _Breached(breaches[0])

    def breach_end(self, stop: "_Breached") -> Run:
        """The run a breach stopped (``stop_on_breach``): BREACH, at the breach."""
        b = stop.breach
        return self.end(Outcome.BREACH, b.t, [f"stopped at the first breach of an assumption "
                                              f"({b.assumption}, by {b.primitive})"])

    def timer(self, t: float, task: str) -> None:
        """A task's time-out expires: said (the live log, the run's ``timeouts``), then fired."""
        expired = TimedOut(t, task, self.engine.timeout_of(task))
        self.timeouts.append(expired)
        if self.listener:
            self.listener(expired)
        self.deliver(self.engine.fire_timer(t, task))

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

    def end(self, outcome: Outcome | None, t: float, note: list[str] | None = None,
            signum: int | None = None) -> Run:
        """The run's result, after the safe stop.

        No outcome is a stall; :attr:`Outcome.TIMELIMIT` and
        :attr:`Outcome.INTERRUPTED` are given with ``note`` saying what was
        still due, or the signal. Either way the diagnosis lists the fault
        first, then the note, then what the mission waits for.
        """
        outcome = outcome or Outcome.STALLED
        # what was still awaited, before the safe stop disables it
        pending = self._pending(note or []) if outcome in NO_RESULT else []
        stopped, failed = self.safe_stop(t)
        waiting: list[str] = []
        why: list[str] = []
        if outcome in NO_RESULT:   # no result: say why the mission stopped
            head = ([self.fault] if self.fault else []) + (note or [])
            waiting, why = head + self._waits(), head + pending
        return Run(outcome, t, self.entries, list(self.engine.ignored), waiting + failed,
                   stopped, self.secured, self.timeouts, signum, why + failed,
                   list(self.watch.breaches))

    def interrupted(self, stop: Interrupted, t: float) -> Run:
        """The run a signal stopped: INTERRUPTED, naming the signal, after the safe stop."""
        return self.end(Outcome.INTERRUPTED, t, [stop.reason], stop.signum)

    def _pending(self, note: list[str]) -> list[str]:
        """What the mission waited for, as the run loop saw it (both engines alike); the
        next time-out unless ``note`` names it already."""
        out = [f"{name}: enabled at t={_time(t)} s, still enabled" for name, t
               in self.enabled.items()]
        out += [f"{name}: disabled at t={_time(t)} s, its 'off' has not come" for name, t
                in self.disabling.items()]
        try:
            timer = self.engine.next_timer()
        except Exception:   # an engine stopped by a signal half-way through a step
            timer = None
        if timer is not None and not any(f"the time-out of {timer[1]} " in n for n in note):
            out.append(f"the time-out of {timer[1]}, due at t={timer[0]:g} s")
        return out

    def _waits(self) -> list[str]:
        try:
            return self.engine.waiting()
        except Exception as e:    # an engine stopped by a signal half-way through a step
            return [f"what the mission waits for cannot be said: {type(e).__name__}: {e}"]

    def safe_stop(self, t: float) -> tuple[list[SafeStop], list[str]]:
        """Disable every primitive still enabled, then bring the vehicle to its safe state;
        the primitives that could not be disabled, in words.

        A signal meanwhile is said and changes nothing, but the third of the run cuts
        the safe state short (:mod:`mcl2pnml.runtime.interrupts`): the run still ends,
        saying so."""
        stopped: list[SafeStop] = []
        failed: list[str] = []
        try:
            with interrupts.current().securing():
                if self.stopped_safe:
                    return stopped, failed
                self.stopped_safe = True
                self._disable_all(t, stopped, failed)
                secure = getattr(self.vehicle, "secure", None)
                if secure is not None:
                    try:
                        self.secured = secure(t)
                    except Exception as e:   # an adapter's own failure: say it, the run ends
                        self.secured = [f"could not be reached: {type(e).__name__}: {e}"]
        except SafeStateCut as e:
            # the steps done before the cut, as the vehicle said them
            self.secured = list(getattr(self.vehicle, "secured_steps", ()))
            failed += [f"safe stop: not sent to {name} (cut short)" for name in self.enabled]
            failed.append(f"the safe state was cut short by {interrupts.name_of(e.signum)}, "
                          "the run's third signal: the vehicle may not be in its safe state")
        for action in stopped:      # logged after: a failing log must not keep the vehicle going
            if self.listener:
                self.listener(action)
        return stopped, failed

    def _disable_all(self, t: float, stopped: list[SafeStop], failed: list[str]) -> None:
        for name in list(self.enabled):
            action = SafeStop(t, ActionKind.DISABLE, name)
            del self.enabled[name]
            stopped.append(action)
            try:
                self.vehicle.act(action)
            except Exception as e:   # the link is gone, or the adapter fails again
                failed.append(f"safe stop: could not disable {name}: {type(e).__name__}: {e}")


class _Fault(Exception):
    """The vehicle failed (its :attr:`_Driver.fault` says how): the run ends STALLED."""


class _Breached(Exception):
    """The vehicle broke an assumption, and the run stops on a breach: it ends BREACH."""

    def __init__(self, breach: Breach):
        super().__init__(breach.words())
        self.breach = breach


def run(engine: Engine, vehicle: Vehicle, *, listener: Listener | None = None,
        max_time: float | None = None, assumptions: Assumptions = Assumptions(),
        stop_on_breach: bool = False) -> Run:
    """Drive ``engine`` against ``vehicle`` in virtual time until a result or a stall.

    ``listener`` sees every action and event as it happens (the live log);
    ``max_time`` stops a mission that would run for ever (a loop whose
    vehicle keeps answering) at that time, with the outcome TIMELIMIT. Whatever the ending,
    primitives still enabled are disabled (:class:`~mcl2pnml.runtime.aal.SafeStop`):
    a signal (:class:`~mcl2pnml.runtime.interrupts.Interrupted`) ends the run
    INTERRUPTED, and an error is passed on after the safe stop (docs/faults.md).
    Each vehicle event is watched against ``assumptions`` (docs/time.md): a breach is
    said, and with ``stop_on_breach`` the first ends the run BREACH at its time.
    """
    d = _Driver(engine, vehicle, listener, assumptions, stop_on_breach)

    def loop() -> Run:
        try:
            d.deliver(engine.start(d.t))
            while engine.outcome is None:
                te = d.vehicle_call(lambda _: vehicle.next_event_time(), None,
                                    "its next event")
                timer = engine.next_timer()
                if te is None and timer is None:
                    # nothing more will come: an acknowledgement still due never will
                    d.breached(d.watch.overdue(None), stop=False)
                    return d.end(None, d.t)
                by_vehicle = timer is None or (te is not None and te <= timer[0])
                at = te if by_vehicle else timer[0]
                d.due(at if max_time is None else min(at, max_time))
                if max_time is not None and at > max_time:
                    # cut short, not stalled: the stop (and its safe stop) is at the limit
                    due = "a vehicle event" if by_vehicle else f"the time-out of {timer[1]}"
                    return d.end(Outcome.TIMELIMIT, max_time,
                                 [f"stopped at the time limit of {max_time:g} s; {due} was "
                                  f"due at t={at:g} s"])
                d.t = at
                vehicle.advance(at)
                if by_vehicle:
                    d.event(d.vehicle_call(lambda _: vehicle.take_event(), None,
                                           "its next event"))
                else:
                    d.timer(at, timer[1])
        except _Fault:
            return d.end(None, d.t)
        except _Breached as stop:
            return d.breach_end(stop)
        return d.end(engine.outcome, d.t)

    return d.drive(loop, lambda: d.t)


def run_realtime(engine: Engine, vehicle, *, clock: Callable[[], float] | None = None,
                 listener: Listener | None = None, max_time: float | None = None,
                 open_vehicle: bool = False, assumptions: Assumptions = Assumptions(),
                 stop_on_breach: bool = False) -> Run:
    """Drive ``engine`` against a real vehicle (a :class:`~mcl2pnml.runtime.bridge.MappedVehicle`).

    Time is the wall clock from the start, or the vehicle's own clock where
    it keeps one (an autopilot's, so that a simulator sped up 100 times
    gives the same run); time-outs fire when it reaches them, and events
    count from when they arrive: one read after a time-out it came after is taken after
    that time-out, however late the run reads it. A real vehicle can always
    still answer, so a run ends with a result, at ``max_time`` (TIMELIMIT), when
    the link drops (STALLED, saying so), or when a signal stops it (INTERRUPTED);
    each way with the safe stop of :func:`run`, then the vehicle's own safe
    state (:meth:`~mcl2pnml.runtime.aal.LiveVehicle.secure`). ``open_vehicle``:
    the vehicle is opened here (connected, made ready: an autopilot is armed), so
    that a signal or an error meanwhile brings it to its safe state too. The
    assumptions are watched as :func:`run` watches them, an acknowledgement that has
    not come by its due time as soon as that time passes.
    """
    own = getattr(vehicle, "clock", None)
    if clock is None and own is not None:
        now = own       # the vehicle's own clock (an autopilot's): its seconds are the run's
    else:
        clock = clock or time.monotonic
        start = clock()
        now = lambda: clock() - start    # noqa: E731
    d = _Driver(engine, vehicle, listener, assumptions, stop_on_breach)

    def loop() -> Run:
        try:
            if open_vehicle:
                vehicle.open()
            d.deliver(engine.start(0.0))
            while engine.outcome is None:
                timer = engine.next_timer()
                due = d.watch.next_due()
                limit = [x for x in (timer[0] if timer else None, max_time,
                                     None if due is None else float(due)) if x is not None]
                wait = max(0.0, min(limit) - now()) if limit else None
                event = d.vehicle_call(lambda w: vehicle.wait_event(w, now), wait, "waiting")
                if event is not None:
                    # the time-outs due before the event came fire first: a run late to
                    # read its vehicle (a loaded machine; an autopilot sped up, whose
                    # seconds are the run's) must not take a report that came after a
                    # time-out as in time
                    while (timer := engine.next_timer()) is not None and timer[0] < event.t \
                            and engine.outcome is None:
                        d.timer(timer[0], timer[1])
                    if engine.outcome is None:
                        d.due(event.t)
                        d.event(event)
                    continue
                d.due(now() if max_time is None else min(now(), max_time))
                if timer is not None and now() >= timer[0]:
                    d.timer(timer[0], timer[1])
                elif max_time is not None and now() >= max_time:
                    # a real vehicle can always still answer: the limit cuts the run short
                    return d.end(Outcome.TIMELIMIT, max_time,
                                 [f"stopped at the time limit of {max_time:g} s"])
        except _Fault:
            return d.end(None, now())
        except _Breached as stop:
            return d.breach_end(stop)
        return d.end(engine.outcome, now())

    return d.drive(loop, now)
