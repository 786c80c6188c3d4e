"""TAPAAL's timed-arc Petri nets: a compiled mission under its timed semantics, and queries.

TAPAAL's discrete-time engine, verifydtapn, reads a timed-arc net in
TAPAAL's PNML dialect (one flat ``<net>``; ``<place invariant="&lt;= 10">``,
``<transition urgent="true">``, ``<inputArc inscription="[a,b]">``,
``<outputArc>``, ``<transportArc>``, ``<inhibitorArc>``) and a query as
text, one of ``EF φ``, ``AG φ``, ``AF φ``, ``EG φ`` over place names,
``and``, ``or``, ``not`` and ``deadlock``. There, time lives in the tokens:
each token has an age, a place's invariant bounds the ages of its tokens
(time cannot pass beyond it), an input arc's interval guards the age of the
token it takes, an output arc makes a token of age 0, a transport arc moves
one and keeps its age, and an urgent transition lets no time pass while it
is enabled (urgency, not priority: other transitions may fire first at the
same instant).

The semantics written is the project's (:func:`mcl2pnml.core.timing.mission_timing`):
every transition has a static interval whose clock starts when it becomes
enabled, a primitive's reports are some seconds apart, and the supervisor's
steps are urgent, not first (``Assumptions(priority=False)``: TAPAAL has
urgency and no priorities). It is written in token ages as follows:

* ``[0, ∞)`` (a report): an ordinary transition;
* ``[0, 0]`` (a supervisor step; an acknowledgement when they come at once):
  an urgent transition;
* anything else (a time-out ``[T, T]``, an acknowledgement ``[0, K]``): a
  clock, a token of its own in a place ``CLK`` that nothing else reads, one per
  transition or per group of :attr:`~mcl2pnml.core.timing.TimedNet.shared`
  (a disable's three acknowledgements ``off_C``, ``off_S1``, ``off_S2``: one
  clock, which starts when the first of them becomes enabled and runs while
  one of them is). An urgent ``start`` per member makes it the instant that
  member is enabled (it reads the member's inputs and is inhibited by
  ``CLK``); an urgent ``stop`` takes it the instant no member is enabled, one
  per way of disabling them all (inhibited by one input place of each
  member, the minimal sets). A member takes the clock token with the guard
  ``[a, b]``, and ``CLK`` has the invariant ``<= b``: it fires between a and b
  units after the clock started, or every member is disabled before; when a
  member fires and another stays enabled, ``start`` makes a new clock at
  once, as the semantics restarts it. A token's age in an input place would
  not do: a time-out reads its primitive's ``ON``, which the vehicle marks up
  to K seconds after the task's ``EXE``. Urgency alone would let the group be
  disabled and enabled again at one instant before ``stop`` took the old
  clock; so a transition that marks a member's input place without taking a
  token from it (in a 1-safe net it can fire only when that place is empty,
  that member disabled) is written once inhibited by ``CLK`` (it waits, at
  the same instant, for ``stop``) and once per other member, reading that
  member's inputs (``..._while_M``: M is enabled, the clock is not stale and
  runs on; a report that moves the goal while the disable is pending). The
  construction needs the places it watches to hold one token at most, as in
  every compiled mission (the mission's certificate proves it); arcs of
  weight 2 or more on them, or two initial tokens, are refused, and
  :func:`safety_query` asks verifydtapn to check the rest;
* a primitive's reports, at least d units apart: a place ``FIRST`` (one
  token) and a place ``GAP``; each report is written twice, once taking
  ``FIRST`` (the first report of the run, at any time) and once taking
  ``GAP``'s token with the guard ``[d, ∞)``, both putting a token of age 0
  in ``GAP``;
* read arcs are transport arcs from the place back to it (the token keeps
  its age).

Time bounds are whole numbers in verifydtapn: bounds that are not whole
seconds are written in a finer unit (a power of ten, named in a comment at
the top of the file), as :func:`mcl2pnml.core.timing.mission_timing` chose
it. Fairness (a primitive that is on reports eventually) is beyond what a
timed-arc net says without priorities and is refused, as is ``priority``.

Names in text queries are letters, digits and ``_``: every node id is
written so (``mission.OK`` as ``mission_OK``), one distinct name per node,
the original id in a comment beside every node whose name differs, and the
mapping kept in :attr:`TimedArcNet.names` for the queries.
"""
from __future__ import annotations

