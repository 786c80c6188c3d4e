"""Timed verdicts: the zones of a time Petri net with priorities, searched on the fly.

The semantics is :mod:`mcl2pnml.core.timing`'s (docs/time.md): each
transition has a static interval and a clock that starts when it becomes
enabled; priority transitions (the supervisor's steps) preempt every other,
and eager ones (acknowledgements at once) every other but those;
gap groups (a primitive's reports) fire at least a number of units apart;
fairness groups (a primitive's first report) eventually fire when one of
them stays enabled. Time is dense; every bound is a whole number of units.

**Zones.** A state is a marking and a difference-bound matrix over the
clocks that matter in it (Dill's DBMs; Bengtsson and Yi, "Timed automata:
semantics, algorithms and tools", 2004): one per enabled transition whose
interval is neither ``[0,0]`` nor ``[0,inf)`` (a time-out, a late
acknowledgement) and one per gap group whose gap has not yet passed. A
clock that can no longer change a guard is dropped (active clock reduction,
Daws and Yovine 1996), and every zone is extrapolated by its clocks' own
lower and upper bounds (Extra+_LU, Behrmann, Bouyer, Larsen and Pelanek
2006): a time-out's clock by its seconds, an acknowledgement's only from
above, a report gap's only from below.

**On the fly, with inclusion.** The graph is expanded as a search asks for
it. A successor whose zone is included in one already found with the same
marking and clocks is not added: its edge goes to the larger zone, which can
do all it can (the simulation graph of Tripakis 1999; inclusion abstraction,
Laarman, Olesen, Dalsgaard, Larsen and van de Pol 2013). Reachability and the
end times are exact on that graph. Each property is read on its product with
the observer of :mod:`mcl2pnml.analysis.checking.observers`, depth first
(Tarjan's strongly connected components, each judged when it closes), and the
search stops at its first counterexample.

**Runs that end, and runs that do not.** A run is time-divergent: a state
where time may pass for ever with nothing forced (no urgent transition, no
enabled transition with a deadline) *waits forever*, and a run may stop
there: with an obligation open it violates the property (a finite
counterexample). A cycle is an infinite run only if time diverges along it:
it fires a *progress* transition (a lower bound of one unit or more, or a
member of a gap group of one unit or more), so it takes a unit a turn; and
no transition with a deadline stays enabled along it without firing (its
deadline would bound the time), nor, with fairness, a fairness group. These
are generalized Büchi conditions, so a strongly connected component has such
a cycle iff every condition is met somewhere in it (Couvreur 1999). Where a
cycle may take no time and fires no progress transition (a report gap or a
time-out of 0 s), the search is run again with one more clock that ticks
once a unit (Tripakis, Yovine and Bouajjani 2005), and a cycle that ticks
diverges.

**Widened first.** Each property is first read on a graph whose timers' clocks are
forgotten but for their own bounds (``0 <= x <= hi``): a graph with every run of the net
and more, where a loop beside a long timer takes the same zones whatever the timer's
length. What holds there holds; a counterexample found there is replayed as below. Past
:data:`DEPTH_FIRST_STATES` product states depth first, or where it finds no run, the
timers' values are searched: depth first again, then breadth first.

**Clocks per location.** A clock exists only where it matters (a timer while one of its
transitions is enabled, a gap until it has passed), and its bounds are its own
transition's or primitive's, so the bounds of Extra+_LU are those of the location.

**Every counterexample is replayed.** Inclusion makes a covering graph: every
run of the net is a path of it, so "holds" is proven, but one of its paths
need not be a run. A counterexample is therefore fired again, zone by zone,
without inclusion: a prefix is kept if every step is possible; a cycle is
repeated until its zone comes back. One that is not a run sends the search
back to the exact zone graph (no inclusion), which answers alone.

**End times.** With a clock that is never reset nor extrapolated, the
earliest and latest times at which a run first reaches an end marking are
the bounds of that clock where it does (inclusion keeps both: a larger zone
reaches every end time a smaller one does). The earliest is searched in the
order of that clock; the latest is bounded on a graph whose loops are widened
(:meth:`ZoneGraph._widen_loop`), then a run that reaches the bound is looked
for (:func:`end_times`).

Safe nets only (every marking 0 or 1, as compiled missions are): a firing
that would put a second token in a place is refused with its reason. May
import :mod:`mcl2pnml.core` and the observers of :mod:`mcl2pnml.analysis.checking`.
"""
from __future__ import annotations

import heapq
import operator
from collections import deque
from dataclasses import dataclass
from typing import Iterable, Sequence

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


#: A clock never compared from that side (Extra+_LU's minus infinity).
NONE = -(1 << 40)


class TimedLimit(Mcl2PnmlError):
    """More zones than the limit: the verdicts are unknown."""

    def __init__(self, states: int, limit: int):
        super().__init__(f"more than {limit:,} states of the zone graph")
        self.states, self.limit = states, limit


