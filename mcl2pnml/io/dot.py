"""graphviz's DOT: nets as drawings a student can follow the tokens in (and SVG, PNG).

Conventions of the drawings (a legend is part of every figure):

* places are circles with their name and their tokens (``●``); interface
  (fusion) places have a double border;
* transitions are bars with their name; a timed transition (a time-out) is
  drawn filled, with its delay;
* arcs run left to right, the way tokens flow; a read arc (the transition
  tests the place and leaves its token) is dashed and has no arrow head;
* ``clusters`` group the nodes of one component (the primitive in the task,
  each subordinate structure in a control structure, each task, structure
  and call site of a mission), named inside their box without the box's
  name; the places where boxes meet (fusion places) are drawn outside
  every box, between the boxes they join;
* every node has a ``class`` (``place``, ``transition``, ``copy``,
  ``legend``), which SVG keeps, so that a page or a script can find them;
* a place that many transitions give tokens back to (a mutex) is drawn again,
  dashed and small, beside each of them, like PNML's reference places.
"""
from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Mapping, Sequence

import graphviz

from mcl2pnml.core.errors import OptionError
from mcl2pnml.core.files import atomic_write_bytes, atomic_write_text
from mcl2pnml.core.net import ArcKind, Net
from mcl2pnml.core.payloads import read_transition

TOKEN = "\u25cf"
#: graphviz settings that bound dot's slowest phases, network simplex
#: (``nslimit``) and crossing minimisation (``mclimit``): without them dot
#: takes 45 s on the paper's mission (421 nodes). ``newrank`` ranks the
#: instance boxes together, which is faster still and avoids graphviz 2.43's
#: "trouble in init_rank" on missions of 50 calls and more.
DOT_SPEED = {"nslimit": "2", "nslimit1": "2", "mclimit": "0.5", "newrank": "true"}
#: A place that this many arcs return tokens to is drawn again beside each of them.
COPY_RETURNS = 3


def _tokens(n: int) -> str:
    return TOKEN * n if n <= 3 else f"{n}{TOKEN}"


def node_name(node_id: str) -> str:
    """A node's name in DOT: its id, unless DOT would read that id as something else.

    In an edge ``a:b`` is node ``a``, port ``b``; ``<...>`` is an HTML string
    (markup graphviz renders, images it reads from disk included); a
    backslash or a quote can end a quoted name early; graphviz keeps names
    that start with ``%`` for its anonymous nodes. Such an id is named
    ``~x`` and its UTF-8 in hex, which :func:`node_id` reads back; an id that
    starts with ``~x`` is encoded too, so that an encoded name is never a real id.
    """
    if (any(c in node_id for c in ':\\"') or node_id.startswith(("%", _ENCODED))
            or (node_id.startswith("<") and node_id.endswith(">"))):
        return _ENCODED + node_id.encode().hex()
    return node_id


def node_id(name: str) -> str:
    """The id of the node named ``name`` in DOT (the inverse of :func:`node_name`)."""
    if name.startswith(_ENCODED):
        try:
            return bytes.fromhex(name[len(_ENCODED):]).decode()
        except ValueError:      # a copy of a place (``NAME~3``), not a node of the net
            return ""
    return name


_ENCODED = "~x"


def _text(label: str) -> str:
    """A label as plain text: graphviz must neither read it as HTML nor expand ``\\N``."""
    return graphviz.escape(label)