import json
import re
from dataclasses import dataclass, field, replace
from fractions import Fraction
from pathlib import Path
from typing import Iterable, Mapping

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.files import atomic_write_text
from mcl2pnml.core.net import ArcKind, Net
from mcl2pnml.core.payloads import RESULT_PLACES
from mcl2pnml.core.patterns import (Grouping, Pattern, Predicate, PredicateSyntax, Property,
                                      ScopeKind, describe)
from mcl2pnml.core.timing import (Assumptions, TimedNet, exact_seconds, mission_timing,
                                  seconds_text)
from mcl2pnml.core.version import __version__
from mcl2pnml.core.vocabulary import ENDS, STALL

#: The assumptions a timed-arc net is written under unless told: TAPAAL's urgency, no priority.
TAPAAL_ASSUMPTIONS = Assumptions(priority=False)
NAMESPACE = "http://www.informatik.hu-berlin.de/top/pnml/ptNetb"
#: Words of verifydtapn's query language, never used as a name.
_RESERVED = frozenset({"ef", "eg", "af", "ag", "and", "or", "not", "deadlock", "true",
                       "false", "e", "a", "f", "g", "x", "u"})
_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")


class TapnError(Mcl2PnmlError):
    """A net or an assumption a timed-arc net cannot say exactly."""


# -- the timed-arc net -----------------------------------------------------------------------

@dataclass(frozen=True)
class TPlace:
    id: str
    tokens: int = 0
    #: the age bound of its tokens, in units (None: no bound)
    invariant: int | None = None


@dataclass(frozen=True)
class TTransition:
    id: str
    urgent: bool = False


@dataclass(frozen=True)
class TArc:
    """One arc: ``kind`` input, output, transport (``via`` the transition) or inhibitor."""

    kind: str
    source: str
    target: str
    #: the guard on the age of the token taken, in units (an input or transport arc)
    guard: tuple[int, int | None] = (0, None)
    weight: int = 1
    via: str | None = None


@dataclass(frozen=True)
class TimedArcNet:
    """A net written for verifydtapn, and how it relates to the net it was written from."""

    name: str
    places: tuple[TPlace, ...]
    transitions: tuple[TTransition, ...]
    arcs: tuple[TArc, ...]
    #: original node id -> its name here
    names: Mapping[str, str]
    #: original transition id -> the transitions here that fire it (a report: two)
    copies: Mapping[str, tuple[str, ...]]
    #: the length of one unit of time, in seconds
    unit: Fraction
    assumptions: Assumptions
    #: the places whose safety the clocks rest on (names here)
    watched: tuple[str, ...] = ()
    #: what the file says first, for its reader
    notes: tuple[str, ...] = ()
    #: each added node's name -> what it is for
    added: Mapping[str, str] = field(default_factory=dict)

    def name_of(self, node_id: str) -> str:
        """The name of an original node here; an id the net does not have is an error."""
        try:
            return self.names[node_id]
        except KeyError:
            raise TapnError(f"net '{self.name}' has no node '{node_id}'") from None

    @property
    def bound(self) -> int:
        """A k-bound for verifydtapn (``-k``) no reachable marking exceeds in a 1-safe net."""
        return max(1, len(self.places) + sum(p.tokens for p in self.places))

    def units(self, seconds: Fraction | int | float, what: str) -> int:
        """``seconds`` in this net's units; refused when it is not a whole number of them."""
        value = exact_seconds(seconds) / self.unit
        if value.denominator != 1 or value < 0:
            raise TapnError(f"{what} ({seconds_text(exact_seconds(seconds))} s) is not a whole "
                            f"number of the net's time unit ({seconds_text(self.unit)} s)")
        return int(value)


class _Names:
    """Distinct query-safe names: letters, digits and ``_``, never a word of the language."""

    def __init__(self) -> None:
        self.used: set[str] = set()

    def take(self, wanted: str) -> str:
        base = re.sub(r"[^A-Za-z0-9_]", "_", wanted) or "n"
        if not base[0].isalpha():
            base = "n" + base
        name, k = base, 1
        while name in self.used or name.lower() in _RESERVED:
            k += 1
            name = f"{base}_{k}"
        self.used.add(name)
        return name


