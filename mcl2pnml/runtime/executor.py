"""The Petri-net executor: the paper's Mission Control System (section 2.1).

It plays a compiled mission net, from MCL or from its PNML alone, against a
vehicle. Everything it needs is in the net, read once through the records
of :mod:`mcl2pnml.core.payloads`: the transitions that send actions
(:class:`~mcl2pnml.core.payloads.ActionSpec`), the transitions that vehicle
events fire (:class:`~mcl2pnml.core.payloads.EventBinding`), the arguments of
every call (:class:`~mcl2pnml.core.payloads.CallEntry` on the call sites'
``enter``), and the time-outs (timed transitions).

How it fires:

* **immediate transitions** fire as soon as they are enabled, the one
  enabled longest first; transitions enabled by the same firing go in the
  order of the net (the documented conflict rule);
* **call entries** (a call site's ``enter``, which takes a shared task or
  function) fire last: only when nothing else can fire at this instant,
  and then the first in program order (the order of the call sites in the
  net). So when a task is free, of all the calls waiting for it at that
  instant, the one written first gets it, however the instant unfolded;
* **event transitions** fire only when their primitive reports that event;
  an event that no enabled transition waits for is ignored, with a reason;
* **timed transitions** fire when they have been enabled, without a break,
  for their delay (the earliest time of their interval).

Enabling is incremental, with *watched inputs* (as SAT solvers watch
literals): a disabled transition waits on one input place that lacks
tokens, the one with the fewest other consumers, and is looked at again
only when that place gains tokens; an enabled one is looked at again when
one of its inputs loses tokens. A task's shared result place has a
consumer in every call site, but only the call site that is inside waits
on it, so one event costs the same in a mission of ten tasks or of ten
thousand (a test counts the transitions each event makes it examine).
"""
from __future__ import annotations

import copy
import heapq
import weakref
from dataclasses import dataclass
from typing import Any

from mcl2pnml.runtime.aal import Action, ActionKind, Event, EventKind
from mcl2pnml.runtime.engine import Engine, Outcome
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import SUMMARY_MARKED, Net
from mcl2pnml.core.payloads import MISSION, MissionPlace, TransitionPayload, read_transition
from mcl2pnml.core.structure import structure

RESULTS = {MissionPlace.OK.id: Outcome.OK, MissionPlace.FAIL.id: Outcome.FAIL,
           MissionPlace.ABORTED.id: Outcome.ABORTED}
#: Firings allowed at one instant before the run is stopped as a zero-time loop.
ZENO_LIMIT = 1_000_000
#: Bindings of tasks and functions past which a mission's enable arguments are not listed.
ENABLE_ARGUMENTS_LIMIT = 100_000


@dataclass(frozen=True, eq=False)
class _Tables:
    """What a run reads of its net and never changes: worked out once per net and shared
    by every engine on it (a campaign or the exact odds build an engine per run, and
    reading the payloads again took most of a short run's time)."""

    places: tuple[str, ...]
    transitions: tuple[str, ...]
    pre: tuple[tuple[tuple[int, int], ...], ...]       # consumed: (place, weight), arc order
    test: tuple[tuple[tuple[int, int], ...], ...]      # read
    post: tuple[tuple[tuple[int, int], ...], ...]
    inputs: tuple[tuple[tuple[int, int], ...], ...]    # the most private input first
    delay: tuple[float | None, ...]
    payload: tuple[TransitionPayload, ...]
    by_event: dict[tuple[str, EventKind], list[int]]
    event_driven: frozenset[int]
    result_places: dict[int, Outcome]
    changes: tuple[tuple[tuple[int, bool], ...], ...]
    results_marked: tuple[tuple[int, ...], ...]
    entry: tuple[bool, ...]
    net: "weakref.ref[Net]"


#: The tables of the nets alive, by the net's identity (a net never changes; its equality
#: compares its whole content, too dear for a lookup per run).
_TABLES: dict[int, _Tables] = {}


def _tables(net: Net) -> _Tables:
    """The net's tables, read once while the net lives."""
    known = _TABLES.get(id(net))
    if known is not None and known.net() is net:
        return known
    made = _read_tables(net)
    _TABLES[id(net)] = made
    weakref.finalize(net, _TABLES.pop, id(net), None)
    return made


