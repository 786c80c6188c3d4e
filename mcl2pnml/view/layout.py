"""Positions for drawing a net, so that PNML opens as a picture, not a heap.

PIPE, TAPAAL, WoPeD and TINA's nd draw a net where its ``<graphics>`` say.
Small nets are laid out by graphviz ``dot`` as :mod:`mcl2pnml.view.drawing` draws
them, top down in the direction tokens flow, and each arc gets the points
of dot's curve as its bend points (PNML's arc ``<graphics>``), so that an
editor draws the arcs around the nodes as the SVG does. A compiled mission
is laid out in two levels, as its overview: each call's nodes compactly in
its box, the boxes and the places between them by the call hierarchy (a
few screens, not one column 25,000 points long); an arc between a place
outside a box and a node inside runs along the overview's arc to the box,
then inside it along its border to a way in that passes no other node
(:func:`_way_in`). The token-game page (:mod:`mcl2pnml.view.show`) draws
the same picture: it also takes the drawing's boxes and its copies of a
place read or given back to by many transitions (Fig. 2's ON, OFF, MTX),
which PNML has not. Large nets, where ``dot``
would take minutes, are laid out in columns by their breadth-first
distance from the initially marked places, which is linear in the size of
the net and still shows the flow from start to end. Above
:data:`LAYERS_LIMIT` nodes no editor draws a net usefully, so ``auto`` gives
no positions at all (``<graphics>`` is optional in PNML): a 10,000-call
survey is written a third faster and 15% smaller.

Coordinates follow PNML: x to the right, y downwards, in points, all >= 0.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
from dataclasses import dataclass, field, replace
from typing import Mapping, Sequence

from mcl2pnml.core.net import Marking, Net

#: Above this many nodes, ``dot`` is too slow and the layered layout is used.
DOT_LIMIT = 1500
#: Seconds dot may take before the layered layout is used instead.
DOT_TIMEOUT = 30
#: Above this many nodes, ``auto`` lays nothing out.
LAYERS_LIMIT = 100_000
ENGINES = ("auto", "dot", "layers", "none")
#: Distance between neighbouring columns and rows of the layered layout.
SPACING = 80.0
MARGIN = 40.0
#: An overview this many times taller than wide is laid out left to right instead.
TALL = 2.0


def dot_available() -> bool:
    return shutil.which("dot") is not None


@dataclass(frozen=True)
class Drawn:
    """Where a net is drawn: each node's position and each arc's bend points.

    ``positions`` holds the net's own nodes only (what PNML's ``<graphics>``
    say). ``bends`` maps an arc's (source, target) to the points its line
    passes through between its ends, in order from the source (PNML's arc
    ``<graphics>``); an arc without bends is a straight line.

    ``copies`` are the small dashed copies of a place that the drawing puts
    beside each transition reading it or giving a token back to it (a
    primitive's ON and OFF, a task's MTX: :mod:`mcl2pnml.view.drawing`), by their
    DOT name: the place they stand for and where. An arc drawn to a copy
    has its bends under the copy's name instead of the place's, a key that
    is no arc of the net, so that the PNML writer, which looks bends up by
    the net's arcs, draws such an arc as a straight line to the place
    itself. ``boxes`` are the boxes of the drawing (a task's primitive, a
    structure's T1 and T2, a mission's calls): name -> (x0, y0, x1, y1).
    ``sizes`` (half width, half height) and ``texts`` (the text drawn inside and its
    font size) are each node's and copy's as dot laid them out, where it did: a page
    draws the nodes so, and no text then lies on another.
    """

    positions: dict[str, tuple[float, float]]
    bends: dict[tuple[str, str], list[tuple[float, float]]] = field(default_factory=dict)
    copies: dict[str, tuple[str, tuple[float, float]]] = field(default_factory=dict)
    boxes: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)
    sizes: dict[str, tuple[float, float]] = field(default_factory=dict)
    texts: dict[str, tuple[str, int]] = field(default_factory=dict)

    def whole(self) -> "Drawn":
        """The positions and bend points in whole points, as a file keeps them: WoPeD
        truncates every coordinate to an integer (817.5 becomes 817), so a file of
        whole coordinates reads the same in every editor as in ours."""
        def point(xy: tuple[float, float]) -> tuple[float, float]:
            return float(round(xy[0])), float(round(xy[1]))
        return replace(self, positions={k: point(v) for k, v in self.positions.items()},
                       bends={k: [point(p) for p in v] for k, v in self.bends.items()})


def layout(net: Net, engine: str = "auto") -> dict[str, tuple[float, float]]:
    """Node id -> (x, y), for every node or (engine ``"none"``) for none.

    ``engine`` is one of :data:`ENGINES`; ``"auto"`` picks ``dot`` up to
    :data:`DOT_LIMIT` nodes (when graphviz is installed), ``layers`` up to
    :data:`LAYERS_LIMIT`, and ``none`` above.
    """
    return drawn_layout(net, engine).positions


def drawn_layout(net: Net, engine: str = "auto",
                 clusters: Mapping[str, Sequence[str]] | None = None) -> Drawn:
    """Positions for every node and, laid out by dot, bend points for the arcs.

    A net of instances (a compiled mission) is laid out in two levels, as its
    overview drawing shows it (:func:`mcl2pnml.view.drawing.dot_graph` with every box
    shut): each instance's nodes compactly in its box, the boxes and the
    places between them ranked by the calls. Another net (a template) is
    laid out as its drawing, with ``clusters`` as its boxes (the primitive of
    Fig. 2's task, T1 and T2 of Fig. 4's structures). The layered layout
    gives no bend points.
    """
    if engine not in ENGINES:
        raise ValueError(f"unknown layout engine {engine!r}; one of {', '.join(ENGINES)}")
    nodes = len(net.places) + len(net.transitions)
    if engine == "auto":
        engine = ("dot" if nodes <= DOT_LIMIT and dot_available()
                  else "layers" if nodes <= LAYERS_LIMIT else "none")
    if engine == "dot":
        drawn = _dot_drawn(net, clusters)
        if drawn is not None and len(drawn.positions) == nodes:
            return drawn
        # dot failed, ran out of time or left a node out (every node has a position,
        # whoever asks): the layered layout is linear, always ends, places every node
    if engine in ("dot", "layers"):
        return Drawn(_layered_layout(net))
    return Drawn({})


def _dot_layout(net: Net) -> dict[str, tuple[float, float]] | None:
    """Where dot puts each node (None: dot failed)."""
    drawn = _dot_drawn(net)
    return None if drawn is None else drawn.positions


def _run_dot(source: str) -> dict | None:
    """dot's layout of ``source`` as its JSON (``-Tjson``), None if dot failed or took
    longer than :data:`DOT_TIMEOUT`."""
    try:
        result = subprocess.run(["dot", "-Tjson"], input=source.encode(),
                                capture_output=True, check=True, timeout=DOT_TIMEOUT)
    except (subprocess.TimeoutExpired, subprocess.CalledProcessError):
        return None   # too slow, or one of dot's internal failures: lay out in layers
    return json.loads(result.stdout)


def _dot_drawn(net: Net, clusters: Mapping[str, Sequence[str]] | None = None) -> Drawn | None:
    # graphviz (0.03 s, python -X importtime) comes with these: only when dot lays out, never
    # on the CLI's start (cli_options imports this module)
    from mcl2pnml.io.dot import dot_missing
    from mcl2pnml.view.drawing import border_out, dot_graph, instance_clusters
    if not dot_available():
        raise dot_missing("layout_engine", "the layouts layers and none work without it, "
                                           "and auto lays out in layers when it is missing")
    boxes = border_out(net, instance_clusters(net)) if clusters is None else {}
    if not boxes:
        texts: dict[str, tuple[str, int]] = {}
        graph = _run_dot(dot_graph(net, clusters=clusters, legend=False, expand=None,
                                   texts=texts).source)
        if graph is None:
            return None
        frame = _Frame(graph)
        nodes, splines, copies = _read(graph)
        drawn = Drawn({n: frame(*p) for n, p in nodes.items()},
                      {arc: [frame(*p) for p in pts] for arc, pts in splines.items()},
                      {c: (place, frame(*nodes[c])) for c, place in copies.items()},
                      {name: _framed(frame, *bb) for name, bb in _cluster_boxes(graph).items()},
                      _half_sizes(graph), _by_id(texts))
    else:
        drawn = _two_levels(net, boxes)
    return drawn and _of(net, drawn)


@dataclass(frozen=True)
class CallView:
    """One call of a mission laid out, its callees shut (:mod:`mcl2pnml.view.calls`):
    ``drawn`` its nodes (the call's own, the places it marks in its callees, the places
    of others it touches), their copies, sizes and texts, its arcs' bend points and its
    own dashed frame (``drawn.boxes``); ``shut`` each callee's box, ``names`` the text
    drawn in it, ``frames`` each callee's grey frame with its places; ``box_arcs`` the
    arcs between a shut box and a place, once per place and way: (callee, place, ``in``,
    ``out`` or ``read``, bends)."""

    drawn: Drawn
    shut: dict[str, tuple[float, float, float, float]]
    names: dict[str, str]
    frames: dict[str, tuple[float, float, float, float]]
    box_arcs: list[tuple[str, str, str, list[tuple[float, float]]]]


def call_layouts(net: Net, calls, labels: Mapping[str, str]) -> dict[str, CallView] | None:
    """Every call of the mission ``net`` (``calls``: :func:`mcl2pnml.view.calls.mission_calls`)
    laid out as its view, its callees' boxes named by ``labels``; None where dot failed."""
    # graphviz (0.03 s, python -X importtime) comes with these: only when dot lays out
    from mcl2pnml.view.calls import call_net, short_label
    from mcl2pnml.view.drawing import dot_graph
    made = []
    for name in calls.clusters:
        part, boxes = call_net(net, calls, [name])
        texts: dict[str, tuple[str, int]] = {}
        graph = dot_graph(part, clusters=boxes, legend=False, expand=[name], flow=True,
                          labels={n: short_label(labels.get(n, n)) for n in boxes},
                          texts=texts)
        made.append((name, part, texts, graph.source))
    graphs = _run_dots([source for *_, source in made])
    if graphs is None or len(graphs) != len(made):
        return None
    return {name: _call_view(part, graph, texts, calls)
            for (name, part, texts, _), graph in zip(made, graphs)}