@dataclass(frozen=True)
class _Timers:
    """The clocks of a net, fixed before the search: one per timer (a transition whose
    interval is neither ``[0,0]`` nor ``[0,inf)``, or a group of them sharing one,
    :attr:`TimedNet.shared`), then one per gap group, then the tick and the global clock if any."""

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
    Clocks are numbered: timers ``0..K-1``, gap groups ``K..K+G-1``, then the tick
    (``tick``, only when asked for), then the global clock (``glob``, only when end
    times are asked for)."""

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
    tick: int | None
    """The clock that ticks once a unit (only when cycles that may take no time are
    judged): the clock ``K+G``; its transition is :attr:`tick_t`."""
    glob: int | None
    """The clock of the whole run (only when end times are asked for): the last one."""
    ceiling: tuple[int, ...]
    """Per clock but the global one, the constant past which it no longer matters to a
    clock without an upper bound (active clock reduction)."""
    lower: tuple[int, ...]
    """Per clock but the global one, the largest constant it is compared with from
    below (a guard ``x >= c``; :data:`NONE` if none): Extra+_LU's L."""
    upper: tuple[int, ...]
    """Per clock but the global one, the largest constant it is compared with from
    above (a deadline ``x <= c``; :data:`NONE` if none): Extra+_LU's U."""
    progress: int
    """The progress transitions (a lower bound of a unit or more, or a gap of one, or
    the tick), as a bit mask."""
    bounded: tuple[int, ...]
    """The timers with a deadline, as bit masks of their transitions: along a cycle on
    which time diverges, none stays enabled without firing."""
    fair: tuple[int, ...]
    """The fairness groups, as bit masks of their transitions."""
    end: int
    """The end places, as a bit mask (0 without ends)."""
    m0: int
    """The initial marking, as a bit mask."""

    @property
    def tick_t(self) -> int:
        """The tick's transition number: one past the net's transitions."""
        return len(self.transitions)

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


def _timed_structure(tn: TimedNet, ends: Iterable[str] | None, tick: bool = False
                     ) -> _TimedStructure:
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
    ticks = [1] if tick else []
    ceiling = tuple([max(timers.lo[k], timers.hi[k] or 0) for k in range(K)] + list(gap)
                    + ticks)
    if ends is None:
        lower = tuple([timers.lo[k] if timers.lo[k] > 0 else NONE for k in range(K)]
                      + list(gap) + ticks)
        upper = tuple([NONE if timers.hi[k] is None else timers.hi[k] for k in range(K)]
                      + [NONE] * (G + len(ticks)))
    else:
        # with the clock of the whole run, one constant a clock (Extra+_M): its exact
        # differences keep what Extra+_LU forgets, and the zones split more than they merge
        lower = upper = ceiling
    progress = _mask_of(j for j in range(T)
                        if lo[j] >= 1 or (group_of[j] >= 0 and gap[group_of[j]] >= 1))
    end = 0 if ends is None else _mask_of(s.place_index[p] for p in ends if p in s.place_index)
    index = s.transition_index
    return _TimedStructure(
        tuple(s.places), tuple(s.transitions), tuple(pre), tuple(need), tuple(post), tuple(lo),
        priority=_mask_of(j for j, t in enumerate(s.transitions) if t in tn.priority),
        eager=_mask_of(j for j, t in enumerate(s.transitions) if t in tn.eager),
        urgent=_mask_of(j for j in range(T) if hi[j] == 0),
        deadline=_mask_of(j for j in range(T) if hi[j] is not None),
        timers=timers, group_of=tuple(group_of), gap=gap,
        tick=K + G if tick else None,
        glob=K + G + len(ticks) if ends is not None else None, ceiling=ceiling,
        lower=lower, upper=upper,
        progress=progress | (1 << T if tick else 0),
        bounded=tuple(m for m, h in zip(timers.members, timers.hi) if h is not None),
        fair=tuple(_mask_of(index[t] for t in group) for group in tn.fair),
        end=end, m0=_mask_of(p for p, n in enumerate(s.initial_vector()) if n))

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
    """Extra+_LU (Behrmann, Bouyer, Larsen and Pelanek 2006) in place, then the closure:
    a bound is forgotten where no guard or deadline of its clock can tell it from a
    larger one (the global clock kept whole)."""
    n = len(d)
    glob = ts.glob
    low = [NONE] * n          # per index, L of its clock (the constant: 0)
    up = [NONE] * n
    low[0] = up[0] = 0
    whole = [False] * n       # the global clock: never extrapolated
    for i, c in enumerate(clocks, 1):
        if c == glob:
            whole[i] = True
        else:
            low[i], up[i] = ts.lower[c], ts.upper[c]
    row0 = list(d[0])
    changed = False
    for i in range(1, n):
        if whole[i]:
            continue
        li = _le(low[i])
        drop = row0[i] < _le(-low[i])          # x_i is past its L everywhere
        row = d[i]
        for j in range(n):
            if j != i and row[j] < INF and (drop or row[j] > li or
                                            (j and not whole[j] and row0[j] < _le(-up[j]))):
                row[j] = INF
                changed = True
    for j in range(1, n):
        if whole[j] or row0[j] >= _le(-up[j]):
            continue
        # x_j is past its U everywhere: keep only that (0 when it has no U)
        bound = LE0 if up[j] == NONE else _lt(-up[j])
        if d[0][j] != bound:
            d[0][j] = bound
            changed = True
    if changed:
        _canonical(d)


def _drop_inactive(ts: _TimedStructure, clocks: tuple, d: list[list[int]]
                   ) -> tuple[tuple, list[list[int]]]:
    """The clocks and DBM without the clocks that no longer change a guard (active clock
    reduction, Daws and Yovine 1996): a gap clock past its gap, the tick past its unit, or
    a clock of an interval ``[a, inf)`` past ``a`` (absent means "long enough")."""
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
    """Let time pass (where it may), bound it by the deadlines, drop the clocks that no
    longer matter, extrapolate; the state's key and whether it is urgent, or None if
    time-locked."""
    urgent = _let_time_pass(ts, en, clocks, d)
    if urgent is None:
        return None
    # dropped first: the extrapolation forgets the lower bounds that tell a clock is past
    clocks, d = _drop_inactive(ts, clocks, d)
    _extrapolate(ts, clocks, d)
    if any(a > b for a, b in zip(clocks, clocks[1:])):
        # one order of the clocks, so that one zone has one key whatever order they started
        order = [0] + [i + 1 for i in sorted(range(len(clocks)), key=clocks.__getitem__)]
        clocks = tuple(sorted(clocks))
        d = [[d[i][j] for j in order] for i in order]
    return (m, clocks, tuple(v for row in d for v in row)), urgent