def timed_arc_net(net: Net, assumptions: Assumptions = TAPAAL_ASSUMPTIONS,
                  timed: TimedNet | None = None) -> TimedArcNet:
    """``net`` under ``assumptions`` as a timed-arc net (see the module's documentation).

    ``timed``: the timed semantics to write, when the caller has one already
    (default: :func:`~mcl2pnml.core.timing.mission_timing` of ``net``).
    """
    _refuse_unsaid(assumptions)
    try:
        timed = timed or mission_timing(net, assumptions)
    except Mcl2PnmlError as e:
        raise TapnError(f"net '{net.name}': {e.message}") from None
    names = _Names()
    name = {p.id: names.take(p.id) for p in net.places}
    name.update({t.id: names.take(t.id) for t in net.transitions})
    added: dict[str, str] = {}

    def new(wanted: str, what: str) -> str:
        n = names.take(wanted)
        added[n] = what
        return n

    places = [TPlace(name[p.id], net.initial[p.id]) for p in net.places]
    inputs, urgent = _inputs(net, timed, name)
    extra_t: list[TTransition] = []
    extra_a: list[TArc] = []
    watched: dict[str, None] = {}
    # per original transition: the clocks it must not restart by mistake, each a list of
    # the ways it may fire (see _clock)
    guards: dict[str, list[list[tuple[str, str, list[TArc]]]]] = {t.id: [] for t in net.transitions}
    for members, (lo, hi) in _timers(net, timed):
        _clock(net, members, (lo, hi), name, new, places, inputs, extra_t, extra_a, guards,
               watched)
    _one_token_each(net, watched)
    gap_of = _report_gaps(timed, new, places)
    transitions, arcs, copies = _variants(net, name, new, inputs, urgent, guards, gap_of)
    notes = [f"{net.name or 'net'}: written by mcl2pnml {__version__} for TAPAAL's "
             "verifydtapn (discrete time)",
             f"time unit: {seconds_text(timed.unit)} s (every age bound below counts this unit)",
             f"assumptions: {assumptions.words()}"]
    return TimedArcNet(net.name or "net", tuple(places), tuple(transitions + extra_t),
                       tuple(arcs + extra_a), name, copies, timed.unit, assumptions,
                       tuple(name[p] for p in watched), tuple(notes), added)


def _refuse_unsaid(assumptions: Assumptions) -> None:
    """Refuse the assumptions a timed-arc net cannot say."""
    if assumptions.priority:
        raise TapnError("TAPAAL's urgent transitions are not first at their instant: a "
                        "timed-arc net is written with the supervisor's steps urgent only "
                        "(assumptions without priority)")
    if assumptions.fair:
        raise TapnError("a timed-arc net cannot say that a primitive reports eventually "
                        "(fairness) without a bound; it is written without it")


def _inputs(net: Net, timed: TimedNet, name: Mapping[str, str]
            ) -> tuple[dict[str, list[TArc]], set[str]]:
    """Per original transition, its input arcs here (a read arc a transport arc back into
    its place), to which the clocks and gaps add; and the transitions that are urgent."""
    inputs: dict[str, list[TArc]] = {}
    urgent: set[str] = set()
    for t in net.transitions:
        lo, hi = timed.intervals.get(t.id, (0, None))
        n = name[t.id]
        arcs = []
        for a in net.pre[t.id]:
            if a.kind is ArcKind.READ:
                arcs.append(TArc("transport", name[a.source], name[a.source], weight=a.weight,
                                 via=n))
            else:
                arcs.append(TArc("input", name[a.source], n, weight=a.weight))
        inputs[t.id] = arcs
        if (lo, hi) == (0, 0):
            urgent.add(t.id)
    return inputs, urgent


def _one_token_each(net: Net, watched: Mapping[str, None]) -> None:
    """Refuse a place a clock watches that may hold two tokens: the clocks are written for
    places of one token."""
    for p in watched:
        if net.initial[p] > 1:
            raise TapnError(f"place '{p}' starts with {net.initial[p]} tokens: the clocks of "
                            "the transitions it enables are written for places of one token")
        for a in net.arcs:
            if p in (a.source, a.target) and a.weight != 1:
                raise TapnError(f"place '{p}' has an arc of weight {a.weight} "
                                f"({a.source} -> {a.target}): the clocks of the transitions "
                                "it enables are written for places of one token")


