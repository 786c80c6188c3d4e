"""A property's counterexample in the mission's terms, the vehicle script that replays it, and the replay.

:func:`mcl2pnml.analysis.checking.on_graph.check_property` answers a failing property with a firing
sequence of the compiled net. A mission engineer reads a run of the mission:
which calls started and ended with what, which primitives the mission
enabled with which arguments (section 2.1's actions), what the vehicle
reported (its events) and which time-outs expired. This module turns the one
into the other (:func:`explain`), using what the compiler left in the net's
payloads (:mod:`mcl2pnml.core.payloads`) and the places the property atoms
read (:mod:`mcl2pnml.language.declared_properties`).

**Time.** A firing sequence has no clock; the engines have one
(:mod:`mcl2pnml.runtime.engine`: one stimulus at a time, in time order; a
stimulus is a vehicle report or a task's time-out, and what it causes
happens at its instant). The counterexample's stimuli get times that make
the engines take them in the sequence's order: each report a second (or, if
the time-outs leave no room, a tenth, a hundredth...) after the stimulus
before it; each time-out exactly its seconds after the stimulus that
started its timer; and every report before each timer still running
expires. These are difference constraints, solved as longest paths
(Bellman-Ford, by networkx), the earliest times that meet them all; none
exist when the time-outs' order contradicts the sequence.

**The vehicle script** (cli.md's ``{"PRIMITIVE": ["ok@5", "fail@3",
"never"]}``) gives each enabling of a primitive one reply. So a run where a
primitive reports twice in one enabling (it loses its goal and regains it:
``lost``, ``regained``) has no script, and :func:`explain` says so and why.

**The replay** (:func:`replay`) runs the script on both engines: the
Petri-net executor's firings must show the property violated, read by the
same observer as the checker's (:func:`mcl2pnml.analysis.checking.on_graph.judge`), and the
reference engine must send the same actions and see the same events. A
prefix's violation is reached when the observer can no longer be satisfied;
a finite run's when the run ends with an obligation open; a lasso's (an
infinite run) when the run comes back to the same marking with the same
obligation open: the vehicle repeating its answers forever, the obligation
is never met.

It sits between the facade and the layers it joins, and may import
:mod:`mcl2pnml.core`, :mod:`mcl2pnml.language` (the atoms' places),
:mod:`analysis` (the observer) and :mod:`mcl2pnml.runtime` (the engines and
the scripted vehicle); only :mod:`mcl2pnml.pipeline` imports it.
"""
from __future__ import annotations

import copy
import enum
import json
from collections import deque
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Iterable, Sequence

from mcl2pnml.analysis.checking.observers import BAD, initial, pending, step, truths
from mcl2pnml.analysis.checking.on_graph import judge
from mcl2pnml.core.net import Net
from mcl2pnml.core.patterns import Predicate, Property, holds, places_of
from mcl2pnml.core.payloads import MISSION, ActionKind, EventKind, read_transition
from mcl2pnml.core.structure import structure
from mcl2pnml.core.timing import exact_seconds, mission_timing, seconds_text
from mcl2pnml.language import ast
from mcl2pnml.language.declared_properties import RESULTS, predicate
from mcl2pnml.runtime.aal import Action, Event, Reply, ScriptedVehicle, _time
from mcl2pnml.runtime.engine import canonical_trace, run
from mcl2pnml.runtime.executor import PetriEngine
from mcl2pnml.runtime.reference import ReferenceEngine


class StepKind(enum.Enum):
    """What one firing of a counterexample is, in the mission's terms."""

    INTERNAL = "internal"
    """A step of the supervisor alone: nothing the vehicle sees, no call starts."""

    CALL = "call"
    """A call site enters its task or function, with the call's arguments."""

    REPORT = "report"
    """The vehicle reports that a primitive achieved or failed its goal: a stimulus."""

    ACK = "ack"
    """The vehicle acknowledges an enable (``on``) or a disable (``off``) at once."""

    TIMEOUT = "timeout"
    """A task's time-out expires: a stimulus."""


