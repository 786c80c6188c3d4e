"""The graph searches of :mod:`mcl2pnml.analysis.contest.answers` in Python: the backend where the loops in C
(``analysis/statespace/loops/_native.c``: ``scc``, ``back_reach``, ``ltl_product``) were not built.

The same functions, the same arguments and results, so that one test suite runs both
(tests/test_graph_kernels.py); these are the same algorithms written plainly, for a
machine without a C compiler, and slower by the interpreter's factor.
"""
from __future__ import annotations

import numpy as np


def scc(indptr: np.ndarray, indices: np.ndarray, keep: np.ndarray, label: np.ndarray) -> int:
    """The strongly connected components of the graph restricted to the kept nodes, by
    Tarjan's algorithm without recursion: ``label[v]`` v's component (-1 where not kept),
    numbered in the order they complete; returns their number."""
    n = len(indptr) - 1
    ptr, idx, kept = indptr.tolist(), indices.tolist(), keep.astype(bool).tolist()
    num, low = [0] * n, [0] * n                 # num 0: not met; -1: its component is done
    out = [-1] * n
    count, nxt = 0, 1
    for root in range(n):
        if not kept[root] or num[root]:
            continue
        num[root] = low[root] = nxt
        nxt += 1
        open_, call = [root], [[root, ptr[root]]]
        while call:
            frame = call[-1]
            v, e = frame
            if e < ptr[v + 1]:
                frame[1] = e + 1
                w = idx[e]
                if not kept[w]:
                    continue
                if not num[w]:
                    num[w] = low[w] = nxt
                    nxt += 1
                    open_.append(w)
                    call.append([w, ptr[w]])
                elif num[w] > 0 and num[w] < low[v]:
                    low[v] = num[w]
                continue
            call.pop()
            if low[v] == num[v]:
                while True:
                    w = open_.pop()
                    num[w] = -1
                    out[w] = count
                    if w == v:
                        break
                count += 1
            if call:
                u = call[-1][0]
                low[u] = min(low[u], low[v])
    label[:] = out
    return count


def back_reach(indptr: np.ndarray, indices: np.ndarray, through: np.ndarray,
               out: np.ndarray) -> None:
    """With the predecessors' CSR, add to ``out`` every node of ``through`` from which a
    path inside ``through`` reaches one of its nodes: E(through U out), a frontier at a
    time."""
    mark = out.view(bool)
    allowed = through.astype(bool)
    frontier = np.flatnonzero(mark)
    while len(frontier):
        starts, ends = indptr[frontier], indptr[frontier + 1]
        sizes = ends - starts
        if not sizes.sum():
            break
        # the predecessors of the whole frontier, gathered at once
        offsets = np.repeat(starts - np.cumsum(sizes) + sizes, sizes) + np.arange(sizes.sum())
        found = np.unique(indices[offsets])
        frontier = found[allowed[found] & ~mark[found]]
        mark[frontier] = True


def ltl_product(indptr, indices, a_ptr, a_succ, label, acc, all_sets: int, initial, num,
                max_states: int) -> tuple[int, int]:
    """Couvreur's on-the-fly emptiness check of the graph's product with a generalised
    Büchi automaton (analysis/statespace/loops/_native.c's ``ltl_product``, its arguments and result):
    ``(1, states)`` an accepting cycle, ``(0, states)`` none, ``(-1, states)`` past
    ``max_states``."""
    n, k = len(indptr) - 1, len(a_ptr) - 1
    ptr, idx = indptr.tolist(), indices.tolist()
    aptr, asucc = a_ptr.tolist(), a_succ.tolist()
    reads, sets = label.astype(bool).tolist(), [int(x) for x in acc]
    nxt = 1
    for first in initial.tolist():
        if num[first]:
            continue
        num[first] = nxt
        nxt += 1
        open_, roots, call = [first], [[num[first], sets[first % k]]], [[first, 0]]
        while call:
            frame = call[-1]
            p, cursor = frame
            s, a = divmod(p, k)
            degree, moves = ptr[s + 1] - ptr[s], aptr[a + 1] - aptr[a]
            if cursor < degree * moves:
                frame[1] = cursor + 1
                b = asucc[aptr[a] + cursor // degree]
                t = idx[ptr[s] + cursor % degree]
                if not reads[b * n + t]:
                    continue
                q = t * k + b
                if not num[q]:
                    if nxt > max_states:
                        return -1, nxt - 1
                    num[q] = nxt
                    nxt += 1
                    open_.append(q)
                    roots.append([num[q], sets[b]])
                    call.append([q, 0])
                elif num[q] > 0:
                    # a cycle closes: every root above q's joins the component below
                    met = 0
                    while roots[-1][0] > num[q]:
                        met |= roots.pop()[1]
                    roots[-1][1] |= met
                    if roots[-1][1] == all_sets:
                        return 1, nxt - 1
                continue
            call.pop()
            if roots[-1][0] == num[p]:
                roots.pop()
                while True:
                    w = open_.pop()
                    num[w] = -1
                    if w == p:
                        break
    return 0, nxt - 1
