"""The interface contract of a task or a control structure, checked on its state space.

Sections 2.3 to 2.5 of the paper argue compositionally: a task pattern or a
control structure is started by its place B, may be aborted through A, and
ends in exactly one of OK, FAIL and ABORTED, after which it can be started
again; a structure that joins children keeping this behaviour keeps it
too, and the reduced model of Fig. 3 (B to OK, FAIL or ABORTED; B and A to
ABORTED) stands for any child that does. This module states that behaviour
once, over a net's fusion places, as the clauses a component must meet, and
checks each one by exploring the net (a template with its children reduced
is a few hundred markings at most).

The **rest** marking is the net's M0 without tokens in B and A: a called
component waits there, its mutex MTX (and its children's, and any lock)
marked. Then, for the component started from rest:

* ``interface``: B and A are the caller's to mark, the results its to take:
  no transition of the component marks its own B or A, and none takes or
  reads its own OK, FAIL or ABORTED (a component that marked its own A
  would be aborted at its next start, with no abort asked);
* ``asleep``: at rest, only B wakes it: each of its own transitions needs B
  or a place of its own that is empty at rest, whatever the places it
  shares with other parts hold (a task that read its primitive at rest
  would be woken by another task driving the same primitive: the lock keeps
  their runs apart, not what an idle task reads);
* ``idle``: at rest, and at rest with only A marked (an abort that comes
  after the component has ended, which the caller drains), nothing can fire;
* ``safe``: started (rest + B, and rest + B + A: an abort pending from the
  start, which covers one that comes at any later moment), no place ever
  holds two tokens;
* ``ends``: every dead marking so reached is an end: one token in exactly
  one of OK, FAIL and ABORTED, B consumed, every other place back at rest
  (its MTX, its children's and the locks given back, nothing left inside);
* ``abort``: A is consumed exactly when the end is ABORTED; without A the
  end is never ABORTED;
* ``always ends``: from every reachable marking an end can still be reached
  (no livelock, no deadlock);
* ``result last``: whenever a result is marked, every other place is
  already at rest, so a caller may take the result and start the component
  again at once;
* ``result final``: whenever a result is marked, nothing in the component
  can fire: the result stands until the caller takes it out. Without it a
  component could end OK and then take its own OK back to end FAIL: its
  dead markings say "only FAIL", but a caller takes the OK first, and a
  signature read from the dead markings alone would lie to the caller
  (docs/certificate.md, the composition argument);
* ``abortable``: started with an abort pending, it can end ABORTED and in
  each result it can give without one, and in no other: what the reduced
  model does, so that the reduced model with the same results stands for it;
* ``caller``: for a component checked with reduced children (a structure,
  a call site), it starts a child only when the child is at rest: whenever
  a child's B is marked, the child is not running and holds no result. This
  is what the contract assumes of a component's environment (it was checked
  started from rest, never restarted while it runs), so each parent proves
  it of its children (assume-guarantee: docs/certificate.md).

The results a component can give from rest + B (a subset of OK and FAIL)
are its **results** (:attr:`Verdict.results`). With them, and whether it
may instead run for ever until aborted (the one clause a loop with no way
out breaks), they are its signature: the reduced model restricted to it
(:func:`restricted`) behaves toward a caller as the component does, both in
what it can do and in what it can still do, which is what an end always
being reachable depends on (a loop whose condition can never fail never
ends, though every part keeps the rest of the contract).

A component that meets them, fused with its caller on B, A, OK, FAIL and
ABORTED, behaves toward the caller as the reduced model does (the paper's
section 2.3). May import the core and the rest of ``analysis``.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import NamedTuple

from mcl2pnml.core.net import Arc, Net, Place, Transition

from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore

#: The version of the contract: stored proofs of another version are proven again
#: (2: the ``interface``, ``asleep``, ``result final`` and ``caller`` clauses).
VERSION = 2

#: The fusion places of a component's control interface, by role (the places' labels).
START, ABORT = "B", "A"
RESULTS = ("OK", "FAIL", "ABORTED")


class Clause(enum.Enum):
    """One clause of the contract (see the module's documentation)."""

    INTERFACE = "interface"
    """No transition marks the component's own B or A, or takes or reads its own results:
    those are the caller's moves (version 2)."""

    ASLEEP = "asleep"
    """Each of the component's own transitions needs B or one of its own places that is
    empty at rest: at rest, what the parts it shares (its primitives, its children) do
    cannot wake it (version 2)."""

    IDLE = "idle"
    """At rest, and at rest with A alone, nothing fires."""

    SAFE = "safe"
    """Started, with or without an abort pending, no place holds two tokens."""

    ENDS = "ends"
    """Every dead marking is an end: one result, B consumed, the rest restored."""

    ABORT = "abort"
    """A is consumed exactly when the end is ABORTED; never ABORTED without A."""

    ALWAYS_ENDS = "always ends"
    """From every reachable marking an end can still be reached."""

    RESULT_LAST = "result last"
    """Whenever a result is marked, everything else is already at rest: a caller that
    takes the result may start the component again at once (section 2.3's reusability,
    which a check of the dead markings alone misses: a task that gives its result while
    its primitive still holds a request would get a second one)."""

    RESULT_FINAL = "result final"
    """Whenever a result is marked, no transition of the component is enabled: a result
    once given is final until the caller takes it, so the results a caller can see are
    exactly the component's ends (version 2 of the contract; without it a component that
    ends OK and may take its OK back to end FAIL showed the signature "only FAIL")."""

    ABORTABLE = "abortable"
    """Started with an abort pending, it can end ABORTED and in every result it can give
    without one, and in no other: the reduced model with the same results stands for it
    (a structure above may have to abort it, or wait for a result it can give)."""

    CALLER = "caller"
    """A child (a reduced model in a slot) is started only at rest: whenever its B is
    marked, it is not running (nor stuck) and none of its results is marked. The contract
    of the child was checked from rest, so this is the assumption a parent discharges for
    each of its children (version 2)."""


@dataclass(frozen=True)
class Breach:
    """A clause broken: from which start, the firing sequence to the marking that shows
    it, that marking (its marked places), and what is wrong there."""

    clause: Clause
    start: str
    path: tuple[str, ...]
    marking: tuple[str, ...]
    why: str

    def __str__(self) -> str:
        steps = " ".join(self.path) or "(no firing)"
        return (f"{self.clause.value}: from {self.start}, after {steps}: {self.why} "
                f"(marked: {', '.join(self.marking) or 'nothing'})")


@dataclass(frozen=True)
class Verdict:
    """The contract checked: the breaches found (none: the component keeps it) and the
    markings explored from each start."""

    breaches: tuple[Breach, ...]
    markings: int
    #: the results it can end in from rest + B (OK, FAIL), and from rest + B + A
    results: frozenset[str] = frozenset()
    results_aborted: frozenset[str] = frozenset()

    @property
    def kept(self) -> bool:
        return not self.breaches


class NoInterface(ValueError):
    """The net has not the control interface the contract is stated over."""


def roles(net: Net) -> dict[str, str]:
    """The place of each role of the control interface (B, A, OK, FAIL, ABORTED), by the
    places' interface labels; a missing or doubled role is :class:`NoInterface`."""
    found: dict[str, list[str]] = {}
    for p in net.places:
        if p.interface in (START, ABORT, *RESULTS):
            found.setdefault(p.interface, []).append(p.id)
    wanted = (START, ABORT, *RESULTS)
    missing = [r for r in wanted if r not in found]
    doubled = [r for r in wanted if len(found.get(r, ())) > 1]
    if missing or doubled:
        raise NoInterface(f"net '{net.name}': " + "; ".join(
            ([f"no place labelled {', '.join(missing)}"] if missing else [])
            + [f"{len(found[r])} places labelled {r}" for r in doubled]))
    return {r: found[r][0] for r in wanted}


class Own(NamedTuple):
    """What of a composed net is the component's own: its transitions, and the places of
    the other parts it is composed with (its primitives', its children's), not its own."""

    transitions: frozenset[str]
    foreign: frozenset[str]


def check_contract(net: Net, max_states: int = 100_000, children: tuple[str, ...] = (),
          own: Own | None = None) -> Verdict:
    """Every clause of the contract on ``net`` (a component with the control interface);
    ``children``: the prefixes of the places of its reduced children (``T1_``, ``T.``),
    each held to the ``caller`` clause; ``own``: what of the net is the component's, held
    to the ``asleep`` clause (None: every transition and place)."""
    role = roles(net)
    rest = {p: n for p, n in net.initial.items() if p not in (role[START], role[ABORT])}
    inputs, outputs = {role[START], role[ABORT]}, {role[r] for r in RESULTS}
    breaches: list[Breach] = [
        Breach(Clause.INTERFACE, "the net", (), (),
               f"{a.source} marks {a.target}, the caller's to mark" if a.target in inputs
               else f"{a.target} takes {a.source}, the caller's to take")
        for a in net.arcs if a.target in inputs or a.source in outputs]
    breaches += _discipline(net, children) + _asleep(net, role, own)
    explored = 0
    for label, extra in (("rest", {}), ("rest + A", {role[ABORT]: 1})):
        space = _explore(net, {**rest, **extra}, max_states)
        explored += space.states
        st, m = space.structure, space.markings[0]
        fires = [t for j, t in enumerate(st.transitions) if st.enabled(m, j)]
        if fires:
            breaches.append(Breach(Clause.IDLE, label, (), _marked(space, 0),
                                   f"{', '.join(fires)} can fire though the component was "
                                   "not started"))
    ends: list[frozenset[str]] = []
    for label, extra in (("rest + B", {role[START]: 1}),
                         ("rest + B + A", {role[START]: 1, role[ABORT]: 1})):
        space = _explore(net, {**rest, **extra}, max_states)
        explored += space.states
        found, got = _started(space, role, rest, label, aborted=role[ABORT] in extra)
        breaches += found + _callers(space, children, label)
        ends.append(got)
    plain, aborted = ends
    if not breaches and aborted != plain | {"ABORTED"}:
        breaches.append(Breach(
            Clause.ABORTABLE, "rest + B + A", (), (),
            f"with an abort pending it ends {_names(aborted)}, without one "
            f"{_names(plain)}: not these and ABORTED, as the reduced model would"))
    return Verdict(tuple(breaches), explored, plain, aborted)


def _names(results) -> str:
    return " or ".join(r for r in RESULTS if r in results) or "never"


def restricted(net: Net, results, stuck: bool = False) -> Net:
    """The reduced model ``net`` (Fig. 3) giving only ``results`` of OK and FAIL when not
    aborted: its transitions into the other results' places removed, with their arcs;
    ``stuck``: besides, a running model may stray into a place it never leaves (``STUCK``,
    looping on itself) until it is aborted: a child that may run for ever."""
    role = roles(net)
    gone = {a.source for a in net.arcs
            if a.target in {role[r] for r in RESULTS[:2] if r not in results}}
    places, arcs = list(net.places), [a for a in net.arcs
                                      if a.source not in gone and a.target not in gone]
    transitions = [t for t in net.transitions if t.id not in gone]
    if stuck:
        # the abort of a running model (Fig. 3's t4: EXE, A -> ABORTED, MTX) shows where
        # it runs, and what an abort gives back
        pre = {t.id: [a for a in net.arcs if a.target == t.id] for t in net.transitions}
        abort = next((t.id for t in net.transitions
                      if {a.source for a in pre[t.id]} & {role[ABORT]}
                      and not {a.source for a in pre[t.id]} & {role[START]}), None)
        if abort is None:
            raise NoInterface(f"net '{net.name}': no transition aborts it while it runs (one "
                              "taking A but not B): it cannot stand for a child that may run "
                              "for ever until aborted")
        running = [a.source for a in pre[abort] if a.source != role[ABORT]]
        places.append(Place("STUCK"))
        transitions += [Transition("stray"), Transition("spin"), Transition("stop")]
        arcs += [Arc(p, "stray") for p in running] + [
            Arc("stray", "STUCK"), Arc("STUCK", "spin"), Arc("spin", "STUCK"),
            Arc("STUCK", "stop"), Arc(role[ABORT], "stop")]
        arcs += [Arc("stop", a.target) for a in net.arcs if a.source == abort]
    return Net(net.name, tuple(places), tuple(transitions), tuple(arcs), net.initial)


def _explore(net: Net, marking: dict[str, int], max_states: int):
    try:
        return explore(net.with_initial({p: n for p, n in marking.items() if n}),
                       max_states=max_states)
    except ExplorationLimit as e:
        raise ExplorationLimit(f"net '{net.name}' has more than {max_states:,} markings from "
                               "its start: a component's contract is checked on a small net "
                               "(its children reduced)") from e


#: What a parent may do with a child's places: mark its B and A (and a callee's gate, given
#: back), take its results and a left A. Nothing else: not its mutex, not its inside.
PARENT_MARKS, PARENT_TAKES = {START, ABORT, "GATE"}, {ABORT, "GATE", *RESULTS}


def _discipline(net: Net, children: tuple[str, ...]) -> list[Breach]:
    """The structural half of the ``caller`` clause: the parent's transitions touch each
    child's places only as :data:`PARENT_MARKS` and :data:`PARENT_TAKES` say, with plain
    arcs (a parent that read a child's B, or took its mutex, would see the child in a
    state its reduced model has not)."""
    out = []
    for a in net.arcs:
        for prefix in children:
            child_place = a.target if a.target.startswith(prefix) else (
                a.source if a.source.startswith(prefix) else None)
            other = a.source if child_place == a.target else a.target
            if child_place is None or other.startswith(prefix):
                continue
            role = child_place[len(prefix):]
            marks = child_place == a.target
            if a.kind.value != "normal" or role not in (PARENT_MARKS if marks else PARENT_TAKES):
                out.append(Breach(Clause.CALLER, "the net", (), (),
                                  f"{other} {'marks' if marks else 'takes'} {child_place}"
                                  + ("" if a.kind.value == "normal" else f" ({a.kind.value})")
                                  + ": a parent only marks a child's B and A, and takes its "
                                    "results and a left A"))
    return out


def _asleep(net: Net, role: dict[str, str], own: Own | None) -> list[Breach]:
    """The ``asleep`` clause: each own transition needs B or an own place empty at rest."""
    transitions = own.transitions if own is not None else {t.id for t in net.transitions}
    foreign = own.foreign if own is not None else frozenset()
    interface = {role[r] for r in (ABORT, *RESULTS)}
    wakers = {role[START]} | {p.id for p in net.places if p.id not in foreign
                              and p.id not in interface and not net.initial[p.id]}
    needs: dict[str, bool] = dict.fromkeys(transitions, False)
    for a in net.arcs:
        if a.target in needs and a.source in wakers:
            needs[a.target] = True
    return [Breach(Clause.ASLEEP, "the net", (), (),
                   f"{t} needs neither B nor a place of its own that is empty at rest: at "
                   "rest, the places it shares with other parts could wake it")
            for t in sorted(t for t, ok in needs.items() if not ok)]


def _callers(space, children: tuple[str, ...], label: str) -> list[Breach]:
    """The ``caller`` clause: each child (places prefixed so) started only at rest."""
    out: list[Breach] = []
    index = space.structure.place_index
    for prefix in children:
        start = index.get(f"{prefix}{START}")
        if start is None:       # never a child that is held to nothing
            raise NoInterface(f"no place {prefix}{START}: the child '{prefix}' cannot be "
                              "held to the caller clause")
        busy = [index[f"{prefix}{p}"] for p in ("EXE", "STUCK", *RESULTS)
                if f"{prefix}{p}" in index]
        node = next((n for n in range(space.states) if space.markings[n][start]
                     and any(space.markings[n][k] for k in busy)), None)
        if node is not None:
            out.append(Breach(Clause.CALLER, label, tuple(space.path_to(node)),
                              _marked(space, node), f"{prefix}{START} is marked while the "
                              "child is running or holds a result"))
    return out


def _marked(space, node: int) -> tuple[str, ...]:
    return tuple(space.format(node))


def _started(space, role: dict[str, str], rest: dict[str, int], label: str,
             aborted: bool) -> tuple[list[Breach], frozenset[str]]:
    """The breaches found from one start, and the results its ends give."""
    s = space.structure
    index = s.place_index
    out: list[Breach] = []

    def breach(clause: Clause, node: int, why: str) -> None:
        out.append(Breach(clause, label, tuple(space.path_to(node)), _marked(space, node), why))

    if not space.bounded or space.bound > 1:
        node = next(n for n in range(space.states) if max(space.markings[n]) > 1)
        twice = [s.places[k] for k, n in enumerate(space.markings[node]) if n > 1]
        breach(Clause.SAFE, node, f"{', '.join(twice)} holds two tokens or more")
        return out, frozenset()   # the other clauses are read on a safe net's markings
    # every marking decoded once: the clauses below read each several times
    markings = list(space.markings)
    results = [index[role[r]] for r in RESULTS]
    control = {index[role[START]], index[role[ABORT]], *results}
    ends = []
    for node in space.terminal:
        m = markings[node]
        held = [r for r, k in zip(RESULTS, results) if m[k]]
        left = [s.places[k] for k in range(len(s.places)) if k not in control
                and m[k] != rest.get(s.places[k], 0)]
        if len(held) != 1 or m[index[role[START]]]:
            breach(Clause.ENDS, node, "a dead marking that is no end: "
                   + (f"results {', '.join(held)}" if held else "no result")
                   + (", B still marked" if m[index[role[START]]] else ""))
            continue
        if left:
            breach(Clause.ENDS, node, f"ended {held[0]} with {', '.join(left)} not back at rest")
            continue
        ends.append(node)
        a_left = bool(m[index[role[ABORT]]])
        if held[0] == "ABORTED" and (not aborted or a_left):
            breach(Clause.ABORT, node, "ended ABORTED " + ("with no abort asked" if not aborted
                                                           else "and A still marked"))
        elif held[0] != "ABORTED" and aborted and not a_left:
            breach(Clause.ABORT, node, f"ended {held[0]} but consumed A")
    late = next((n for n in range(space.states)
                 if any(markings[n][k] for k in results)
                 and any(markings[n][k] != rest.get(s.places[k], 0)
                         for k in range(len(s.places)) if k not in control)), None)
    if late is not None:
        m = markings[late]
        busy = [s.places[k] for k in range(len(s.places)) if k not in control
                and m[k] != rest.get(s.places[k], 0)]
        breach(Clause.RESULT_LAST, late, f"a result is marked while {', '.join(busy)} "
                                         "is not back at rest")
    dead = set(space.terminal)
    moving = next((n for n in range(space.states) if n not in dead
                   and any(markings[n][k] for k in results)), None)
    if moving is not None:
        m = markings[moving]
        fires = [t for j, t in enumerate(s.transitions) if s.enabled(m, j)]
        breach(Clause.RESULT_FINAL, moving, f"a result is marked and {', '.join(fires)} can "
                                            "still fire: a caller may take the result first")
    if ends:
        reach = space.can_reach(ends)
        stuck = next((n for n in range(space.states) if not reach[n]), None)
        if stuck is not None:
            breach(Clause.ALWAYS_ENDS, stuck, "no end can be reached from here")
    elif not space.terminal:
        breach(Clause.ALWAYS_ENDS, 0, "the component never ends")
    return out, frozenset(RESULTS[next(k for k, r in enumerate(results)
                                       if markings[n][r])] for n in ends)