def _report_gaps(timed: TimedNet, new, places: list[TPlace]) -> dict[str, tuple[str, str, int]]:
    """The reports' gaps: per primitive, a place of no report yet and one whose token's age
    is the time since the last report (added to ``places``); per report transition, those
    two places and its gap."""
    gap_of: dict[str, tuple[str, str, int]] = {}
    for members, gap in timed.gaps:
        if gap <= 0:
            continue
        who = timed.names.get(min(members), min(members))
        first = new(f"FIRST_{who}", f"no report of {who} yet")
        last = new(f"GAP_{who}", f"the time since the last report of {who}")
        places += [TPlace(first, 1), TPlace(last, 0)]
        for t_id in members:
            gap_of[t_id] = (first, last, gap)
    return gap_of


def _variants(net: Net, name: Mapping[str, str], new, inputs: Mapping[str, list[TArc]],
              urgent: set[str], guards: Mapping[str, list], gap_of: Mapping[str, tuple]
              ) -> tuple[list[TTransition], list[TArc], dict[str, tuple[str, ...]]]:
    """Each original transition as its copies here, with their arcs: a report twice (the
    first of the run, and one after a gap), each copy once per way of firing a clock it
    must not restart by mistake; and the copies of each."""
    transitions: list[TTransition] = []
    arcs: list[TArc] = []
    copies: dict[str, tuple[str, ...]] = {}
    for t in net.transitions:
        n = name[t.id]
        variants = [(n, [])]
        if t.id in gap_of:
            first, last, gap = gap_of[t.id]
            again = new(f"{n}_again", f"{t.id} after an earlier report of its primitive")
            variants = [(n, [TArc("input", first, n)]),
                        (again, [TArc("input", last, again, guard=(gap, None))])]
        for guard in guards[t.id]:
            # a clock it must not restart by mistake: each variant once per way of firing
            variants = [(v if k == 0 else new(f"{v}_{suffix}", f"{t.id} {what}"), own + extra)
                        for v, own in variants for k, (suffix, what, extra) in enumerate(guard)]
        copies[t.id] = tuple(v for v, _ in variants)
        for v, own in variants:
            transitions.append(TTransition(v, urgent=t.id in urgent))
            for a in inputs[t.id] + own:
                arcs.append(replace(a, via=v) if a.kind == "transport" else replace(a, target=v))
            for a in net.post[t.id]:
                arcs.append(TArc("output", v, name[a.target], weight=a.weight))
            if t.id in gap_of:
                arcs.append(TArc("output", v, gap_of[t.id][1]))
    return transitions, arcs, copies


def _timers(net: Net, timed: TimedNet) -> list[tuple[list[str], tuple[int, int | None]]]:
    """The clocks to write: one per group of :attr:`TimedNet.shared` and one per other
    transition whose interval is neither ``[0, 0]`` nor ``[0, inf)``; each as its members
    (in the net's order) and their interval."""
    order = {t.id: k for k, t in enumerate(net.transitions)}
    out, grouped = [], set()
    for group in timed.shared:
        members = sorted(group, key=order.__getitem__)
        spans = {timed.intervals.get(t, (0, None)) for t in members}
        if len(spans) > 1:
            raise TapnError("transitions sharing a clock must share their interval: "
                            + ", ".join(members))
        (span,) = spans
        grouped.update(members)
        if span not in ((0, 0), (0, None)):
            out.append((members, span))
    for t in net.transitions:
        span = timed.intervals.get(t.id, (0, None))
        if t.id not in grouped and span not in ((0, 0), (0, None)):
            out.append(([t.id], span))
    return out


#: The most transitions a clock's ``stop`` may need (one per way of disabling every member).
MAX_STOPS = 64


