"""Drawings of nets a student can follow the tokens in: what is drawn, and how.

The rules of the drawings live here; the drawing is a graphviz graph, whose
DOT text :mod:`mcl2pnml.io.dot` writes, or has graphviz's ``dot`` render as
SVG or PNG.

Conventions of the drawings (a legend is part of every figure):

* tokens flow top down, from the places nothing writes (B, A: where the
  structure above starts and aborts) to the results (OK, FAIL, ABORTED),
  which are drawn once each at the bottom;
* places are circles with their name and their tokens (``●``); interface
  (fusion) places have a double border;
* transitions are boxes with their name inside: dot keeps a node clear of
  every arc and every other node, where an external label (``xlabel``) is
  placed after the arcs and lands on them; a time-out is dark, with its
  delay (``◷ 300 s``; the task pattern's ``t03``, section 2.3);
* a read arc (the transition tests the place and leaves its token) is
  dashed and has no arrow head; a token going back (a primitive switched
  off) is grey and does not rank the nodes;
* ``clusters`` group the nodes of one component (the primitive in the task,
  Fig. 2; T1 and T2 in a structure, Fig. 4; each task, structure and call
  site of a mission), named inside their box without the box's name; the
  places where boxes meet (fusion places) are drawn outside every box,
  between the boxes they join;
* a mission is drawn one call at a time (:mod:`mcl2pnml.view.calls`): the
  call's net in its dashed frame, each call it makes one node, a box named as
  MCL writes the call (``Dive(Depth)``, its instance's name under it), framed
  (grey) with the places the call marks in it (B, A, OK, FAIL, ABORTED...), so
  that every circle says whose it is, ranked as the tokens flow: a readable
  slide whatever the mission's size; ``expand`` names the calls drawn (the
  mission's own net by default); with every box open (``--expand all``) the
  boxes are ranked by the calls, each framed with its border places, a page
  rather than a strip of every call side by side (and the page lays a mission
  out whole as its overview: every box shut, ranked by the call hierarchy);
* a figure wider than a slide (16:9) has its widest rows wrapped: every
  other node (or frame) of such a row one rank down (:func:`_wrap`);
* every node has a ``class`` (``place``, ``transition``, ``copy``, ``box``,
  ``legend``), which SVG keeps, so that a page or a script can find them;
* a place that many transitions give tokens back to (a mutex) is drawn again,
  dashed and small, beside each of them, like PNML's reference places.

``tests/view/test_drawings.py`` holds every template, Figs. 1-4 and every example
to dot's own layout: no label on an arc, a node or another label, no node on
a box's border, no arc through a node.
"""
from __future__ import annotations

import contextlib
import html
import json
import re
from typing import Collection, Iterator, Mapping, Sequence

import graphviz

from mcl2pnml.core.errors import did_you_mean
from mcl2pnml.core.net import Arc, ArcKind, Net, Place, Transition
from mcl2pnml.core.payloads import read_transition
from mcl2pnml.core.settings import SettingError
from mcl2pnml.core.timing import exact_seconds, seconds_text
from mcl2pnml.io.dot import node_name
from mcl2pnml.view.calls import (Calls, call_net, calls_of, instance_clusters,
                                    mission_calls, short_label)

TOKEN = "\u25cf"
#: Top down: tokens flow from B at the top to OK, FAIL and ABORTED at the bottom, and
#: the nets joined by fusion (a task and its primitive, a structure's two tasks) stand
#: side by side, the page as wide as the net is parallel rather than as long as it is deep.
RANKDIR = "TB"
#: graphviz settings that bound dot's slowest phases, network simplex
#: (``nslimit``) and crossing minimisation (``mclimit``): without them dot
#: takes 45 s on the paper's mission (421 nodes). ``newrank`` ranks the
#: instance boxes together, which is faster still and avoids graphviz 2.43's
#: "trouble in init_rank" on missions of 50 calls and more.
DOT_SPEED = {"nslimit": "2", "nslimit1": "2", "mclimit": "0.5", "newrank": "true"}
#: Nets up to this many nodes (every template, a small mission, an overview) are laid out
#: with dot's full effort: a second at most, and the arcs straighter.
FAST_ABOVE = 300
#: A place that this many arcs return tokens to is drawn again beside each of them.
COPY_RETURNS = 3


#: Font sizes (points) of the drawings: every text at least :data:`SMALL`, and the
#: spaces between nodes small beside it, so that a figure fitted to a 1920 x 1080
#: slide shows every text at least 14 pixels high (``tests/view/test_drawings.py``).
FONT = 12
SMALL = 11
TITLE = 16


#: The mark of a time-out (a clock face; DejaVu and Liberation fonts have it).
CLOCK = "\u25f7"


def timeout_text(t: Transition) -> str | None:
    """What a time-out transition says of its delay (``◷ 300 s``), None for the others.

    A compiled task's ``t03`` carries its delay (section 2.3); the pattern's
    own ``t03`` is a time-out of no set length yet.
    """
    if t.timing is not None:
        lo, hi = (None if b is None else seconds_text(exact_seconds(b))
                  for b in (t.timing.earliest, t.timing.latest))
        return f"{CLOCK} {lo} s" if hi == lo else f"{CLOCK} [{lo}, {hi or 'inf'}] s"
    if read_transition(t).timeout is not None:
        return f"{CLOCK} time-out"
    return None


