"""The reachability graph of a small net, as the token-game page draws it.

A node is a reachable marking, an edge a firing (section 2.3 of the paper
reads a net's behaviour off this graph: its dead markings, whether the
proper end is always reached). The graph is computed here, by the explorer
``analyze`` chooses (:func:`mcl2pnml.analysis.statespace.explore.explore`), not in the page,
so that the page shows the markings the analysis counts; above
:data:`GRAPH_LIMIT` markings a drawing would be a heap nobody can read, and
the page says so instead.

``layers`` gives each marking its breadth-first distance from M0 (the
length of a shortest firing sequence that reaches it). The page draws the
graph layered (a Sugiyama drawing made by its script): the cycles broken
where a depth-first walk from M0 closes them, each node on the layer of the
longest path to it, an edge that spans layers routed through gaps kept for
it in the layers between (so that it is drawn through no other marking),
one that goes back or along a layer drawn as a curve; each edge is
labelled with its transitions' names. Past :data:`CONDENSE_ABOVE` markings
the page draws the condensed graph: the strongly connected components
(``components``, numbered in a topological order of the condensation, M0's
first) as nodes, the component of the current marking expanded into its
markings.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from mcl2pnml.core.net import Net

#: Above this many reachable markings the page draws no graph, and says so.
GRAPH_LIMIT = 2_000
#: Above this many markings the page draws the strongly connected components as nodes,
#: the current marking's expanded (a drawing of every marking would be a heap).
CONDENSE_ABOVE = 300


@dataclass(frozen=True)
class Graph:
    """The reachability graph of one net, or why there is none.

    ``markings[k]`` lists marking k's marked places as (place index, tokens);
    marking 0 is M0. ``edges`` are (from, to, transition index); ``layers[k]``
    is marking k's distance from M0; ``dead`` the markings where nothing is
    enabled; ``components[k]`` marking k's strongly connected component, the
    components numbered in a topological order of the condensation (so M0's is 0,
    and an edge never goes from a component to one numbered lower). ``reason`` is set, and the rest empty, when the graph is not
    given: more than :data:`GRAPH_LIMIT` markings, or an unbounded net.
    """

    markings: tuple[tuple[tuple[int, int], ...], ...] = ()
    edges: tuple[tuple[int, int, int], ...] = ()
    layers: tuple[int, ...] = ()
    dead: tuple[int, ...] = ()
    components: tuple[int, ...] = ()
    reason: str | None = None

    def to_json(self) -> dict[str, Any]:
        """The graph as the page's data (and ``show --graph-json``)."""
        if self.reason is not None:
            return {"reason": self.reason, "limit": GRAPH_LIMIT}
        return {"markings": [list(map(list, m)) for m in self.markings],
                "edges": [list(e) for e in self.edges], "layers": list(self.layers),
                "dead": list(self.dead), "components": list(self.components),
                "condense": CONDENSE_ABOVE, "limit": GRAPH_LIMIT}


def reachability_graph(net: Net, limit: int = GRAPH_LIMIT) -> Graph:
    """The reachability graph of ``net`` from its M0, if it has at most ``limit`` markings."""
    # numpy with the explorers, 0.17 s (python -X importtime): only when a page has a
    # graph, not for every page or run log of the view
    from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore

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
    return Graph(markings, edges, tuple(layers), tuple(int(k) for k in space.terminal),
                 components(space.states, edges))


def components(states: int, edges: tuple[tuple[int, int, int], ...]) -> tuple[int, ...]:
    """Each marking's strongly connected component (networkx's condensation), the
    components numbered in a topological order of the condensation, ties broken by their
    first marking, so that M0's (from which every marking is reached) is 0."""
    import networkx as nx   # 0.11 s (python -X importtime): as reachability_graph's explorers

    g = nx.DiGraph()
    g.add_nodes_from(range(states))
    g.add_edges_from((a, b) for a, b, _ in edges)
    dag = nx.condensation(g)
    first = {c: min(dag.nodes[c]["members"]) for c in dag}
    order = nx.lexicographical_topological_sort(dag, key=first.__getitem__)
    number = {c: k for k, c in enumerate(order)}
    mapping = dag.graph["mapping"]
    return tuple(number[mapping[k]] for k in range(states))