@dataclass(frozen=True)
class Step:
    """One firing of the counterexample, with its time and what it means.

    ``number`` counts from 1 as the firing sequence does; ``t`` is the
    virtual time it happens at in the replay (None where no schedule
    exists); ``changes`` the property atoms that became true (``+``) or
    false (``-``) with it, as the property language writes them.
    """

    number: int
    transition: str
    kind: StepKind
    t: float | None
    text: str
    actions: tuple[Action, ...] = ()
    event: Event | None = None
    changes: tuple[str, ...] = ()


@dataclass(frozen=True)
class Counterexample:
    """A failing property's run, in the net's terms and in the mission's, and its script.

    ``script`` is the vehicle script (None when there is none, ``why_not``
    saying why); ``loop`` the firing after which a lasso's cycle starts.
    """

    property: Property
    shape: str
    steps: tuple[Step, ...]
    loop: int | None
    script: dict[str, list[str]] | None
    why_not: str | None
    end: float | None
    """The time of the last stimulus: where the replay has shown the violation."""
    departs: str | None = None
    """Where the run departs from the engines' urgency (they fire every step of the
    supervisor before time passes), if it does: its replay may then take another run."""

    def lines(self) -> list[str]:
        """The run in the mission's terms: one line per step that means something there."""
        out = []
        for s in self.steps:
            if s.number == (self.loop or 0) + 1 and self.loop is not None:
                out.append("  -- the cycle starts here, repeated forever --")
            if s.kind is StepKind.INTERNAL and not s.actions and not s.changes:
                continue
            when = "" if s.t is None else f"t={_time(s.t)}"
            what = [s.text] if s.text else []
            what += [_action_text(a) for a in s.actions]
            what += list(s.changes)
            out.append(f"{when:>9}  {'; '.join(what)}  [{s.number}]")
        return out

    def script_json(self) -> str | None:
        """The vehicle script as ``run --vehicle`` reads it, or None."""
        return None if self.script is None else json.dumps(self.script, indent=2) + "\n"

    def run_log(self) -> list[dict[str, Any]]:
        """The counterexample as a run log (``run --log``'s JSON lines), which ``show --run``
        steps through: each event, firing and action at its time, with notes in the
        mission's terms."""
        out: list[dict[str, Any]] = [{"t": 0, "note": f"property {self.property.name}: "
                                                      f"{self.property.text}"}]
        for s in self.steps:
            t = _time(s.t) if s.t is not None else 0
            if self.loop is not None and s.number == self.loop + 1:
                out.append({"t": t, "note": "the cycle starts here, repeated forever"})
            if s.event is not None:
                out.append(s.event.as_json())
            out.append({"t": t, "fire": s.transition})
            out += [a.as_json() for a in s.actions]
            if s.kind in (StepKind.CALL, StepKind.TIMEOUT) or s.changes:
                out.append({"t": t, "note": "; ".join(([s.text] if s.text else [])
                                                       + list(s.changes))})
        end = _time(self.steps[-1].t) if self.steps and self.steps[-1].t is not None else 0
        out.append({"t": end, "note": f"the property is violated ({self.shape})"})
        return out


def _action_text(a: Action) -> str:
    if a.kind is ActionKind.ENABLE:
        return f"enable {a.primitive}({_args(a.args)})"
    return f"disable {a.primitive}"


def _args(args: Iterable[Any]) -> str:
    return ", ".join(_value(a) for a in args)


def _value(v: Any) -> str:
    if isinstance(v, tuple):
        return f"({_args(v)})"
    return json.dumps(v) if isinstance(v, str) else f"{v:g}" if isinstance(v, float) else str(v)


# -- the mission's terms -------------------------------------------------------------------------

def atoms(primitives: Iterable[str], callables: Iterable[str]) -> list[tuple[str, Predicate]]:
    """Every property atom on these names, as written, with its predicate on the net
    (:mod:`mcl2pnml.language.declared_properties`' table), in the order a reader wants them."""
    found = []
    for p in primitives:
        found += [ast.PropAtom(k, (p,)) for k in ("enabled", "achieved", "failed")]
    for c in callables:
        found += [ast.PropAtom("running", (c,))]
        found += [ast.PropAtom("ended", (c, r)) for r in RESULTS]
    found += [ast.PropAtom("outcome", (r,)) for r in RESULTS]
    return [(f"{a.kind}({', '.join(a.args)})", predicate(a)) for a in found]