def _start(ts: _TimedStructure) -> tuple[tuple, bool, int]:
    """The initial state: its key, whether it is urgent, its enabled transitions. Every
    enabled timer at 0, and the global clock."""
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
    return got[0], got[1], en0


def _clocks_after(ts: _TimedStructure, en: int, en2: int, j: int, clocks: tuple,
                  d: list[list[int]]) -> tuple[list, list[list[int]]]:
    """The clocks and DBM after ``j`` fires: a timer starts when its transitions become
    enabled, or again when one of them fires and one stays enabled; it stops when none
    is; ``j``'s gap group (or the tick) starts its clock again."""
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
    if j == ts.tick_t:
        c = ts.tick
    else:
        gj = ts.group_of[j]
        c = K + gj if gj >= 0 and ts.gap[gj] > 0 else None
    if c is not None:
        if c in new_clocks:
            _reset(d2, new_clocks.index(c) + 1)
        else:
            _add_clock(new_clocks, d2, c)
    return new_clocks, d2


def _widened(ts: _TimedStructure, key: tuple) -> tuple:
    """``key`` with every timer's clock (a time-out's, a late acknowledgement's) free of
    every bound but ``0 <= x <= hi``: a larger zone, so that a graph of widened zones has
    every run of the net (each real successor lies in a widened one), whatever the timers'
    values; the report gaps and the tick are kept, which make a cycle take time."""
    m, clocks, flat = key
    K = ts.timer_count
    free = [i for i, c in enumerate(clocks, 1) if c < K]
    if not free:
        return key
    n = len(clocks) + 1
    d = [list(flat[i * n:(i + 1) * n]) for i in range(n)]
    for i in free:
        for j in range(n):
            if j != i:
                d[i][j] = d[j][i] = INF
        d[0][i] = LE0
        hi = ts.timers.hi[clocks[i - 1]]
        d[i][0] = INF if hi is None else _le(hi)
    _canonical(d)
    return m, clocks, tuple(v for row in d for v in row)


def _firable(ts: _TimedStructure, en: int, urgent: bool) -> int:
    """What may fire in a state enabling ``en``, as a bit mask: the supervisor's steps
    before all, then the acknowledgements at once, else every enabled transition; and
    the tick where time may pass."""
    out = en & ts.priority or en & ts.eager or en
    if ts.tick is not None and not urgent:
        out |= 1 << ts.tick_t
    return out


#: How many times a loop comes back to one marking and clocks, larger each time, before its
#: zone is widened (:meth:`ZoneGraph._widen_loop`): once is often a sequence that passes
#: the same marking again, not a loop that grows.
WIDEN_AFTER = 2


#: What :func:`_post` gives when the firing is possible but no time may pass after it.
LOCKED = "time-locked"


def _post(ts: _TimedStructure, en: int, key: tuple, j: int):
    """The successor of state ``key`` (enabling ``en``) by ``j`` (the tick if
    ``ts.tick_t``): ``(key, urgent, enabled, end)`` with ``end`` the bounds of the
    global clock when it reaches an end (else None); None if ``j``'s guard is false
    everywhere in the zone; :data:`LOCKED` if it fires into a time-lock."""
    m, clocks, flat = key
    n = len(clocks) + 1
    d = [list(flat[i * n:(i + 1) * n]) for i in range(n)]
    K = ts.timer_count
    if j == ts.tick_t:
        # the tick: a unit since the last, a step of no transition
        if ts.tick in clocks and not _constrain(d, 0, clocks.index(ts.tick) + 1, _le(-1)):
            return None
        m2, en2 = m, en
    else:
        # the guard: its own clock at its lower bound, its group's gap passed
        tj, gj = ts.timers.timer_of[j], ts.group_of[j]
        if tj >= 0 and ts.lo[j] > 0 and tj in clocks:
            if not _constrain(d, 0, clocks.index(tj) + 1, _le(-ts.lo[j])):
                return None
        if gj >= 0 and (K + gj) in clocks:
            if not _constrain(d, 0, clocks.index(K + gj) + 1, _le(-ts.gap[gj])):
                return None
        rest = m & ~ts.pre[j]
        if rest & ts.post[j]:
            raise Mcl2PnmlError(
                f"timed analysis needs a safe net: firing '{ts.transitions[j]}' puts a "
                f"second token in '{ts.places[(rest & ts.post[j]).bit_length() - 1]}'")
        m2 = rest | ts.post[j]
        en2 = ts.enabled(m2)
    new_clocks, d2 = _clocks_after(ts, en, en2, j, clocks, d)
    end = None
    if ts.glob is not None and m2 & ts.end:
        gi = new_clocks.index(ts.glob) + 1
        end = (-(d2[0][gi] >> 1), None if d2[gi][0] >= INF else d2[gi][0] >> 1)
    got = _finish(ts, m2, en2, tuple(new_clocks), d2)
    if got is None:
        return LOCKED
    return got[0], got[1], en2, end


# -- the graph, expanded on demand ----------------------------------------------------------

