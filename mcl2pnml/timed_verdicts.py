"""A mission's timed verdicts in its own terms: does it always end, when, and its properties.

:mod:`mcl2pnml.analysis.timed.zones` answers on any :class:`~mcl2pnml.core.timing.TimedNet`;
this module asks it about a compiled mission (docs/time.md): the mission's
semantics under the vehicle's :class:`~mcl2pnml.core.timing.Assumptions`
(:func:`~mcl2pnml.core.timing.mission_timing`), "every run ends"
(the existence of a result, Dwyer et al.'s *eventually*, on every
time-divergent run), the earliest and latest end times, and, when a run
never ends, what it waits for, in words: "FindCross waits for DetectCross's
report, and has no time-out", or the cycle it repeats, call by call with each
call's line. The property verdicts are handed back as
:class:`mcl2pnml.analysis.checking.on_graph.Verdict`, so that the counterexample machinery of
:mod:`mcl2pnml.counterexample` reads them as it reads the untimed ones.

Sits beside :mod:`mcl2pnml.counterexample`, between the facade and the layers
it joins: may import :mod:`mcl2pnml.core` and :mod:`mcl2pnml.analysis`; the facade
(:mod:`mcl2pnml.pipeline`) imports it. Named for what it gives, so that no module shares
a name with :mod:`mcl2pnml.analysis.timed`.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import Any, Mapping, NamedTuple, Sequence

from mcl2pnml.core.bounds import MAX_CHECK_STATES
from mcl2pnml.analysis.statespace.explore import explore
from mcl2pnml.analysis.timed import zones as engine
from mcl2pnml.analysis.checking.on_graph import Shape, Status, Verdict
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.memory import Budget, BudgetExceeded, floored, guard, release
from mcl2pnml.core.net import Net
from mcl2pnml.core.payloads import ENTER, MissionPlace, read_transition
from mcl2pnml.core.patterns import Pattern, Property, Scope, ScopeKind, Tokens
from mcl2pnml.core.timing import Assumptions, TimedNet, mission_timing, seconds_text
from mcl2pnml.core.vocabulary import CYCLE, ENDS as EVERY_RUN_ENDS, STALL

#: The mission's result places: a run has ended once one is marked.
ENDS = (MissionPlace.OK.id, MissionPlace.FAIL.id, MissionPlace.ABORTED.id)


def semantics(net: Net, assumptions: Assumptions) -> TimedNet:
    """The mission's timed semantics, or one error if ``net`` is no compiled mission."""
    missing = [p for p in ENDS if p not in net.place_index]
    if missing:
        raise Mcl2PnmlError(f"net '{net.name}' is not a compiled mission (it has no place "
                            f"{', '.join(missing)}): a timed verdict reads a mission's time-outs "
                            "and vehicle events (compile MCL with `mcl2pnml compile`)")
    if not any(read_transition(t).event is not None for t in net.transitions):
        raise Mcl2PnmlError(f"net '{net.name}' has no transition fired by the vehicle: its file "
                            "lost the mission's payloads, without which time has no meaning")
    return mission_timing(net, assumptions)


def ends_property() -> Property:
    """"Every run ends": one of the results, eventually, on every run."""
    return Property("AlwaysEnds", Pattern.EXISTENCE, Tokens(ENDS, 1),
                    scope=Scope(ScopeKind.GLOBALLY),
                    text="eventually outcome(OK) or outcome(FAIL) or outcome(ABORTED)")


class Site(NamedTuple):
    """Where an instance of the compiled net comes from in the mission: a call as written
    (``Goto(Approach)``) or a structure's kind (``while``), and its line."""

    label: str
    line: int


#: How much of a cycle the answer shows: its first steps, each with its first transitions.
CYCLE_STEPS, STEP_TRANSITIONS = 12, 12