_HEARD = {EventKind.ON: "{} is on", EventKind.OFF: "{} is off",
          EventKind.ACHIEVED: "{} reports achieved", EventKind.FAILED: "{} reports failed"}


def explain(net: Net, prop: Property, transitions: Sequence[str], *, shape: str,
            loop: int | None, primitives: Iterable[str],
            callables: Iterable[str], gap: Fraction | None = None) -> Counterexample:
    """The counterexample ``transitions`` (a failing verdict's, :class:`mcl2pnml.analysis.checking.on_graph.
    Verdict`) in the mission's terms, timed, with the vehicle script that replays it.

    ``primitives`` and ``callables`` (tasks and functions) are the mission's names, whose
    atoms each step's changes are told in. ``gap``: a primitive's reports at least this
    many seconds apart (a timed verdict's assumption, docs/time.md), which the times meet.
    """
    s = structure(net)
    known = [(text, pred) for text, pred in atoms(primitives, callables)
             if places_of(pred) <= net.place_index.keys()]
    m = list(s.initial_vector())

    def marking() -> dict[str, int]:
        return {s.places[k]: n for k, n in enumerate(m) if n}

    true_now = {text for text, pred in known if holds(pred, marking())}
    env: dict[str, dict[str, Any]] = {MISSION: {}}
    kinds, raw, changes = [], [], []
    for tid in transitions:
        t = net.transition_index[tid]
        payload = read_transition(t)
        s.fire(m, s.transition_index[tid])
        if payload.entry is not None:
            e = payload.entry
            scope = env.get(e.scope, {})
            env[e.callee] = {name: arg.evaluate(scope) for name, arg in e.bindings}
            kind = StepKind.CALL
            text = f"call {e.callee}({_args(env[e.callee].values())})"
        elif payload.event is not None and payload.event.primitive is not None:
            ev = payload.event
            kind = (StepKind.REPORT if ev.kind in (EventKind.ACHIEVED, EventKind.FAILED)
                    else StepKind.ACK)
            text = _HEARD[ev.kind].format(ev.primitive)
        elif t.timing is not None:
            kind = StepKind.TIMEOUT
            task = tid.rsplit(".", 1)[0]
            text = (f"the time-out of {task} ({seconds_text(exact_seconds(t.timing.earliest))}"
                    " s) expires")
        else:
            kind, text = StepKind.INTERNAL, ""
        acts = tuple((a.kind, a.primitive, tuple(x.evaluate(env.get(a.scope, {})) for x in a.args))
                     for a in payload.actions)
        here = marking()
        now = {text_ for text_, pred in known if holds(pred, here)}
        changes.append(tuple([f"+{a}" for a, _ in known if a in now - true_now]
                             + [f"-{a}" for a, _ in known if a in true_now - now]))
        true_now = now
        kinds.append(kind)
        raw.append((tid, kind, text, acts, payload.event))
    times, departs, why_not = schedule(net, transitions, kinds, loop, gap)
    script, no_script = _script(raw)
    why_not = no_script or why_not
    steps = []
    for n, ((tid, kind, text, acts, ev), change) in enumerate(zip(raw, changes), 1):
        t = None if times is None else float(times[n - 1])
        actions = tuple(Action(t or 0.0, k, p, args) for k, p, args in acts)
        event = None
        if ev is not None and ev.primitive is not None:
            event = Event(t or 0.0, ev.kind, ev.primitive)
        steps.append(Step(n, tid, kind, t, text, actions, event, change))
    end = None if times is None else float(times[-1]) if times else 0.0
    if why_not is not None:
        script = None
    elif times is not None:
        script = _delays(script, raw, times, loop)
    return Counterexample(prop, shape, tuple(steps), loop, script, why_not, end, departs)


# -- the schedule --------------------------------------------------------------------------------