def _clock(net: Net, members: list[str], span: tuple[int, int | None], name: dict, new,
           places: list, inputs: dict, extra_t: list, extra_a: list, guards: dict,
           watched: dict) -> None:
    """One clock shared by ``members`` (see the module's documentation): its place, a
    ``start`` per member, a ``stop`` per way of disabling them all, each member guarded by
    it, and the guards of the transitions that could enable a member while a stale clock
    is still there."""
    pre, post = net.pre, net.post
    lo, hi = span
    single = len(members) == 1
    label = name[members[0]] if single else _common(name[t] for t in members)
    what = members[0] if single else ", ".join(members)
    clock = new(f"CLK_{label}", f"the clock of {what}: its age is the time since "
                + ("it was" if single else "one of them was first") + " enabled")
    places.append(TPlace(clock, 0, hi))
    needs = {}
    for t_id in members:
        needs[t_id] = [a.source for a in pre[t_id]]
        for a in pre[t_id]:
            if a.weight != 1:
                raise TapnError(f"transition '{t_id}' is timed and takes {a.weight} tokens "
                                f"from '{a.source}': its clock is written for places of one "
                                "token")
            watched[a.source] = None
        start = new(f"start_{name[t_id]}", f"starts the clock of {t_id} when it is enabled"
                    + ("" if single else " and no other of its clock is"))
        extra_t.append(TTransition(start, urgent=True))
        extra_a.append(TArc("inhibitor", clock, start))
        extra_a.append(TArc("output", start, clock))
        for p in needs[t_id]:
            extra_a.append(TArc("transport", name[p], name[p], via=start))
        inputs[t_id].append(TArc("input", clock, name[t_id], guard=(lo, hi)))
    # stop: every member disabled, by one empty input place each (minimal sets only)
    ways: list[frozenset[str]] = [frozenset()]
    for t_id in members:
        ways = list({w | {p} for w in ways for p in needs[t_id]})
        ways = [w for w in ways if not any(o < w for o in ways)]
        if len(ways) > MAX_STOPS:
            raise TapnError(f"the clock shared by {what} needs more than {MAX_STOPS} "
                            "transitions to stop")
    for way in sorted(ways, key=sorted):
        empty = sorted(way)
        stop = new(f"stop_{label}_" + "_".join(name[p] for p in empty),
                   f"takes the clock of {what} when " + " and ".join(empty)
                   + (" is" if len(empty) == 1 else " are") + " emptied")
        extra_t.append(TTransition(stop, urgent=True))
        extra_a.append(TArc("input", clock, stop))
        extra_a.extend(TArc("inhibitor", name[p], stop) for p in empty)
    # a transition that marks a member's input place without taking a token from it can
    # fire only when that place is empty (the net is 1-safe): that member is disabled.
    # Unless another member is enabled, the clock is then stale (stop takes it at this
    # instant): it waits for stop, or it fires while another member is enabled (the clock
    # runs on, the group stays enabled before it)
    for u in net.transitions:
        if u.id in members:
            continue
        taken = {a.source for a in pre[u.id]}
        made = {a.target for a in post[u.id]} - {a.source for a in pre[u.id]
                                                  if a.kind is ArcKind.NORMAL}
        if not any(made & set(needs[t_id]) for t_id in members):
            continue
        ways_u = [("", "", [TArc("inhibitor", clock, name[u.id])])]
        for t_id in members if not single else ():
            if made & set(needs[t_id]):
                continue     # it cannot be enabled when u fires
            reads = [p for p in needs[t_id] if p not in taken]
            ways_u.append((f"while_{name[t_id]}", f"while {t_id} is enabled (the clock of "
                           f"{what} runs on)",
                           [TArc("transport", name[p], name[p], via=name[u.id]) for p in reads]))
        guards[u.id].append(ways_u)


def _common(names) -> str:
    """The longest common prefix of ``names``, without a trailing ``_``."""
    names = list(names)
    prefix = names[0]
    for n in names[1:]:
        while not n.startswith(prefix):
            prefix = prefix[:-1]
    return prefix.rstrip("_") or "shared"


# -- writing -------------------------------------------------------------------------------

def _interval(guard: tuple[int, int | None]) -> str:
    lo, hi = guard
    return f"[{lo},inf)" if hi is None else f"[{lo},{hi}]"


def _comment(text: str) -> str:
    return "<!-- " + text.replace("--", "-\\u002d") + " -->"


