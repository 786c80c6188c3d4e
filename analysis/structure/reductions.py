"""Structural reductions: a smaller net that answers a question as the net does.

A question sees some places and transitions: the places its atoms count, the transitions
whose fireability it asks, and those transitions' input places (*visible*; the rest is
*hidden*). :func:`reduced` rewrites the net, rule after rule until none applies, keeping

    (R) the markings the reduced net reaches, restricted to the visible places, are exactly
        the reachable markings of the net restricted to them; and a visible transition is
        kept with all its input arcs.

So ``E F φ``, ``A G φ`` (φ a state formula over visible places and transitions, without
``deadlock``) and the upper bound of a sum of visible places have the same answer on both
nets. Deadlocks are *not* kept (a hidden transition removed may have been the only one
enabled), and paths (CTL, LTL) only by the rules :class:`Keep` names for them (one that
fires for ever may be gone). Every rule below keeps (R) on its own, so their sequence
does. They are Berthelot's ("Checking
properties of nets using transformations", 1986) and verifypn's (Bonneland, Dyhr, Jensen,
Johannsen and Srba, "Stubborn versus structural reductions for Petri nets", 2019), with the
conditions written beside each:

* ``DEAD``: a transition with an input place that no run can mark (the places that may
  hold a token are closed from M0 under "every input place may hold one, so the outputs
  may") never fires; removed, it changes no reachable marking.
* ``CONSTANT``: a hidden place whose count no transition changes holds M0(p) in every
  reachable marking. A transition needing more is dead and removed; the others do not
  need the place's arc, always satisfied; the place goes.
* ``IRRELEVANT`` (verifypn's relevance rule): the transitions that change a visible place,
  or an input place of such a transition, and so on, are the relevant ones, with those
  places. Any other transition changes no relevant place and no relevant transition needs
  what it changes, so removing it keeps every run's relevant part fireable, and the
  relevant places' counts.
* ``DUPLICATE_TRANSITION``: two transitions with the same arcs fire alike; a hidden one
  goes where another stays.
* ``IMPLICIT_PLACE`` (verifypn's rule C, read arcs counted as needs): a hidden place q and
  another place p, with m the least number such that every transition needing q needs p,
  and no more than m times as much of q as of p; if every transition changes q by at
  least m times what it changes p by, and M0(q) >= m M0(p), then M(q) >= m M(p) in every
  reachable marking (by induction on the run), so q never stops a transition that p
  lets fire; removed, the runs are the same.
* ``SEQUENTIAL_PLACE`` (verifypn's rule A): a hidden place p, read by none, whose one
  consumer t takes w tokens from it and nothing else, is hidden and puts tokens in hidden
  places other than p only; every producer puts a multiple k w of tokens in p. t can fire
  as soon as its tokens are there and takes nothing anyone else needs, so it is fired at
  once: each producer puts k times t's outputs in their places instead, M0's tokens in p
  go on through t, and t and p go. A marking with tokens still in p differs from the one
  after t's firings only on hidden places.
* ``POST_AGGLOMERATION`` (Berthelot): a hidden place p, empty at M0, read by no
  transition, whose every consumer f takes one token from p and nothing else, is hidden
  and puts tokens in hidden places only; whose every producer h puts one token in p, is
  hidden and is not a consumer. Each pair becomes one transition "h then f". A consumer
  can fire as soon as its token is there and takes nothing anyone else needs, so every
  run can be reordered with each f right after its h, reaching the same marking; and a
  marking with tokens still in p differs from the one after its consumers only on hidden
  places. Applied only where the pairs are no more than the transitions they replace.
* ``PRE_AGGLOMERATION`` (Berthelot; verifypn's rule B): a hidden place p, empty at M0,
  read by none, with one consumer f, hidden and reading nothing, whose every producer h
  puts exactly f's weight in p and nothing else, reads nothing, is hidden and takes only
  from hidden places. Each h is delayed until f fires and fused with it (h's inputs and
  f's other inputs taken, f's outputs given); f and p go. In a run, delaying h only
  leaves more tokens in the places h takes from (so every other firing stays enabled),
  and those places and p, where the markings differ meanwhile, are hidden; a token h
  put in p that f never took is a firing of h left out, again hidden.
"""
from __future__ import annotations