# Its two halves share their many lists: one pass over the firings gathers the timers set,
# the time-outs, the reports to space and the stimuli as the marking changes, and the
# difference constraints they make are then solved: so the one function is 88 lines long.
def schedule(net: Net, transitions: Sequence[str], kinds: Sequence[StepKind],
             loop: int | None = None, gap: Fraction | None = None
             ) -> tuple[list[Fraction] | None, str | None, str | None]:
    """The earliest times, one per firing, at which the engines take the stimuli in the
    sequence's order (see the module's documentation), or None; where the sequence departs
    from what the engines do at once (a stimulus while a step of the supervisor is still to
    fire), the first such place, in words; why no times exist, if none do. A lasso (its
    cycle from firing ``loop`` on) has none if a time-out runs all along the cycle: time
    passing as the cycle repeats, it would expire. ``gap``: each primitive's reports at
    least that many seconds apart (and a lasso's cycle at least that long, when the cycle
    has a report of the primitive that reports first in it again)."""
    import networkx as nx   # a tenth of a second to import: only a counterexample

    s = structure(net)
    m = list(s.initial_vector())
    timed = {j: Fraction(str(net.transitions[j].timing.earliest))
             for j in range(len(s.transitions)) if net.transitions[j].timing is not None}

    # stimulus 0 is the start; each report and time-out is the next one
    stimulus_of = []                       # per firing: the stimulus it happens in
    set_at = {j: 0 for j in timed if s.enabled(m, j)}   # running timers: when each was set
    fixed: list[tuple[int, int, Fraction]] = []    # (stimulus, timer set at, seconds)
    before: list[tuple[int, int, Fraction]] = []   # stimulus must precede that timer
    # what the engines do at once, before time passes: every step of the supervisor, and the
    # vehicle's acknowledgements (its answers at the instant of the action)
    urgent = [j for j, t in enumerate(net.transitions)
              if t.timing is None and _event_kind(t) not in (EventKind.ACHIEVED, EventKind.FAILED)]
    current, departs = 0, None
    last_report: dict[str, int] = {}       # primitive -> the stimulus of its last report
    spaced: list[tuple[int, int]] = []     # (earlier, later) reports of one primitive
    for n, (tid, kind) in enumerate(zip(transitions, kinds), 1):
        j = s.transition_index[tid]
        if kind is StepKind.REPORT and gap:
            prim = _event_primitive(net.transitions[j])
            if prim in last_report:
                spaced.append((last_report[prim], current + 1))
            last_report[prim] = current + 1
        if kind in (StepKind.REPORT, StepKind.TIMEOUT):
            waiting = next((k for k in urgent if s.enabled(m, k)), None)
            if waiting is not None and departs is None:
                what = "a report" if kind is StepKind.REPORT else "a time-out"
                departs = (f"at step {n} {what} comes while {s.transitions[waiting]} can still "
                           "fire, which the engines fire at once, before time passes")
            current += 1
            if kind is StepKind.TIMEOUT:
                fixed.append((current, set_at[j], timed[j]))
            before += [(current, at, timed[k]) for k, at in set_at.items() if k != j]
        if n - 1 == loop:
            at_loop = dict(set_at)
        stimulus_of.append(current)
        s.fire(m, j)
        for k in timed:    # a timer is set when its time-out becomes enabled, dropped when not
            if s.enabled(m, k):
                set_at.setdefault(k, current)
            else:
                set_at.pop(k, None)
    if loop is not None:
        kept = sorted(s.transitions[k] for k, at in set_at.items() if at_loop.get(k) == at)
        if kept:
            return None, departs, (f"the time-out {kept[0]} runs all along the cycle: repeated, "
                                   "time passes and it expires")
    for epsilon in (Fraction(1), Fraction(1, 10), Fraction(1, 100), Fraction(1, 1000)):
        g = nx.DiGraph()
        g.add_nodes_from(range(current + 1))

        def at_least(u: int, v: int, w: Fraction) -> None:   # time(v) >= time(u) + w
            if g.has_edge(u, v):
                w = max(w, -g[u][v]["weight"])
            g.add_edge(u, v, weight=-w)

        for k in range(1, current + 1):
            at_least(k - 1, k, epsilon)
        for k, at, seconds in fixed:
            at_least(at, k, seconds)
            at_least(k, at, -seconds)
        for k, at, seconds in before:
            at_least(k, at, epsilon - seconds)
        for earlier, later in spaced:
            at_least(earlier, later, gap)
        try:
            dist = nx.single_source_bellman_ford_path_length(g, 0)
        except nx.NetworkXUnbounded:
            continue
        times = [-dist[k] for k in range(current + 1)]
        return [times[k] for k in stimulus_of], departs, None
    return None, departs, ("no times make the time-outs expire in the sequence's order (a report "
                  "would have to come after a time-out that the run has not met yet)")


