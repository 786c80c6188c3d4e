"""Watching the assumptions on the vehicle while a mission runs (docs/time.md).

``analyze --timed`` proves its verdicts (the earliest and latest end times, the
properties) under :class:`~mcl2pnml.core.timing.Assumptions` on the vehicle. A vehicle
that breaks one gives runs the proof never looked at: reports 0.8 s apart end a mission
later than its proven latest end. :class:`Watch` checks each vehicle event the run loop
(:mod:`mcl2pnml.runtime.engine`) takes against the assumptions, the same for both
engines since the loop is theirs, and says each breach as a :class:`Breach`:

* ``ack_within`` K: a request (``enable``, ``disable``) is acknowledged (``on``,
  ``off``) at most K seconds after the vehicle could answer it: after the request,
  or after the answer to the request before it, where that one was still due (the
  net's ``on`` needs ``OFF``, its ``off`` needs ``ON``). An acknowledgement that comes
  later, or has not come when time passes its due time, breaks it;
* ``report_gap`` d: a report (``achieved``, ``failed``) the mission takes comes at
  least d seconds after the previous report the mission took of that primitive (the
  first at any time).

Only the events the mission takes count (:meth:`~mcl2pnml.runtime.engine.Engine.waits_for`):
an event the mission ignores fires no transition, so that the proof's runs do not see
it either. ``fair_reports`` (a primitive that is on reports eventually) cannot be
broken in finite time: a silent primitive may still report later. Nor is the order of
the events of one instant checked (an acknowledgement "at once" before the reports of
its instant): the run loop takes them in an order of its own (docs/running.md).

Times are read to the microsecond, as the run log writes them, and compared exactly:
a report at 1.4 s is 1 s after one at 0.3 + 0.1 s, not the 0.999... s of the floats.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from mcl2pnml.core.timing import Assumptions, seconds_text as seconds
from mcl2pnml.runtime.aal import Action, ActionKind, Event, EventKind

#: The resolution of a run's times (the run log's: :func:`mcl2pnml.runtime.aal._time`).
MICRO = 1_000_000

#: The acknowledgement each request waits for.
ANSWER = {ActionKind.ENABLE: EventKind.ON, ActionKind.DISABLE: EventKind.OFF}


def exact(t: float) -> Fraction:
    """A time of the run, to the microsecond the log writes it with, as an exact number."""
    return Fraction(round(t * MICRO), MICRO)


@dataclass(frozen=True)
class Breach:
    """The vehicle broke the assumption ``assumption`` (a field of
    :class:`~mcl2pnml.core.timing.Assumptions`) at ``at``: ``what`` happened."""

    at: Fraction
    assumption: str
    primitive: str
    what: str

    @property
    def t(self) -> float:
        """Its time, as the run's other entries have theirs."""
        return float(self.at)

    def words(self) -> str:
        return (f"the vehicle broke assumption {self.assumption} at {seconds(self.at)} s: "
                f"{self.what}; the proven bounds no longer apply")

    def as_json(self) -> dict[str, Any]:
        """As the run log and ``run --json`` (under ``breaches``) write it."""
        at: int | float = self.at.numerator if self.at.denominator == 1 else float(self.at)
        return {"t": at, "breach": self.assumption, "primitive": self.primitive,
                "message": self.words()}


class Watch:
    """The assumptions of one run, and what the vehicle has done against them so far.

    The run loop tells it each request it sends (:meth:`request`), each event before the
    mission takes it (:meth:`event`), and each time it is about to reach
    (:meth:`overdue`); each answers the breaches it finds, kept in :attr:`breaches`.
    """

    def __init__(self, assumptions: Assumptions = Assumptions()):
        self.assumptions = assumptions
        #: each primitive's requests not yet acknowledged, in order: (kind, sent at)
        self.requests: dict[str, list[tuple[ActionKind, Fraction]]] = {}
        self.answered: dict[str, Fraction] = {}         # its last acknowledgement
        self.late: set[str] = set()                     # its first request is said overdue
        self.reported: dict[str, tuple[Fraction, EventKind]] = {}    # its last report
        self.breaches: list[Breach] = []

    def request(self, action: Action) -> None:
        """The mission sent ``action``: its acknowledgement is now due."""
        self.requests.setdefault(action.primitive, []).append((action.kind, exact(action.t)))

    def due(self, primitive: str) -> Fraction | None:
        """When the primitive's first pending request must be acknowledged by (None: none)."""
        pending = self.requests.get(primitive)
        if not pending:
            return None
        sent = pending[0][1]
        # the vehicle can answer once the request before it is answered (the net's on
        # needs OFF, its off needs ON): its clock starts then
        return max(sent, self.answered.get(primitive, sent)) + self.assumptions.ack_within

    def next_due(self) -> Fraction | None:
        """The earliest due time not yet passed unsaid: a live run wakes up for it."""
        due = [d for p in self.requests if p not in self.late
               for d in [self.due(p)] if d is not None]
        return min(due, default=None)

    def overdue(self, now: float | None) -> list[Breach]:
        """The acknowledgements whose due time passes before ``now`` (None: nothing more
        will come, every one still due), said once each."""
        found = []
        for name in sorted(self.requests):
            due = self.due(name)
            if due is not None and name not in self.late \
                    and (now is None or due < exact(now)):
                self.late.add(name)
                found.append(Breach(due, "ack_within", name,
                                    f"{self._request(name, 0)} was not acknowledged "
                                    f"{self._within()}"))
        return self._said(found)

    def event(self, event: Event, taken: bool) -> list[Breach]:
        """``event`` came; ``taken``: the mission takes it (it does not ignore it)."""
        if not taken:
            return []
        name, at = event.primitive, exact(event.t)
        if event.kind in (EventKind.ON, EventKind.OFF):
            return self._said(self._answer(name, event.kind, at))
        found = []
        last = self.reported.get(name)
        gap = self.assumptions.report_gap
        if last is not None and at - last[0] < gap:
            found.append(Breach(at, "report_gap", name, (
                f"{name} reported {event.kind.value} {seconds(at - last[0])} s after its "
                f"previous report ({last[1].value} at {seconds(last[0])} s), closer than the "
                f"{seconds(gap)} s assumed")))
        self.reported[name] = (at, event.kind)
        return self._said(found)

    def _answer(self, name: str, kind: EventKind, at: Fraction) -> list[Breach]:
        pending = self.requests.get(name, [])
        i = next((i for i, (asked, _) in enumerate(pending) if ANSWER[asked] is kind), None)
        if i is None:      # taken, yet no request of ours: the engine's own (a resumed run)
            return []
        due, said, request = self.due(name), name in self.late, self._request(name, i)
        pending.pop(i)
        if i == 0:
            self.late.discard(name)
            self.answered[name] = at
        if said or i != 0 or due is None or at <= due:
            return []
        return [Breach(at, "ack_within", name, f"{request} was acknowledged at "
                                               f"{seconds(at)} s, not {self._within()}")]

    def _request(self, name: str, i: int) -> str:
        """"Pump's enable, sent at 0 s": the primitive's i-th pending request, with when
        its clock started where that is later than its sending."""
        asked, sent = self.requests[name][i]
        start = self.due(name) - self.assumptions.ack_within if i == 0 else sent
        since = f" and answerable from {seconds(start)} s" if start != sent else ""
        return f"{name}'s {asked.value}, sent at {seconds(sent)} s{since},"

    def _within(self) -> str:
        k = self.assumptions.ack_within
        return "at once" if k == 0 else f"within {seconds(k)} s"

    def _said(self, found: list[Breach]) -> list[Breach]:
        self.breaches += found
        return found