import enum
import time
from dataclasses import dataclass
from fractions import Fraction
from typing import Iterable

import numpy as np

from mcl2pnml.core.net import Arc, ArcKind, Marking, Net, Transition

#: The rules in the order each round applies them.
RULES = ("DEAD", "CONSTANT", "IRRELEVANT", "DUPLICATE_TRANSITION", "IMPLICIT_PLACE",
         "SEQUENTIAL_PLACE", "POST_AGGLOMERATION", "PRE_AGGLOMERATION")


class Keep(enum.Enum):
    """What the reduced net must answer as the net does."""

    REACHABLE = "reachable"
    """The reachable markings on the visible places (R above): ``E F φ``, ``A G φ`` and
    upper bounds. Every rule."""

    PATHS = "paths"
    """Besides, every path up to repeated visible markings (stuttering), branching
    included: the reduced graph is divergence-sensitive branching bisimilar to the net's,
    so CTL and LTL without ``X`` and without ``deadlock`` answer alike (De Nicola and
    Vaandrager 1995). The rules that only drop what never fires or never matters (dead
    transitions, constant places, duplicate transitions, implicit places), the
    sequential places (the transition fired at once is an inert step that nothing
    disables and that commutes with every other: Groote and Sellink's confluence), and
    the irrelevant transitions where no run can fire them alone for ever (no
    ``x >= 0``, ``x != 0``, over them with ``C x >= 0``: by Dickson's lemma a run that
    did would repeat such a segment), as each then is a finite stutter."""


#: The rules each kind of question keeps its answer under.
KEPT_BY = {Keep.REACHABLE: RULES,
           Keep.PATHS: ("DEAD", "CONSTANT", "IRRELEVANT", "DUPLICATE_TRANSITION",
                        "IMPLICIT_PLACE", "SEQUENTIAL_PLACE")}
#: Seconds the rules may take on one net; each rule started is finished (one pass over
#: the net), so the result is the net after whole rules.
REDUCTION_SECONDS = 2.0


@dataclass(frozen=True)
class Reduced:
    """The reduced net, and how many places and transitions each rule removed."""

    net: Net
    removed: tuple[tuple[str, int], ...]

    @property
    def smaller(self) -> bool:
        """Whether any rule applied."""
        return bool(self.removed)


def reduced(net: Net, places: Iterable[str] = (), transitions: Iterable[str] = (),
            seconds: float = REDUCTION_SECONDS, keep: Keep = Keep.REACHABLE) -> Reduced:
    """``net`` reduced for a question that sees ``places`` and the fireability of
    ``transitions`` (the module's documentation: their input places are visible too).
    Kept places and transitions keep their ids, so the question reads the reduced net as
    it is; an agglomerated transition gets a new one. ``keep``: what it answers alike
    (:class:`Keep`), and so which rules apply. Past ``seconds``, no rule is
    started: the net as the rules applied so far left it is as sound. A name ``net``
    lacks raises KeyError."""
    work = _Work(net, places, transitions, keep)
    counts: dict[str, int] = {}
    deadline = time.monotonic() + seconds
    changed = True
    while changed and time.monotonic() < deadline:
        changed = False
        for rule in KEPT_BY[keep]:
            if time.monotonic() > deadline:
                break
            n = getattr(work, rule.lower())()
            if n:
                counts[rule] = counts.get(rule, 0) + n
                changed = True
    if not counts:
        return Reduced(net, ())
    return Reduced(work.net(), tuple(counts.items()))