def transition_label(t: Transition, box_name: str | None = None) -> str:
    """A transition's text, drawn inside its box: its name, and its delay if it is timed.

    Inside, not beside (an ``xlabel``): dot places an external label after
    routing the arcs, on top of them; a label inside the node is a node's
    width that dot keeps clear of every arc and every other node.
    """
    name = _inside(t.label, box_name)
    delay = timeout_text(t)
    return name if delay is None else f"{name}\n{delay}"


def transition_style(t: Transition) -> dict[str, str]:
    """A transition's box: light, or dark with white text for a time-out."""
    style = {"shape": "box", "style": "filled", "fillcolor": "gray94", "height": "0.3",
             "width": "0.3", "margin": "0.05,0.02", "fontsize": str(FONT)}
    if timeout_text(t) is not None:
        style.update(fillcolor="gray25", fontcolor="white", style="filled,bold")
    return style


def _diameter(label: str, size: int, least: float) -> str:
    """The width (inches) of a circle that holds ``label`` in a font of ``size`` points:
    the diagonal of the text's box, at least ``least`` times the font size."""
    lines = label.split("\n")
    w, h = 0.7 * size * max(len(line) for line in lines), 1.15 * size * len(lines)
    return f"{max(least * size, (w * w + h * h) ** 0.5 + 2) / 72:.2f}"


def _tokens(n: int) -> str:
    return TOKEN * n if n <= 3 else f"{n}{TOKEN}"



def _text(label: str) -> str:
    """A label as plain text: graphviz must neither read it as HTML nor expand ``\\N``,
    nor take ``&amp;`` in it for the entity of ``&`` (it decodes entities in every label)."""
    return graphviz.escape(label.replace("&", "&amp;"))


def dot_graph(net: Net, *, marking: Mapping[str, int] | None = None,
              clusters: Mapping[str, Sequence[str]] | None = None, title: str | None = None,
              legend: bool = True, expand: Collection[str] | None = None,
              box_sizes: Mapping[str, tuple[float, float]] | None = None,
              by_calls: bool = False, labels: Mapping[str, str] | None = None,
              flow: bool = False, texts: dict[str, tuple[str, int]] | None = None
              ) -> graphviz.Digraph:
    """The net as a graphviz graph (``.source`` for the text, ``.pipe()`` to render).

    ``expand`` names the boxes drawn open; every other box of ``clusters`` is
    drawn shut, as one node (:func:`box_node`) that the arcs of its nodes
    lead to, once per place and direction. None: every box open.
    ``box_sizes`` (points) makes a shut box as large as its inside laid out
    (:mod:`mcl2pnml.view.layout` places the nodes of a mission so).
    ``by_calls`` ranks the open boxes as the overview ranks the shut ones, by
    the call hierarchy (:func:`_call_edge`), each box's inside by its flow:
    a mission with every call open is a page of the calls' nets stacked, a
    callee below its callers, not a strip of them side by side.
    ``labels`` names boxes (a call as MCL writes it: ``Dive(Depth)``), the box's
    own name under it. ``flow``: the view of one call (:mod:`mcl2pnml.view.calls`),
    its callees shut, each framed with the places the call marks in it, ranked as the
    tokens flow (a callee's B above its box, its results below). ``texts``, if given,
    is filled with the text drawn in each node and its size, by the node's DOT name.
    """
    d = _Drawer(net, net.initial if marking is None else marking, clusters or {}, title,
                legend, expand, by_calls)
    d.labels, d.flow, d.texts = labels or {}, flow, {} if texts is None else texts
    if flow and not legend:
        # one call's view on a page: as close as a slide's, its text as large as it can be
        d.g.graph_attr.update(nodesep="0.09", ranksep="0.25")
    # (in this order: the DOT text lists the nodes, boxes and arcs as they are drawn)
    d.loose_nodes()
    d.shut_boxes(box_sizes)
    d.open_boxes()
    first, last = d.ends()
    d.arcs(set(last))
    d.count_marks()
    if legend:
        d.legend(first, last)
    return d.g