def _call_view(part: Net, graph: dict, texts: Mapping[str, tuple[str, int]], calls) -> CallView:
    """One call's view read from dot's layout ``graph`` of its part of the net ``part``."""
    from mcl2pnml.view.drawing import box_node   # graphviz: as _dot_drawn says
    frame = _Frame(graph)
    nodes, splines, copies = _read(graph, fine=True)
    sizes = _half_sizes(graph)
    named = {box_node(name): name for name in calls.clusters}
    shut = {}
    for node, (x, y) in nodes.items():
        if node in named:
            w, h = sizes[node]
            shut[named[node]] = _framed(frame, x - w, y - h, x + w, y + h)
    clusters = _cluster_boxes(graph)
    frames = {name[len("call_"):]: _framed(frame, *bb) for name, bb in clusters.items()
              if name.startswith("call_")}
    opened = {name: _framed(frame, *bb) for name, bb in clusters.items()
              if not name.startswith("call_")}
    box_arcs, bends = [], {}
    kinds = {(a.source, a.target): a.kind.value for a in part.arcs}
    for (tail, head), pts in splines.items():
        points = [frame(*p) for p in pts]
        if tail in named:
            box_arcs.append((named[tail], head, "out", points))
        elif head in named:
            box_arcs.append((named[head], tail, "in", points))
        else:
            bends[(tail, head)] = points
    # a read arc (dashed, from the place): the box reads it, never takes its token
    reads = {(calls_box, p) for calls_box, p, way, _ in box_arcs if way == "in"
             and any(kinds.get((p, t)) == "read" for t in calls.clusters[calls_box])}
    box_arcs = [(b, p, "read" if (b, p) in reads else way, pts) for b, p, way, pts in box_arcs]
    drawn = Drawn({n: frame(*p) for n, p in nodes.items() if n in part.place_index
                   or n in part.transition_index},
                  bends, {c: (place, frame(*nodes[c])) for c, place in copies.items()},
                  opened, sizes, _by_id(texts))
    return CallView(_of(part, drawn), shut,
                    {name: texts[box_node(name)][0] for name in shut}, frames, box_arcs)


