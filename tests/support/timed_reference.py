"""A second, independent reading of docs/time.md's semantics: discrete time, one state per
unit, every clock's value kept (capped where it no longer matters). Exact for our closed
intervals (digitization), slow with large constants: the tests hold the zone graph of
:mod:`mcl2pnml.analysis.timed.zones` to it on small nets and short time-outs."""
from __future__ import annotations

from collections import deque

from mcl2pnml.core.structure import structure
from mcl2pnml.core.timing import TimedNet


class Discrete:
    def __init__(self, tn: TimedNet):
        s = structure(tn.net)
        self.s, self.tn = s, tn
        self.T = len(s.transitions)
        self.lo = [tn.intervals.get(t, (0, None))[0] for t in s.transitions]
        self.hi = [tn.intervals.get(t, (0, None))[1] for t in s.transitions]
        self.prio = [t in tn.priority for t in s.transitions]
        self.eager = [t in tn.eager for t in s.transitions]
        self.group = [-1] * self.T
        self.gap = [g for _, g in tn.gaps]
        for k, (members, _) in enumerate(tn.gaps):
            for t in members:
                self.group[s.transition_index[t]] = k
        # one timer per transition, or per group sharing a clock
        self.timer = list(range(self.T))
        for group in tn.shared:
            idx = sorted(s.transition_index[t] for t in group)
            for j in idx:
                self.timer[j] = idx[0]
        self.cap = [max(self.lo[j], self.hi[j] or 0) for j in range(self.T)]

    def on(self, en, k) -> bool:
        """Whether timer k runs: one of its transitions is enabled."""
        return any(self.timer[j] == k for j in en)

    def enabled(self, m) -> list[int]:
        return [j for j in range(self.T) if self.s.enabled(list(m), j)]

    def initial(self):
        m = tuple(self.s.initial_vector())
        en = self.enabled(m)
        clocks = tuple(0 if self.on(en, k) else None for k in range(self.T))
        gaps = tuple(self.gap)      # the first report of a group is unconstrained
        return (m, clocks, gaps)

    def moves(self, state):
        """(label, next state, delay) for each discrete firing (label the transition index)
        and the tick (label None, delay 1)."""
        m, clocks, gaps = state
        en = self.enabled(m)
        cand = [j for j in en if self.prio[j]] or [j for j in en if self.eager[j]] or en
        out = []
        for j in cand:
            if clocks[self.timer[j]] < self.lo[j]:
                continue
            g = self.group[j]
            if g >= 0 and gaps[g] < self.gap[g]:
                continue
            mm = list(m)
            self.s.fire(mm, j)
            mm = tuple(mm)
            en2 = set(self.enabled(mm))
            tj = self.timer[j]
            nc = tuple((0 if (k == tj or clocks[k] is None) else clocks[k])
                       if self.on(en2, k) else None for k in range(self.T))
            ng = tuple(0 if k == g else v for k, v in enumerate(gaps))
            out.append((j, (mm, nc, ng), 0))
        urgent = any(self.hi[j] == 0 for j in en) or any(self.prio[j] for j in en)
        if not urgent and all(self.hi[j] is None or clocks[self.timer[j]] + 1 <= self.hi[j]
                              for j in en):
            nc = tuple(None if c is None else min(c + 1, self.cap[k]) for k, c in enumerate(clocks))
            ng = tuple(min(v + 1, self.gap[k]) for k, v in enumerate(gaps))
            out.append((None, (m, nc, ng), 1))
        return out

    def end_times(self, ends, limit=2_000_000):
        """(earliest, latest) global time of a first end; latest None if some run reaches
        a state again without ending (and time passes on the way) or waits for ever."""
        idx = [self.s.place_index[p] for p in ends if p in self.s.place_index]
        start = (self.initial(), 0)
        seen = {start}
        queue = deque([start])
        earliest = latest = None
        while queue:
            state, t = queue.popleft()
            if any(state[0][i] for i in idx):
                earliest = t if earliest is None else min(earliest, t)
                latest = t if latest is None else max(latest, t)
                continue
            for _, nxt, d in self.moves(state):
                item = (nxt, t + d)
                if item not in seen:
                    if len(seen) > limit:
                        raise RuntimeError(f"more than {limit:,} discrete states")
                    seen.add(item)
                    queue.append(item)
        return earliest, latest

    def always_ends(self, ends, limit=500_000) -> bool:
        """Whether every time-divergent run reaches an end: no cycle of states without an
        end (time passing on it: a tick) is reachable, waiting for ever included (a tick
        that changes nothing)."""
        import networkx as nx
        idx = [self.s.place_index[p] for p in ends if p in self.s.place_index]
        start = self.initial()
        seen = {start: 0}
        order = [start]
        g = nx.DiGraph()
        k = 0
        while k < len(order):
            state = order[k]
            k += 1
            if any(state[0][i] for i in idx):
                continue
            for j, nxt, d in self.moves(state):
                if nxt not in seen:
                    if len(seen) > limit:
                        raise RuntimeError(f"more than {limit:,} discrete states")
                    seen[nxt] = len(order)
                    order.append(nxt)
                if not any(nxt[0][i] for i in idx):
                    a, b = seen[state], seen[nxt]
                    g.add_edge(a, b, tick=(g.get_edge_data(a, b, {}).get("tick", False) or d > 0))
        for comp in nx.strongly_connected_components(g):
            sub = g.subgraph(comp)
            if any(d["tick"] for _, _, d in sub.edges(data=True)):
                return False
        return True