class _Drawer:
    """One drawing as it is made: the graph, and what the steps of :func:`dot_graph`
    share (the boxes, shut or open, where each node is drawn, the marks used)."""

    def __init__(self, net: Net, marking: Mapping[str, int],
                 clusters: Mapping[str, Sequence[str]], title: str | None, legend: bool,
                 expand: Collection[str] | None, by_calls: bool) -> None:
        self.net, self.marking, self.title, self.by_calls = net, marking, title, by_calls
        # dot's speed limits only where a flat drawing is large: an overview has a node
        # per call, a template a few dozen; the overview's small places sit closer
        large = expand is None and len(net.places) + len(net.transitions) > FAST_ABOVE
        self.g = graphviz.Digraph(net.name, graph_attr={
            # (the page, laid out without a legend, keeps its wider spaces: its arcs run
            # along dot's routes, which a tighter layout leads through transitions)
            "rankdir": RANKDIR,
            "nodesep": "0.1" if legend else "0.3" if expand is None else "0.15",
            "ranksep": "0.22" if legend else "0.45",
            "fontname": "Helvetica", "fontsize": str(TITLE), "label": _text(title or ""),
            "labelloc": "t", **(DOT_SPEED if large else {"newrank": "true"})},
            node_attr={"fontname": "Helvetica", "fontsize": str(FONT)},
            edge_attr={"arrowsize": "0.7"})
        self.used: set[str] = set()      # the marks drawn, each explained by the legend
        self.clusters = border_out(net, clusters)
        self.shut = (set() if expand is None
                     else set(self.clusters) - set(check_expand(self.clusters, expand)))
        self.box = {n: name for name, members in self.clusters.items() for n in members}
        # where each node is drawn: itself, or the box it is shut in
        self.drawn = {n: box_node(b) for n, b in self.box.items() if b in self.shut}
        # a shut box is framed with the places on its border that are its own (its B, A,
        # OK, FAIL, ABORTED...): the frame says whose each circle is, the box its name
        self.framed: dict[str, list[Place]] = {}
        self.copies = 0
        self.marks: set[str] = set()     # the arcs' marks, apart until the legend's count
        # (set by dot_graph: the boxes' names, one call's view, the texts drawn)
        self.labels: Mapping[str, str] = {}
        self.flow = False
        self.texts: dict[str, tuple[str, int]] = {}

    def _framed_by(self, owner: str) -> bool:
        """Whether the places of box ``owner``'s border are drawn in its frame."""
        return owner in self.shut or (self.by_calls and owner in self.clusters)

    def place(self, target, p: Place, box_name: str | None = None) -> None:
        """Place ``p`` as a circle in ``target`` (the graph or a box of it)."""
        tokens = self.marking.get(p.id, 0)
        owner = p.id.rpartition(".")[0]
        # a place on the border of a shut box is named as inside it (B, OK...): its
        # arc to the box says whose it is, and the overview stays small
        shown = _inside(p.label, owner if self._framed_by(owner) else box_name)
        label = shown + (f"\n{_tokens(tokens)}" if tokens else "")
        # circles all of one size read best; long names get a larger one
        # (the overview's places: only their short names; one call's view keeps them as large
        # as the call's own)
        small = owner in self.shut and not self.flow
        size = SMALL if small else FONT
        self.texts[node_name(p.id)] = (shown, size)
        target.node(node_name(p.id), _text(label), shape="circle",
                    width=_diameter(label, size, 3.0 if small else 3.6),
                    fixedsize="true", fontsize=str(size),
                    peripheries="2" if p.interface is not None else "1",
                    **{"class": "place"})

    def transition(self, target, t: Transition, box_name: str | None = None) -> None:
        """Transition ``t`` as a box in ``target``, its name inside."""
        self.texts[node_name(t.id)] = (transition_label(t, box_name), FONT)
        target.node(node_name(t.id), _text(transition_label(t, box_name)),
                    **transition_style(t), **{"class": "transition"})

    def loose_nodes(self) -> None:
        """The nodes in no box, and each framed box's border places set aside."""
        for p in self.net.places:
            if p.id in self.box:
                continue
            owner = p.id.rpartition(".")[0]
            if self._framed_by(owner):
                self.framed.setdefault(owner, []).append(p)
            else:
                self.place(self.g, p)
        for t in self.net.transitions:
            if t.id not in self.box:
                self.transition(self.g, t)

    @contextlib.contextmanager
    def frame(self, name: str) -> Iterator:
        """The frame of box ``name`` with its border places (a grey cluster), if it has
        any: the subgraph to draw the box in."""
        if name not in self.framed:
            yield self.g
            return
        with self.g.subgraph(name=f"cluster_call_{name}") as c:
            c.attr(label="", style="rounded", color="gray75", margin="2")
            self.used.add("call")
            yield c

    def shut_boxes(self, box_sizes: Mapping[str, tuple[float, float]] | None) -> None:
        """Each shut box, one node (as large as ``box_sizes`` says), its places beside it."""
        for name in self.clusters:
            if name not in self.shut:
                continue
            fixed = {}
            if box_sizes and name in box_sizes:
                w, h = box_sizes[name]
                fixed = {"width": f"{w / 72:.2f}", "height": f"{h / 72:.2f}",
                         "fixedsize": "true"}
            with self.frame(name) as c:
                said = self.labels.get(name)
                self.texts[box_node(name)] = (said or name, FONT)
                c.node(box_node(name), _text(f"{said}\n{name}" if said else
                                             f"{name}\n({len(self.clusters[name])} nodes)"),
                       shape="box", style="rounded,dashed,filled", fillcolor="gray97",
                       color="gray40", fontsize=str(FONT), margin="0.1,0.05", **fixed,
                       **{"class": "box"})
                if self.flow:       # one call's view: the callee's places where tokens put them
                    for p in self.framed.get(name, ()):
                        self.place(c, p)
                    self.used.add("shut")
                    continue
                # the places beside the box, not a row of their own above it: the
                # overview as deep as the calls, a row each
                with c.subgraph() as r:
                    r.attr(rank="same")
                    r.node(box_node(name))
                    for p in self.framed.get(name, ()):
                        self.place(r, p)
            self.used.add("shut")

    def open_boxes(self) -> None:
        """Each open box, a dashed frame with its nodes in the net's order."""
        for name, members in self.clusters.items():
            if name in self.shut:
                continue
            # (a page ranked by calls: each open box framed with its border places, a row
            # above it, as the overview frames a shut box)
            with self.frame(name) as f:
                with f.subgraph() as r:
                    r.attr(rank="same")
                    for p in self.framed.get(name, ()):
                        self.place(r, p)
                with f.subgraph(name=f"cluster_{name}") as c:
                    c.attr(label=_text(self.labels.get(name, name)), style="rounded,dashed",
                           color="gray50",
                           fontsize=str(FONT), margin="6")
                    self.used.add("box")
                    for m in members:   # net order within the cluster, as given
                        if m in self.net.place_index:
                            self.place(c, self.net.place_index[m], name)
                        else:
                            self.transition(c, self.net.transition_index[m], name)

    def ends(self) -> tuple[list[str], list[str]]:
        """The loose places where tokens come in (ranked first) and where results come
        out (ranked last), the ranks drawn unless the drawing is ranked by its calls."""
        net = self.net
        written = {a.target for a in net.arcs if a.target in net.place_index}
        read_or_taken = {a.source for a in net.arcs if a.source in net.place_index}
        # (only what nothing writes: a marked place that tokens come back to, like
        # the primitive's OFF, sits where its arcs put it, not at the far left)
        first = [p.id for p in net.places if p.id not in self.box and p.id not in written]
        # (a place no arc touches is a start, not also an end: dot would rank the two as one)
        last = [p.id for p in net.places if p.id not in self.box
                and p.id not in read_or_taken and p.id in written]
        for rank, members in (("source", first), ("sink", last)):
            # (an overview, or a page ranked by calls, is ranked by its calls: _call_edge)
            if members and not self.shut and not self.by_calls:
                with self.g.subgraph() as r:
                    r.attr(rank=rank)
                    for m in members:
                        r.node(node_name(m))
        return first, last

    def copy(self, place: Place, box_name: str | None) -> str:
        """A copy of ``place``, dashed and small, in the box ``box_name`` (the box of the
        transition it is drawn beside), if any: its DOT name."""
        self.copies += 1
        name = f"{node_name(place.id)}~{self.copies}"
        owner = place.id.rpartition(".")[0]
        # (a copy of a place framed with its box is named as there: ON, not KeepDepth.ON)
        shown = _inside(place.label, owner if self.flow and owner in self.shut else box_name)
        with contextlib.ExitStack() as stack:
            c = self.g
            # (into the box where it is drawn: inside its frame on a page ranked by calls)
            if box_name in self.framed:
                c = stack.enter_context(c.subgraph(name=f"cluster_call_{box_name}"))
            if box_name:
                c = stack.enter_context(c.subgraph(name=f"cluster_{box_name}"))
            self.texts[name] = (shown, SMALL)
            c.node(name, _text(shown), shape="circle", fixedsize="true", style="dashed",
                   width=_diameter(shown, SMALL, 3.0), fontsize=str(SMALL),
                   **{"class": "copy"})
        return name

    def arcs(self, outputs: set[str]) -> None:
        """Every arc: to and from shut boxes once each, ranked by the calls between
        boxes, as a copy of a place read or given back by many, or as itself."""
        net, box = self.net, self.box
        back, returns = _back_arcs(net, outputs)
        reads: dict[str, int] = {}
        for a in net.arcs:
            if a.kind is ArcKind.READ:
                reads[a.source] = reads.get(a.source, 0) + 1
        joined: set = set()        # the arcs to and from a shut box, drawn once each
        levels = (box_levels(net, self.clusters) if self.shut or self.by_calls
                  else ({}, {}))
        between = _between(net, box) if self.by_calls else set()
        for a in net.arcs:
            if a.source in self.drawn or a.target in self.drawn:
                ends = (self.drawn.get(a.source, node_name(a.source)),
                        self.drawn.get(a.target, node_name(a.target)), a.kind)
                if ends[0] != ends[1] and ends not in joined:   # inside the box: hidden
                    joined.add(ends)
                    if self.flow:
                        self.g.edge(ends[0], ends[1], **(
                            {"style": "dashed", "dir": "none"} if a.kind is ArcKind.READ
                            else {}))
                    else:
                        _call_edge(self.g, a, ends, box, levels)
                    self.marks.add("read" if a.kind is ArcKind.READ else "arc")
                continue
            if (a.source in between or a.target in between) and a.weight == 1:
                _call_edge(self.g, a, (node_name(a.source), node_name(a.target), a.kind),
                           box, levels)
                self.marks.add("read" if a.kind is ArcKind.READ else "arc")
                continue
            self.arc(a, reads.get(a.source, 0), a in back, returns.get(a.target, 0))

    def arc(self, a: Arc, read_by: int, goes_back: bool, returned: int) -> None:
        """One arc between nodes drawn as themselves: its source read by ``read_by``
        transitions, ``goes_back`` against the flow into a place ``returned`` arcs go back
        to."""
        source, target = node_name(a.source), node_name(a.target)
        attrs = {}
        if a.weight != 1:
            attrs["label"] = str(a.weight)
            self.marks.add("weight")
        if a.kind is ArcKind.READ and read_by >= COPY_RETURNS:
            # a place many transitions test (a primitive's ON and OFF): each test
            # reads a copy of the place drawn beside its transition, instead of
            # dashed arcs across the whole drawing
            source = self.copy(self.net.place_index[a.source], self.box.get(a.target))
            attrs.update(style="dashed", arrowhead="none")
            self.marks.update(("read", "copy"))
        elif a.kind is ArcKind.READ:
            # a test is not a flow of tokens: it must not bend the layout
            attrs.update(style="dashed", arrowhead="none", constraint="false")
            self.marks.add("read")
        elif goes_back and returned >= COPY_RETURNS and not self.flow:
            # many tokens going back to one place (a mutex freed by every
            # ending): each arc goes to a copy of the place drawn beside its
            # transition, as PNML's reference places do, instead of crossing
            # the whole drawing
            target = self.copy(self.net.place_index[a.target], self.box.get(a.source))
            self.marks.update(("arc", "copy"))
        elif goes_back:
            # a token going back (a primitive switched off): drawn, but the
            # top-down order follows the forward flow
            attrs.update(constraint="false", color="gray40")
            self.marks.add("back")
        else:
            self.marks.add("arc")
        self.g.edge(source, target, **attrs)

    def count_marks(self) -> None:
        """The marks the drawing shows, for its legend."""
        for p in self.net.places:
            if p.interface is not None and (p.id not in self.drawn):
                self.used.add("fusion")
            if self.marking.get(p.id, 0) and p.id not in self.drawn:
                self.used.add("token")
        for t in self.net.transitions:
            if t.id not in self.drawn:
                self.used.add("timeout" if timeout_text(t) is not None else "transition")
        self.used.add("place")
        self.used.update(self.marks)

    def legend(self, first: Sequence[str], last: Sequence[str]) -> None:
        """The title and legend as the graph's label, its widest rows wrapped first if it
        is wider than a slide (:func:`_wrap`), the arcs into a transition spread."""
        g, framed, shut, clusters = self.g, self.framed, self.shut, self.clusters
        # a unit of a row: a call's frame moves as one, every other node alone
        unit = {box_node(name): name for name in framed}
        unit.update((node_name(p.id), name) for name, places in framed.items() for p in places)
        # (on a page ranked by calls, an open box moves with its frame, every node in it)
        anchor = {name: box_node(name) for name in framed if name in shut}
        if self.by_calls:
            unit.update((node_name(m), name) for name in framed for m in clusters[name])
            anchor.update((name, node_name(places[0].id)) for name, places in framed.items())
        title, used = self.title or "", self.used
        # (a large drawing, every box or some open, is laid out once: dot takes seconds;
        # a page ranked by calls is laid out fast, dot's effort limited)
        nodes = len(self.net.places) + len(self.net.transitions)
        if self.by_calls or nodes - len(self.drawn) + len(shut) <= FAST_ABOVE:
            _wrap(g, lambda width: legend_label(title, used, width), unit, anchor,
                  {node_name(m) for m in (*first, *last)},
                  # (some box open: as large as a page, wrapped as one)
                  **({"wraps": PAGE_WRAPS, "rows": 1}
                     if self.by_calls or 0 < len(shut) < len(clusters) else {}))
        g.graph_attr["label"] = legend_label(title, used, _spread(g))