def _run_dots(sources: Sequence[str]) -> list[dict] | None:
    """dot's layouts of several graphs, a run of dot each (several graphs in one run are
    laid out differently from one run to the next: a page must be the same every time
    it is written), as many at once as there are processors; None if one failed."""
    # concurrent.futures, 5 ms (python -X importtime) at the CLI's start, which imports this
    # module: only for a page's calls (threads, waiting on dot: the paper's 21 in 0.3 s)
    from concurrent.futures import ThreadPoolExecutor
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        graphs = list(pool.map(_run_dot, sources))
    return None if any(g is None for g in graphs) else graphs


def _cluster_boxes(graph: dict) -> dict[str, tuple[float, float, float, float]]:
    """The open boxes of dot's layout: name -> its rectangle in graphviz's points."""
    return {o["name"][len("cluster_"):]: tuple(float(v) for v in o["bb"].split(","))
            for o in graph.get("objects", []) if o.get("name", "").startswith("cluster_")
            and "bb" in o}


def _framed(frame: "_Frame", x0: float, y0: float, x1: float, y1: float
            ) -> tuple[float, float, float, float]:
    """A rectangle of graphviz's points as (left, top, right, bottom) in PNML's."""
    (left, top), (right, bottom) = frame(x0, y1), frame(x1, y0)
    return (left, top, right, bottom)