def _read_tables(net: Net) -> _Tables:
    s = structure(net)
    pindex = s.place_index
    pre = tuple(tuple(arcs.items()) for arcs in s.pre)
    test = tuple(tuple(arcs.items()) for arcs in s.read)
    consumers = [len(ts) for ts in s.place_post]          # p•, readers included
    # the inputs of each transition, the most private first: the one to watch
    inputs = tuple(tuple(sorted(pre[i] + test[i], key=lambda pw: consumers[pw[0]]))
                   for i in range(len(s.transitions)))
    payload = tuple(read_transition(t) for t in net.transitions)
    by_event: dict[tuple[str, EventKind], list[int]] = {}
    for i, p in enumerate(payload):
        event = p.event
        if event is not None and event.primitive is not None:
            by_event.setdefault((event.primitive, event.kind), []).append(i)
    result_places = {pindex[p]: o for p, o in RESULTS.items()}
    # what each firing changes (its column of the incidence matrix), worked
    # out once: the places whose count falls or rises (True: falls), in
    # place order, and the result places among those that rise
    changes, results_marked = [], []
    for change in s.incidence:
        rows = sorted(change)
        changes.append(tuple((p, change[p] < 0) for p in rows))
        results_marked.append(tuple(p for p in rows
                                    if change[p] > 0 and p in result_places))
    return _Tables(
        places=s.places, transitions=s.transitions, pre=pre, test=test,
        post=tuple(tuple(arcs.items()) for arcs in s.post), inputs=inputs,
        delay=tuple(t.timing.earliest if t.timing is not None else None
                    for t in net.transitions),
        payload=payload, by_event=by_event,
        event_driven=frozenset(i for ts in by_event.values() for i in ts),
        result_places=result_places, changes=tuple(changes),
        results_marked=tuple(results_marked),
        entry=tuple(p.entry is not None for p in payload), net=weakref.ref(net))