def _back_arcs(net: Net, outputs: set[str]) -> tuple[set[Arc], dict[str, int]]:
    """The arcs that go back against the flow (:func:`flow_depth`), and how many go back
    into each place.

    An arc into a result (a place nothing takes from: OK, FAIL, ABORTED) is
    forward, however early a short path reaches the result: results stay at
    the end of the flow, one node each, not copied beside every ending.
    """
    depth = flow_depth(net)
    back = {a for a in net.arcs if a.kind is ArcKind.NORMAL and a.target not in outputs
            and depth.get(a.target, -1) <= depth.get(a.source, -1) and a.target in depth}
    returns: dict[str, int] = {}
    for a in back:
        if a.target in net.place_index:
            returns[a.target] = returns.get(a.target, 0) + 1
    return back, returns


def _between(net: Net, box: Mapping[str, str]) -> set[str]:
    """The places between two boxes or more, whose arcs rank the boxes by calls."""
    touching: dict[str, set[str]] = {}
    for a in net.arcs:
        for p, t in ((a.source, a.target), (a.target, a.source)):
            if p in net.place_index and p not in box and t in box:
                touching.setdefault(p, set()).add(box[t])
    return {p for p, boxes in touching.items() if len(boxes) > 1}


#: The slide a figure is made for (points or pixels: only its shape counts), and how many
#: times dot lays a figure out again at most to wrap its widest rows (:func:`_wrap`).
SLIDE = (1920, 1080)
WRAPS = 6
#: A page (every call open, or some) is laid out again fewer times, its widest row
#: only: each layout takes dot a second.
PAGE_WRAPS = 3
PATIENCE = 1

