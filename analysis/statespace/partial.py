"""The part of a reachability graph that an exploration built before a limit stopped it.

A breadth-first exploration stopped at its limit holds its markings in the order found
(:class:`~mcl2pnml.analysis.statespace.general.FoundMarkings`): the first ``expanded`` had
all their successors found, each among the rows; the others are its frontier. Their
firings are fired again here, by the bounded nets' loops (a safe net's rows are the same
rows with one-bit counters), and looked up among the found rows:

* every edge of an expanded marking, so that a path of this graph is a run of the net
  and every run from M0 stays in it until it meets the frontier;
* which frontier markings are dead (they enable nothing: nothing is hidden behind them,
  they are as good as expanded); the others are **open**: their futures are unknown.

The contest's labelling reads it three-valued (:class:`mcl2pnml.analysis.contest.answers.
PartialGraph`; Bruns and Godefroid's partial Kripke structures, 1999): a formula is
decided at M0 where it is the same whatever the open markings do.
"""
from __future__ import annotations

import numpy as np

from mcl2pnml.core.memory import default_memory
from mcl2pnml.core.structure import Structure

from mcl2pnml.analysis.statespace.counters import Layout, counter_net
from mcl2pnml.analysis.statespace.general import FoundMarkings
from mcl2pnml.analysis.statespace.loops.backends import chosen

#: Bytes a marking and an edge of a partial graph take while it is labelled: the lookup
#: table and out-degree, then the edges (three int32), their two compressed copies in
#: int64 (successors, predecessors) and the labels' working columns.
STATE_BYTES, EDGE_BYTES = 64, 48


class PartialStateSpace:
    """The found markings (node n the n-th found, node 0 the initial one), the edges of
    the expanded ones (``src``, ``trans``, ``dst``) and the ``open`` frontier."""

    coverability = False

    def __init__(self, structure: Structure, found: FoundMarkings, open_: np.ndarray,
                 edges: tuple[np.ndarray, np.ndarray, np.ndarray]):
        self.structure, self.found, self.open = structure, found, open_
        self.src, self.trans, self.dst = edges

    @property
    def states(self) -> int:
        return self.found.states

    def tokens(self, place: int) -> np.ndarray:
        return self.found.tokens(place)

    def open_markings(self) -> FoundMarkings:
        """The open markings alone, in node order, packed as found."""
        f = self.found
        return FoundMarkings(f.rows[self.open], f.word, f.shift, f.mask)


def partial_space(s: Structure, found: FoundMarkings, max_memory: int | None = None,
                  max_edges: int | None = None) -> PartialStateSpace | None:
    """The graph of what was found (the module's documentation), or None where the found
    rows are not packed as counters are, none was expanded, or its edges are more than
    ``max_edges`` (none: as many as int32 numbers) or would not fit in ``max_memory`` (default:
    :func:`~mcl2pnml.core.memory.default_memory`)."""
    layout = Layout([int(m).bit_length() for m in found.mask[:len(s.places)]])
    n, expanded = found.states, found.expanded
    if (expanded <= 0 or layout.word != found.word[:len(s.places)]
            or layout.shift != found.shift[:len(s.places)]
            or layout.words != found.rows.shape[1]):
        return None
    budget = default_memory() if max_memory is None else max_memory
    if n * STATE_BYTES > budget:
        return None
    loops, net = chosen(), counter_net(s, layout)
    rows = np.ascontiguousarray(found.rows)
    degree = loops.counter_out_degree(rows, net)
    total = int(degree[:expanded].sum(dtype=np.int64))
    most = 2 ** 31 - 1 if max_edges is None else min(max_edges, 2 ** 31 - 1)
    if n * STATE_BYTES + total * EDGE_BYTES > budget or total > most:
        return None
    index = loops.counter_search(rows, np.full(n, -1, dtype=np.int64), n, expanded).index
    edges = loops.counter_edges(rows, index, net, total)
    del index
    open_ = degree > 0
    open_[:expanded] = False
    return PartialStateSpace(s, found, open_, edges)