class ZoneGraph:
    """The zones reached from the initial state, each expanded when a search asks for its
    successors; per state its marking (a bit mask), key, edges, and whether time may pass
    for ever there (``waits``) or not at all (``urgent``).

    With ``subsume``, a successor included in a state of the same marking and clocks is
    that state (see the module's documentation); ``stop_at_ends``: a state with an end
    place marked has no successor (its run has ended), and each firing into one is
    recorded in :attr:`ends` with the bounds of the global clock; ``earliest_only``: a
    state reached no earlier than an end already found has no successor either;
    ``cover``: what inclusion compares (:meth:`_seen`); ``widen``: every timer's clock
    forgotten but its own bounds (:func:`_widened`), a graph that has every run of the
    net and more (its "holds" is proven, its counterexamples replayed); ``widen_loops``:
    a zone that comes back to the marking and clocks of one of its ancestors, larger, is
    widened against it (:meth:`_widen_loop`), also a graph with every run and more.
    """

    def __init__(self, tn: TimedNet, ts: _TimedStructure, *, max_states: int = MAX_CHECK_STATES,
                 subsume: bool = True, stop_at_ends: bool = False, earliest_only: bool = False,
                 cover: str = "zone", widen: bool = False, widen_loops: bool = False):
        self.tn, self.ts, self.max_states, self.cover = tn, ts, max_states, cover
        self.widen, self.widen_loops = widen, widen_loops
        self.subsume, self.stop_at_ends, self.earliest_only = subsume, stop_at_ends, earliest_only
        self.places, self.transitions = list(ts.places), list(ts.transitions)
        if ts.tick is not None:
            self.transitions.append(TICK)
        self.progress = ts.progress
        self.markings: list[int] = []
        self.keys: list[tuple] = []
        self.succ: list[list[tuple[int, int]] | None] = []
        self.parent: list[tuple[int, int] | None] = []
        self.widened: list[bool] = []
        """Per state, whether its zone was widened, or one of its parents' was (with
        ``widen_loops``): it may then hold valuations that no run reaches."""
        self.waits: list[bool] = []
        self.urgent: list[bool] = []
        self.enabled: list[int] = []
        self.ends: list[tuple[int, int, int, int | None]] = []
        """(state, transition, earliest, latest) of each firing into an end, in units,
        latest None if unbounded (with ``stop_at_ends``)."""
        self._exact: dict[tuple, int] = {}
        self._cover: dict[tuple, list[int]] = {}
        self._compared: list[tuple] = []
        self.best = INF
        key, urgent, en = _start(ts)
        self._add(_widened(ts, key) if widen else key, urgent, en, None)

    @property
    def states(self) -> int:
        return len(self.markings)

    def marked(self, s: int) -> list[str]:
        return marked_places(self.places, self.markings[s])

    def _add(self, key: tuple, urgent: bool, en: int, parent, widened: bool = False) -> int:
        """The state of ``key``: the one already found (equal, or including it), else a new
        one."""
        k = self._exact.get(key)
        if k is not None:
            return k
        if self.subsume:
            seen = self._seen(key)
            cover = self._cover.setdefault(key[:2], [])
            keys = self._compared
            for c in cover:
                if all(map(operator.le, seen, keys[c])):
                    return c
            # the new zone replaces, as a cover, every one it includes
            cover[:] = [c for c in cover if not all(map(operator.le, keys[c], seen))]
        k = len(self.markings)
        if k >= self.max_states:
            raise TimedLimit(k, self.max_states)
        self._exact[key] = k
        if self.subsume:
            cover.append(k)
            self._compared.append(seen)
        self.markings.append(key[0])
        self.keys.append(key)
        self.succ.append(None)
        self.parent.append(parent)
        self.widened.append(widened)
        self.urgent.append(urgent)
        self.enabled.append(en)
        self.waits.append(not urgent and not (en & self.ts.deadline))
        return k

    def _seen(self, key: tuple) -> tuple:
        """The bounds of ``key``'s zone that inclusion compares: all of them, or all but
        those of the global clock from below (``latest``: a zone whose clock of the whole
        run may be later can do all a zone can, and end no earlier) or from above
        (``earliest``)."""
        if self.cover == "zone":
            return key[2]
        clocks, flat = key[1], key[2]
        n = len(clocks) + 1
        gi = clocks.index(self.ts.glob) + 1
        if self.cover == "latest":
            return tuple(v for k, v in enumerate(flat) if k % n != gi)
        return flat[:gi * n] + flat[(gi + 1) * n:]

    def successors(self, k: int) -> list[tuple[int, int]]:
        """The edges ``(state, transition)`` from state ``k``, found the first time asked."""
        got = self.succ[k]
        if got is not None:
            return got
        ts = self.ts
        out: list[tuple[int, int]] = []
        self.succ[k] = out
        key, en = self.keys[k], self.enabled[k]
        if self.stop_at_ends and ts.end & key[0]:
            return out        # the run has ended: its time was recorded when it got here
        if self.earliest_only and self.ends:
            clocks, flat = key[1], key[2]
            gi = clocks.index(ts.glob) + 1
            if -(flat[gi] >> 1) >= self.best:
                return out
        for j in _bits(_firable(ts, en, self.urgent[k])):
            got = _post(ts, en, key, j)
            if got is None or got is LOCKED:
                continue
            key2, urgent2, en2, end = got
            if end is not None and self.stop_at_ends:
                # every way in counts: past the end time passes, so the end states of
                # different times may share one zone
                self.ends.append((k, j, end[0], end[1]))
                self.best = min(self.best, end[0])
            if self.widen:
                key2 = _widened(ts, key2)
            widened = False
            if self.widen_loops:
                key2, widened = self._widen_loop(k, key2)
            out.append((self._add(key2, urgent2, en2, (k, j), widened or self.widened[k]), j))
        return out

    def _widen_loop(self, k: int, key: tuple) -> tuple[tuple, bool]:
        """``key`` (a successor of state ``k``) widened against its nearest ancestor of the
        same marking and clocks, once it has :data:`WIDEN_AFTER` such ancestors and is not
        included in the nearest: every bound that grew from
        the ancestor's is dropped, then the deadlines and ``x >= 0`` put back (the widening
        of Cousot and Halbwachs on difference-bound matrices, Mine 2001). The result
        includes both zones, and a loop's growing bounds reach their deadline, or none, in
        one step, so that a loop beside a long timer takes as many zones whatever its
        length; the clock of the whole run keeps its difference with the timer that bounds
        it, since neither changes it."""
        m, clocks, flat = key
        found: list[int] = []
        s: int | None = k
        while s is not None and len(found) < WIDEN_AFTER:
            if self.keys[s][:2] == (m, clocks):
                found.append(s)
            p = self.parent[s]
            s = None if p is None else p[0]
        if len(found) < WIDEN_AFTER:
            return key, False
        old = self.keys[found[0]][2]
        if all(map(operator.le, flat, old)):
            return key, False
        n = len(clocks) + 1
        d = [[o if f <= o else INF for f, o in zip(flat[i * n:(i + 1) * n], old[i * n:(i + 1) * n])]
             for i in range(n)]
        K, t_hi = self.ts.timer_count, self.ts.timers.hi
        for i, c in enumerate(clocks, 1):
            d[i][i] = LE0
            d[0][i] = min(d[0][i], LE0)
            if c < K and t_hi[c] is not None:
                # every state lies within its deadlines: time stops at them
                d[i][0] = min(d[i][0], _le(t_hi[c]))
        _canonical(d)
        return (m, clocks, tuple(v for row in d for v in row)), True

    def _glob(self, s: int) -> tuple[int, int]:
        """The lower and upper bounds of the global clock in state ``s``, in units (the
        upper ``INF >> 1`` if none)."""
        _, clocks, flat = self.keys[s]
        n = len(clocks) + 1
        gi = clocks.index(self.ts.glob) + 1
        return -(flat[gi] >> 1), flat[gi * n] >> 1

    def explore_earliest(self) -> None:
        """The states in the order of their earliest time (Dijkstra's order on the global
        clock's lower bound, which no step lowers), up to the first end: every state not
        expanded is reached no earlier than it (with ``earliest_only``)."""
        heap = [(self._glob(0)[0], 0)]
        seen = {0}
        while heap:
            t, s = heapq.heappop(heap)
            if self.ends and self.best <= t:
                return
            for child, _ in self.successors(s):
                if child not in seen:
                    seen.add(child)
                    heapq.heappush(heap, (self._glob(child)[0], child))

    def explore_latest(self, bound: int) -> None:
        """The states latest first (the global clock's upper bound, largest first), until an
        end is found at ``bound`` or unbounded, or every state is: a run that ends at the
        bound of a graph with every run and more ends latest."""
        heap = [(-self._glob(0)[1], 0, 0)]
        seen = {0}
        while heap:
            _, _, s = heapq.heappop(heap)
            known = len(self.ends)
            for child, _ in self.successors(s):
                if child not in seen:
                    seen.add(child)
                    heapq.heappush(heap, (-self._glob(child)[1], -child, child))
            if any(lt is None or lt >= bound for _, _, _, lt in self.ends[known:]):
                return

    def explore(self) -> None:
        """Every state reached, each expanded once, breadth first (inclusion then finds
        the larger zones first)."""
        queue = deque([0])
        seen = {0}
        while queue:
            for child, _ in self.successors(queue.popleft()):
                if child not in seen:
                    seen.add(child)
                    queue.append(child)