_EDGE = re.compile(r'^\t("(?:[^"\\]|\\.)*"|\S+) -> ("(?:[^"\\]|\\.)*"|\S+)( \[|$)')


def _edge_ends(line: str) -> tuple[str, str, int] | None:
    """The tail and head (DOT names) of an edge statement of a graph's body, and where
    the head ends in the line (a port goes there); None for any other statement."""
    m = _EDGE.match(line)
    if not m:
        return None
    tail, head = (v[1:-1].replace('\\"', '"') if v.startswith('"') else v
                  for v in m.groups()[:2])
    return tail, head, m.end(2)


def _wrap(g: graphviz.Digraph, label, unit: Mapping[str, str], anchor: Mapping[str, str],
          fixed: Collection[str], *, wraps: int = WRAPS, rows: int = 3) -> None:
    """Wrap the rows of ``g`` (top down) that make it wider than a slide onto two rows.

    dot lays ``g`` out (``label(width)``: the graph's label for a drawing so wide);
    while the drawing is wider than :data:`SLIDE`'s shape, every other unit of its
    widest row (a node, or a call's frame with its places, ``unit``) goes one rank
    down: each arc that ranks it (not ``constraint=false``) comes into it at least
    two ranks long; a frame's row is its ``anchor`` node's. The places ranked first
    or last (``fixed``) stay. The layout that fits the slide at the largest scale is
    kept.
    """
    body = list(g.body)
    key = "".join(body) + repr(sorted(unit.items())) + repr(sorted(fixed)) + label(None)
    if key in _WRAPPED:         # the same drawing again (a figure saved twice)
        g.body[:] = _WRAPPED[key]
        return
    into: dict[str, list[int]] = {}     # each unit: the lines of the arcs that rank it
    for k, line in enumerate(body):
        ends = _edge_ends(line)
        if ends is None or "constraint=false" in line:
            continue
        tail, head, _ = ends
        if unit.get(tail, tail) != unit.get(head, head):
            into.setdefault(unit.get(head, head), []).append(k)

    def lay_out(down: Mapping[str, int], width: float | None):
        g.body[:] = body
        for u, n in down.items():
            for k in into.get(u, ()):
                line = g.body[k].rstrip("\n")
                g.body[k] = (line[:-1] + f" minlen={1 + n}]\n" if line.endswith("]")
                             else line + f" [minlen={1 + n}]\n")
        g.graph_attr["label"] = label(width)
        # json0: the layout alone (positions, sizes, boxes), which is all a wrap reads;
        # dot writes it in a fifth less time and a third the text of json's drawing
        layout = json.loads(g.pipe(format="json0"))
        _, _, w, h = (float(v) for v in layout["bb"].split(","))
        return min(SLIDE[0] / w, SLIDE[1] / h), w, h, layout, list(g.body)

    try:
        best = lay_out({}, None)
    except (graphviz.ExecutableNotFound, graphviz.CalledProcessError, ValueError):
        g.body[:] = body
        return
    down: dict[str, int] = {}
    here, worse = best, 0
    for _ in range(wraps):
        _, w, h, layout, _ = here
        if w * SLIDE[1] <= h * SLIDE[0]:
            break
        tried = []
        for moved in _splits(layout, unit, anchor, into, fixed, rows):
            more = dict(down)
            for u in moved:
                more[u] = more.get(u, 0) + 1
            try:
                tried.append((lay_out(more, w), more))
            except (graphviz.CalledProcessError, ValueError):
                continue        # one of dot's internal failures: not this way
        if not tried:
            break
        # the best wrap of this row, even if no better yet: one more wrap may be
        (here, down) = max(tried, key=lambda t: t[0][0])
        if here[0] > best[0] * 1.001:
            best, worse = here, 0
        else:
            worse += 1
            if worse > PATIENCE:
                break
    g.body[:] = best[4]
    if len(_WRAPPED) >= 64:
        _WRAPPED.clear()
    _WRAPPED[key] = best[4]