class PetriEngine(Engine):
    """Runs one mission net (see the module's documentation for the firing rules)."""

    def __init__(self, net: Net):
        super().__init__()
        missing = [p for p in RESULTS if p not in net.place_index]
        if missing:
            raise Mcl2PnmlError(f"net '{net.name}' is not a compiled mission: it has no place "
                                f"{', '.join(missing)} (compile MCL with `mcl2pnml compile`)")
        self.net = net
        tables = _tables(net)
        self.places, self.transitions = tables.places, tables.transitions
        self.pre, self.test, self.post = tables.pre, tables.test, tables.post
        self.inputs, self.delay, self.payload = tables.inputs, tables.delay, tables.payload
        self.by_event, self.event_driven = tables.by_event, tables.event_driven
        self.result_places = tables.result_places
        self.changes, self.results_marked = tables.changes, tables.results_marked
        self.entry = tables.entry
        n = len(self.transitions)
        self.watch: list[set[int]] = [set() for _ in self.places]      # disabled, waiting on p
        # the watch list whose sets this engine may change in place: those of the places
        # named (None: every one), see _watchers
        self._owned: tuple[list[set[int]], set[int] | None] = (self.watch, None)
        self.enabled_on: list[set[int]] = [set() for _ in self.places]  # enabled, using p
        self.watching: list[int | None] = [None] * n
        self._timeouts: dict[str, float] | None = None     # each task's, by timeout_of
        self.marking = [net.initial[p] for p in self.places]
        self.env: dict[str, dict[str, Any]] = {MISSION: {}}
        self.ready: list[tuple[int, int, int]] = []  # (step enabled, index, version)
        self.entries: list[tuple[int, int]] = []     # call entries: (index, version)
        self.timers: list[tuple[float, str, int, int]] = []  # (due, task, index, version)
        self.version = [0] * n
        self.enabled = [False] * n
        self.step = 0
        self.now = 0.0

    # -- enabling ------------------------------------------------------------------

    def _update(self, i: int) -> None:
        """Re-examine transition ``i`` after a change of its input places."""
        m = self.marking
        lacking = None
        for p, w in self.inputs[i]:
            if m[p] < w:
                lacking = p
                break
        now = lacking is None
        if not now:   # watch the first input that lacks tokens
            old = self.watching[i]
            if old != lacking:
                if old is not None:
                    self._watchers(old).discard(i)
                self._watchers(lacking).add(i)
                self.watching[i] = lacking
        if now == self.enabled[i]:
            return
        self.enabled[i] = now
        for p, _ in self.inputs[i]:
            (self.enabled_on[p].add if now else self.enabled_on[p].discard)(i)
        if now and self.watching[i] is not None:
            self._watchers(self.watching[i]).discard(i)
            self.watching[i] = None
        self.version[i] += 1          # a timer set before a break no longer counts
        if not now or i in self.event_driven:
            return
        if self.entry[i]:
            heapq.heappush(self.entries, (i, self.version[i]))
        elif self.delay[i] is None:
            heapq.heappush(self.ready, (self.step, i, self.version[i]))
        else:
            task = self.transitions[i].rsplit(".", 1)[0]
            heapq.heappush(self.timers, (self.now + self.delay[i], task, i, self.version[i]))

    def _watchers(self, p: int) -> set[int]:
        """``watch[p]`` to change: this engine's own set, copied on its first change since
        a clone shared it (a clone copied every place's set, most of the exact odds' time)."""
        watch, owned = self._owned
        if watch is not self.watch:         # a new list: none of its sets is known ours
            watch, owned = self._owned = (self.watch, set())
        if owned is not None and p not in owned:
            watch[p] = set(watch[p])
            owned.add(p)
        return watch[p]

    def _fire(self, i: int) -> list[Action]:
        m = self.marking
        for p, w in self.pre[i]:
            m[p] -= w
        for p, w in self.post[i]:
            m[p] += w
        self.step += 1
        if self.on_fire is not None:
            self.on_fire(self.now, self.transitions[i])
        update = self._update
        for p, falls in self.changes[i]:
            if falls:       # enabled ones may lose an input
                for j in sorted(self.enabled_on[p]):
                    update(j)
            else:           # the ones waiting on p may now be enabled
                for j in sorted(self.watch[p]):
                    update(j)
        for p in self.results_marked[i]:
            if m[p]:
                self.outcome = self.result_places[p]
        return self._effects(i)

    def _effects(self, i: int) -> list[Action]:
        payload = self.payload[i]
        entry = payload.entry
        if entry is not None:      # a call site's enter: bind the callee's parameters
            scope = self.env.get(entry.scope, {})
            self.env[entry.callee] = {name: arg.evaluate(scope) for name, arg in entry.bindings}
        actions = []
        for a in payload.actions:
            scope = self.env.get(a.scope, {})
            args = tuple(x.evaluate(scope) for x in a.args)
            actions.append(Action(self.now, a.kind, a.primitive, args))
        return actions

    def _settle(self) -> list[Action]:
        """Fire immediate transitions, the one enabled longest first, until none is."""
        actions: list[Action] = []
        fired = 0
        while (self.ready or self.entries) and self.outcome is None:
            if self.ready:
                _, i, version = heapq.heappop(self.ready)
            else:   # nothing else can fire: the first waiting call in program order
                i, version = heapq.heappop(self.entries)
            if version != self.version[i] or not self.enabled[i]:
                continue   # disabled since, or queued again later
            actions += self._fire(i)
            fired += 1
            if fired > ZENO_LIMIT:
                raise Mcl2PnmlError(
                    f"the mission fires for ever at t={self.now:g} s without time passing "
                    "(a while loop whose condition and body end at once?)")
        return actions

    # -- copies, for the exact odds ----------------------------------------------------

    def clone(self) -> "PetriEngine":
        """A copy that runs on alone from here: the net's tables shared, the run's state
        copied (the exact odds run every choice of the vehicle from one state,
        :mod:`mcl2pnml.odds`). What it ignored so far is not copied."""
        other = copy.copy(self)
        other.marking = list(self.marking)
        # the watch sets are shared, and copied by either engine as it changes one
        other.watch = list(self.watch)
        self._owned, other._owned = (self.watch, set()), (other.watch, set())
        other.enabled_on = [set(e) for e in self.enabled_on]
        other.watching = list(self.watching)
        other.env = {scope: dict(values) for scope, values in self.env.items()}
        other.ready, other.entries = list(self.ready), list(self.entries)
        other.timers = list(self.timers)
        other.version, other.enabled = list(self.version), list(self.enabled)
        other.ignored = []
        return other

    def state(self) -> tuple:
        """What decides this engine's future between stimuli: the marking, the time-outs
        running (their time left) and the outcome. Two engines settled at their instant
        with equal states fire alike on equal stimuli (the event transitions in net
        order, the immediate ones from an empty queue); the call arguments (``env``) only
        name the actions' arguments."""
        running = sorted((due - self.now, i) for due, _, i, version in self.timers
                         if version == self.version[i] and self.enabled[i])
        return tuple(self.marking), tuple(running), self.outcome

    # -- the engine interface ----------------------------------------------------------

    def start(self, t: float) -> list[Action]:
        self.now = t
        for i in range(len(self.transitions)):
            self._update(i)
        return self._settle()

    def on_event(self, event: Event) -> list[Action]:
        self.now = event.t
        candidates = self.by_event.get((event.primitive, event.kind))
        if not candidates:
            known = sorted({p for p, _ in self.by_event})
            reason = (f"no primitive '{event.primitive}' in this mission"
                      if event.primitive not in known else
                      f"'{event.primitive}' never reports '{event.kind.value}'")
            self.ignored.append((event, reason))
            return []
        ready = [i for i in candidates if self.enabled[i]]
        if not ready:
            self.ignored.append((event, f"nothing waits for '{event.kind.value}' from "
                                        f"'{event.primitive}' now"))
            return []
        actions = self._fire(ready[0])
        return actions + self._settle()

    def waits_for(self, event: Event) -> bool:
        return any(self.enabled[i] for i in self.by_event.get((event.primitive, event.kind), ()))

    def next_timer(self) -> tuple[float, str] | None:
        while self.timers:
            due, task, i, version = self.timers[0]
            if version == self.version[i] and self.enabled[i]:
                return due, task
            heapq.heappop(self.timers)   # cancelled: disabled since it was set
        return None

    def fire_timer(self, t: float, name: str) -> list[Action]:
        due, task, i, version = heapq.heappop(self.timers)
        assert task == name and due == t
        self.now = t
        actions = self._fire(i)
        return actions + self._settle()

    def timeout_of(self, task: str) -> float | None:
        # a timer's name is its transition's task (as _enable names it): found once
        if self._timeouts is None:
            self._timeouts = {name.rsplit(".", 1)[0]: delay for name, delay
                              in zip(self.transitions, self.delay) if delay is not None}
        return self._timeouts.get(task)

    def enable_arguments(self) -> dict[str, list[tuple]] | None:
        # The arguments are constants passed down call sites (no arithmetic),
        # so the bindings each scope can have are a finite set: grown from the
        # mission's, through every call entry, until nothing new appears.
        envs: dict[str, dict[str, dict[str, Any]]] = {MISSION: {"{}": {}}}
        entries = [p.entry for p in self.payload if p.entry is not None]
        changed = True
        while changed:
            changed = False
            for entry in entries:
                for env in list(envs.get(entry.scope, {}).values()):
                    try:
                        bound = {name: arg.evaluate(env) for name, arg in entry.bindings}
                    except KeyError:        # a scope this call site never runs in
                        continue
                    callee = envs.setdefault(entry.callee, {})
                    key = repr(sorted(bound.items()))
                    if key not in callee:
                        if sum(map(len, envs.values())) > ENABLE_ARGUMENTS_LIMIT:
                            return None     # too many to list: checked as they are sent
                        callee[key], changed = bound, True
        out: dict[str, dict[str, tuple]] = {}
        for payload in self.payload:
            for a in payload.actions:
                if a.kind is not ActionKind.ENABLE:
                    continue
                for env in envs.get(a.scope, {"{}": {}}).values() if a.scope else [{}]:
                    try:
                        args = tuple(x.evaluate(env) for x in a.args)
                    except KeyError:
                        continue
                    out.setdefault(a.primitive, {})[repr(args)] = args
        return {p: list(found.values()) for p, found in out.items()}

    def primitives_used(self) -> set[str]:
        # the primitives whose events some transition waits for
        return {p for p, _ in self.by_event}

    def waiting(self) -> list[str]:
        out = []
        for (prim, kind), ts in sorted(self.by_event.items(), key=lambda kv: (kv[0][0],
                                                                           kv[0][1].value)):
            if any(self.enabled[i] for i in ts):
                out.append(f"{prim}: waits for the vehicle's '{kind.value}'")
        for due, task, i, version in sorted(self.timers):
            if version == self.version[i] and self.enabled[i]:
                out.append(f"{self.transitions[i]}: the time-out of {task} at t={due:g} s")
        marked = [f"{p}" + (f"*{n}" if n > 1 else "")
                  for p, n in zip(self.places, self.marking) if n]
        shown = marked[:SUMMARY_MARKED] + ([f"... {len(marked) - SUMMARY_MARKED:,} more"]
                                           if len(marked) > SUMMARY_MARKED else [])
        out.append(f"marked ({len(marked)} places): " + ", ".join(shown))
        return out
