"""The reachability graph of a small net, as the token-game page draws it.

A node is a reachable marking, an edge a firing (section 2.3 of the paper
reads a net's behaviour off this graph: its dead markings, whether the
proper end is always reached). The graph is computed here, by the explorer
``analyze`` chooses (:func:`analysis.statespace.explore`), not in the page,
so that the page shows the markings the analysis counts; above
:data:`GRAPH_LIMIT` markings a drawing would be a heap nobody can read, and
the page says so instead.

The drawing is layered: a marking's layer is its breadth-first distance
from M0 (the length of a shortest firing sequence that reaches it), and
markings keep the explorer's order within a layer.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from mcl2pnml.core.net import Net

#: Above this many reachable markings the page draws no graph, and says so.
GRAPH_LIMIT = 2_000


@dataclass(frozen=True)
class Graph:
    """The reachability graph of one net, or why there is none.

    ``markings[k]`` lists marking k's marked places as (place index, tokens);
    marking 0 is M0. ``edges`` are (from, to, transition index); ``layers[k]``
    is marking k's distance from M0; ``dead`` the markings where nothing is
    enabled. ``reason`` is set, and the rest empty, when the graph is not
    given: more than :data:`GRAPH_LIMIT` markings, or an unbounded net.
    """

    markings: tuple[tuple[tuple[int, int], ...], ...] = ()
    edges: tuple[tuple[int, int, int], ...] = ()
    layers: tuple[int, ...] = ()
    dead: tuple[int, ...] = ()
    reason: str | None = None

    def to_json(self) -> dict[str, Any]:
        """The graph as the page's data (and ``show --graph-json``)."""
        if self.reason is not None:
            return {"reason": self.reason, "limit": GRAPH_LIMIT}
        return {"markings": [list(map(list, m)) for m in self.markings],
                "edges": [list(e) for e in self.edges], "layers": list(self.layers),
                "dead": list(self.dead), "limit": GRAPH_LIMIT}


def reachability_graph(net: Net, limit: int = GRAPH_LIMIT) -> Graph:
    """The reachability graph of ``net`` from its M0, if it has at most ``limit`` markings."""
    from analysis.statespace import ExplorationLimit, explore

    try:
        # the explorer analyze chooses (for a safe net, the native one: milliseconds where
        # the general one takes seconds), so the graph has the markings analyze counts
        space = explore(net, max_states=limit)
    except ExplorationLimit:
        return Graph(reason=f"more than {limit:,} reachable markings: the page draws the "
                            f"graph of smaller nets only (analyze counts them)")
    if space.coverability:
        return Graph(reason="the net is unbounded: its markings are infinitely many "
                            "(analyze gives its coverability graph)")
    edges = tuple((int(a), int(b), int(t)) for a, b, t in zip(space.src, space.dst, space.trans))
    after: list[list[int]] = [[] for _ in range(space.states)]
    for a, b, _ in edges:
        after[a].append(b)
    layers = [-1] * space.states
    layers[0], frontier = 0, [0]
    while frontier:   # breadth first: a marking's layer is its distance from M0
        nxt = []
        for a in frontier:
            for b in after[a]:
                if layers[b] < 0:
                    layers[b] = layers[a] + 1
                    nxt.append(b)
        frontier = nxt
    markings = tuple(tuple((p, int(n)) for p, n in enumerate(m) if n) for m in space.markings)
    return Graph(markings, edges, tuple(layers), tuple(int(k) for k in space.terminal))