def _of(net: Net, drawn: Drawn) -> Drawn:
    """Only the net's nodes and arcs, and the copies of its places with their arcs: not
    the nodes that stand for a shut box (their boxes are in ``boxes``)."""
    ids = net.place_index.keys() | net.transition_index.keys()
    arcs = {(a.source, a.target) for a in net.arcs}
    copies = {c: (place, at) for c, (place, at) in drawn.copies.items() if place in ids}
    # an arc drawn to a copy: the copy at one end, a transition of the net at the other
    drawn_arcs = arcs | {(c, t) for (c, t) in drawn.bends if c in copies and t in ids} \
        | {(t, c) for (t, c) in drawn.bends if c in copies and t in ids}
    kept = ids | copies.keys()
    return Drawn({n: p for n, p in drawn.positions.items() if n in ids},
                 {arc: pts for arc, pts in drawn.bends.items() if arc in drawn_arcs and pts},
                 copies, drawn.boxes, {n: s for n, s in drawn.sizes.items() if n in kept},
                 {n: t for n, t in drawn.texts.items() if n in kept})


def _two_levels(net: Net, boxes: dict[str, list[str]]) -> Drawn | None:
    """A net of boxes laid out as its overview: each box's inside laid out on its own
    (one dot run, every box a component), then the overview with each shut box as
    large as its inside (a second run); each node placed in its box."""
    from mcl2pnml.view.drawing import box_node, dot_graph   # graphviz: as _dot_drawn says
    box = {n: name for name, members in boxes.items() for n in members}
    inside = Net(net.name, tuple(p for p in net.places if p.id in box),
                 tuple(t for t in net.transitions if t.id in box),
                 tuple(a for a in net.arcs if a.source in box and box[a.source] == box.get(a.target)),
                 Marking({p: k for p, k in net.initial.items() if p in box}))
    texts: dict[str, tuple[str, int]] = {}
    inner = _run_dot(dot_graph(inside, clusters=boxes, legend=False, expand=None,
                               texts=texts).source)
    if inner is None:
        return None
    extent = {o["name"][len("cluster_"):]: [float(v) for v in o["bb"].split(",")]
              for o in inner.get("objects", []) if o.get("name", "").startswith("cluster_")}
    sizes = {name: (x1 - x0, y1 - y0) for name, (x0, y0, x1, y1) in extent.items()}
    outside: dict[str, tuple[str, int]] = {}
    outer = _overview(dot_graph(net, clusters=boxes, legend=False, expand=(), box_sizes=sizes,
                                texts=outside))
    if outer is None:
        return None
    frame = _Frame(outer)
    centres = {o["name"]: [float(v) for v in o["pos"].split(",")]
               for o in outer.get("objects", []) if "pos" in o}
    nodes, splines, copied = _read(inner)
    positions, bends, copies, rects = {}, {}, {}, {}
    shift = {}
    for name, (x0, y0, x1, y1) in extent.items():
        cx, cy = centres[box_node(name)]
        dx, dy = cx - (x0 + x1) / 2, cy - (y0 + y1) / 2
        shift[name] = (dx, dy)
        rects[name] = _framed(frame, x0 + dx, y0 + dy, x1 + dx, y1 + dy)
    # a copy of a place is in the box of the transition it is drawn beside
    for (a, b) in splines:
        for c, t in ((a, b), (b, a)):
            if c in copied and t in box:
                box.setdefault(c, box[t])
    for n, (x, y) in nodes.items():
        if n in box:
            dx, dy = shift[box[n]]
            positions[n] = frame(x + dx, y + dy)
    for (a, b), pts in splines.items():
        dx, dy = shift[box[a]]
        bends[(a, b)] = [frame(x + dx, y + dy) for x, y in pts]
    for c, place in copied.items():
        if c in positions:
            copies[c] = (place, positions.pop(c))
    loose, drawn, _ = _read(outer)
    for n, p in loose.items():
        positions.setdefault(n, frame(*p))
    # an arc between a box and a place outside it runs along the overview's arc to the
    # box, then inside the box to its node (_way_in), not across the box's other nodes
    sizes = _half_sizes(inner)
    spots = {**positions, **{c: at for c, (_, at) in copies.items()}}   # a copy is in the way too
    lanes: dict[str, int] = {}       # arcs along each box's border so far

    def way_in(name: str, outside: tuple[float, float], node: str) -> list[tuple[float, float]]:
        # each arc along its own lane, so that arcs along one border stay apart
        lane = lanes[name] = lanes.get(name, -1) + 1
        return _way_in(rects[name], outside, node, spots, box, sizes, LANES[lane % len(LANES)])
    for arc in net.arcs:
        ends = (arc.source if arc.source not in box else box_node(box[arc.source]),
                arc.target if arc.target not in box else box_node(box[arc.target]))
        if ends[0] == ends[1] or (arc.source, arc.target) in bends:
            continue
        pts = drawn.get(ends) or list(reversed(drawn.get(ends[::-1], [])))
        if pts:
            pts = [frame(*p) for p in pts]
            if arc.target in box:
                pts += way_in(box[arc.target], pts[-1], arc.target)
            if arc.source in box:
                pts = way_in(box[arc.source], pts[0], arc.source)[::-1] + pts
            bends[(arc.source, arc.target)] = pts
    # each node's size and text as dot drew it: inside its box, or (between boxes) in the
    # overview
    return Drawn(positions, bends, copies, rects, {**_half_sizes(outer), **sizes},
                 {**_by_id(outside), **_by_id(texts)})