def _event_primitive(t) -> str | None:
    event = read_transition(t).event
    return None if event is None else event.primitive


def _event_kind(t) -> EventKind | None:
    event = read_transition(t).event
    return None if event is None or event.primitive is None else event.kind


# -- the vehicle script --------------------------------------------------------------------------

def _script(raw) -> tuple[dict[str, list[tuple[int, int, EventKind | None]]], str | None]:
    """Per primitive, each enabling's (firing of the enable, firing of its reply or -1,
    the reply); or why no script gives this run."""
    enablings: dict[str, list[list[Any]]] = {}
    open_: dict[str, list[Any]] = {}
    for n, (tid, kind, text, acts, ev) in enumerate(raw):
        if kind is StepKind.REPORT:
            prim = ev.primitive
            current = open_.get(prim)
            if current is None:
                return {}, (f"{prim} reports {ev.kind.value} at step {n + 1} while the mission "
                            "has not enabled it")
            if current[2] is not None:
                first = raw[current[1]][4].kind.value
                return {}, (f"{prim} reports twice in one enabling ({first} at step "
                            f"{current[1] + 1}, then {ev.kind.value} at step {n + 1}): its goal "
                            "lost or regained; a vehicle script gives each enabling one reply")
            current[1], current[2] = n, ev.kind
        for k, prim, _ in acts:
            if k is ActionKind.ENABLE:
                open_[prim] = [n, -1, None]
                enablings.setdefault(prim, []).append(open_[prim])
            else:
                open_.pop(prim, None)
    return {p: [tuple(e) for e in es] for p, es in enablings.items()}, None


#: How many times a lasso's script gives the replies of its cycle: enough to see it repeat.
CYCLE_REPEATS = 3


def _delays(script, raw, times, loop: int | None) -> dict[str, list[str]]:
    """The script's replies; a lasso's cycle (enablings from firing ``loop`` on) given
    :data:`CYCLE_REPEATS` times, the vehicle answering each time round as the first."""
    out = {}
    for prim, enablings in sorted(script.items()):
        replies, cycle = [], []
        for enabled_at, reply_at, kind in enablings:
            if kind is None:
                reply = "never"
            else:
                delay = _time(float(times[reply_at] - times[enabled_at]))
                reply = f"{'ok' if kind is EventKind.ACHIEVED else 'fail'}@{delay}"
            (cycle if loop is not None and enabled_at >= loop else replies).append(reply)
        replies += cycle * CYCLE_REPEATS
        while replies and replies[-1] == "never":   # past its list a primitive says never
            replies.pop()
        out[prim] = replies
    return {p: r for p, r in out.items() if r}


# -- the replay ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class Replay:
    """What replaying a counterexample's script did on each engine."""

    reached: bool
    """The Petri-net executor's run shows the property violated."""
    same_on_reference: bool
    """The reference engine sent the same actions and saw the same events."""
    fired: tuple[str, ...]
    trace: tuple[dict[str, Any], ...]
    detail: str


def vehicle(script: dict[str, list[str]]) -> ScriptedVehicle:
    """The scripted vehicle of ``script`` (the form :attr:`Counterexample.script` has)."""
    return ScriptedVehicle({p: [Reply.parse(r, p) for r in replies]
                            for p, replies in script.items()})