#: The rows :func:`_wrap` chose for each drawing it wrapped (its body), by the drawing.
_WRAPPED: dict[str, list[str]] = {}


def _splits(layout: dict, unit: Mapping[str, str], anchor: Mapping[str, str],
            into: Mapping[str, Sequence[int]], fixed: Collection[str],
            rows: int = 3) -> list[list[str]]:
    """The ways to wrap a row of dot's ``layout`` that :func:`_wrap` tries: every other
    movable unit (odd ones, or even ones) of each of the ``rows`` widest rows."""
    found: dict[float, dict[str, tuple[float, float]]] = {}
    frames = {o["name"][len("cluster_call_"):]: o for o in layout.get("objects", [])
              if o.get("name", "").startswith("cluster_call_") and "bb" in o}
    for o in layout.get("objects", []):
        if "pos" not in o:
            continue
        x, y = (float(v) for v in o["pos"].split(","))
        u = unit.get(o["name"], o["name"])
        if u in frames:
            if o["name"] != anchor.get(u):
                continue
            x0, _, x1, _ = (float(v) for v in frames[u]["bb"].split(","))
            found.setdefault(round(y), {})[u] = (x, x1 - x0)
        else:
            found.setdefault(round(y), {})[u] = (x, float(o["width"]) * 72)
    ways = []
    widest = sorted(found, key=lambda y: -sum(v for _, v in found[y].values()))[:rows]
    for y in widest:
        row = [u for u, _ in sorted(found[y].items(), key=lambda kv: kv[1][0])]
        if len(row) < 3:
            continue
        for step, first in ((2, 1), (2, 0)):
            moved = [u for u in row[first::step] if u in into and u not in fixed]
            if moved:
                ways.append(moved)
        if y == widest[0]:
            ways.extend([u] for u in row if u in frames and u in into and u not in fixed)
    return ways


