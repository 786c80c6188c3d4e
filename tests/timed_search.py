"""The engines' own search for a mission's longest run: the Petri-net executor driven by
every vehicle that matters for the end time, without the zone graph.

From each state where the executor waits, the vehicle may report (achieved or failed, for
each primitive whose report something waits for) at the earliest instant its report gap
allows, or at the instant the next time-out is due (the engines take a vehicle event before
a time-out of its instant), or stay silent until that time-out fires. Reporting later than
that gains nothing the time-out does not, reporting earlier than the gap allows is not
allowed: so the longest run of these is the longest of all (docs/time.md). Acknowledgements
come at once, as a script's do. Depth-first, the executor's states cloned."""
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

    def acks(self, engine: PetriEngine, actions) -> None:
        due: dict[str, EventKind] = {}
        while True:
            for a in actions:
                due[a.primitive] = EventKind.ON if a.kind is ActionKind.ENABLE else EventKind.OFF
            if not due or engine.outcome is not None:
                return
            name = min(due)
            actions = engine.on_event(Event(engine.now, due.pop(name), name))

    def run(self) -> tuple[float | None, list]:
        engine = PetriEngine(self.net)
        self.acks(engine, engine.start(0.0))
        self.go(engine, {}, [])
        return (None, []) if self.longest is None else self.longest

    def go(self, engine: PetriEngine, last: dict[str, float], trail: list) -> None:
        self.visited += 1
        if self.visited > self.limit:
            raise RuntimeError(f"more than {self.limit:,} runs")
        if engine.outcome is not None:
            if self.longest is None or engine.now > self.longest[0]:
                self.longest = (engine.now, list(trail))
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
                self.acks(child, child.on_event(Event(at, kind, prim)))
                self.go(child, {**last, prim: at}, trail + [(at, prim, kind.value)])
        if timer is not None:
            child = _clone(engine)
            self.acks(child, child.fire_timer(timer[0], timer[1]))
            self.go(child, last, trail + [(timer[0], "timeout", timer[1])])
        elif waiting:
            self.never = True     # the vehicle may stay silent for ever here