class _Work:
    """The net being reduced, by indices: arcs as {place: weight} per transition, and
    each place's producers, consumers and readers, kept in step as nodes go."""

    def __init__(self, net: Net, places: Iterable[str], transitions: Iterable[str],
                 keep: Keep = Keep.REACHABLE):
        self.source = net
        self.keep = keep
        self.place_ids = [p.id for p in net.places]
        self.transitions = {t.id: t for t in net.transitions}
        pi = {p: i for i, p in enumerate(self.place_ids)}
        self.m0 = [net.initial[p] for p in self.place_ids]
        self.places = set(range(len(self.place_ids)))
        self.pre: dict[str, dict[int, int]] = {t: {} for t in self.transitions}
        self.read: dict[str, dict[int, int]] = {t: {} for t in self.transitions}
        self.post: dict[str, dict[int, int]] = {t: {} for t in self.transitions}
        for a in net.arcs:
            if a.source in self.transitions:
                self.post[a.source][pi[a.target]] = a.weight
            elif a.kind is ArcKind.READ:
                self.read[a.target][pi[a.source]] = a.weight
            else:
                self.pre[a.target][pi[a.source]] = a.weight
        self.seen_t = set(transitions)
        for t in self.seen_t:
            if t not in self.transitions:
                raise KeyError(t)
        self.seen_p = {pi[p] for p in places}
        for t in self.seen_t:
            self.seen_p.update(self.pre[t], self.read[t])
        # producers, consumers, readers of each place
        self.into: list[set[str]] = [set() for _ in self.place_ids]
        self.out: list[set[str]] = [set() for _ in self.place_ids]
        self.reads: list[set[str]] = [set() for _ in self.place_ids]
        for t in self.transitions:
            self._index(t)
        self.fresh = 0

    # -- bookkeeping --------------------------------------------------------------------------

    def _incident(self, t: str):
        """Each place index that lists ``t`` (producers, consumers, readers), with the
        places of ``t``'s arcs of that kind."""
        return ((self.into, self.post[t]), (self.out, self.pre[t]), (self.reads, self.read[t]))

    def _index(self, t: str) -> None:
        for index, arcs in self._incident(t):
            for p in arcs:
                index[p].add(t)

    def _drop_transition(self, t: str) -> None:
        for index, arcs in self._incident(t):
            for p in arcs:
                index[p].discard(t)
        for arcs in (self.pre, self.read, self.post):
            del arcs[t]
        del self.transitions[t]

    def _drop_place(self, p: int) -> None:
        for t in self.into[p]:
            del self.post[t][p]
        for t in self.out[p]:
            del self.pre[t][p]
        for t in self.reads[p]:
            del self.read[t][p]
        self.into[p], self.out[p], self.reads[p] = set(), set(), set()
        self.places.discard(p)

    def _changes(self, p: int) -> set[str]:
        """The transitions that change p's count (a self-loop does not)."""
        return {t for t in self.into[p] | self.out[p] if self._change(p, t)}

    # -- the rules, each returning how many nodes it removed ----------------------------------

    def dead(self) -> int:
        may = {p for p in self.places if self.m0[p] > 0}
        missing = {t: sum(1 for p in set(self.pre[t]) | set(self.read[t]) if p not in may)
                   for t in self.transitions}
        queue = [t for t, n in missing.items() if n == 0]
        while queue:
            t = queue.pop()
            for p in self.post[t]:
                if p not in may:
                    may.add(p)
                    for u in self.out[p] | self.reads[p]:
                        missing[u] -= 1
                        if missing[u] == 0:
                            queue.append(u)
        dead = [t for t, n in missing.items() if n and t not in self.seen_t]
        for t in dead:
            self._drop_transition(t)
        return len(dead)

    def constant(self) -> int:
        removed = 0
        for p in sorted(self.places - self.seen_p):
            if self._changes(p):
                continue
            for t in list(self.out[p] | self.reads[p]):
                if self._need(p, t) > self.m0[p]:   # never enabled: needs more than p holds
                    self._drop_transition(t)
                    removed += 1
            self._drop_place(p)
            removed += 1
        return removed

    def irrelevant(self) -> int:
        places = set(self.seen_p)
        kept = set(self.seen_t)
        queue = list(places)
        while queue:
            p = queue.pop()
            for t in self._changes(p) - kept:
                kept.add(t)
                for r in set(self.pre[t]) | set(self.read[t]):
                    if r not in places:
                        places.add(r)
                        queue.append(r)
        gone_t = [t for t in self.transitions if t not in kept]
        gone_p = [p for p in self.places if p not in places]
        if self.keep is Keep.PATHS and gone_t and self._repeatable(gone_t):
            return 0
        for t in gone_t:
            self._drop_transition(t)
        for p in gone_p:
            self._drop_place(p)
        return len(gone_t) + len(gone_p)

    def _repeatable(self, ts: list[str]) -> bool:
        """Whether some x >= 0, x != 0, over ``ts`` has C x >= 0 (then they might fire
        alone for ever; else not: Keep.PATHS). A linear program (HiGHS); where it fails
        to answer, repeatable."""
        # scipy takes a fifth of a second to import: only a question on paths asks
        from scipy.optimize import linprog
        rows = sorted({p for t in ts for p in set(self.pre[t]) | set(self.post[t])})
        if not rows:
            return True            # transitions that change nothing fire for ever
        at = {p: i for i, p in enumerate(rows)}
        a = np.zeros((len(rows) + 1, len(ts)))
        for j, t in enumerate(ts):
            for p, w in self.pre[t].items():
                a[at[p], j] -= w
            for p, w in self.post[t].items():
                a[at[p], j] += w
        # -C x <= 0 and -sum x <= -1
        a = -a
        a[-1, :] = -1.0
        b = np.zeros(len(rows) + 1)
        b[-1] = -1.0
        found = linprog(np.zeros(len(ts)), A_ub=a, b_ub=b, bounds=(0, None), method="highs")
        return found.status != 2            # 2: infeasible, proven

    def duplicate_transition(self) -> int:
        groups: dict[tuple, list[str]] = {}
        for t in self.transitions:
            key = tuple(frozenset(arcs[t].items()) for arcs in (self.pre, self.read, self.post))
            groups.setdefault(key, []).append(t)
        gone = []
        for group in groups.values():
            if len(group) > 1:
                seen = [t for t in group if t in self.seen_t]
                hidden = [t for t in group if t not in self.seen_t]
                gone += hidden if seen else hidden[1:]
        for t in gone:
            self._drop_transition(t)
        return len(gone)

    def _need(self, p: int, t: str) -> int:
        return self.pre[t].get(p, 0) or self.read[t].get(p, 0)

    def _change(self, p: int, t: str) -> int:
        return self.post[t].get(p, 0) - self.pre[t].get(p, 0)

    def implicit_place(self) -> int:
        removed = 0
        for q in sorted(self.places - self.seen_p):
            needers = self.out[q] | self.reads[q]
            if not needers:
                continue
            least = min(needers, key=lambda t: (len(self.pre[t]) + len(self.read[t]), t))
            for p in sorted(set(self.pre[least]) | set(self.read[least])):
                if p != q and self._dominates(p, q, needers):
                    self._drop_place(q)
                    removed += 1
                    break
        return removed

    def _dominates(self, p: int, q: int, needers: set[str]) -> bool:
        """Whether M(q) >= m M(p) in every reachable marking, with m the least factor by
        which p's needs cover q's (the rule's conditions)."""
        if any(self._need(p, t) == 0 for t in needers):
            return False
        m = max(Fraction(self._need(q, t), self._need(p, t)) for t in needers)
        if self.m0[q] < m * self.m0[p]:
            return False
        touching = self.into[p] | self.out[p] | self.into[q] | self.out[q]
        return all(self._change(q, t) >= m * self._change(p, t) for t in touching)

    def sequential_place(self) -> int:
        removed = 0
        for p in sorted(self.places - self.seen_p):
            if p not in self.places or self.reads[p] or len(self.out[p]) != 1:
                continue
            [t] = self.out[p]
            w = self.pre[t][p]
            if t in self.seen_t or len(self.pre[t]) != 1 or self.read[t] or p in self.post[t] \
                    or any(r in self.seen_p for r in self.post[t]) \
                    or any(self.post[h][p] % w for h in self.into[p]):
                continue
            outputs = dict(self.post[t])
            producers = list(self.into[p])
            initially = self.m0[p] // w
            self._drop_transition(t)
            for h in producers:
                k = self.post[h].pop(p) // w
                self.into[p].discard(h)
                for r, v in outputs.items():
                    self.post[h][r] = self.post[h].get(r, 0) + k * v
                    self.into[r].add(h)
            for r, v in outputs.items():
                self.m0[r] += initially * v
            self.m0[p] = 0
            self._drop_place(p)
            removed += 2
        return removed

    def pre_agglomeration(self) -> int:
        removed = 0
        for p in sorted(self.places - self.seen_p):
            if p not in self.places or self.m0[p] or self.reads[p] or len(self.out[p]) != 1:
                continue
            [f] = self.out[p]
            producers = list(self.into[p])
            w = self.pre[f][p]
            if f in self.seen_t or self.read[f] or not producers or f in producers:
                continue
            if any(h in self.seen_t or self.read[h] or self.post[h] != {p: w}
                   or any(r in self.seen_p for r in self.pre[h]) for h in producers):
                continue
            takes = {r: v for r, v in self.pre[f].items() if r != p}
            gives = dict(self.post[f])
            self._drop_transition(f)
            for h in producers:
                pre = dict(self.pre[h])
                for r, v in takes.items():
                    pre[r] = pre.get(r, 0) + v
                node = self.transitions[h]
                self._drop_transition(h)
                self.transitions[h] = node
                self.pre[h], self.read[h], self.post[h] = pre, {}, dict(gives)
                self._index(h)
            self._drop_place(p)
            removed += 2
        return removed

    def post_agglomeration(self) -> int:
        removed = 0
        for p in sorted(self.places - self.seen_p):
            if p not in self.places or self.m0[p] or self.reads[p]:
                continue
            producers, consumers = set(self.into[p]), set(self.out[p])
            if not producers or not consumers or producers & consumers \
                    or len(producers) * len(consumers) > len(producers) + len(consumers):
                continue
            if any(t in self.seen_t for t in producers | consumers):
                continue
            if any(self.pre[f] != {p: 1} or self.read[f] or
                   any(r in self.seen_p for r in self.post[f]) for f in consumers):
                continue
            if any(self.post[h][p] != 1 for h in producers):
                continue
            for h in producers:
                for f in consumers:
                    post = {r: w for r, w in self.post[h].items() if r != p}
                    for r, w in self.post[f].items():
                        post[r] = post.get(r, 0) + w
                    t = self._new_id()
                    self.transitions[t] = Transition(t)
                    self.pre[t], self.read[t], self.post[t] = \
                        dict(self.pre[h]), dict(self.read[h]), post
                    self._index(t)
            for t in producers | consumers:
                self._drop_transition(t)
            self._drop_place(p)
            removed += 1 + len(producers) + len(consumers) - len(producers) * len(consumers)
        return removed

    def _new_id(self) -> str:
        while True:
            self.fresh += 1
            t = f"agglomerated{self.fresh}"
            if t not in self.transitions and t not in self.source.place_index:
                return t

    # -- the result ---------------------------------------------------------------------------

    def net(self) -> Net:
        names = self.place_ids
        arcs = []
        for t in self.transitions:
            arcs += [Arc(names[p], t, w) for p, w in self.pre[t].items()]
            arcs += [Arc(names[p], t, w, ArcKind.READ) for p, w in self.read[t].items()]
            arcs += [Arc(t, names[p], w) for p, w in self.post[t].items()]
        kept = sorted(self.places)
        initial = Marking({names[p]: self.m0[p] for p in kept if self.m0[p]})
        return Net(self.source.name, tuple(self.source.places[p] for p in kept),
                   tuple(self.transitions.values()), tuple(arcs), initial)