#: The tick's name in a run (it fires nothing: time passes).
TICK = "(a unit passes)"


def marked_places(places: Sequence[str], mask: int) -> list[str]:
    """The places a marking (a bit mask) marks."""
    return [p for k, p in enumerate(places) if mask >> k & 1]


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
    """The markings the run passes through (M0's first), as bit masks."""


#: Why a verdict is unknown when a cycle may take no time even with the tick.
ZENO = ("a cycle of the zone graph without a transition that makes time pass (a report gap "
        "or a time-out of 0 s): whether time diverges along it is not decided")


class _Spurious(Exception):
    """A counterexample of the covering graph that is no run: search without inclusion."""


class _Budget(Exception):
    """The depth-first search visited as many product states as it was given."""


def check_timed_property(graph: ZoneGraph, prop: Property, budget: int | None = None
                         ) -> TimedVerdict:
    """``prop`` on every time-divergent run of ``graph``'s net (see the module's
    documentation); ``unknown`` with :data:`ZENO` when only a cycle that may take no
    time is left undecided. Past ``budget`` product states, :class:`_Budget`; where
    the counterexample found is no run, :class:`_Spurious`."""
    obs = ObserverTable(prop)
    preds = truths(prop)
    index = {p: k for k, p in enumerate(graph.places)}
    wanted = [index[p] for p in _places_of_preds(preds) if p in index]
    cache: dict[int, int] = {}

    def code(s: int) -> int:
        m = graph.markings[s]
        got = cache.get(m)
        if got is None:
            marking = {graph.places[p]: 1 for p in wanted if m >> p & 1}
            p_, s_, q_, r_ = (holds(x, marking) for x in preds)
            got = cache[m] = 8 * p_ + 4 * s_ + 2 * q_ + r_
        return got

    search = _ProductSearch(graph, obs, code, budget)
    found = search.run()
    if found is None:
        status, reason = ("unknown", ZENO) if search.undecided else ("holds", None)
        return TimedVerdict(prop, status, states=search.count, reason=reason)
    shape, trans, loop = found
    replayed = _replay(graph.ts, trans, loop)
    if replayed is None:
        raise _Spurious
    trans, loop, path = replayed
    return TimedVerdict(prop, "fails", tuple(graph.transitions[t] for t in trans), shape,
                        loop=loop, states=search.count, path=path)


#: The product states a breadth-first search for the shortest counterexample may visit
#: beyond those the depth-first search did (a shorter run explains better, at a price).
NEAREST_STATES = 2_000


