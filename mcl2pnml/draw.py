"""Drawing nets with graphviz, laid out so that a student can follow the tokens.

Conventions of the drawings (a legend is part of every figure):

* places are circles with their name and their tokens (``●``); interface
  (fusion) places have a double border;
* transitions are bars with their name; a timed transition (a time-out) is
  drawn filled, with its delay;
* arcs run left to right, the way tokens flow; a read arc (the transition
  tests the place and leaves its token) is dashed and has no arrow head;
* ``clusters`` group the nodes of one component (the primitive in the task,
  each subordinate structure in a control structure).
"""
from __future__ import annotations

from typing import Mapping, Sequence

import graphviz

from .files import atomic_write_bytes
from .net import ArcKind, Net

TOKEN = "\u25cf"


def _tokens(n: int) -> str:
    return TOKEN * n if n <= 3 else f"{n}{TOKEN}"


def to_dot(net: Net, *, marking: Mapping[str, int] | None = None,
           clusters: Mapping[str, Sequence[str]] | None = None, title: str | None = None,
           legend: bool = True) -> graphviz.Digraph:
    """The net as a graphviz graph (``.source`` for the text, ``.pipe()`` to render)."""
    marking = net.initial if marking is None else marking
    g = graphviz.Digraph(net.name, graph_attr={
        "rankdir": "LR", "nodesep": "0.35", "ranksep": "0.55", "fontname": "Helvetica",
        "fontsize": "12", "label": title or "", "labelloc": "t"},
        node_attr={"fontname": "Helvetica", "fontsize": "10"},
        edge_attr={"arrowsize": "0.6"})
    clustered = {n for members in (clusters or {}).values() for n in members}

    def add_place(target, p) -> None:
        tokens = marking.get(p.id, 0)
        label = p.label + (f"\n{_tokens(tokens)}" if tokens else "")
        target.node(p.id, label, shape="circle", width="0.75", fixedsize="true",
                    peripheries="2" if p.interface is not None else "1")

    def add_transition(target, t) -> None:
        label = t.label
        attrs = {"shape": "box", "height": "0.5", "width": "0.12", "style": "filled",
                 "fillcolor": "white", "xlabel": label, "label": ""}
        if t.timing is not None or (t.payload and t.payload.get("timeout")):
            delay = f" {t.timing}" if t.timing is not None else " (time-out)"
            attrs.update(fillcolor="gray35", xlabel=label + delay)
        target.node(t.id, **attrs)

    for p in net.places:
        if p.id not in clustered:
            add_place(g, p)
    for t in net.transitions:
        if t.id not in clustered:
            add_transition(g, t)
    for name, members in (clusters or {}).items():
        with g.subgraph(name=f"cluster_{name}") as c:
            c.attr(label=name, style="rounded,dashed", color="gray50", fontsize="11")
            members = set(members)
            for p in net.places:
                if p.id in members:
                    add_place(c, p)
            for t in net.transitions:
                if t.id in members:
                    add_transition(c, t)
    for a in net.arcs:
        attrs = {}
        if a.weight != 1:
            attrs["label"] = str(a.weight)
        if a.kind is ArcKind.READ:
            attrs.update(style="dashed", arrowhead="none")
        g.edge(a.source, a.target, **attrs)
    if legend:
        with g.subgraph(name="cluster_legend") as k:
            k.attr(label="legend", fontsize="9", style="rounded", color="gray70")
            k.node("legend_place", f"place\n{TOKEN} token", shape="circle", width="0.6",
                   fixedsize="true", fontsize="8")
            k.node("legend_iface", "fusion\nplace", shape="circle", width="0.6",
                   fixedsize="true", peripheries="2", fontsize="8")
            k.node("legend_t", "", shape="box", height="0.4", width="0.1", xlabel="transition",
                   fontsize="8")
            k.node("legend_timed", "", shape="box", height="0.4", width="0.1", style="filled",
                   fillcolor="gray35", xlabel="time-out", fontsize="8")
            k.edge("legend_place", "legend_t", label="arc", fontsize="8")
            k.edge("legend_iface", "legend_timed", label="read arc", style="dashed",
                   arrowhead="none", fontsize="8")
    return g


def render(graph: graphviz.Digraph, path: str, fmt: str) -> None:
    """Render to ``path`` in ``fmt`` (svg, png...), written whole or not at all."""
    atomic_write_bytes(path, graph.pipe(format=fmt))