def _by_id(texts: Mapping[str, tuple[str, int]]) -> dict[str, tuple[str, int]]:
    """The texts a drawing recorded by DOT name, by the net's ids (a copy's or a box's by
    its DOT name, as :func:`_read` names them)."""
    from mcl2pnml.io.dot import node_id   # graphviz: as _dot_drawn says
    return {(node_id(name) or name): text for name, text in texts.items()}


def _overview(overview) -> dict | None:
    """dot's layout of a drawing of shut boxes (its JSON), top down, or left to right where
    that is less tall; None where dot fails."""
    outer = _run_dot(overview.source)
    if outer is None:
        return None
    _, _, w, h = (float(v) for v in outer["bb"].split(","))
    if h > TALL * w:
        # boxes as tall as their insides, one level of calls under another: a column
        # no screen shows; the levels side by side instead, if that is less tall
        overview.graph_attr["rankdir"] = "LR"
        wide = _run_dot(overview.source)
        if wide is not None:
            _, _, w2, h2 = (float(v) for v in wide["bb"].split(","))
            outer = wide if max(w2, h2) < max(w, h) else outer
    return outer


#: How far inside its box an arc runs along the box's border, one lane after another
#: (dot keeps the nodes 8 points inside a box's border).
LANES = (2.0, 4.0, 6.0)