#: The legend's entries, in its order: a mark (HTML, graphviz's subset) and what it means.
LEGEND = {
    "place": ("\u25ef", "place"),
    "token": (TOKEN, "token"),
    "fusion": ("\u25ce", "fusion place (nets joined)"),
    "transition": ("\u25ad", "transition"),
    "timeout": (f'<FONT COLOR="gray25">\u25ac</FONT> {CLOCK}', "time-out, its delay"),
    "arc": ("\u2500\u2500\u25b6", "arc: tokens flow"),
    "back": ('<FONT COLOR="gray40">\u2500\u2500\u25b6</FONT>',
             "grey arc: a token goes back (not ranked)"),
    "read": ("\u254c\u254c\u254c", "dashed arc: read, the token stays"),
    "copy": ("\u25cc", "dashed circle: a copy of the place"),
    "weight": ("\u2500 2 \u25b6", "arc weight"),
    "box": ("\u2b1a", "dashed frame: a part of the net"),
    "shut": ("\u25a2", "shut box: a call, its nodes inside"),
    "call": ("\u25a2\u25ce", "grey frame: a call and its own border places"),
}


def legend_label(title: str, used: Collection[str], width: float | None = None) -> str:
    """The drawing's title and, below it, its legend: an entry for every mark in
    ``used`` (:data:`LEGEND`), as many a row as the drawing is ``width`` points wide
    (None: two); an HTML label of graphviz, which dot keeps clear of the drawing."""
    entries = [(mark, text) for key, (mark, text) in LEGEND.items() if key in used]
    widest = max(0.62 * SMALL * (len(text) + 4) for _, text in entries)
    per_row = 2 if width is None else max(1, min(len(entries), int(width // widest)))
    rows = [entries[k:k + per_row] for k in range(0, len(entries), per_row)]
    cells = "".join("<TR>" + "".join(
        f'<TD ALIGN="LEFT"><FONT POINT-SIZE="{SMALL}">{mark} {html.escape(text)}</FONT></TD>'
        for mark, text in r) + "</TR>" for r in rows)
    return (f'<<TABLE BORDER="0" CELLSPACING="0" CELLPADDING="1">'
            f'<TR><TD COLSPAN="{per_row}"><FONT POINT-SIZE="{TITLE}">{html.escape(title)}'
            f'</FONT></TD></TR>{cells}</TABLE>>')


#: The compass points where arcs end on a transition with this many arcs coming in,
#: from the left: distinct points, so that arcs into one box do not merge.
PORTS = {2: ("nw", "ne"), 3: ("nw", "n", "ne"), 4: ("w", "nw", "ne", "e"),
         5: ("w", "nw", "n", "ne", "e")}


def _spread_heads(g: graphviz.Digraph, layout: dict) -> None:
    """Each arc into a transition that several arcs come into ends at its own point of
    the box (:data:`PORTS`), in the order of the arcs' sources from left to right in
    ``layout`` (dot's JSON of ``g``)."""
    objects = layout.get("objects", [])
    x = {o["name"]: float(o["pos"].split(",")[0]) for o in objects if "pos" in o}
    boxes = {o["name"] for o in objects if o.get("class") == "transition"}
    name = {o["_gvid"]: o["name"] for o in objects if "pos" in o}
    into: dict[str, list[str]] = {}
    for e in layout.get("edges", []):
        tail, head = name.get(e["tail"]), name.get(e["head"])
        if head in boxes and tail in x and e.get("dir") != "back":
            into.setdefault(head, []).append(tail)
    port = {}
    for head, tails in into.items():
        if len(set(tails)) == len(tails) and len(tails) in PORTS:
            for tail, compass in zip(sorted(tails, key=x.__getitem__), PORTS[len(tails)]):
                port[(tail, head)] = compass
    for k, line in enumerate(g.body):
        ends = _edge_ends(line)
        if ends is not None and ends[:2] in port:
            tail, head, end = ends
            g.body[k] = line[:end] + ":" + port[(tail, head)] + line[end:]


def _spread(g: graphviz.Digraph) -> float | None:
    """Lay ``g`` out once (dot's JSON), spread the arcs into each transition
    (:func:`_spread_heads`) and return the drawing's width in points; None if dot is
    not installed (the DOT source is written without it)."""
    try:
        layout = json.loads(g.pipe(format="json"))
    except (graphviz.ExecutableNotFound, graphviz.CalledProcessError, ValueError):
        return None
    _spread_heads(g, layout)
    return float(layout["bb"].split(",")[2])


def _call_edge(g: graphviz.Digraph, a: Arc, ends: tuple[str, str, ArcKind], box: Mapping[str, str],
               levels: tuple[Mapping[str, int], Mapping[str, int]]) -> None:
    """An arc of a shut box, drawn between the box and a place on its border, ranked by
    the call hierarchy rather than by the flow of tokens.

    A call's places (B, A, OK, FAIL, ABORTED...) sit below the box that calls
    and above the box called, whichever way their tokens go (``dir=back`` draws
    an arc against its rank order): the overview reads top down as the
    mission's calls, and is as deep as the hierarchy, not as the flow.
    """
    level, place_level = levels
    into_place = a.source in box and box[a.source] != box.get(a.target)
    transition, place = (a.source, a.target) if into_place else (a.target, a.source)
    where = box.get(transition)
    # the box called is deeper than the shallowest box the place touches (its caller)
    # (a place inside another shut box, a primitive's LOCK taken by one call site: at
    # that box's depth)
    box_first = level.get(where, 0) <= place_level.get(place, level.get(box.get(place), 0))
    tail, head = (ends[0], ends[1]) if into_place == box_first else (ends[1], ends[0])
    if a.kind is ArcKind.READ:
        g.edge(tail, head, style="dashed", dir="none")
    elif tail == ends[0]:
        g.edge(tail, head)
    else:
        g.edge(tail, head, dir="back")


def box_levels(net: Net, clusters: Mapping[str, Sequence[str]]
               ) -> tuple[dict[str, int], dict[str, int]]:
    """How deep each box is in the call hierarchy, and each place between boxes: the
    shallowest box it touches.

    A box calls another when its transitions mark the other's begin place B
    (or a task its primitive's E: :func:`~mcl2pnml.view.calls.calls_of`). A box's
    depth is the longest chain of calls above it, so that a shared net (a task, a
    function, a primitive, entered from every call site) sits below all its call
    sites, not beside the first one found; a box no call reaches is at the top, and
    a box on a circle of calls (not from MCL, which has no recursion) below all the
    others.
    """
    box = {n: name for name, members in clusters.items() for n in members}
    touches: dict[str, set[str]] = {}
    for a in net.arcs:
        place, transition = ((a.source, a.target) if a.source in net.place_index
                             else (a.target, a.source))
        if place not in box and transition in box:
            touches.setdefault(place, set()).add(box[transition])
    calls = calls_of(net, clusters)
    # longest chains by Kahn's algorithm: a box's level once all its callers have theirs
    above = {name: 0 for name in clusters}
    for callees in calls.values():
        for c in callees:
            above[c] += 1
    level = {name: 0 for name, n in above.items() if n == 0}
    ready = list(level)
    while ready:
        b = ready.pop()
        for c in calls[b]:
            level[c] = max(level.get(c, 0), level[b] + 1)
            above[c] -= 1
            if above[c] == 0:
                ready.append(c)
    bottom = max(level.values(), default=-1) + 1
    level.update((name, bottom) for name in clusters if above[name] > 0)
    place_level = {p: min(level[b] for b in boxes) for p, boxes in touches.items()}
    return level, place_level


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


def box_node(name: str) -> str:
    """The DOT name of a shut box: ``~box`` and the box's name in hex, which no id of
    the net is drawn as (:func:`node_name` encodes every id starting with ``~x``, and
    :func:`node_id` reads this as no node)."""
    return "~box" + name.encode().hex()


#: What ``--expand`` takes to open every box.
EXPAND_ALL = "all"


def check_expand(clusters: Mapping[str, Sequence[str]], expand: Collection[str]) -> list[str]:
    """The boxes ``expand`` names, each one of ``clusters``; a name of none is an
    :class:`~mcl2pnml.core.settings.SettingError` of ``expand`` naming the boxes there are."""
    for name in expand:
        if name not in clusters:
            raise SettingError("expand", f"no box {name!r} in this drawing"
                               + did_you_mean(name, clusters, "boxes"))
    return list(expand)


def drawing(net: Net, title: str | None = None, *,
            clusters: Mapping[str, Sequence[str]] | None = None,
            expand: Collection[str] | None = (),
            labels: Mapping[str, str] | None = None) -> graphviz.Digraph:
    """The figure of ``net``, titled, with the legend.

    ``clusters`` are its boxes (a template's slots: the primitive of a task,
    T1 and T2 of a structure), all drawn open. None: a compiled mission, one
    call at a time (:mod:`mcl2pnml.view.calls`): ``expand`` names the calls
    drawn (by their names, or their ``labels`` where one call alone has it),
    each open, its callees shut in boxes named by ``labels`` (``Dive(Depth)``, as
    MCL writes the call); by default the mission's own net, the root of its
    calls. ``expand`` None draws every call open, the whole net ranked by its calls:
    a poster, not a slide.
    """
    if clusters is not None:
        return dot_graph(net, clusters=clusters, title=title or net.name, legend=True,
                         expand=expand)
    if expand is None:
        return dot_graph(net, clusters=instance_clusters(net), title=title or net.name,
                         legend=True, expand=None, by_calls=True, labels=labels)
    calls = mission_calls(net)
    if not calls.roots and not expand:
        # no calls: a net that is not a compiled mission (a template, another tool's) is
        # drawn whole, as it is
        return dot_graph(net, title=title or net.name, legend=True)
    names = labels or {}
    opened = [calls.name(n, names) for n in expand] or list(calls.roots)
    part, boxes = call_net(net, calls, opened)
    said = ", ".join(short_label(names.get(n, n)) for n in opened)
    return dot_graph(part, clusters=boxes, title=f"{title or net.name}: {said}", legend=True,
                     expand=opened, labels={n: short_label(names.get(n, n)) for n in boxes},
                     flow=True)