@dataclass(frozen=True)
class TimedEnds:
    """Whether and when the mission's runs end, under ``assumptions`` (docs/time.md).

    ``always_ends``: every time-divergent run reaches a result (None: unknown,
    ``reason`` says why); ``deadlock``: some state has nothing that can happen
    and no result (time passes for ever there: a stall); ``earliest`` and
    ``latest``: the first and last times, in seconds, at which a run reaches its
    result (``latest`` None when a run never ends); ``waits``: what a run that
    never ends waits for, in words; ``cycle``: the transitions of the cycle such a
    run repeats, if it does (once round); ``calls``: the net's call sites, each with
    the shared nets it enters (its callee's, its primitives'); ``sites``: each
    instance's call and line, from the mission, where it is known (:meth:`cycle_steps`
    puts the cycle in the mission's terms); ``never``: that run's verdict (its firings);
    ``latest_run``: the firings of a run that ends at ``latest``; ``states`` and
    ``time_states``: the zones the verdict and the end times searched;
    ``latest_bound_states``: of the latter, those that bound the latest end on a graph
    whose loops are widened (docs/time.md, "How it is computed").
    """

    assumptions: Assumptions
    always_ends: bool | None
    deadlock: bool
    earliest: Fraction | None
    latest: Fraction | None
    waits: tuple[str, ...]
    never: Verdict | None
    states: int
    reason: str | None = None
    latest_run: tuple[str, ...] = ()
    time_states: int = 0
    latest_bound_states: int = 0
    cycle: tuple[str, ...] = ()
    calls: Mapping[str, frozenset[str]] = field(default_factory=dict)
    sites: Mapping[str, Site] = field(default_factory=dict)

    def placed(self, sites: Mapping[str, Site]) -> "TimedEnds":
        """These answers with the mission's ``sites``: the cycle told by calls and lines."""
        return replace(self, sites=sites)

    def cycle_steps(self) -> list[tuple[str, tuple[str, ...]]]:
        """The cycle in the mission's terms: each stretch of it in one call or structure,
        as (the call and its line, its transitions), in the order the cycle runs.

        A transition's instance is its name's prefix (``Goto-2.return_OK``: the call
        ``Goto-2``). A task's or function's own net, and a primitive's, is shared by the
        calls that enter it (a call of a task takes its primitives' locks): its
        transitions (``Goto.t02``, ``GoToWayPoint.off_S2``) are the call's that entered it
        last, read round the cycle (a cycle may enter at its end what it runs at its
        start).
        """
        owners = [tid.rsplit(".", 1)[0] for tid in self.cycle]
        inside: dict[str, str] = {}      # a shared net -> the call last entered into it
        for owner in owners:             # once round: what the cycle enters at its end
            inside.update((n, owner) for n in self.calls.get(owner, ()))
        steps: list[tuple[str, list[str]]] = []
        for tid, owner in zip(self.cycle, owners):
            if owner in self.calls:
                inside.update((n, owner) for n in self.calls[owner])
            elif owner in inside and owner not in self.sites:   # a function's root
                owner = inside[owner]             # structure is told as itself, a site
            if not steps or steps[-1][0] != owner:
                steps.append((owner, []))
            steps[-1][1].append(tid)
        return [(self._where(owner), tuple(tids)) for owner, tids in steps]

    def _where(self, instance: str) -> str:
        site = self.sites.get(instance)
        return instance if site is None else f"{site.label} (line {site.line})"

    def said(self) -> list[str]:
        """What a run that never ends does, in words: what it waits for, or the calls and
        structures of the cycle it repeats, each once, in the order the cycle meets them."""
        if not self.cycle:
            return list(self.waits)
        met = list(dict.fromkeys(where for where, _ in self.cycle_steps()))
        more = len(met) - CYCLE_STEPS
        return [*self.waits, f"{CYCLE} through " + ", ".join(met[:CYCLE_STEPS])
                + (f", ... ({more:,} more)" if more > 0 else "")]

    def lines(self) -> list[str]:
        """The answer as ``analyze --timed`` prints it."""
        out = [f"timed (docs/time.md): {self.assumptions.words()}"]
        if self.always_ends is None:
            out.append(f"  {EVERY_RUN_ENDS}: unknown ({self.reason})")
        elif self.always_ends:
            out.append(f"  {EVERY_RUN_ENDS}: yes ({self.states:,} zones)")
        elif self.cycle:
            out.append(f"  {EVERY_RUN_ENDS}: no, {CYCLE}:")
            steps = self.cycle_steps()
            for where, tids in steps[:CYCLE_STEPS]:
                shown = " ".join(tids[:STEP_TRANSITIONS])
                out.append(f"    {where}: {shown}" + (" ..." if len(tids) > STEP_TRANSITIONS
                                                      else ""))
            if len(steps) > CYCLE_STEPS:
                out.append(f"    ... ({len(steps) - CYCLE_STEPS:,} more; --json: all of it)")
        else:
            out.append(f"  {EVERY_RUN_ENDS}: no, " + "; ".join(self.waits))
        if self.deadlock:
            out.append(f"  {STALL}: yes (a stall)")
        if self.earliest is not None:
            latest = (f"{_s(self.latest)} s" if self.latest is not None else
                      f"unbounded ({self.reason})" if self.always_ends else
                      "never (a run does not end)")
            out.append(f"  end time: earliest {_s(self.earliest)} s, latest {latest} "
                       f"({self.time_states:,} zones)")
        elif self.always_ends is not None and self.reason:
            out.append(f"  end time: not computed ({self.reason})")
        return out

    def as_json(self) -> dict[str, Any]:
        return {"assumptions": self.assumptions.as_json(), "always_ends": self.always_ends,
                "deadlock": self.deadlock, "reason": self.reason,
                "earliest": _num(self.earliest), "latest": _num(self.latest),
                "waits": self.said(), "zones": self.states,
                "end_time_zones": self.time_states,
                "latest_bound_zones": self.latest_bound_states,
                "latest_run": list(self.latest_run),
                "cycle": [{"in": where, "transitions": list(tids)}
                          for where, tids in self.cycle_steps()],
                "never": None if self.never is None else {
                    "shape": self.never.shape.value, "transitions": list(self.never.transitions),
                    "loop": self.never.loop}}