class _ProductSearch:
    """Tarjan's depth-first search of the product of ``graph`` with an observer, stopping
    at the first counterexample: a state past the observer's ``bad``, a state that waits
    for ever with an obligation open, or a strongly connected component of open states
    with a time-divergent (and fair) cycle."""

    def __init__(self, graph: ZoneGraph, obs: ObserverTable, code, budget: int | None):
        self.graph, self.obs, self.code, self.budget = graph, obs, code, budget
        self.count = 0
        self.undecided = False
        self.parent: dict = {}

    def children(self, node) -> list:
        z, o = node
        after, code = self.obs.after, self.code
        return [((c, after(o, code(c))), t) for c, t in self.graph.successors(z)]

    def stops(self, node) -> str | None:
        """The shape of the counterexample ``node`` ends, if it ends one."""
        z, o = node
        obs, graph = self.obs, self.graph
        if o == obs.bad:
            return "prefix"
        if graph.waits[z] and obs.pending[o] and _fair_wait(graph, z):
            return "finite"
        return None

    def run(self):
        """``(shape, transitions, loop)`` of the first counterexample, or None."""
        # long: Tarjan's algorithm kept iterative and in one piece, its stacks side by side
        start = (0, self.obs.after(self.obs.start, self.code(0)))
        self.parent[start] = None
        index, low, on_stack = {start: 0}, {start: 0}, {start}
        stack, succ = [start], {}
        shape = self.stops(start)
        if shape is not None:
            return shape, [], None
        succ[start] = self.children(start)
        work = [(start, 0)]
        while work:
            node, i = work[-1]
            edges = succ[node]
            if i < len(edges):
                work[-1] = (node, i + 1)
                child, t = edges[i]
                if child not in index:
                    if self.budget is not None and len(index) >= self.budget:
                        raise _Budget
                    index[child] = low[child] = len(index)
                    self.parent[child] = (node, t)
                    shape = self.stops(child)
                    if shape is not None:
                        self.count = len(index)
                        # the shortest such run explains best: breadth first, now that
                        # one is known to exist
                        found = self._nearest(lambda n: self.stops(n) is not None, child)
                        return self.stops(found), self._path(found), None
                    stack.append(child)
                    on_stack.add(child)
                    succ[child] = [] if child[1] == self.obs.bad else self.children(child)
                    work.append((child, 0))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                up = work[-1][0]
                low[up] = min(low[up], low[node])
            if low[node] != index[node]:
                continue
            comp = []
            while True:
                x = stack.pop()
                on_stack.discard(x)
                comp.append(x)
                if x == node:
                    break
            found = self._cycle(comp, succ)
            if found is not None:
                self.count = len(index)
                entry, cycle = found
                trans = self._path(self._nearest(lambda n: n == entry, entry))
                return "lasso", trans + [t for _, t in cycle], len(trans)
        self.count = len(index)
        return None

    def _nearest(self, wanted, found):
        """The first product state in breadth-first order that is ``wanted``, its
        :attr:`parent` rewritten to the breadth-first tree; ``found`` (one that is, found
        depth first) where breadth first would visit more than :data:`NEAREST_STATES`
        and as many as depth first did, which the shortest run is not worth."""
        start = next(n for n, p in self.parent.items() if p is None)
        parent = {start: None}
        queue = deque([start])
        limit = max(NEAREST_STATES, len(self.parent))
        while queue and len(parent) <= limit:
            node = queue.popleft()
            if wanted(node):
                self.parent = parent
                return node
            if node[1] == self.obs.bad:
                continue
            for child, t in self.children(node):
                if child not in parent:
                    parent[child] = (node, t)
                    queue.append(child)
        return found

    def _path(self, node) -> list[int]:
        return path_to(self.parent, node)[1]

    def _cycle(self, comp: list, succ: dict):
        """A time-divergent, fair cycle of open states in the component ``comp``, as
        ``(entry, [(state, transition), ...])``, or None (noting an undecided one)."""
        obs, graph = self.obs, self.graph
        open_ = {n for n in comp if n[1] != obs.bad and obs.pending[n[1]]}
        if not open_ or (len(comp) == 1 and all(c != comp[0] for c, _ in succ[comp[0]])):
            return None
        dg = nx.DiGraph()
        for n in open_:
            dg.add_node(n)
            for child, t in succ[n]:
                if child in open_:
                    dg.add_edge(n, child, t=t)
        ts = graph.ts
        groups = list(ts.fair) + list(ts.bounded)
        for part in nx.strongly_connected_components(dg):
            if len(part) == 1:
                (n,) = part
                if not dg.has_edge(n, n):
                    continue
            sub = dg.subgraph(part)
            # every edge, not the graph's: two transitions between the same two states
            # are one edge of it, with one label
            edges = [(a, b, t) for a in part for b, t in succ[a] if b in part]
            fired = 0
            for _, _, t in edges:
                fired |= 1 << t
            if any(not fired & grp and all(graph.enabled[n[0]] & grp for n in part)
                   for grp in groups):
                continue        # a deadline or fairness group stays enabled, never fires
            if not fired & graph.progress:
                if not all(graph.urgent[n[0]] for n in part):
                    self.undecided = True
                continue        # no time passes along it: Zeno, no run
            entry = min(part, key=lambda n: self.order(n))
            return entry, _covering_cycle(sub, edges, entry, graph, groups)
        return None

    def order(self, node) -> int:
        """How deep ``node`` was found (its path's length): the entry of a cycle is its
        shallowest state."""
        return len(self._path(node))


def _places_of_preds(preds) -> set[str]:
    out: set[str] = set()
    for x in preds:
        out |= set(places_of(x))
    return out


def _fair_wait(graph: ZoneGraph, z: int) -> bool:
    """Whether waiting in ``z`` for ever is fair: no fairness group is enabled there."""
    en = graph.enabled[z]
    return not any(en & grp for grp in graph.ts.fair)