def _half_sizes(graph: dict) -> dict[str, tuple[float, float]]:
    """Each node's half width and half height in dot's layout, in points."""
    from mcl2pnml.io.dot import node_id   # graphviz: as _dot_drawn says
    return {node_id(o["name"]) or o["name"]: (float(o["width"]) * 36, float(o["height"]) * 36)
            for o in graph.get("objects", []) if "pos" in o and "width" in o}


def _way_in(rect: tuple[float, float, float, float], outside: tuple[float, float], node: str,
            positions: Mapping[str, tuple[float, float]], box: Mapping[str, str],
            sizes: Mapping[str, tuple[float, float]], inset: float) -> list[tuple[float, float]]:
    """The points from the box's border, where the overview's arc from ``outside`` comes
    in, to ``node`` inside the box: along the border (just inside it, where dot puts no
    node) to a door on a side, then to the node by a way that passes no other node of
    the box: straight from the door, or out of the node up or down into the gap between
    dot's ranks and along it to the door; the shortest such way (the straight way from
    the nearest side if none is clear). The border is followed ``inset`` points inside."""
    x0, y0, x1, y1 = rect[0] + inset, rect[1] + inset, rect[2] - inset, rect[3] - inset
    nx, ny = positions[node]
    others = [(positions[m], sizes.get(m, (0.0, 0.0))) for m, b in box.items()
              if b == box[node] and m != node and m in positions]

    def clear(way):
        return not any(_segment_meets(a, b, c, h) for a, b in zip(way, way[1:])
                       for c, h in others)
    ways = [[q] for q in ((nx, y0), (nx, y1), (x0, ny), (x1, ny))]
    half = sizes.get(node, (0.0, 0.0))[1]
    for step in range(4, 64, 4):
        for y in (ny - half - step, ny + half + step):
            if y0 < y < y1:
                ways += [[(x0, y), (nx, y)], [(x1, y), (nx, y)]]

    def length(way):
        pts = [*way, (nx, ny)]
        return sum(abs(a[0] - b[0]) + abs(a[1] - b[1]) for a, b in zip(pts, pts[1:]))
    ways.sort(key=length)
    way = next((w for w in ways if clear([*w, (nx, ny)])), ways[0])
    entry = (min(max(outside[0], x0), x1), min(max(outside[1], y0), y1))
    if x0 < entry[0] < x1 and y0 < entry[1] < y1:    # inside: to the nearest side
        entry = min(((entry[0], y0), (entry[0], y1), (x0, entry[1]), (x1, entry[1])),
                    key=lambda q: abs(q[0] - entry[0]) + abs(q[1] - entry[1]))
    return [*_along((x0, y0, x1, y1), entry, way[0]), *way[1:]]