#: A time as the answers print it: exactly (core.timing.seconds_text).
_s = seconds_text


def _num(x: Fraction | None) -> int | float | None:
    if x is None:
        return None
    return x.numerator if x.denominator == 1 else float(x)


def ends(net: Net, assumptions: Assumptions = Assumptions(),
         max_states: int = MAX_CHECK_STATES, budget: Budget | None = None) -> TimedEnds:
    """Whether every run of the mission ends, when, and what one that does not waits for;
    each search stopped at ``max_states`` zones or at the memory ``budget`` (the default
    one if None), its answer then unknown with the reason."""
    tn = semantics(net, assumptions)
    budget = budget or Budget()
    (verdict,) = _within(budget, lambda: engine.check_timed_properties(
        tn, [ends_property()], max_states), lambda why: [engine.TimedVerdict(
            ends_property(), "unknown", reason=why)])
    if verdict.status == "unknown":
        return TimedEnds(assumptions, None, False, None, None, (), None, verdict.states,
                         verdict.reason)
    times = _within(budget, lambda: engine.end_times(tn, ENDS, verdict, max_states),
                    lambda why: engine.EndTimes(None, None, None, 0, reason=why))
    unit = tn.unit
    earliest = None if times.earliest is None else times.earliest * unit
    latest = None if times.latest is None else times.latest * unit
    places = engine.places(tn)
    never = None if verdict.status == "holds" else as_verdict(places, verdict)
    waits = () if never is None else tuple(waiting(tn, places, verdict))
    cycle = _period(verdict.transitions[verdict.loop:]) if never is not None \
        and verdict.shape == "lasso" else ()
    stalls = _within(budget, lambda: _stalls(tn, verdict, max_states), lambda why: False)
    return TimedEnds(assumptions, verdict.status == "holds", stalls,
                     earliest, latest, waits, never, verdict.states, times.reason,
                     latest_run=times.latest_path, time_states=times.states,
                     latest_bound_states=times.bound_states, cycle=cycle,
                     calls=_call_sites(net) if cycle else {})


def _period(loop: Sequence[str]) -> tuple[str, ...]:
    """The shortest sequence that ``loop`` repeats whole: the zones may close a cycle only
    after going round it several times (a clock's value recurs later than the marking)."""
    n = len(loop)
    for p in range(1, n):
        if n % p == 0 and all(loop[i] == loop[i - p] for i in range(p, n)):
            return tuple(loop[:p])
    return tuple(loop)


def _call_sites(net: Net) -> dict[str, frozenset[str]]:
    """The call sites of a compiled mission, by their instances' names (``Goto-2``), each
    with the shared nets it enters: its callee's (its entry's payload says which) and its
    primitives' (whose locks its entry takes)."""
    out = {}
    for t in net.transitions:
        if t.id.endswith("." + ENTER):
            entry = read_transition(t).entry
            if entry is not None:
                locks = (a.source.rsplit(".", 1)[0] for a in net.pre[t.id]
                         if a.source.endswith(".LOCK"))
                out[t.id.rsplit(".", 1)[0]] = frozenset([entry.callee, *locks])
    return out


