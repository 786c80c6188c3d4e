"""One marking at a time: which transitions it enables and the markings it leads to, for
the searches that walk the net from the initial marking without a graph (CTL on the fly,
the best-first search for bounds).

A marking is an array of token counts (int64), a column per place; enabledness is tested
on every input arc at once (pre and read arcs, weights summed), and the enabled
transitions fired at once, each adding its column of the incidence matrix.
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from mcl2pnml.core.structure import Structure


class Firing:
    """The net's firing on markings as arrays of token counts: which transitions a marking
    enables is tested on every input arc at once, and the enabled ones fired at once."""

    def __init__(self, s: Structure):
        needs, deltas = [], []
        for pre, read, post in zip(s.pre, s.read, s.post):
            need = dict(read)
            for p, w in pre.items():
                need[p] = need.get(p, 0) + w
            needs.append(sorted(need.items()))
            d = dict(post)
            for p, w in pre.items():
                d[p] = d.get(p, 0) - w
            deltas.append([(p, w) for p, w in sorted(d.items()) if w])
        self.needs = needs
        needy = [j for j, need in enumerate(needs) if need]
        self.free = np.array([j for j, need in enumerate(needs) if not need], dtype=np.int64)
        self.needy = np.array(needy, dtype=np.int64)
        self.arc_place = np.array([p for j in needy for p, _ in needs[j]], dtype=np.int64)
        self.arc_weight = np.array([w for j in needy for _, w in needs[j]], dtype=np.int64)
        self.starts = np.cumsum([0] + [len(needs[j]) for j in needy[:-1]], dtype=np.int64)
        self.delta_ptr = np.cumsum([0] + [len(d) for d in deltas], dtype=np.int64)
        self.delta_place = np.array([p for d in deltas for p, _ in d], dtype=np.int64)
        self.delta_weight = np.array([w for d in deltas for _, w in d], dtype=np.int64)

    @cached_property
    def need_arrays(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Each transition's input places and the tokens it needs in each, as arrays."""
        return [(np.array([p for p, _ in need], dtype=np.int64),
                 np.array([w for _, w in need], dtype=np.int64)) for need in self.needs]

    def enabled(self, m: np.ndarray, j: int) -> bool:
        return all(m[p] >= w for p, w in self.needs[j])

    def enabled_all(self, m: np.ndarray) -> np.ndarray:
        """The transitions ``m`` enables, in order."""
        if not len(self.needy):
            return self.free
        ok = np.logical_and.reduceat(m[self.arc_place] >= self.arc_weight, self.starts)
        found = self.needy[ok]
        return np.union1d(found, self.free) if len(self.free) else found

    def fire(self, m: np.ndarray, j: int) -> np.ndarray:
        """The marking ``m`` leads to by firing transition ``j`` (enabled: not checked)."""
        after = m.copy()
        first, last = self.delta_ptr[j], self.delta_ptr[j + 1]
        after[self.delta_place[first:last]] += self.delta_weight[first:last]
        return after

    def successors(self, m: np.ndarray) -> np.ndarray:
        """The markings ``m`` leads to, a row each (one per enabled transition)."""
        fired = self.enabled_all(m)
        rows = np.repeat(m[None, :], len(fired), axis=0)
        first, last = self.delta_ptr[fired], self.delta_ptr[fired + 1]
        counts = last - first
        total = int(counts.sum())
        if total:
            offset = np.repeat(first - (np.cumsum(counts) - counts), counts)
            arcs = offset + np.arange(total)
            rows[np.repeat(np.arange(len(fired)), counts), self.delta_place[arcs]] += \
                self.delta_weight[arcs]
        return rows