def replay(cex: Counterexample, net: Net, checked, silent: Sequence[str] = ()) -> Replay:
    """Run ``cex``'s script on the Petri-net executor (of ``net``) and on the reference
    engine (of ``checked``), up to the counterexample's last stimulus, and judge the runs
    (``silent``: the transitions a run may end with enabled, :func:`mcl2pnml.analysis.checking.on_graph.
    judge`)."""
    if cex.script is None or cex.end is None:
        raise ValueError(f"property {cex.property.name}: no script ({cex.why_not})")
    petri = PetriEngine(net)
    fired: list[str] = []
    petri.on_fire = lambda t, tid: fired.append(tid)
    ran = run(petri, vehicle(cex.script), max_time=cex.end)
    shown = judge(net, cex.property, fired, silent)
    reference = run(ReferenceEngine(checked), vehicle(cex.script), max_time=cex.end)
    trace = canonical_trace(ran.entries)
    same = trace == canonical_trace(reference.entries)
    detail = (f"the executor's run ({len(fired)} firings, {ran.outcome.value} at "
              f"t={ran.time:g} s) " + (f"shows the violation ({shown.shape.value}, after "
                                      f"{shown.step} firings)" if shown else
                                      "does not show the violation"))
    detail += "; the reference engine " + ("runs the same trace" if same else
                                           "runs another trace")
    return Replay(shown is not None, same, tuple(fired), tuple(trace), detail)


# -- a run the engines take ------------------------------------------------------------------------

class SearchLimit(Exception):
    """:func:`engine_run` met its bound before it could answer."""


#: The most states of the executor :func:`engine_run` searches, unless told: each is a
#: copy of the engine, far larger than a marking, for a search the explanation may skip.
ENGINE_RUN_STATES = 200_000