def _within(budget: Budget, search, otherwise):
    """``search()`` under the memory ``budget``; past it, ``otherwise(reason)``."""
    try:
        with guard(floored(budget), "the timed search"):
            return search()
    except BudgetExceeded as e:
        return otherwise(e.message)
    finally:
        release()


def _stalls(tn: TimedNet, verdict: engine.TimedVerdict, max_states: int) -> bool:
    """Whether a run stalls (nothing left to happen, no result): never when every run
    ends, at once when the run that does not end stops with nothing enabled, else
    searched for (False if the search passes its limit: the verdict says why)."""
    if verdict.status == "holds":
        return False
    if verdict.status == "fails" and verdict.shape == "finite" and not engine.enables(
            tn, verdict.path[-1]):
        return True     # its run that does not end stops with nothing enabled
    if _no_untimed_stall(tn, max_states):
        return False    # the markings of the runs in time are among those of the net
    try:
        return engine.stalls(tn, ENDS, max_states)
    except engine.TimedLimit:
        return False


def _no_untimed_stall(tn: TimedNet, max_states: int) -> bool:
    """Whether every dead marking of the net, time aside, has a result marked (False if
    its markings pass ``max_states``): explored in C, far faster than the zones."""
    try:
        space = explore(tn.net, max_states=max_states)
    except Mcl2PnmlError:
        return False
    index = [space.structure.place_index[p] for p in ENDS]
    return all(any(space.markings[n][i] for i in index) for n in space.terminal)


def waiting(tn: TimedNet, places: list[str], verdict: engine.TimedVerdict) -> list[str]:
    """What a run that never ends waits for, in the mission's words (a run that goes round
    a cycle waits for nothing: :meth:`TimedEnds.said` tells its cycle)."""
    marked = set(engine.marked_places(places, verdict.path[-1]))
    timeouts = {t.id.rsplit(".", 1)[0] for t in tn.net.transitions if t.timing is not None}
    out = []
    tasks = [] if verdict.shape == "lasso" else sorted(
        p.rsplit(".", 1)[0] for p in marked if p.endswith(".EXE"))
    for task in tasks:
        prims = sorted(p.rsplit(".", 1)[0] for p in marked if p.endswith(".ON")
                       and _uses(tn.net, task, p.rsplit(".", 1)[0]))
        what = f"{task} waits for " + (" and ".join(f"{p}'s report" for p in prims) or
                                       "its primitives")
        what += ", and has no time-out" if task not in timeouts else ""
        out.append(what)
    if verdict.shape == "lasso":
        return out
    if not out:
        out.append("the run waits for ever with " + ", ".join(sorted(marked)[:8]) + " marked")
    if verdict.shape == "finite" and tasks:
        out[-1] += " (nothing aborts it)"
    return out


def _uses(net: Net, task: str, prim: str) -> bool:
    """Whether ``task``'s net is fused with ``prim``'s (its t01 asks ``prim`` to start)."""
    t01 = f"{task}.t01"
    if t01 not in net.transition_index:
        return True
    return any(a.target.startswith(prim + ".") for a in net.post[t01])


def as_verdict(places: list[str], v: engine.TimedVerdict) -> Verdict:
    """A timed verdict in the untimed checker's type (:class:`mcl2pnml.analysis.checking.on_graph.Verdict`)."""
    status = {"holds": Status.HOLDS, "fails": Status.FAILS, "unknown": Status.UNKNOWN}[v.status]
    if status is not Status.FAILS:
        return Verdict(v.property, status, states=v.states, reason=v.reason)
    markings = tuple(tuple((p, 1) for p in engine.marked_places(places, m)) for m in v.path)
    shape = {"prefix": Shape.PREFIX, "finite": Shape.FINITE, "lasso": Shape.LASSO}[v.shape]
    return Verdict(v.property, status, v.transitions, markings, shape, v.loop, v.states)


def check_properties_timed(net: Net, properties: Sequence[Property],
                           assumptions: Assumptions = Assumptions(),
                           max_states: int = MAX_CHECK_STATES,
                           budget: Budget | None = None) -> list[Verdict]:
    """Each property's verdict on the mission's time-divergent runs (docs/time.md), unknown
    past ``max_states`` zones or the memory ``budget``."""
    tn = semantics(net, assumptions)
    places = engine.places(tn)
    verdicts = _within(budget or Budget(), lambda: engine.check_timed_properties(
        tn, properties, max_states), lambda why: [engine.TimedVerdict(p, "unknown", reason=why)
                                                  for p in properties])
    return [as_verdict(places, v) for v in verdicts]
