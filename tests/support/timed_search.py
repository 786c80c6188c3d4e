"""The engines' own search for a mission's longest run: the Petri-net executor driven by
every vehicle that matters for the end time, without the zone graph.

From each state where the executor waits, the vehicle may report (achieved or failed, for
each primitive whose report something waits for) at the earliest instant its report gap
allows, or at the instant the next time-out is due (the engines take a vehicle event before
a time-out of its instant), or stay silent until that time-out fires. Reporting later than
that gains nothing the time-out does not, reporting earlier than the gap allows is not
allowed: so the longest run of these is the longest of all (docs/time.md), among the runs a
vehicle script gives (one report an enabling). Acknowledgements come at once, as a script's
do. Depth-first, the executor's states cloned."""
from __future__ import annotations

from fractions import Fraction

from mcl2pnml.core.payloads import ActionKind, EventKind
from mcl2pnml.counterexample import _clone
from mcl2pnml.runtime.aal import Event
from mcl2pnml.runtime.executor import PetriEngine


class Search:
    def __init__(self, net, gap: Fraction = Fraction(1), limit: int = 200_000):
        self.net, self.gap, self.limit = net, gap, limit
        self.visited = 0
        self.longest: tuple[float, list] | None = None     # (end time, stimuli)
        self.never = False        # a run that waits for ever with no result

    def acks(self, engine: PetriEngine, actions, script: dict | None = None) -> dict:
        """The acknowledgements, at once; each enabling noted in ``script`` (a copy is
        returned): per primitive, [enabled at, reply] lists in order."""
        script = {p: [list(e) for e in es] for p, es in (script or {}).items()}
        due: dict[str, EventKind] = {}
        while True:
            for a in actions:
                due[a.primitive] = EventKind.ON if a.kind is ActionKind.ENABLE else EventKind.OFF
                if a.kind is ActionKind.ENABLE:
                    script.setdefault(a.primitive, []).append([a.t, None])
            if not due or engine.outcome is not None:
                return script
            name = min(due)
            actions = engine.on_event(Event(engine.now, due.pop(name), name))

    def run(self) -> tuple[float | None, dict]:
        """The longest run's end time and its vehicle script (``run --vehicle``'s)."""
        engine = PetriEngine(self.net)
        script = self.acks(engine, engine.start(0.0))
        self.go(engine, {}, script)
        return (None, {}) if self.longest is None else self.longest

    def go(self, engine: PetriEngine, last: dict[str, float], script: dict) -> None:
        self.visited += 1
        if self.visited > self.limit:
            raise RuntimeError(f"more than {self.limit:,} runs")
        if engine.outcome is not None:
            if self.longest is None or engine.now > self.longest[0]:
                replies = {p: [r or "never" for _, r in es] for p, es in script.items()}
                self.longest = (engine.now, replies)
            return
        timer = engine.next_timer()
        waiting = [(prim, kind) for (prim, kind), ts in sorted(
            engine.by_event.items(), key=lambda kv: (kv[0][0], kv[0][1].value))
            if kind in (EventKind.ACHIEVED, EventKind.FAILED) and any(engine.enabled[i] for i in ts)]
        if timer is None and not waiting:
            self.never = True
            return
        for prim, kind in waiting:
            earliest = max(engine.now, last.get(prim, -1e18) + float(self.gap))
            times = {earliest}
            if timer is not None and timer[0] >= earliest:
                times.add(timer[0])
            for at in sorted(times):
                if timer is not None and at > timer[0]:
                    continue
                child = _clone(engine)
                noted = {p: [list(e) for e in es] for p, es in script.items()}
                enabled_at, reply = noted[prim][-1]
                if reply is not None:
                    continue      # a script gives one report an enabling
                word = "ok" if kind is EventKind.ACHIEVED else "fail"
                noted[prim][-1][1] = f"{word}@{at - enabled_at:g}"
                noted = self.acks(child, child.on_event(Event(at, kind, prim)), noted)
                self.go(child, {**last, prim: at}, noted)
        if timer is not None:
            child = _clone(engine)
            self.go(child, last, self.acks(child, child.fire_timer(timer[0], timer[1]), script))
        elif waiting:
            self.never = True     # the vehicle may stay silent for ever here