# Its helpers (the observer watching each firing, the vehicle's acknowledgements, a fresh
# start) are closures over the engine being explored and the observer's state, which the
# breadth-first search reads after every move; apart, they would hand that state back and
# forth on every firing: so the one function is 109 lines long.
def engine_run(net: Net, prop: Property, max_states: int = ENGINE_RUN_STATES
               ) -> tuple[str, ...] | None:
    """A shortest violating run that the Petri-net executor takes with some vehicle: or None
    when it takes none (:class:`SearchLimit` past ``max_states`` states of the executor).

    The checker's counterexample is a run of the untimed net; the engines
    fire every step of the supervisor at once, in their own order, before
    the next stimulus. Here the executor itself is explored: from each state
    where it waits, every stimulus a vehicle script can give (a report of an
    enabled primitive that has not reported in this enabling; a running
    timer's expiry), each followed by what the engine does at once and the
    vehicle's acknowledgements, breadth first, the observer reading every
    marking the executor passes through. It finds a prefix that violates the
    property, or a run that ends (nothing enabled) with an obligation open;
    failing both, an infinite run: a cycle of the executor's states with an
    obligation open at every marking along it, reached by the shortest
    prefix (strongly connected components of those moves). Time is left out here:
    :func:`schedule` then finds the times, if any, that order the stimuli so.
    """
    import networkx as nx   # a tenth of a second to import: only a counterexample


    root = PetriEngine(net)
    places = root.places
    preds = truths(prop)
    trail: list[str] = []
    box: dict[str, Any] = {}

    def watch(_t: float, tid: str) -> None:
        trail.append(tid)
        if box["obs"] is not BAD:
            marking = {places[k]: n for k, n in enumerate(box["engine"].marking) if n}
            box["obs"] = step(prop, box["obs"], *(holds(x, marking) for x in preds))
            box["open"] = box.get("open", False) and pending(prop, box["obs"])

    def settle(engine: PetriEngine, actions: list[Action], replied: frozenset[str]):
        """The vehicle's acknowledgements, at once, in its order (by primitive name)."""
        due: dict[str, EventKind] = {}
        while True:
            for a in actions:
                due[a.primitive] = EventKind.ON if a.kind is ActionKind.ENABLE else EventKind.OFF
                replied = replied - {a.primitive}      # a new enabling, or none
            if not due or engine.outcome is not None or box["obs"] is BAD:
                return replied
            name = min(due)
            actions = engine.on_event(Event(engine.now, due.pop(name), name))

    def start():
        engine = PetriEngine(net)
        box["engine"], box["obs"] = engine, None
        marking = {places[k]: n for k, n in enumerate(engine.marking) if n}
        box["obs"] = step(prop, initial(prop.scope.kind), *(holds(x, marking) for x in preds))
        engine.on_fire = watch
        replied = settle(engine, engine.start(0.0), frozenset())
        return engine, replied

    def key(engine, obs, replied):
        return tuple(engine.marking), obs, replied

    trail.clear()
    engine, replied = start()
    root_key = key(engine, box["obs"], replied)
    nodes = {root_key: tuple(trail)}           # each state's shortest run from the start
    loops = nx.DiGraph()                        # moves with an obligation open throughout
    queue = deque([(root_key, engine, replied)])
    while queue:
        here, engine, replied = queue.popleft()
        path, obs = nodes[here], here[1]
        if obs is BAD:
            return path
        stimuli = [("report", prim, kind) for (prim, kind), ts in sorted(
                       root.by_event.items(), key=lambda kv: (kv[0][0], kv[0][1].value))
                   if kind in (EventKind.ACHIEVED, EventKind.FAILED) and prim not in replied
                   and any(engine.enabled[i] for i in ts)] if engine.outcome is None else []
        if engine.outcome is None:
            stimuli += [("timer", i, None) for _, _, i, version in sorted(engine.timers)
                        if version == engine.version[i] and engine.enabled[i]]
        if not stimuli and pending(prop, obs):
            m = engine.marking
            dead = not any(all(m[p] >= w for p, w in engine.inputs[i])
                           for i in range(len(engine.transitions)))
            if dead:
                return path
        for what, a, b in stimuli:
            child = _clone(engine)
            trail.clear()
            box["engine"], box["obs"], box["open"] = child, obs, pending(prop, obs)
            child.on_fire = watch
            if what == "report":
                actions = child.on_event(Event(child.now, b, a))
                now_replied = replied | {a}
            else:
                actions = child._fire(a) + child._settle()
                now_replied = replied
            now_replied = settle(child, actions, now_replied)
            k = key(child, box["obs"], now_replied)
            if box["open"] and box["obs"] is not BAD:
                loops.add_edge(here, k, firings=tuple(trail))
            if k in nodes:
                continue
            if len(nodes) >= max_states:
                raise SearchLimit(f"the executor's runs have more than {max_states:,} states")
            nodes[k] = path + tuple(trail)
            queue.append((k, child, now_replied))
    return _engine_lasso(nodes, loops)


def _engine_lasso(nodes, loops) -> tuple[str, ...] | None:
    """The shortest prefix and cycle of the executor's states with an obligation open all
    along the cycle (:func:`engine_run`'s infinite runs), as one firing sequence."""
    import networkx as nx   # a tenth of a second to import: only a counterexample
    best = None
    for scc in nx.strongly_connected_components(loops):
        inside = loops.subgraph(scc)
        if not inside.number_of_edges():
            continue
        for start in scc:
            lengths = nx.single_source_dijkstra_path_length(
                inside, start, weight=lambda u, v, d: len(d["firings"]))
            for u in inside.predecessors(start):
                if u in lengths:
                    size = len(nodes[start]) + lengths[u] + len(inside[u][start]["firings"])
                    if best is None or size < best[0]:
                        best = (size, start, u, inside)
    if best is None:
        return None
    _, start, last, inside = best
    hops = nx.dijkstra_path(inside, start, last, weight=lambda u, v, d: len(d["firings"]))
    cycle: list[str] = []
    for u, v in zip(hops, hops[1:] + [start]):
        cycle += loops[u][v]["firings"]
    return nodes[start] + tuple(cycle)