def timed_arc_text(tnet: TimedArcNet) -> str:
    """The timed-arc net as TAPAAL's PNML (the dialect verifydtapn reads)."""
    original = {v: k for k, v in tnet.names.items() if k != v}
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', f'<pnml xmlns="{NAMESPACE}">']
    lines += ["  " + _comment(n) for n in tnet.notes]
    lines.append(f'  <net id="{tnet.name if _NAME.match(tnet.name) else "net"}" '
                 'type="P/T net">')

    def note(node: str) -> None:
        if node in original:
            lines.append("    " + _comment(f"{node}: {json.dumps(original[node])}"))
        elif node in tnet.added:
            lines.append("    " + _comment(f"{node}: {tnet.added[node]}"))

    for p in tnet.places:
        note(p.id)
        inv = "&lt; inf" if p.invariant is None else f"&lt;= {p.invariant}"
        lines.append(f'    <place id="{p.id}" name="{p.id}" invariant="{inv}" '
                     f'initialMarking="{p.tokens}"/>')
    for t in tnet.transitions:
        note(t.id)
        lines.append(f'    <transition id="{t.id}" name="{t.id}" '
                     f'urgent="{"true" if t.urgent else "false"}"/>')
    for a in tnet.arcs:
        weight = "" if a.weight == 1 else f' weight="{a.weight}"'
        if a.kind == "input":
            lines.append(f'    <inputArc inscription="{_interval(a.guard)}" source="{a.source}" '
                         f'target="{a.target}"{weight}/>')
        elif a.kind == "output":
            lines.append(f'    <outputArc inscription="1" source="{a.source}" '
                         f'target="{a.target}"{weight}/>')
        elif a.kind == "transport":
            lines.append(f'    <transportArc inscription="{_interval(a.guard)}" '
                         f'source="{a.source}" transition="{a.via}" target="{a.target}"'
                         f'{weight}/>')
        else:
            lines.append(f'    <inhibitorArc inscription="[0,inf)" source="{a.source}" '
                         f'target="{a.target}"{weight}/>')
    lines += ["  </net>", "</pnml>"]
    return "\n".join(lines) + "\n"


def to_tapn(net: Net, *, timing: Assumptions | None = None) -> str:
    """``net`` as TAPAAL's timed-arc PNML under ``timing`` (None: :data:`TAPAAL_ASSUMPTIONS`)."""
    return timed_arc_text(timed_arc_net(net, timing or TAPAAL_ASSUMPTIONS))


def write_tapn(net: Net, path: str | Path, *, timing: Assumptions | None = None) -> Path:
    """Write ``net`` to ``path`` as a timed-arc net under ``timing``, whole or not at all."""
    atomic_write_text(path, to_tapn(net, timing=timing))
    return Path(path)


# -- queries ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Query:
    """One query for verifydtapn: a name (the file's middle suffix), what it asks, its text."""

    name: str
    description: str
    text: str


def predicate_text(predicate: Predicate, tnet: TimedArcNet) -> str:
    """A predicate on places in verifydtapn's words, with the net's names: the one printer
    of predicates (:func:`mcl2pnml.core.patterns.describe`) in verifydtapn's syntax."""
    return describe(predicate, PredicateSyntax(name=tnet.name_of, grouping=Grouping.WHOLE,
                                               empty_sum_as_truth=True))


def _results(tnet: TimedArcNet) -> list[str]:
    missing = [r.id for r in RESULT_PLACES if r.id not in tnet.names]
    if missing:
        raise TapnError(f"net '{tnet.name}' is not a compiled mission: it has no "
                        f"{', '.join(missing)}")
    return [tnet.names[r.id] for r in RESULT_PLACES]


def ends_query(tnet: TimedArcNet) -> Query:
    """"Every run ends": every run, however time passes, marks a result."""
    some = " or ".join(f"{r} = 1" for r in _results(tnet))
    return Query("ends", f"{ENDS} (AF a result)", f"AF ({some})\n")


def deadlock_query(tnet: TimedArcNet) -> Query:
    """A stall: nothing can fire now or after any delay, and no result is marked."""
    none = " and ".join(f"{r} = 0" for r in _results(tnet))
    return Query("deadlock", f"{STALL} (EF deadlock and no result)",
                 f"EF (deadlock and {none})\n")


def safety_query(tnet: TimedArcNet) -> Query | None:
    """What the clocks rest on: the places they watch never hold two tokens (None: none)."""
    if not tnet.watched:
        return None
    each = " and ".join(f"{p} <= 1" for p in tnet.watched)
    return Query("safe", "the places the clocks watch hold one token at most (AG)",
                 f"AG ({each})\n")


def property_query(prop: Property, tnet: TimedArcNet) -> Query | None:
    """A mission's property as one query, where a single state formula says it exactly
    (None: not so). Absence and universality globally are invariants (``AG``); existence
    globally is ``AF``: on every maximal timed run, time passing for ever included."""
    if prop.scope.kind is not ScopeKind.GLOBALLY:
        return None
    p = predicate_text(prop.p, tnet)
    if prop.pattern is Pattern.ABSENCE:
        text = f"AG not ({p})"
    elif prop.pattern is Pattern.UNIVERSALITY:
        text = f"AG ({p})"
    elif prop.pattern is Pattern.EXISTENCE:
        text = f"AF ({p})"
    else:
        return None
    return Query(f"property.{_file_part(prop.name)}", f"{prop.name}: {prop.text or prop.pattern.value}",
                 text + "\n")