def _segment_meets(a: tuple[float, float], b: tuple[float, float], centre: tuple[float, float],
                   half: tuple[float, float]) -> bool:
    """Whether the segment ab passes through the rectangle of ``half`` sizes around
    ``centre`` (Liang-Barsky clipping)."""
    lo, hi = 0.0, 1.0
    dx, dy = b[0] - a[0], b[1] - a[1]
    for p, q in ((-dx, a[0] - (centre[0] - half[0])), (dx, centre[0] + half[0] - a[0]),
                 (-dy, a[1] - (centre[1] - half[1])), (dy, centre[1] + half[1] - a[1])):
        if p == 0:
            if q < 0:
                return False
        elif p < 0:
            lo = max(lo, q / p)
        else:
            hi = min(hi, q / p)
        if lo > hi:
            return False
    return True


def _along(rect: tuple[float, float, float, float], a: tuple[float, float],
           b: tuple[float, float]) -> list[tuple[float, float]]:
    """From ``a`` to ``b``, both on the rectangle's outline, along it the shorter way
    round: ``a``, the corners passed, ``b``."""
    x0, y0, x1, y1 = rect
    w, h = x1 - x0, y1 - y0
    perimeter = 2 * (w + h)

    def s(q):   # distance along the outline, clockwise from the top left corner
        x, y = q
        return (x - x0 if y == y0 else w + y - y0 if x == x1 else
                w + h + x1 - x if y == y1 else 2 * w + h + y1 - y)
    corners = [(0.0, (x0, y0)), (w, (x1, y0)), (w + h, (x1, y1)), (2 * w + h, (x0, y1))]
    sa, sb = s(a), s(b)
    forward = (sb - sa) % perimeter
    if forward <= perimeter / 2:
        passed = sorted(((c - sa) % perimeter, q) for c, q in corners
                        if 0 < (c - sa) % perimeter < forward)
    else:
        passed = sorted(((sa - c) % perimeter, q) for c, q in corners
                        if 0 < (sa - c) % perimeter < perimeter - forward)
    return [(round(a[0], 1), round(a[1], 1)), *(q for _, q in passed),
            (round(b[0], 1), round(b[1], 1))]


class _Frame:
    """graphviz's points to PNML's: y downwards, the drawing's box moved to the margin."""

    def __init__(self, graph: dict):
        x0, y0, _, y1 = (float(v) for v in graph.get("bb", "0,0,0,0").split(","))
        self.x0, self.y1 = x0, y1

    def __call__(self, x: float, y: float) -> tuple[float, float]:
        return (round(x - self.x0 + MARGIN, 1), round(self.y1 - y + MARGIN, 1))


#: Where each Bézier piece of dot's spline is sampled, besides its end.
_SAMPLES = (0.25, 0.5, 0.75)
#: The same on a page's view of one call, whose nodes dot packs closer: a straight line
#: between quarters may cut the corner of the next transition.
_FINE = tuple(k / 8 for k in range(1, 8))


