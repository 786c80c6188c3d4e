"""A graph's edges in compressed rows (CSR): the row pointers, and the edges in a stable
order by source, by a counting sort in the loops (O(edges); a comparison sort was most of
what labelling a graph of tens of millions of edges took). The property checker's product
and the contest's labelling both read their graphs so."""
from __future__ import annotations

import numpy as np

from mcl2pnml.analysis.statespace.loops.backends import chosen


def _rows(src: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    src = np.ascontiguousarray(src, dtype=np.int64)
    ptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(src, minlength=n), out=ptr[1:])
    return src, ptr


def by_source(src: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``(ptr, order)``: row ``v``'s edges are ``order[ptr[v]:ptr[v + 1]]``, in the order
    ``src`` gave them (positions into ``src`` and its sibling arrays)."""
    src, ptr = _rows(src, n)
    order = np.empty(len(src), dtype=np.int64)
    chosen().scatter_by_source(src, np.arange(len(src), dtype=np.int64), ptr[:-1].copy(),
                               order)
    return ptr, order


def compressed_rows(src: np.ndarray, dst: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A graph's edges as compressed rows: row pointers, then the targets in source order."""
    src, ptr = _rows(src, n)
    dst = np.ascontiguousarray(dst, dtype=np.int64)
    if len(src) < 2 or bool((src[1:] >= src[:-1]).all()):
        # already by source (an explorer that fires a marking's transitions in turn):
        # the targets are the rows as they stand
        return ptr, dst
    targets = np.empty(len(src), dtype=np.int64)
    chosen().scatter_by_source(src, dst, ptr[:-1].copy(), targets)
    return ptr, targets