def to_dot(net: Net, *, marking: Mapping[str, int] | None = None,
           clusters: Mapping[str, Sequence[str]] | None = None, title: str | None = None,
           legend: bool = True) -> graphviz.Digraph:
    """The net as a graphviz graph (``.source`` for the text, ``.pipe()`` to render)."""
    marking = net.initial if marking is None else marking
    g = graphviz.Digraph(net.name, graph_attr={
        "rankdir": "LR", "nodesep": "0.35", "ranksep": "0.55", "fontname": "Helvetica",
        "fontsize": "12", "label": title or "", "labelloc": "t", **DOT_SPEED},
        node_attr={"fontname": "Helvetica", "fontsize": "10"},
        edge_attr={"arrowsize": "0.6"})
    clusters = border_out(net, clusters or {})
    box = {n: name for name, members in clusters.items() for n in members}
    clustered = set(box)

    def add_place(target, p, box_name: str | None = None) -> None:
        tokens = marking.get(p.id, 0)
        shown = _inside(p.label, box_name)
        label = shown + (f"\n{_tokens(tokens)}" if tokens else "")
        # circles all of one size read best; long names get a larger one
        width = max(0.75, 0.085 * len(shown) + 0.15)
        target.node(node_name(p.id), _text(label), shape="circle", width=f"{width:.2f}",
                    fixedsize="true",
                    peripheries="2" if p.interface is not None else "1",
                    **{"class": "place"})

    def add_transition(target, t, box_name: str | None = None) -> None:
        label = _inside(t.label, box_name)
        attrs = {"shape": "box", "height": "0.5", "width": "0.12", "style": "filled",
                 "fillcolor": "white", "xlabel": _text(label), "label": "",
                 "class": "transition"}
        if t.timing is not None or read_transition(t).timeout is not None:
            delay = f" {t.timing}" if t.timing is not None else " (time-out)"
            attrs.update(fillcolor="gray35", xlabel=_text(label + delay))
        target.node(node_name(t.id), **attrs)

    for p in net.places:
        if p.id not in clustered:
            add_place(g, p)
    for t in net.transitions:
        if t.id not in clustered:
            add_transition(g, t)
    for name, members in clusters.items():
        with g.subgraph(name=f"cluster_{name}") as c:
            c.attr(label=_text(name), style="rounded,dashed", color="gray50", fontsize="11")
            for m in members:   # net order within the cluster, as given
                if m in net.place_index:
                    add_place(c, net.place_index[m], name)
                else:
                    add_transition(c, net.transition_index[m], name)
    # where tokens come in on the left, where results come out on the right
    written = {a.target for a in net.arcs if a.target in net.place_index}
    read_or_taken = {a.source for a in net.arcs if a.source in net.place_index}
    first = [p.id for p in net.places if p.id not in clustered
             and (p.id not in written or (p.interface is not None and p.id in net.initial))]
    last = [p.id for p in net.places if p.id not in clustered and p.id not in read_or_taken]
    for rank, members in (("source", first), ("sink", last)):
        if members:
            with g.subgraph() as r:
                r.attr(rank=rank)
                for m in members:
                    r.node(node_name(m))
    depth = flow_depth(net)
    back = {a for a in net.arcs if a.kind is ArcKind.NORMAL
            and depth.get(a.target, 0) <= depth.get(a.source, 0)}
    returns: dict[str, int] = {}
    for a in back:
        if a.target in net.place_index:
            returns[a.target] = returns.get(a.target, 0) + 1
    copies = 0
    for a in net.arcs:
        attrs = {}
        target = node_name(a.target)
        if a.weight != 1:
            attrs["label"] = str(a.weight)
        if a.kind is ArcKind.READ:
            # a test is not a flow of tokens: it must not bend the layout
            attrs.update(style="dashed", arrowhead="none", constraint="false")
        elif a in back and returns.get(a.target, 0) >= COPY_RETURNS:
            # many tokens going back to one place (a mutex freed by every
            # ending): each arc goes to a copy of the place drawn beside its
            # transition, as PNML's reference places do, instead of crossing
            # the whole drawing
            copies += 1
            target = f"{target}~{copies}"
            place = net.place_index[a.target]
            name = box.get(a.source)   # in its transition's box, if it has one
            where = g.subgraph(name=f"cluster_{name}") if name else contextlib.nullcontext(g)
            shown = _inside(place.label, name)
            with where as c:
                c.node(target, _text(shown), shape="circle", fixedsize="true", style="dashed",
                       width=f"{max(0.55, 0.07 * len(shown) + 0.15):.2f}", fontsize="8",
                       **{"class": "copy"})
        elif a in back:
            # a token going back (a primitive switched off): drawn, but the
            # left-to-right order follows the forward flow
            attrs.update(constraint="false", color="gray40")
        g.edge(node_name(a.source), target, **attrs)
    if legend:
        with g.subgraph(name="cluster_legend") as k:
            k.attr(label="legend", fontsize="9", style="rounded", color="gray70")
            k.attr("node", **{"class": "legend"})
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


