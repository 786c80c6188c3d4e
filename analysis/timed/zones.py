"""Timed verdicts: the zone graph of a time Petri net with priorities, and what it proves.

The semantics is :mod:`mcl2pnml.core.timing`'s (docs/time.md): each
transition has a static interval and a clock that starts when it becomes
enabled; priority transitions (the supervisor's steps) preempt every other,
and eager ones (acknowledgements at once) every other but those;
gap groups (a primitive's reports) fire at least a number of units apart;
fairness groups (a primitive's first report) eventually fire when one of
them stays enabled. Time is dense; every bound is a whole number of units.

**Method.** Zones, not one state per unit of time: a state is a marking and
a difference-bound matrix over the clocks that matter in it (Dill's DBMs;
Bengtsson and Yi, "Timed automata: semantics, algorithms and tools", 2004),
so that a time-out of 900 s costs no more than one of 9 s. The clocks are
those of the enabled transitions whose interval is neither ``[0,0]`` nor
``[0,inf)`` (one per enabled time-out or late acknowledgement) and one per
gap group whose gap has not yet passed; a clock that can no longer change a
guard is dropped (active clock reduction, Daws and Yovine 1996), and every
zone is extrapolated by the largest constant each clock is compared with
(Extra_M, Behrmann, Bouyer, Larsen and Pelanek 2006), which keeps the graph
finite and exact for every guard. The graph is built once by breadth-first
search; every property is then read on its product with the observer of
:mod:`mcl2pnml.analysis.checking.observers` (the same observer the untimed checker uses).

**Runs that end, and runs that do not.** A run is time-divergent: a state
where time may pass for ever with nothing forced (no urgent transition, no
enabled transition with a deadline) *waits forever*, and a run may stop
there: with an obligation open it violates the property (a finite
counterexample: "the mission waits here for ever"). A cycle of the zone
graph is an infinite run; it is a run of the semantics only if time
diverges along it. A cycle that fires a *progress* transition (a lower bound
of one unit or more, or a member of a gap group of one unit or more) takes
at least one unit a turn, so it diverges; a cycle through urgent states only
takes no time at all (Zeno) and is no run; any other cycle is undecided, and
a verdict that would rest on one says so (unknown). With fairness groups, a
cycle (or a wait) in which a group stays enabled and never fires is no run
either: a strongly connected component is fair iff every group is disabled
somewhere in it or fires somewhere in it (then one cycle covers it all).

**End times.** With a clock that is never reset nor extrapolated, the
earliest and latest times at which a run first reaches an end marking are
the bounds of that clock in the zones where it does (exact: the
extrapolation of the other clocks keeps every guard's answer).

Safe nets only (every marking 0 or 1, as compiled missions are): a firing
that would put a second token in a place is refused with its reason. May
import :mod:`mcl2pnml.core` and the observers of :mod:`mcl2pnml.analysis.checking`.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Callable, Iterable, Sequence

import networkx as nx

from mcl2pnml.core.bounds import MAX_CHECK_STATES
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.patterns import Property, holds, places_of
from mcl2pnml.core.structure import Structure, structure
from mcl2pnml.core.timing import TimedNet
from mcl2pnml.analysis.checking.observers import ObserverTable, path_to, truths

# -- bounds: (c, <=) is 2c+1, (c, <) is 2c, no bound is INF ----------------------------

INF = 1 << 62
LE0 = 1           # (0, <=)
LT0 = 0           # (0, <)


def _le(c: int) -> int:
    return 2 * c + 1


def _lt(c: int) -> int:
    return 2 * c


def _add(a: int, b: int) -> int:
    if a >= INF or b >= INF:
        return INF
    return (((a >> 1) + (b >> 1)) << 1) | (a & b & 1)


def _canonical(d: list[list[int]]) -> bool:
    """Floyd-Warshall closure in place; False if the zone is empty."""
    n = len(d)
    for k in range(n):
        dk = d[k]
        for i in range(n):
            dik = d[i][k]
            if dik >= INF:
                continue
            di = d[i]
            for j in range(n):
                v = dk[j]
                if v < INF:
                    s = (((dik >> 1) + (v >> 1)) << 1) | (dik & v & 1)
                    if s < di[j]:
                        di[j] = s
        if d[k][k] < LE0:
            return False
    return all(d[i][i] >= LE0 for i in range(n))


def _constrain(d: list[list[int]], i: int, j: int, b: int) -> bool:
    """x_i - x_j <= b (index 0 is the constant 0) on a canonical DBM, kept canonical;
    False if the zone becomes empty."""
    if b >= d[i][j]:
        return True
    if _add(d[j][i], b) < LE0:
        return False
    d[i][j] = b
    n = len(d)
    for k in range(n):
        dki = d[k][i]
        if dki >= INF:
            continue
        via = _add(dki, b)
        dk = d[k]
        for m in range(n):
            v = _add(via, d[j][m])
            if v < dk[m]:
                dk[m] = v
    return True


# -- the zone graph ----------------------------------------------------------------------

@dataclass
class ZoneGraph:
    """The zone graph: per state its marking (a bit mask), clocks and DBM, its edges, and
    whether time may pass for ever there (``waits``) or not at all (``urgent``)."""

    tn: TimedNet
    places: list[str]
    transitions: list[str]
    markings: list[int] = field(default_factory=list)
    zones: list[tuple] = field(default_factory=list)
    succ: list[list[tuple[int, int]]] = field(default_factory=list)
    parent: list[tuple[int, int] | None] = field(default_factory=list)
    waits: list[bool] = field(default_factory=list)
    urgent: list[bool] = field(default_factory=list)
    enabled: list[int] = field(default_factory=list)
    """Per state, the transitions enabled by its marking, as a bit mask."""
    progress: int = 0
    """The progress transitions, as a bit mask."""
    stuck: list[int] = field(default_factory=list)
    """States where time cannot pass and nothing can fire (a time-lock)."""
    ends: list[tuple[int, int, int, int | None]] = field(default_factory=list)
    """With a global clock: (state, transition, earliest, latest) of each firing that
    reaches an end from ``state``, the times in units, latest None if unbounded."""

    @property
    def states(self) -> int:
        return len(self.markings)

    def marked(self, s: int) -> list[str]:
        m = self.markings[s]
        return [p for k, p in enumerate(self.places) if m >> k & 1]


class TimedLimit(Mcl2PnmlError):
    """More zones than the limit: the verdicts are unknown."""

    def __init__(self, states: int, limit: int):
        super().__init__(f"more than {limit:,} states of the zone graph")
        self.states, self.limit = states, limit


@dataclass(frozen=True)
class _Timers:
    """The clocks of a net, fixed before the search: one per timer (a transition whose
    interval is neither ``[0,0]`` nor ``[0,inf)``, or a group of them sharing one,
    :attr:`TimedNet.shared`), then one per gap group, then the global clock if any."""

    timer_of: tuple[int, ...]
    """Per transition, its timer, or -1 if it has none."""
    members: tuple[int, ...]
    """Per timer, its transitions as a bit mask."""
    lo: tuple[int, ...]
    """Per timer, its lower bound."""
    hi: tuple[int | None, ...]
    """Per timer, its upper bound (None: unbounded)."""


def _timers(tn: TimedNet, s: Structure, lo: list[int], hi: list[int | None]) -> _Timers:
    """The timers of ``tn``: its groups sharing one clock first, then one per other
    transition that needs one."""
    timer_of = [-1] * len(s.transitions)
    members: list[int] = []
    t_lo: list[int] = []
    t_hi: list[int | None] = []
    for group in tn.shared:
        idx = sorted(s.transition_index[t] for t in group)
        if len({(lo[j], hi[j]) for j in idx}) > 1:
            raise Mcl2PnmlError("transitions sharing a clock must share their interval: "
                                + ", ".join(s.transitions[j] for j in idx))
        if lo[idx[0]] == 0 and hi[idx[0]] in (0, None):
            continue
        for j in idx:
            timer_of[j] = len(members)
        members.append(sum(1 << j for j in idx))
        t_lo.append(lo[idx[0]])
        t_hi.append(hi[idx[0]])
    for j in range(len(s.transitions)):
        if timer_of[j] < 0 and not (lo[j] == 0 and hi[j] in (0, None)):
            timer_of[j] = len(members)
            members.append(1 << j)
            t_lo.append(lo[j])
            t_hi.append(hi[j])
    return _Timers(tuple(timer_of), tuple(members), tuple(t_lo), tuple(t_hi))


def _safe_arcs(s: Structure) -> tuple[list[int], list[int], list[int]]:
    """Per transition, the places it takes a token from, those it needs marked (its
    inputs and read arcs) and those it marks, as bit masks; a net that is not safe by
    its initial marking or its weights refused with the reason."""
    for p, n in enumerate(s.initial_vector()):
        if n > 1:
            raise Mcl2PnmlError(f"timed analysis needs a safe net: '{s.places[p]}' holds "
                                f"{n} tokens initially")
    T = len(s.transitions)
    pre_mask, need_mask, post_mask = [0] * T, [0] * T, [0] * T
    for j in range(T):
        for p, w in s.pre[j].items():
            if w != 1:
                raise Mcl2PnmlError(f"timed analysis needs a safe net: the arc from "
                                    f"'{s.places[p]}' to '{s.transitions[j]}' has weight {w}")
            pre_mask[j] |= 1 << p
        need_mask[j] = pre_mask[j]
        for p in s.read[j]:
            need_mask[j] |= 1 << p
        for p, w in s.post[j].items():
            if w != 1:
                raise Mcl2PnmlError(f"timed analysis needs a safe net: the arc from "
                                    f"'{s.transitions[j]}' to '{s.places[p]}' has weight {w}")
            post_mask[j] |= 1 << p
    return pre_mask, need_mask, post_mask


def _mask_of(indices: Iterable[int]) -> int:
    out = 0
    for j in indices:
        out |= 1 << j
    return out


@dataclass(frozen=True)
class _TimedStructure:
    """A safe time Petri net as bit masks, with its clocks: what the search reads of it.
    Clocks are numbered: timers ``0..K-1``, gap groups ``K..K+G-1``, the global clock
    ``K+G`` (``glob``, only when end times are asked for)."""

    places: tuple[str, ...]
    transitions: tuple[str, ...]
    pre: tuple[int, ...]
    need: tuple[int, ...]
    post: tuple[int, ...]
    lo: tuple[int, ...]
    """Per transition, the lower bound of its static interval."""
    priority: int
    eager: int
    urgent: int
    """The transitions of interval ``[0,0]``: time does not pass while one is enabled."""
    deadline: int
    """The transitions with a finite upper bound: time passes only up to it."""
    timers: _Timers
    group_of: tuple[int, ...]
    """Per transition, its gap group, or -1."""
    gap: tuple[int, ...]
    """Per gap group, its gap in units."""
    glob: int | None
    ceiling: tuple[int, ...]
    """Per clock but the global one, the largest constant it is compared with (its
    extrapolation bound, Extra_M)."""
    progress: int
    """The progress transitions (a lower bound of a unit or more, or a gap of one)."""
    end: int
    """The end places, as a bit mask (0 without ends)."""
    m0: int
    """The initial marking, as a bit mask."""

    @property
    def timer_count(self) -> int:
        """The number of timers ``K`` (the first clock of a gap group)."""
        return len(self.timers.members)

    def enabled(self, m: int) -> int:
        """The transitions marking ``m`` enables, as a bit mask."""
        e = 0
        for j, nm in enumerate(self.need):
            if m & nm == nm:
                e |= 1 << j
        return e


def _timed_structure(tn: TimedNet, ends: Iterable[str] | None) -> _TimedStructure:
    """``tn`` read once into :class:`_TimedStructure` (its refusals, in the order a
    reader meets them: the initial marking, the weights, the shared clocks)."""
    s = structure(tn.net)
    T = len(s.transitions)
    pre, need, post = _safe_arcs(s)
    lo: list[int] = [0] * T
    hi: list[int | None] = [None] * T
    for j, tid in enumerate(s.transitions):
        lo[j], hi[j] = tn.intervals.get(tid, (0, None))
    timers = _timers(tn, s, lo, hi)
    K, G = len(timers.members), len(tn.gaps)
    group_of = [-1] * T
    gap = tuple(g for _, g in tn.gaps)
    for g, (group, _) in enumerate(tn.gaps):
        for tid in group:
            group_of[s.transition_index[tid]] = g
    ceiling = tuple([max(timers.lo[k], timers.hi[k] or 0) for k in range(K)] + list(gap))
    progress = _mask_of(j for j in range(T)
                        if lo[j] >= 1 or (group_of[j] >= 0 and gap[group_of[j]] >= 1))
    end = 0 if ends is None else _mask_of(s.place_index[p] for p in ends if p in s.place_index)
    return _TimedStructure(
        tuple(s.places), tuple(s.transitions), tuple(pre), tuple(need), tuple(post), tuple(lo),
        priority=_mask_of(j for j, t in enumerate(s.transitions) if t in tn.priority),
        eager=_mask_of(j for j, t in enumerate(s.transitions) if t in tn.eager),
        urgent=_mask_of(j for j in range(T) if hi[j] == 0),
        deadline=_mask_of(j for j in range(T) if hi[j] is not None),
        timers=timers, group_of=tuple(group_of), gap=gap,
        glob=K + G if ends is not None else None, ceiling=ceiling, progress=progress, end=end,
        m0=_mask_of(p for p, n in enumerate(s.initial_vector()) if n))


def _bits(x: int):
    """The indices of the bits set in ``x``, lowest first."""
    while x:
        low = x & -x
        yield low.bit_length() - 1
        x ^= low


def _add_clock(clocks: list, d: list[list[int]], c: int) -> None:
    """A new clock at 0 (kept canonical: a copy of the constant's row and column)."""
    clocks.append(c)
    for row in d:
        row.append(row[0])
    d.append(list(d[0]))
    d[-1][-1] = LE0


def _reset(d: list[list[int]], i: int) -> None:
    """Clock ``i`` back to 0 (a copy of the constant's row and column)."""
    n = len(d)
    for jj in range(n):
        d[i][jj] = d[0][jj]
        d[jj][i] = d[jj][0]
    d[i][i] = LE0


def _let_time_pass(ts: _TimedStructure, en: int, clocks: tuple, d: list[list[int]]
                   ) -> bool | None:
    """Let time pass in ``d`` where it may, up to every enabled deadline; whether the
    state is urgent (time may not pass), or None if the zone becomes empty."""
    urgent = bool(en & ts.urgent) or bool(en & ts.priority)
    if not urgent:
        for i in range(1, len(d)):
            d[i][0] = INF
        K, t_hi = ts.timer_count, ts.timers.hi
        for i, c in enumerate(clocks, 1):
            if c < K and t_hi[c] is not None:
                if not _constrain(d, i, 0, _le(t_hi[c])):
                    return None
    return urgent


def _extrapolate(ts: _TimedStructure, clocks: tuple, d: list[list[int]]) -> None:
    """Extra_M (Behrmann, Bouyer, Larsen and Pelanek 2006) in place, then the closure:
    every bound past a clock's largest constant forgotten (the global clock kept)."""
    n = len(d)
    changed = False
    for i in range(1, n):
        ci = clocks[i - 1]
        if ci == ts.glob:
            continue
        mi = ts.ceiling[ci]
        row = d[i]
        for jj in range(n):
            if jj != i and row[jj] < INF and row[jj] > _le(mi):
                row[jj] = INF
                changed = True
    for jj in range(1, n):
        cj = clocks[jj - 1]
        if cj == ts.glob:
            continue
        bound = _lt(-ts.ceiling[cj])
        for i in range(n):
            if i != jj and d[i][jj] < bound:
                d[i][jj] = bound
                changed = True
    if changed:
        _canonical(d)


def _drop_inactive(ts: _TimedStructure, clocks: tuple, d: list[list[int]]
                   ) -> tuple[tuple, list[list[int]]]:
    """The clocks and DBM without the clocks that no longer change a guard (active clock
    reduction, Daws and Yovine 1996): a gap clock past its gap, or a clock of an interval
    ``[a, inf)`` past ``a`` (absent means "long enough")."""
    n = len(d)
    keep = [0]
    for i in range(1, n):
        c = clocks[i - 1]
        if c != ts.glob and (c >= ts.timer_count or ts.timers.hi[c] is None) \
                and d[0][i] <= _le(-ts.ceiling[c]):
            continue
        keep.append(i)
    if len(keep) < n:
        clocks = tuple(clocks[i - 1] for i in keep[1:])
        d = [[d[i][jj] for jj in keep] for i in keep]
    return clocks, d


def _finish(ts: _TimedStructure, m: int, en: int, clocks: tuple, d: list[list[int]]):
    """Let time pass (where it may), bound it by the deadlines, extrapolate, drop the
    clocks that no longer matter; the state's key and whether it is urgent, or None if
    time-locked."""
    urgent = _let_time_pass(ts, en, clocks, d)
    if urgent is None:
        return None
    _extrapolate(ts, clocks, d)
    clocks, d = _drop_inactive(ts, clocks, d)
    return (m, clocks, tuple(v for row in d for v in row)), urgent


class _Search:
    """The breadth-first search that builds a :class:`ZoneGraph` (see :func:`zone_graph`)."""

    def __init__(self, tn: TimedNet, ts: _TimedStructure, max_states: int, earliest_only: bool,
                 progress: Callable[[int, int], None] | None):
        self.ts, self.max_states = ts, max_states
        self.earliest_only, self.progress = earliest_only, progress
        self.graph = ZoneGraph(tn, list(ts.places), list(ts.transitions), progress=ts.progress)
        self.index: dict = {}
        self.queue: deque[int] = deque()
        self.best = INF          # the earliest end found so far

    def intern(self, key, urgent: bool, en: int, parent) -> int:
        """The state of ``key``, added (and queued) if new."""
        k = self.index.get(key)
        if k is not None:
            return k
        g = self.graph
        k = self.index[key] = len(g.markings)
        if k >= self.max_states:
            raise TimedLimit(k, self.max_states)
        g.markings.append(key[0])
        g.zones.append(key[1:])
        g.succ.append([])
        g.parent.append(parent)
        g.urgent.append(urgent)
        g.enabled.append(en)
        g.waits.append(not urgent and not (en & self.ts.deadline))
        self.queue.append(k)
        if self.progress is not None and k % 20000 == 0 and k:
            self.progress(k, len(self.queue))
        return k

    def start(self) -> None:
        """The initial state: every enabled timer at 0, and the global clock."""
        ts = self.ts
        en0 = ts.enabled(ts.m0)
        clocks0: list = []
        d0 = [[LE0]]
        for k in range(ts.timer_count):
            if en0 & ts.timers.members[k]:
                _add_clock(clocks0, d0, k)
        if ts.glob is not None:
            _add_clock(clocks0, d0, ts.glob)
        got = _finish(ts, ts.m0, en0, tuple(clocks0), d0)
        if got is None:
            raise Mcl2PnmlError("the initial state is time-locked")
        key0, urg0 = got
        self.intern(key0, urg0, en0, None)

    def run(self) -> ZoneGraph:
        """Every state reached, each expanded once, in breadth-first order."""
        self.start()
        g = self.graph
        while self.queue:
            k = self.queue.popleft()
            if self.ts.end & g.markings[k]:
                continue       # the run has ended: its time was recorded when it got here
            clocks, flat = g.zones[k]
            if self.earliest_only and g.ends:
                gi = clocks.index(self.ts.glob) + 1
                if -(flat[gi] >> 1) >= self.best:
                    continue
            en = g.enabled[k]
            cand = en & self.ts.priority or en & self.ts.eager or en
            fired_any = False
            for j in _bits(cand):
                fired_any |= self.fire(k, j)
            if not fired_any and not g.waits[k]:
                g.stuck.append(k)   # time cannot pass for ever, and nothing can fire
        return g

    def fire(self, k: int, j: int) -> bool:
        """Transition ``j`` fired from state ``k`` where its guard allows, its successor
        added; whether the guard allowed it."""
        ts, g = self.ts, self.graph
        clocks, flat = g.zones[k]
        n = len(clocks) + 1
        d = [list(flat[i * n:(i + 1) * n]) for i in range(n)]
        # the guard: its own clock at its lower bound, its group's gap passed
        tj, gj, K = ts.timers.timer_of[j], ts.group_of[j], ts.timer_count
        if tj >= 0 and ts.lo[j] > 0 and tj in clocks:
            if not _constrain(d, 0, clocks.index(tj) + 1, _le(-ts.lo[j])):
                return False
        if gj >= 0 and (K + gj) in clocks:
            if not _constrain(d, 0, clocks.index(K + gj) + 1, _le(-ts.gap[gj])):
                return False
        m = g.markings[k]
        rest = m & ~ts.pre[j]
        if rest & ts.post[j]:
            raise Mcl2PnmlError(
                f"timed analysis needs a safe net: firing '{ts.transitions[j]}' puts a "
                f"second token in '{ts.places[(rest & ts.post[j]).bit_length() - 1]}'")
        m2 = rest | ts.post[j]
        en2 = ts.enabled(m2)
        new_clocks, d2 = self._clocks_after(g.enabled[k], en2, j, clocks, d)
        ends = ts.glob is not None and ts.end and m2 & ts.end
        if ends:
            gi = new_clocks.index(ts.glob) + 1
            earliest = -(d2[0][gi] >> 1)
            latest = None if d2[gi][0] >= INF else d2[gi][0] >> 1
        got = _finish(ts, m2, en2, tuple(new_clocks), d2)
        if got is None:
            return True
        key, urg = got
        g.succ[k].append((self.intern(key, urg, en2, (k, j)), j))
        if ends:
            # every way in counts: past the end time passes, so the end states of
            # different times may share one zone
            g.ends.append((k, j, earliest, latest))
            self.best = min(self.best, earliest)
        return True

    def _clocks_after(self, en: int, en2: int, j: int, clocks: tuple, d: list[list[int]]
                      ) -> tuple[list, list[list[int]]]:
        """The clocks and DBM after ``j`` fires: a timer starts when its transitions become
        enabled, or again when one of them fires and one stays enabled; it stops when none
        is; ``j``'s gap group starts its clock again."""
        ts = self.ts
        K, members = ts.timer_count, ts.timers.members
        restart = [c for c in range(K) if en2 & members[c] and
                   (not en & members[c] or members[c] >> j & 1)]
        keep_idx = [0]
        new_clocks = []
        for i, c in enumerate(clocks, 1):
            if c >= K or (en2 & members[c] and c not in restart):
                keep_idx.append(i)
                new_clocks.append(c)
        d2 = [[d[a][b] for b in keep_idx] for a in keep_idx]
        for c in restart:
            _add_clock(new_clocks, d2, c)
        gj = ts.group_of[j]
        if gj >= 0 and ts.gap[gj] > 0:
            c = K + gj
            if c in new_clocks:
                _reset(d2, new_clocks.index(c) + 1)
            else:
                _add_clock(new_clocks, d2, c)
        return new_clocks, d2


def zone_graph(tn: TimedNet, *, max_states: int = MAX_CHECK_STATES,
               ends: Iterable[str] | None = None, earliest_only: bool = False,
               progress: Callable[[int, int], None] | None = None) -> ZoneGraph:
    """The zone graph of ``tn`` from its initial marking (see the module's documentation).

    ``ends``: places of which any marked is an end; given, the graph stops at
    the first end of each run and records the global time of reaching it
    (:attr:`ZoneGraph.ends`). ``earliest_only``: a state reached no earlier
    than an end already found is not explored further (enough for the
    earliest end, and finite even where runs never end).
    """
    return _Search(tn, _timed_structure(tn, ends), max_states, earliest_only, progress).run()


# -- verdicts ------------------------------------------------------------------------------

@dataclass(frozen=True)
class TimedVerdict:
    """A property's verdict under the timed semantics.

    ``status`` is ``holds``, ``fails`` or ``unknown``; for ``fails``,
    ``transitions`` the run's firings from M0 and ``shape`` one of
    ``prefix`` (violated whatever follows), ``finite`` (the run waits in its
    last state for ever) or ``lasso`` (the cycle from ``loop`` repeated for
    ever, time diverging); ``states`` the product states explored.
    """

    property: Property
    status: str
    transitions: tuple[str, ...] = ()
    shape: str | None = None
    loop: int | None = None
    states: int = 0
    reason: str | None = None
    path: tuple[int, ...] = ()
    """The zone-graph states the run passes through (M0's first)."""


def check_timed_property(graph: ZoneGraph, prop: Property) -> TimedVerdict:
    """``prop`` on every time-divergent run of ``graph`` (see the module's documentation)."""
    obs = ObserverTable(prop)
    preds = truths(prop)
    index = {p: k for k, p in enumerate(graph.places)}
    cache: dict[int, int] = {}

    def code(s: int) -> int:
        m = graph.markings[s]
        got = cache.get(m)
        if got is None:
            marking = {p: 1 for p in _places_of_preds(preds) if p in index and m >> index[p] & 1}
            p_, s_, q_, r_ = (holds(x, marking) for x in preds)
            got = cache[m] = 8 * p_ + 4 * s_ + 2 * q_ + r_
        return got

    start = (0, obs.after(obs.start, code(0)))
    parent = {start: None}
    queue = deque([start])
    order = [start]
    best = None
    succ: dict = {}
    while queue:
        node = queue.popleft()
        z, o = node
        if o == obs.bad:
            best = best or ("prefix", node)
            succ[node] = []
            continue
        if graph.waits[z] and obs.pending[o] and _fair_wait(graph, z):
            best = best or ("finite", node)
        nxt = []
        for child_z, t in graph.succ[z]:
            child = (child_z, obs.after(o, code(child_z)))
            nxt.append((child, t))
            if child not in parent:
                parent[child] = (node, t)
                order.append(child)
                queue.append(child)
        succ[node] = nxt
    if best is not None:
        shape, node = best
        path, trans = path_to(parent, node)
        return TimedVerdict(prop, "fails", tuple(graph.transitions[t] for t in trans), shape,
                            states=len(parent), path=tuple(z for z, _ in path))
    lasso = _lasso(graph, order, succ, lambda o: o != obs.bad and obs.pending[o])
    if isinstance(lasso, str):
        return TimedVerdict(prop, "unknown", states=len(parent), reason=lasso)
    if lasso is None:
        return TimedVerdict(prop, "holds", states=len(parent))
    entry, cycle = lasso
    path, trans = path_to(parent, entry)
    loop = len(trans)
    nodes = [z for z, _ in path]
    for child, t in cycle:
        trans.append(t)
        nodes.append(child[0])
    return TimedVerdict(prop, "fails", tuple(graph.transitions[t] for t in trans), "lasso",
                        loop=loop, states=len(parent), path=tuple(nodes))


def _places_of_preds(preds) -> set[str]:
    out: set[str] = set()
    for x in preds:
        out |= set(places_of(x))
    return out


def _fair_wait(graph: ZoneGraph, z: int) -> bool:
    """Whether waiting in ``z`` for ever is fair: no fairness group is enabled there."""
    en = graph.enabled[z]
    return not any(en & _mask(graph, group) for group in graph.tn.fair)


def _mask(graph: ZoneGraph, group) -> int:
    cache = graph.__dict__.setdefault("_masks", {})
    got = cache.get(group)
    if got is None:
        got = 0
        for k, t in enumerate(graph.transitions):
            if t in group:
                got |= 1 << k
        cache[group] = got
    return got


def _lasso(graph: ZoneGraph, order, succ, open_):
    """A fair, time-divergent cycle of open product states, as (entry, [(state, t), ...]),
    None if there is none, or the reason it is undecided."""
    dg = nx.DiGraph()
    for node in order:
        if open_(node[1]):
            dg.add_node(node)
            for child, t in succ[node]:
                if open_(child[1]):
                    dg.add_edge(node, child, t=t)
    undecided = None
    found = None
    position = {n: k for k, n in enumerate(order)}
    groups = [_mask(graph, grp) for grp in graph.tn.fair]
    for comp in nx.strongly_connected_components(dg):
        if len(comp) == 1:
            (n,) = comp
            if not dg.has_edge(n, n):
                continue
        edges = [(a, b, d["t"]) for a, b, d in dg.subgraph(comp).edges(data=True)]
        fired = 0
        for _, _, t in edges:
            fired |= 1 << t
        always = ~0
        for n in comp:
            always &= graph.enabled[n[0]]
        if any(always & grp and not fired & grp for grp in groups):
            continue        # unfair: a group stays enabled and never fires
        if not fired & graph.progress:
            if all(graph.urgent[n[0]] for n in comp):
                continue    # no time passes along it: Zeno, no run
            undecided = ("a cycle of the zone graph without a transition that makes time "
                         "pass (a report gap or a time-out of 0 s): whether time diverges "
                         "along it is not decided")
            continue
        entry = min(comp, key=position.__getitem__)
        found = (entry, _covering_cycle(dg, comp, entry, graph, groups, fired))
        break
    if found is not None:
        return found
    return undecided


def _covering_cycle(dg, comp, entry, graph, groups, fired):
    """A cycle from ``entry`` inside ``comp`` through a progress transition and, for each
    fairness group, a state where it is disabled or an edge that fires it."""
    sub = dg.subgraph(comp)
    targets = []   # edges (a, b, t) the cycle must take
    prog = [(a, b, d["t"]) for a, b, d in sub.edges(data=True) if graph.progress >> d["t"] & 1]
    targets.append(prog[0])
    for grp in groups:
        edge = next(((a, b, d["t"]) for a, b, d in sub.edges(data=True) if grp >> d["t"] & 1),
                    None)
        if edge is not None:
            targets.append(edge)
            continue
        off = next((n for n in comp if not graph.enabled[n[0]] & grp), None)
        if off is not None:
            targets.append((off, off, None))
    cycle: list = []
    here = entry
    for a, b, t in targets:
        path = nx.shortest_path(sub, here, a)
        for u, v in zip(path, path[1:]):
            cycle.append((v, sub.edges[u, v]["t"]))
        if t is not None:
            cycle.append((b, t))
        here = b
    path = nx.shortest_path(sub, here, entry)
    for u, v in zip(path, path[1:]):
        cycle.append((v, sub.edges[u, v]["t"]))
    if not cycle:     # entry's self-loop
        cycle.append((entry, sub.edges[entry, entry]["t"]))
    return cycle


def check_timed_properties(tn: TimedNet, properties: Sequence[Property],
                           max_states: int = MAX_CHECK_STATES
                           ) -> tuple[ZoneGraph | None, list[TimedVerdict]]:
    """Each property's timed verdict, on one zone graph."""
    try:
        graph = zone_graph(tn, max_states=max_states)
    except TimedLimit as e:
        return None, [TimedVerdict(p, "unknown", states=e.states, reason=str(e))
                      for p in properties]
    return graph, [check_timed_property(graph, p) for p in properties]


@dataclass(frozen=True)
class EndTimes:
    """When the runs of a net end (reach an end marking), in units of ``TimedNet.unit``.

    ``earliest`` and ``latest`` over every run; ``latest`` is None if some run
    never ends (``never`` then holds that run's firings, whose last state waits for
    ever or starts its cycle at ``loop``). ``states``: the zones explored.
    """

    earliest: int | None
    latest: int | None
    never: TimedVerdict | None
    states: int
    reason: str | None = None
    latest_path: tuple[str, ...] = ()
    latest_states: tuple[int, ...] = ()


def end_times(tn: TimedNet, ends: Iterable[str], always: TimedVerdict,
              max_states: int = MAX_CHECK_STATES) -> EndTimes:
    """The earliest and latest end times, given ``always`` (the verdict of "an end is
    always reached" on the same net): when it fails, the latest is unbounded."""
    ends = list(ends)
    bounded = always.status == "holds"
    try:
        graph = zone_graph(tn, max_states=max_states, ends=ends, earliest_only=not bounded)
    except TimedLimit as e:
        # the times are left unknown: the clock of the whole run multiplies the zones
        return EndTimes(None, None, None if bounded else always, e.states,
                        reason=f"{e}, with the clock of the whole run")
    if not graph.ends:
        return EndTimes(None, None, always if not bounded else None, graph.states)
    earliest = min(e for _, _, e, _ in graph.ends)
    if not bounded:
        return EndTimes(earliest, None, always, graph.states)
    if any(lt is None for _, _, _, lt in graph.ends):
        # every run ends (fairness: a report comes eventually), but not by any bound
        return EndTimes(earliest, None, None, graph.states,
                        reason="no bound: a report that comes eventually may come at any time")
    state, last, _, latest = max(graph.ends, key=lambda e: e[3])
    trans, nodes = [graph.transitions[last]], [state]
    while graph.parent[nodes[-1]] is not None:
        k, t = graph.parent[nodes[-1]]
        trans.append(graph.transitions[t])
        nodes.append(k)
    return EndTimes(earliest, latest, None, graph.states, latest_path=tuple(trans[::-1]),
                    latest_states=tuple(nodes[::-1]))