def _file_part(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_-]", "_", text) or "p"


def mission_queries(tnet: TimedArcNet, properties: Iterable[Property] = ()) -> list[Query]:
    """The queries written beside a mission's timed-arc net."""
    out = [ends_query(tnet), deadlock_query(tnet)]
    safe = safety_query(tnet)
    if safe is not None:
        out.append(safe)
    out += [q for q in (property_query(p, tnet) for p in properties) if q is not None]
    return out


def query_path(net_path: str | Path, query: Query) -> Path:
    """Where a query goes beside the net: ``OUT.tapn`` -> ``OUT.ends.q``."""
    path = Path(net_path)
    stem = path.with_suffix("") if path.suffix else path
    return stem.with_name(f"{stem.name}.{query.name}.q")


def query_paths(net: Net, net_path: str | Path, timing: Assumptions | None = None,
                properties: Iterable[Property] = ()) -> list[Path]:
    """The files :func:`write_queries` would write (for checking outputs beforehand)."""
    tnet = timed_arc_net(net, timing or TAPAAL_ASSUMPTIONS)
    return [query_path(net_path, q) for q in mission_queries(tnet, properties)]


def write_queries(net: Net, net_path: str | Path, timing: Assumptions | None = None,
                  properties: Iterable[Property] = ()) -> list[tuple[Path, Query, int]]:
    """Write the mission's queries beside its timed-arc net at ``net_path``; returns each
    file, its query, and the k-bound to give verifydtapn (``-k``)."""
    tnet = timed_arc_net(net, timing or TAPAAL_ASSUMPTIONS)
    written = []
    for q in mission_queries(tnet, properties):
        path = query_path(net_path, q)
        atomic_write_text(path, q.text)
        written.append((path, q, tnet.bound))
    return written


# -- time bounds: an observer --------------------------------------------------------------

def deadline_net(net: Net, seconds: Fraction | int | float,
                 timing: Assumptions | None = None) -> tuple[TimedArcNet, Query]:
    """The net with an observer of time ``seconds`` and the query "some run has no result
    at that time" (``EF LATE = 1``): a place ``CLOCK`` (one token, never reset, no
    invariant), a transition ``late`` that takes it with the guard ``[W, ∞)`` and is
    inhibited by every result place, into ``LATE``. It fires only at W or later, while no
    result is marked; a result stays marked once marked, so it fires on a run exactly when
    that run is still without a result at some moment of time W (perhaps just before the
    result, at the same instant: the query's answer for W is whether a run ends at W or
    later)."""
    tnet = timed_arc_net(net, timing or TAPAAL_ASSUMPTIONS)
    results = _results(tnet)
    w = tnet.units(seconds, "the time bound")
    names = _Names()
    names.used = set(tnet.names.values()) | set(tnet.added)
    clock, late, done = names.take("CLOCK"), names.take("late"), names.take("LATE")
    at = seconds_text(Fraction(w) * tnet.unit)
    observer = TimedArcNet(
        tnet.name, tnet.places + (TPlace(clock, 1), TPlace(done, 0)),
        tnet.transitions + (TTransition(late),),
        tnet.arcs + (TArc("input", clock, late, guard=(w, None)), TArc("output", late, done),
                     *(TArc("inhibitor", r, late) for r in results)),
        tnet.names, tnet.copies, tnet.unit, tnet.assumptions, tnet.watched,
        tnet.notes + (f"observer: {late} fires at {at} s or "
                      f"later while no result is marked",),
        {**tnet.added, clock: "the time since the start", late: "no result yet at the bound",
         done: "a run had no result at the bound"})
    return observer, Query(f"late{w}", f"some run has no result at {at} s",
                           f"EF {done} = 1\n")


def write_deadline(net: Net, path: str | Path, seconds: Fraction | int | float,
                   timing: Assumptions | None = None) -> tuple[Path, Path, int]:
    """Write the observer net of :func:`deadline_net` to ``path`` and its query beside it;
    returns the net's file, the query's, and the k-bound to give verifydtapn."""
    observer, query = deadline_net(net, seconds, timing)
    atomic_write_text(path, timed_arc_text(observer))
    qpath = query_path(path, query)
    atomic_write_text(qpath, query.text)
    return Path(path), qpath, observer.bound