def _covering_cycle(sub, edges, entry, graph: ZoneGraph, groups) -> list:
    """A cycle from ``entry`` inside ``sub`` (its ``edges`` all of them, with their
    transitions) through a progress transition and, for each fairness or deadline group,
    a state where it is disabled or an edge that fires it."""
    targets = []   # edges (a, b, t) the cycle must take
    prog = [(a, b, t) for a, b, t in edges if graph.progress >> t & 1]
    targets.append(prog[0])
    for grp in groups:
        edge = next(((a, b, t) for a, b, t in edges if grp >> t & 1), None)
        if edge is not None:
            targets.append(edge)
            continue
        off = next((n for n in sub if not graph.enabled[n[0]] & grp), None)
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


#: How many turns of a cycle found with inclusion are fired again before it is taken for
#: no run (its zone comes back within as many turns as the zones it passes through).
REPLAY_TURNS = 10_000


def _replay(ts: _TimedStructure, trans: list[int], loop: int | None):
    """``trans`` fired from the initial state without inclusion: ``(transitions, loop,
    markings)`` of the run it stands for (the cycle from ``loop`` turned until its zone
    comes back), or None if some step is not possible (no run)."""
    key, urgent, en = _start(ts)
    marks = [key[0]]
    head = trans if loop is None else trans[:loop]
    out: list[int] = []

    def step(j: int) -> bool:
        nonlocal key, urgent, en
        if not (_firable(ts, en, urgent) >> j & 1):
            return False
        got = _post(ts, en, key, j)
        if got is None or got is LOCKED:
            return False
        key, urgent, en, _ = got
        out.append(j)
        marks.append(key[0])
        return True

    if not all(step(j) for j in head):
        return None
    if loop is None:
        return _without_ticks(ts, out, None, marks)
    cycle = trans[loop:]
    seen = {key: len(out)}
    for _ in range(REPLAY_TURNS):
        if not all(step(j) for j in cycle):
            return None
        back = seen.get(key)
        if back is not None:
            return _without_ticks(ts, out, back, marks)
        seen[key] = len(out)
    return None


def _without_ticks(ts: _TimedStructure, trans: list[int], loop: int | None,
                   marks: list[int]):
    """A run as the net fires it: the tick (time passing) left out of its transitions and
    markings, the loop's start moved with them."""
    keep = [k for k, j in enumerate(trans) if j != ts.tick_t]
    new_loop = None if loop is None else sum(1 for k in keep if k < loop)
    return ([trans[k] for k in keep], new_loop,
            tuple([marks[0]] + [marks[k + 1] for k in keep]))


#: The product states a depth-first search may visit on a graph expanded on demand, before
#: the graph is built breadth first instead: depth first finds a run that never ends at
#: once, but meets small zones before the larger ones that include them, and a property
#: that holds can cost it many times the zones of breadth first (a mission with late
#: acknowledgements: 10^6 against 10^4).
DEPTH_FIRST_STATES = 20_000

#: The zones the graph whose loops are widened may take to bound the latest end time
#: before the exact graph is searched alone: the widened graph is meant to be small (its
#: loops close in a few steps), and past this it is not paying for itself.
WIDENED_END_STATES = 50_000

#: The zones the search for a run that ends at the widened graph's bound may take, without
#: inclusion, before every state is searched with it: a run that turns a loop beside a
#: timer of 10,000 s a thousand times takes about 100,000.
LATEST_RUN_STATES = 200_000


def check_timed_properties(tn: TimedNet, properties: Sequence[Property],
                           max_states: int = MAX_CHECK_STATES) -> list[TimedVerdict]:
    """Each property's timed verdict (see the module's documentation): first on the graph
    whose timers are widened (:class:`ZoneGraph`'s ``widen``), depth first up to
    :data:`DEPTH_FIRST_STATES`, kept where it holds or its counterexample is a run; then
    depth first on the graph with inclusion expanded on demand, up to the same; past them,
    on the graph with inclusion built breadth first; for a property left undecided by a
    cycle that may take no time, again with the tick; where a counterexample found with
    inclusion is no run, on the exact graph."""
    graphs: dict[tuple[bool, str], ZoneGraph] = {}

    def graph(tick: bool, how: str) -> ZoneGraph:
        got = graphs.get((tick, how))
        if got is None:
            got = graphs[tick, how] = ZoneGraph(
                tn, _timed_structure(tn, None, tick), max_states=max_states,
                subsume=how != "exact", widen=how == "widened")
            if how == "breadth":
                got.explore()
        return got

    def verdict(prop: Property, tick: bool) -> TimedVerdict:
        try:
            # first with the timers' values forgotten: where that proves the property or
            # finds a run, the long timers' many zones are never made
            return check_timed_property(graph(tick, "widened"), prop, DEPTH_FIRST_STATES)
        except (_Budget, _Spurious):
            pass
        try:
            try:
                return check_timed_property(graph(tick, "depth"), prop, DEPTH_FIRST_STATES)
            except _Budget:
                return check_timed_property(graph(tick, "breadth"), prop)
        except _Spurious:
            return check_timed_property(graph(tick, "exact"), prop)

    out = []
    for prop in properties:
        try:
            found = verdict(prop, False)
            if found.reason == ZENO:
                found = verdict(prop, True)
        except TimedLimit as e:
            found = TimedVerdict(prop, "unknown", states=e.states, reason=str(e))
        out.append(found)
    return out


def stalls(tn: TimedNet, ends: Iterable[str], max_states: int = MAX_CHECK_STATES) -> bool:
    """Whether a state is reached where nothing can happen, time passes for ever, and no
    end place is marked (a stall)."""
    ts = _timed_structure(tn, None)
    end = _mask_of(ts.places.index(p) for p in ends if p in ts.places)
    graph = ZoneGraph(tn, ts, max_states=max_states)
    graph.explore()
    return any(graph.waits[s] and not graph.enabled[s] and not graph.markings[s] & end
               for s in range(graph.states))


