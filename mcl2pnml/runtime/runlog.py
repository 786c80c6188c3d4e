"""Watching a run: a live log for people, a JSON-lines log for tools.

Each action, event, fired transition and ignored event is one line as it
happens, in virtual time::

    t=  30.000  event     achieved  GoToWayPoint
    t=  30.000  action    disable   GoToWayPoint
    t=  30.000  fire      Survey.AchieveWayPoint-1.return_OK

The JSON-lines log has the same entries as objects (``{"t": 30, "event":
"achieved", "primitive": "GoToWayPoint"}``, ``{"t": 30, "fire": "..."}``,
``{"t": 30, "ignored": {...}, "reason": "..."}``), one per line, so that a
tool can follow a run while it happens or replay it after. The safe stop
at the end of a run (docs/faults.md) is logged as ``safe-stop`` lines
(``"safe_stop": true`` in JSON), a task's time-out that expires as a
``time-out`` line (``{"t": 901, "timeout": "Goto", "seconds": 900}``), and
an assumption of the timed verdicts the vehicle broke (docs/time.md) as a ``breach``
line (``{"t": 1.6, "breach": "report_gap", "primitive": ..., "message": ...}``),
the run's end as ``{"t": ..., "outcome": ...}``, with ``"diagnosis"`` (why a
run without a result stopped: the fault, the signal, what it waited for)
where there is one; a run that ends in an error has ``{"t": ..., "error":
...}`` as its last line instead. An autopilot (docs/ardusub.md) adds its own lines: what
it says and is told (``autopilot``), the safe state it is brought to
(``safe-state``), its track and the markers dropped (JSON only), and each
achieved or failed says who judged it (``"source"``: the autopilot's
telemetry or a simulated sensor). The journal of :mod:`mcl2pnml.runtime.journal` is this log,
written a flushed line at a time.
"""
from __future__ import annotations

import json
from typing import IO, Any

from mcl2pnml.runtime.aal import Action, Event, SafeStop, _time
from mcl2pnml.runtime.engine import Outcome, TimedOut
from mcl2pnml.runtime.watch import Breach


def _args(args: tuple) -> str:
    return ", ".join(json.dumps(a) if not isinstance(a, tuple) else
                     "(" + ", ".join(json.dumps(x) for x in a) + ")" for a in args)


class RunLog:
    """Writes the live log (``text``) and the JSON-lines log (``jsonl``), either or both."""

    def __init__(self, text: IO[str] | None = None, jsonl: IO[str] | None = None,
                 transitions: bool = False, journal: Any = None):
        self.text, self.jsonl, self.transitions = text, jsonl, transitions
        self.journal = journal     # mcl2pnml.runtime.journal's writer: one whole line per write
        self.last_t: float = 0.0   # the time of the last line: an error's line is stamped with it

    def _json(self, obj: dict[str, Any]) -> None:
        self.last_t = obj.get("t", self.last_t)
        line = json.dumps(obj) + "\n"
        if self.jsonl is not None:
            self.jsonl.write(line)
        if self.journal is not None:
            self.journal.write(line)

    def _line(self, t: float, kind: str, what: str, obj: dict[str, Any]) -> None:
        if self.text is not None:
            self.text.write(f"t={t:9.3f}  {kind:<8}  {what}\n")
            self.text.flush()
        self._json(obj)

    def entry(self, entry: Action | Event | TimedOut | Breach) -> None:
        if isinstance(entry, TimedOut):   # why a task ended that no event ended
            self._line(entry.t, "time-out", f"{entry.named()} expired", entry.as_json())
        elif isinstance(entry, Breach):   # the timed verdicts no longer hold for this run
            self._line(entry.t, "breach", entry.words(), entry.as_json())
        elif isinstance(entry, SafeStop):    # the run loop's, not the mission's: say so
            self._line(entry.t, "safe-stop", f"{entry.kind.value:<9} {entry.primitive}",
                       entry.as_json())
        elif isinstance(entry, Action):
            what = f"{entry.kind.value:<9} {entry.primitive}"
            if entry.args:
                what += f"({_args(entry.args)})"
            self._line(entry.t, "action", what, entry.as_json())
        else:
            obj, what = entry.as_json(), f"{entry.kind.value:<9} {entry.primitive}"
            source = getattr(entry, "source", None)
            if source:      # who judged it: the autopilot, or a simulated sensor
                obj.update(source=source, why=entry.why)
                what += f"  ({source}: {entry.why})"
            self._line(entry.t, "event", what, obj)

    def vehicle(self, t: float, kind: str, text: str, obj: dict[str, Any]) -> None:
        """A line of the vehicle's own: what the autopilot says and is told, its safe
        state; its track and markers (JSON only: the live log stays readable)."""
        obj = {"t": _time(t), **obj}
        if text:
            self._line(t, kind, text, obj)
        else:
            self._json(obj)

    def fired(self, t: float, transition: str) -> None:
        if self.text is not None and self.transitions:
            self.text.write(f"t={t:9.3f}  {'fire':<8}  {transition}\n")
        self._json({"t": _time(t), "fire": transition})

    def ignored(self, event: Event, reason: str) -> None:
        self._line(event.t, "ignored", f"{event.kind.value} from {event.primitive}: {reason}",
                   {"t": _time(event.t), "ignored": event.as_json(), "reason": reason})

    def end(self, t: float, outcome: Outcome, diagnosis: list[str] | None = None) -> None:
        """The last line: the run is over (a resumed run has nothing left to do).

        The outcome is written by :meth:`Outcome.as_json`, and the diagnosis
        (why a run without a result stopped) as the run's ``--json`` object has them.
        """
        self._json({"t": _time(t), "outcome": outcome.as_json(),
                    **({"diagnosis": list(diagnosis)} if diagnosis else {})})

    def failed(self, t: float, error: str) -> None:
        """The last line of a run that ended in an error (bad input from the vehicle, a
        mission's own error), after its safe stop; not journaled: the run did not end,
        and a resume may take it on."""
        if self.jsonl is not None:
            self.jsonl.write(json.dumps({"t": _time(t), "error": error}) + "\n")