def _clone(engine):
    """A copy of the executor's state that runs on alone (what a firing changes is copied)."""
    c = copy.copy(engine)
    c.marking = list(engine.marking)
    c.env = {k: dict(v) for k, v in engine.env.items()}
    c.ready, c.entries, c.timers = list(engine.ready), list(engine.entries), list(engine.timers)
    c.version, c.enabled = list(engine.version), list(engine.enabled)
    c.watch = [set(x) for x in engine.watch]
    c.enabled_on = [set(x) for x in engine.enabled_on]
    c.watching = list(engine.watching)
    c.ignored = list(engine.ignored)
    return c


# -- all of it, for one failing verdict ----------------------------------------------------------

@dataclass(frozen=True)
class Witness:
    """A failing verdict, told for a mission engineer.

    ``run`` is the checker's counterexample in the mission's terms. ``replayed``
    is the run a vehicle script leads both engines along to the violation:
    ``run`` itself when it can be, else the engines' own shortest violating run
    (:func:`engine_run`), else None, ``why_not`` saying why.
    """

    run: Counterexample
    replayed: Counterexample | None
    replay: Replay | None
    why_not: str | None


def witness(net: Net, checked, prop: Property, transitions: Sequence[str], *, shape: str,
            loop: int | None, timing=None) -> Witness:
    """The counterexample ``transitions`` of ``prop`` explained, scripted and replayed.

    The checker's run is replayed when a script gives it and the engines take it as it is
    (it fires no stimulus while the engines still have a step to take at once). Otherwise
    the engines' own violating run is taken: the executor's run under the checker's script,
    when that still shows the violation, else the shortest one :func:`engine_run` finds.

    ``timing``: the :class:`~mcl2pnml.core.timing.Assumptions` of a timed verdict
    (docs/time.md): the times meet its report gap, and a run may end where only the
    vehicle's reports are left (the vehicle silent for ever; with ``fair``, only its
    reports after the first of an enabling).
    """
    names = dict(primitives=list(checked.primitives),
                 callables=[*checked.tasks, *checked.functions])
    gap, silent = None, ()
    if timing is not None:
        tn = mission_timing(net, timing)
        fair = set().union(*tn.fair) if tn.fair else set()
        silent = tuple(t for members, _ in tn.gaps for t in members if t not in fair) \
            if tn.gaps else tuple(t for t, (a, b) in tn.intervals.items()
                                  if b is None and a == 0 and t not in fair)
        gap = timing.report_gap
        names["gap"] = gap

    def replayed(seq: Sequence[str]) -> tuple[Counterexample | None, Replay | None, str]:
        shown = judge(net, prop, seq, silent)
        if shown is None:
            return None, None, "it does not show the violation"
        cex = explain(net, prop, seq[:shown.step], shape=shown.shape.value, loop=shown.loop,
                      **names)
        if cex.script is None:
            return cex, None, cex.why_not or ""
        tried = replay(cex, net, checked, silent)
        return cex, tried, "" if tried.reached and tried.same_on_reference else tried.detail

    run_ = explain(net, prop, transitions, shape=shape, loop=loop, **names)
    if run_.script is None:
        why = run_.why_not
    else:
        tried = replay(run_, net, checked, silent)
        if tried.reached and tried.same_on_reference and run_.departs is None:
            return Witness(run_, run_, tried, None)
        why = run_.departs or tried.detail
        if tried.reached and tried.same_on_reference:   # the engines' run violates it too
            cex, again, fault = replayed(tried.fired)
            if not fault:
                return Witness(run_, cex, again, why)
    try:
        own = engine_run(net, prop)
    except SearchLimit as e:
        return Witness(run_, None, None, f"{why}; the engines' own violating runs were not "
                                         f"searched to the end: {e}")
    if own is not None:
        cex, again, fault = replayed(own)
        if not fault:
            return Witness(run_, cex, again, why)
        return Witness(run_, None, None, f"{why}; the engines' own violating run: {fault}")
    return Witness(run_, None, None, f"{why}; no run the engines take, whatever the vehicle "
                   "reports and with the vehicle answering 'on' and 'off' at once (as a script "
                   "does), violates it: this violation is a run of the untimed net only, which "
                   "a slower vehicle or another tool reading the PNML may take")