@dataclass(frozen=True)
class EndTimes:
    """When the runs of a net end (reach an end marking), in units of ``TimedNet.unit``.

    ``earliest`` and ``latest`` over every run; ``latest`` is None if some run
    never ends (``never`` then holds that run's verdict). ``states``: the zones
    explored, ``bound_states`` of them those of the graph whose loops are widened
    (:func:`_latest_bound`); ``latest_path``: the firings of a run that ends at
    ``latest``.
    """

    earliest: int | None
    latest: int | None
    never: TimedVerdict | None
    states: int
    reason: str | None = None
    latest_path: tuple[str, ...] = ()
    bound_states: int = 0


def end_times(tn: TimedNet, ends: Iterable[str], always: TimedVerdict,
              max_states: int = MAX_CHECK_STATES) -> EndTimes:
    """The earliest and latest end times, given ``always`` (the verdict of "an end is
    always reached" on the same net): when it fails, the latest is unbounded. Each
    bound is searched apart, its inclusion blind to the other side of the global clock
    (:meth:`ZoneGraph._seen`), so that runs shifted in time share their zones.

    The earliest: states in the order of their earliest time, up to the first end.
    The latest: searched on a graph whose loops are widened (``widen_loops``), which has
    every run and more, so no run ends later than its latest end. Where a zone on the
    way to that end was widened, a run that ends as late is looked for in the graph
    without widening, latest states first; where none is found, or the widened graph
    has no bound, every state of that graph is searched."""
    ends = list(ends)
    bounded = always.status == "holds"
    ts = _timed_structure(tn, ends)
    states = bound_states = 0
    try:
        first = ZoneGraph(tn, ts, max_states=max_states, stop_at_ends=True, earliest_only=True,
                          cover="earliest")
        first.explore_earliest()
        states = first.states
        last = None
        if bounded:
            last, bound = _latest_bound(tn, ts, max_states)
            states += last.states
            bound_states = last.states
            if bound is not None and bound >= 0:
                last, bound = _latest_run(tn, ts, bound, max_states)
                states += last.states
            if bound is not None:
                last = ZoneGraph(tn, ts, max_states=max_states, stop_at_ends=True,
                                 cover="latest")
                last.explore()
                states += last.states
    except TimedLimit as e:
        # the times are left unknown: the clock of the whole run multiplies the zones
        return EndTimes(None, None, None if bounded else always, states + e.states,
                        reason=f"{e}, with the clock of the whole run")
    if not first.ends:
        return EndTimes(None, None, always if not bounded else None, states)
    earliest = min(e for _, _, e, _ in first.ends)
    if last is None:
        return EndTimes(earliest, None, always, states)
    if any(lt is None for _, _, _, lt in last.ends):
        # every run ends (fairness: a report comes eventually), but not by any bound
        return EndTimes(earliest, None, None, states,
                        reason="no bound: a report that comes eventually may come at any time")
    # of the ends as late, one reached without widening: its path is a run
    state, t, _, latest = max(last.ends, key=lambda e: (e[3], not last.widened[e[0]]))
    # the graph's parents, a list indexed by state, read as path_to reads a map
    trans = path_to(last.parent, state)[1] + [t]
    return EndTimes(earliest, latest, None, states,
                    latest_path=tuple(last.transitions[j] for j in trans),
                    bound_states=bound_states)


def _latest_run(tn: TimedNet, ts: _TimedStructure, bound: int, max_states: int):
    """A run that ends at ``bound`` (a zone on the way to the widened graph's latest end was
    widened), looked for latest states first, without inclusion: it follows the run and
    keeps only the zones it meets, as many as the run's steps and their siblings. The
    graph and None if found, else what it took and -1 (every state is then searched)."""
    graph = ZoneGraph(tn, ts, max_states=min(max_states, LATEST_RUN_STATES),
                      stop_at_ends=True, cover="latest", subsume=False)
    try:
        graph.explore_latest(bound)
    except TimedLimit as e:
        return _Outgrown(e.states), -1
    if any(lt is None or lt >= bound for _, _, _, lt in graph.ends):
        return graph, None
    return graph, -1


class _Outgrown:
    """A graph that outgrew its limit: only its zones are read."""

    def __init__(self, states: int):
        self.states = states


def _latest_bound(tn: TimedNet, ts: _TimedStructure, max_states: int):
    """The graph whose loops are widened, searched to its latest end (``widen_loops``: it
    has every run and more, so no run ends later), and what is left to do: None if that
    end is reached without widening (its graph answers), the bound a run should reach
    otherwise, or -1 if it has none (it outgrew :data:`WIDENED_END_STATES`, or a widened
    zone has no bound): every state is then searched."""
    graph = ZoneGraph(tn, ts, max_states=min(max_states, WIDENED_END_STATES),
                      stop_at_ends=True, cover="latest", widen_loops=True)
    try:
        graph.explore()
    except TimedLimit as e:
        return _Outgrown(e.states), -1
    if not graph.ends:
        return graph, None
    if any(lt is None for _, _, _, lt in graph.ends):
        exact = [e for e in graph.ends if e[3] is None and not graph.widened[e[0]]]
        return graph, (None if exact else -1)
    state, _, _, latest = max(graph.ends, key=lambda e: (e[3], not graph.widened[e[0]]))
    return graph, (None if not graph.widened[state] else latest)


def places(tn: TimedNet) -> list[str]:
    """The places of ``tn`` in the order of the markings' bits."""
    return list(structure(tn.net).places)


def enables(tn: TimedNet, marking: int) -> bool:
    """Whether ``marking`` (a bit mask) enables some transition of ``tn``."""
    return bool(_timed_structure(tn, None).enabled(marking))
