"""Positions for drawing a net, so that PNML opens as a picture, not a heap.

PIPE, TAPAAL, WoPeD and TINA's nd draw a net where its ``<graphics>`` say.
Small nets (the paper's templates, most missions) are laid out by graphviz
``dot``: left to right, in the direction tokens flow. Large nets, where
``dot`` would take minutes, are laid out in columns by their breadth-first
distance from the initially marked places, which is linear in the size of
the net and still shows the flow from start to end. Above
:data:`LAYERS_LIMIT` nodes no editor draws a net usefully, so ``auto`` gives
no positions at all (``<graphics>`` is optional in PNML): a 10,000-call
survey is written a third faster and 15% smaller.

Coordinates follow PNML: x to the right, y downwards, in points, all >= 0.
"""
from __future__ import annotations

import json
import shutil
import subprocess
from typing import Mapping

from mcl2pnml.core.net import Net

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


def dot_available() -> bool:
    return shutil.which("dot") is not None


def layout(net: Net, engine: str = "auto") -> dict[str, tuple[float, float]]:
    """Node id -> (x, y), for every node or (engine ``"none"``) for none.

    ``engine`` is one of :data:`ENGINES`; ``"auto"`` picks ``dot`` up to
    :data:`DOT_LIMIT` nodes (when graphviz is installed), ``layers`` up to
    :data:`LAYERS_LIMIT`, and ``none`` above.
    """
    if engine not in ENGINES:
        raise ValueError(f"unknown layout engine {engine!r}; one of {', '.join(ENGINES)}")
    nodes = len(net.places) + len(net.transitions)
    if engine == "auto":
        engine = ("dot" if nodes <= DOT_LIMIT and dot_available()
                  else "layers" if nodes <= LAYERS_LIMIT else "none")
    if engine == "dot":
        pos = _dot_layout(net)
        if pos is not None and len(pos) == nodes:
            return pos
        # dot failed, ran out of time or left a node out (every node has a position,
        # whoever asks): the layered layout is linear, always ends, places every node
    if engine in ("dot", "layers"):
        return _layered_layout(net)
    return {}


def _dot_layout(net: Net) -> dict[str, tuple[float, float]] | None:
    """Where dot puts each node in the drawing of :mod:`mcl2pnml.io.dot` (None: dot failed).

    The same graph as ``compile --format svg``, so the PNML opens as that
    picture; its boxes around instances also make dot fast (0.2 s instead
    of 18 s on a 600-node mission).
    """
    from mcl2pnml.io.dot import (dot_missing, instance_clusters, node_id,   # imports graphviz:
                                 to_dot)                                # only now
    if not dot_available():
        raise dot_missing("--layout", "the layouts layers and none work without it, and auto "
                                      "lays out in layers when it is missing")

    source = to_dot(net, clusters=instance_clusters(net), legend=False).source
    try:
        result = subprocess.run(["dot", "-Tjson0"], input=source.encode(),
                                capture_output=True, check=True, timeout=DOT_TIMEOUT)
    except (subprocess.TimeoutExpired, subprocess.CalledProcessError):
        return None   # too slow, or one of dot's internal failures: lay out in layers
    graph = json.loads(result.stdout)
    nodes = {n.id for n in (*net.places, *net.transitions)}
    pos: dict[str, tuple[float, float]] = {}
    for obj in graph.get("objects", []):
        name = node_id(obj.get("name", ""))     # the id, where DOT needed it encoded
        if name in nodes and "pos" in obj:
            x, y = (float(v) for v in obj["pos"].split(","))
            pos[name] = (x, y)
    return _normalise(pos, flip_y=True)  # graphviz's y axis points up


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
    # already the normal form (no need for _normalise)
    rows: dict[int, int] = {}
    pos: dict[str, tuple[float, float]] = {}
    for n in successors:
        col = layer[n]
        row = rows.get(col, 0)
        rows[col] = row + 1
        pos[n] = (col * SPACING + MARGIN, row * SPACING + MARGIN)
    return pos


def _normalise(pos: Mapping[str, tuple[float, float]], flip_y: bool) -> dict[str, tuple[float, float]]:
    if not pos:
        return {}
    xs = [x for x, _ in pos.values()]
    ys = [y for _, y in pos.values()]
    x0, y0, y1 = min(xs), min(ys), max(ys)
    out = {}
    for n, (x, y) in pos.items():
        y = (y1 - y) if flip_y else (y - y0)
        out[n] = (round(x - x0 + MARGIN, 1), round(y + MARGIN, 1))
    return out


def positions(net: Net, engine: str = "auto") -> dict[str, tuple[float, float]]:
    """Where to draw each node: the nodes' own positions when all have one, else a layout."""
    from mcl2pnml.io.pnml.writer import own_positions
    return own_positions(net) or layout(net, engine)