def _read(graph: dict, fine: bool = False) -> tuple[dict[str, tuple[float, float]],
                                dict[tuple[str, str], list[tuple[float, float]]],
                                dict[str, str]]:
    """The nodes' positions and the arcs' bend points in dot's JSON, by the ids of the
    net (a box's name or a copy of a place is kept under its DOT name), and each copy's
    place.

    The bend points of an arc are points on dot's spline between its ends:
    each Bézier piece's quarters and end, the last end (at the node) left out,
    close enough to the curve that lines between them pass no node the curve
    passes by (a piece's middle alone cut the corner of a long bend across a
    node). ``fine``: each piece's eighths, and both ends of the spline kept, where dot
    left them on its nodes' borders (a page's view of one call, packed closer).
    """
    from mcl2pnml.io.dot import node_id   # graphviz: as _dot_drawn says
    objects = graph.get("objects", [])
    names = {o["_gvid"]: (node_id(o["name"]) or o["name"]) for o in objects if "pos" in o}
    # a copy is named after its place's DOT name and its number (``OFF~3``), and has
    # the class copy: its name is never taken for a node of the net
    copies = {names[o["_gvid"]]: node_id(o["name"].rpartition("~")[0])
              for o in objects if "pos" in o and o.get("class") == "copy"}
    nodes = {names[o["_gvid"]]: tuple(float(v) for v in o["pos"].split(","))
             for o in objects if "pos" in o}
    splines = {}
    for e in graph.get("edges", []):
        pts = next((op["points"] for op in e.get("_draw_", ()) if op["op"] in ("b", "B")), None)
        if not pts or e["tail"] not in names or e["head"] not in names:
            continue
        on_curve = []
        for k in range(0, len(pts) - 3, 3):
            (x0, y0), (x1, y1), (x2, y2), (x3, y3) = pts[k:k + 4]
            for t in (_FINE if fine else _SAMPLES):
                u = 1 - t
                a, b, c, d = u * u * u, 3 * u * u * t, 3 * u * t * t, t * t * t
                on_curve.append((a * x0 + b * x1 + c * x2 + d * x3,
                                 a * y0 + b * y1 + c * y2 + d * y3))
            on_curve.append((x3, y3))
        tail, head = names[e["tail"]], names[e["head"]]
        if fine:
            on_curve = [tuple(pts[0]), *on_curve, on_curve[-1]]
        if e.get("dir") == "back":    # drawn from head to tail: the arc runs that way
            tail, head, on_curve = head, tail, [*reversed(on_curve[:-1]), pts[0]]
        splines[(tail, head)] = on_curve[:-1]
    return nodes, splines, copies


def _layered_layout(net: Net) -> dict[str, tuple[float, float]]:
    # Column = BFS depth from the marked places, where the net starts; nodes
    # that BFS cannot reach start new columns from the first unreached node.
    # One pass over the arcs in all: linear in the size of the net.
    successors: dict[str, list[str]] = {p.id: [] for p in net.places}
    successors.update((t.id, []) for t in net.transitions)
    sources, targets, _, _ = net.columns
    for source, target in zip(sources, targets):
        successors[source].append(target)
    layer: dict[str, int] = {}
    first = 0
    starts = [[p for p in net.initial]] if net.initial else []
    pending = iter(successors)
    while True:
        if not starts:
            start = next((n for n in pending if n not in layer), None)
            if start is None:
                break
            starts = [[start]]
        frontier = [n for n in starts.pop() if n not in layer]
        depth = first
        while frontier:
            for n in frontier:
                layer[n] = depth
            nxt = []
            for n in frontier:
                for m in successors[n]:
                    if m not in layer:
                        layer[m] = depth + 1  # claimed now, so it is queued once
                        nxt.append(m)
            frontier, depth = nxt, depth + 1
        first = depth
    # rows fill each column from the top, in net order, which keeps the nodes
    # of one component together; columns and rows start at 0, so this is
    # already the normal form: x and y from the margin, y downwards
    rows: dict[int, int] = {}
    pos: dict[str, tuple[float, float]] = {}
    for n in successors:
        col = layer[n]
        row = rows.get(col, 0)
        rows[col] = row + 1
        pos[n] = (col * SPACING + MARGIN, row * SPACING + MARGIN)
    return pos


def positions(net: Net, engine: str = "auto") -> dict[str, tuple[float, float]]:
    """Where to draw each node: the nodes' own positions when all have one, else a layout."""
    # lxml comes with io.pnml (its package loads the reader): 40 ms, measured with
    # python -X importtime, which the CLI's start would pay (cli_options imports this module)
    from mcl2pnml.io.pnml.writer import own_positions
    return own_positions(net) or layout(net, engine)