def flow_depth(net: Net) -> dict[str, int]:
    """How far each node is from where the net starts, along the token flow.

    Breadth-first from the input places (nothing writes to them: B and A, or
    E and D) and from the marked places, over normal arcs only.
    """
    written = {a.target for a in net.arcs if a.target in net.place_index}
    start = [p.id for p in net.places if p.id not in written] + \
        [p for p in net.initial if p in written]
    succ: dict[str, list[str]] = {}
    for a in net.arcs:
        if a.kind is ArcKind.NORMAL:
            succ.setdefault(a.source, []).append(a.target)
    depth = {n: 0 for n in start}
    frontier = list(dict.fromkeys(start))
    while frontier:
        nxt = []
        for n in frontier:
            for m in succ.get(n, ()):
                if m not in depth:
                    depth[m] = depth[n] + 1
                    nxt.append(m)
        frontier = nxt
    return depth


def _inside(label: str, box_name: str | None) -> str:
    """A node's label inside its box: without the box's name, which the box shows."""
    prefix = f"{box_name}." if box_name else None
    return label[len(prefix):] if prefix and label.startswith(prefix) else label


def border_out(net: Net, clusters: Mapping[str, Sequence[str]]) -> dict[str, list[str]]:
    """The clusters without their border places: those joined to other boxes.

    A place that transitions of two boxes (or of a box and the loose nodes)
    put tokens in or take them from is where the boxes meet, a fusion place
    of the composition; drawn outside every box, it sits between the boxes
    it joins, on their borders, and its arcs show which.
    """
    box = {n: name for name, members in clusters.items() for n in members}
    touches: dict[str, set] = {}
    for a in net.arcs:
        place, transition = ((a.source, a.target) if a.source in net.place_index
                             else (a.target, a.source))
        touches.setdefault(place, set()).add(box.get(transition))
    border = {p for p, boxes in touches.items() if len(boxes) > 1}
    kept = {name: [n for n in members if n not in border] for name, members in clusters.items()}
    return {name: members for name, members in kept.items() if members}


def instance_clusters(net: Net) -> dict[str, list[str]]:
    """Nodes grouped by instance: the part of their id before the last dot.

    A compiled mission names every node after its component
    (``mission.sequence-1.t2``), so this draws each task, structure and call
    site in its own box. Ids without a dot, and groups of one, stay loose.
    """
    groups: dict[str, list[str]] = {}
    for node in (*net.places, *net.transitions):
        stem, dot, _ = node.id.rpartition(".")
        if dot and stem:
            groups.setdefault(stem, []).append(node.id)
    return {k: v for k, v in groups.items() if len(v) > 1}


#: How to get graphviz's ``dot`` program, for the message when it is missing.
INSTALL_DOT = ("install graphviz (apt-get install graphviz, dnf install graphviz, "
               "brew install graphviz, or https://graphviz.org/download/)")


def dot_missing(option: str, without: str) -> OptionError:
    """The one message when ``option`` needs graphviz's ``dot`` program and it is not on
    the PATH: what is missing, how to install it, and (``without``) what works without it."""
    return OptionError(option, f"graphviz's 'dot' program is not installed (no 'dot' on "
                               f"the PATH): {INSTALL_DOT}; {without}")


def render(graph: graphviz.Digraph, path: str, fmt: str) -> None:
    """Render to ``path`` in ``fmt`` (svg, png...), written whole or not at all."""
    try:
        data = graph.pipe(format=fmt)
    except graphviz.ExecutableNotFound:
        raise dot_missing("--format", "the formats pnml, tina, lola and dot (the source) "
                                      "work without it") from None
    atomic_write_bytes(path, data)


def drawing(net: Net, title: str | None = None) -> graphviz.Digraph:
    """The figure of ``net``: each instance in its box, titled, with the legend."""
    return to_dot(net, clusters=instance_clusters(net), title=title or net.name, legend=True)


def save_dot(net: Net, path: str | Path, *, title: str | None = None) -> None:
    """The drawing's DOT source, to ``path``, whole or not at all."""
    atomic_write_text(path, drawing(net, title).source)


def save_svg(net: Net, path: str | Path, *, title: str | None = None) -> None:
    render(drawing(net, title), str(path), "svg")


def save_png(net: Net, path: str | Path, *, title: str | None = None) -> None:
    render(drawing(net, title), str(path), "png")
