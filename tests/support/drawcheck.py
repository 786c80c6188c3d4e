"""What a reader of a drawing must never see, found in graphviz's own layout (``dot -Tjson``).

A label (a node's, an arc's weight, a box's title) must not lie on another
node, on another label or on an arc, and a node must not straddle the border
of a box (a fusion place is drawn outside the boxes it joins, or inside one).
Every shape comes from dot's output, not from our idea of it: the nodes'
boxes (``pos``, ``width``, ``height``, ellipses for circles), each line of
text as dot draws it (``_ldraw_`` and the other ``_*ldraw_`` lists: anchor,
alignment, width, font size), the arcs as the Bézier curves dot draws
(``_draw_``) with their arrow heads (``_hdraw_``, ``_tdraw_``), the boxes'
rectangles (``bb``). matplotlib's paths test curves against rectangles.
"""
from __future__ import annotations

import fcntl
import hashlib
import json
import os
import pathlib
import subprocess
import tempfile
from dataclasses import dataclass

from matplotlib.path import Path
from matplotlib.transforms import Bbox

#: Points a label may touch another shape by (dot rounds its numbers to 1/100 pt).
SLACK = 0.75
_TEXTS = ("_ldraw_", "_xldraw_", "_hldraw_", "_tldraw_")


@dataclass(frozen=True)
class Label:
    owner: str          # "node NAME", "arc A->B", "box NAME"
    text: str
    box: Bbox


#: Where dot's outputs are kept for every test process of a run (set by the tests'
#: conftest; None: in this process only). The same drawings are checked by several
#: tests (a figure's overlaps, its legend, its text on a slide), each of which had dot
#: lay it out again, in each worker; the first to ask lays it out, the others wait on its lock.
SHARED: pathlib.Path | None = None
_LAID: dict[tuple[str, str], bytes] = {}
#: The formats dot writes in one run when one of them is asked: the cheap ones together.
_TOGETHER = {"json": ("json", "svg"), "svg": ("json", "svg"), "png": ("png",)}


def laid_out(source: str, fmt: str) -> bytes:
    """dot's output ``-T<fmt>`` of a DOT source (``json``, ``svg`` or ``png``), as
    ``dot`` writes it; each source laid out once per run, for all its formats asked
    together (one layout, several renderings), kept under its digest."""
    digest = hashlib.sha256(source.encode()).hexdigest()[:40]
    if (digest, fmt) not in _LAID:
        if SHARED is None:
            _dot(source, digest, _TOGETHER[fmt])
            return _LAID[digest, fmt]
        kept = SHARED / f"{digest}.{fmt}"
        with open(SHARED / f"{digest}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)    # another worker laying it out: wait for it
            if kept.is_file():
                _LAID[digest, fmt] = kept.read_bytes()
            else:
                _dot(source, digest, _TOGETHER[fmt])
    return _LAID[digest, fmt]


def _dot(source: str, digest: str, formats) -> None:
    with tempfile.TemporaryDirectory(dir=SHARED) as folder:   # (beside: renamed there)
        outputs = {f: pathlib.Path(folder) / f"out.{f}" for f in formats}
        command = ["dot"] + [a for f in formats for a in (f"-T{f}", "-o", str(outputs[f]))]
        subprocess.run(command, input=source.encode(), capture_output=True, check=True,
                       timeout=120)
        for f, path in outputs.items():
            _LAID[digest, f] = path.read_bytes()
            if SHARED is not None:      # whole or not at all, whichever worker writes it
                os.replace(path, SHARED / f"{digest}.{f}")


def layout_json(source: str) -> dict:
    """dot's layout of a DOT source, as its JSON output (``-Tjson``); a fresh copy,
    which the caller may change."""
    return json.loads(laid_out(source, "json"))


def svg_size(svg: bytes) -> tuple[float, float]:
    """An SVG drawing's width and height in its own units (graphviz: points)."""
    from lxml import etree
    _, _, w, h = (float(v) for v in etree.fromstring(svg).get("viewBox").split())
    return w, h


def fitted_text(svg: bytes, slide: tuple[float, float] = (1920, 1080)
                ) -> tuple[float, tuple[float, float]]:
    """The height in pixels of the smallest text of an SVG drawing fitted into ``slide``
    (scale = the lesser of the slide's width over the drawing's and its height over the
    drawing's; a text's height is its font size), and the drawing's size."""
    from lxml import etree
    w, h = svg_size(svg)
    scale = min(slide[0] / w, slide[1] / h)
    sizes = [float(t.get("font-size")) for t in etree.fromstring(svg).iter(
        "{http://www.w3.org/2000/svg}text") if (t.text or "").strip()]
    return min(sizes) * scale, (w, h)


def _texts(obj: dict, owner: str) -> list[Label]:
    labels = []
    for key in _TEXTS:
        size = 14.0
        for op in obj.get(key, ()):
            if op["op"] == "F":
                size = float(op["size"])
            elif op["op"] == "T" and op["text"].strip():
                x, y = op["pt"]
                w = float(op["width"])
                left = {"l": x, "c": x - w / 2, "r": x - w}[op["align"]]
                # y is the baseline: descenders below it, the rest of the line above
                box = Bbox([[left + SLACK, y - 0.22 * size + SLACK],
                            [left + w - SLACK, y + 0.78 * size - SLACK]])
                labels.append(Label(owner, op["text"], box))
    return labels


def _curves(obj: dict) -> list[Path]:
    paths = []
    for key in ("_draw_", "_hdraw_", "_tdraw_"):
        for op in obj.get(key, ()):
            pts = op.get("points")
            if op["op"] in ("b", "B") and pts:
                codes = [Path.MOVETO] + [Path.CURVE4] * (len(pts) - 1)
                paths.append(Path(pts, codes))
            elif op["op"] in ("p", "P", "L") and pts:
                closed = op["op"] != "L"
                paths.append(Path([*pts, pts[0]] if closed else pts))
    return paths


def _node_shape(node: dict) -> tuple[Bbox, bool]:
    x, y = (float(v) for v in node["pos"].split(","))
    w, h = float(node["width"]) * 36, float(node["height"]) * 36
    round_ = node.get("shape") in ("circle", "ellipse", "doublecircle", "point")
    return Bbox([[x - w, y - h], [x + w, y + h]]), round_


def _hits_node(label: Bbox, shape: Bbox, round_: bool) -> bool:
    if not label.overlaps(shape):
        return False
    if not round_:
        return True
    # the point of the label nearest the ellipse's centre, inside the ellipse?
    cx, cy = (shape.x0 + shape.x1) / 2, (shape.y0 + shape.y1) / 2
    rx, ry = shape.width / 2, shape.height / 2
    px = min(max(cx, label.x0), label.x1)
    py = min(max(cy, label.y0), label.y1)
    return ((px - cx) / rx) ** 2 + ((py - cy) / ry) ** 2 < 1


def problems(graph: dict) -> list[str]:
    """Every overlap a reader would see in dot's layout ``graph`` (``-Tjson``), as sentences.

    Candidates are pairs whose bounding boxes meet (numpy, all at once), then
    tested on their true shapes, so that a mission's drawing takes a second.
    """
    objects = graph.get("objects", [])
    nodes = [o for o in objects if "pos" in o]
    names = {o["_gvid"]: o["name"] for o in nodes}
    boxes = [o for o in objects if o.get("name", "").startswith("cluster") and "bb" in o]
    labels: list[Label] = []
    for n in nodes:
        labels += _texts(n, f"node {n['name']}")
    for b in boxes:
        labels += _texts(b, f"box {b['name']}")
    arcs = []           # (name, its two ends, its curves)
    for e in graph.get("edges", []):
        name = f"arc {names[e['tail']]}->{names[e['head']]}"
        labels += _texts(e, name)
        arcs.append((name, {f"node {names[e['tail']]}", f"node {names[e['head']]}"}, _curves(e)))
    shapes = [_node_shape(n) for n in nodes]
    found = []
    node_boxes = _array([s.extents for s, _ in shapes])
    label_boxes = _array([a.box.extents for a in labels])
    arc_boxes = _array([_extents(c) for _, _, c in arcs])
    for i, j in _meeting(label_boxes, node_boxes):
        a, n = labels[i], nodes[j]
        if a.owner != f"node {n['name']}" and _hits_node(a.box, *shapes[j]):
            found.append(f"label {a.text!r} of {a.owner} on node {n['name']}")
    for i, j in _meeting(label_boxes, label_boxes):
        a, b = labels[i], labels[j]
        if i < j and a.owner != b.owner and a.box.overlaps(b.box):
            found.append(f"label {a.text!r} of {a.owner} on label {b.text!r} of {b.owner}")
    for i, j in _meeting(label_boxes, arc_boxes):
        a, (name, _, curves) = labels[i], arcs[j]
        # an arc's own label too: dot puts it beside the arc, never across it
        if any(c.intersects_bbox(a.box, filled=False) for c in curves):
            found.append(f"label {a.text!r} of {a.owner} on {name}")
    for i, j in _meeting(arc_boxes, node_boxes):
        (name, ends, curves), n = arcs[i], nodes[j]
        if f"node {n['name']}" not in ends and any(
                c.intersects_bbox(_core(*shapes[j]), filled=False) for c in curves):
            found.append(f"{name} through node {n['name']}")
    for b in boxes:
        x0, y0, x1, y1 = (float(v) for v in b["bb"].split(","))
        border = Bbox([[x0, y0], [x1, y1]])
        for n, (shape, _) in zip(nodes, shapes):
            if shape.overlaps(border) and _straddles(shape, border):
                found.append(f"node {n['name']} on the border of box {b['name']}")
    return found


def _array(extents):
    import numpy as np
    return np.array(extents, dtype=float).reshape(-1, 4)


def _extents(curves: list[Path]) -> tuple[float, float, float, float]:
    if not curves:
        return (0.0, 0.0, -1.0, -1.0)          # meets nothing
    ext = [c.get_extents().extents for c in curves]
    return (min(e[0] for e in ext), min(e[1] for e in ext),
            max(e[2] for e in ext), max(e[3] for e in ext))


def _meeting(a, b):
    """The pairs (i, j) of rows of ``a`` and ``b`` (x0, y0, x1, y1) whose rectangles meet."""
    import numpy as np
    if not len(a) or not len(b):
        return []
    hit = ((a[:, None, 0] <= b[None, :, 2]) & (b[None, :, 0] <= a[:, None, 2])
           & (a[:, None, 1] <= b[None, :, 3]) & (b[None, :, 1] <= a[:, None, 3]))
    return list(zip(*np.nonzero(hit)))


def _core(shape: Bbox, round_: bool) -> Bbox:
    """The part of a node an arc must not cross: the whole box, the inscribed square of
    a circle (an arc cut across that is through the circle, not grazing it)."""
    if not round_:
        return Bbox([[shape.x0 + SLACK, shape.y0 + SLACK], [shape.x1 - SLACK, shape.y1 - SLACK]])
    cx, cy = (shape.x0 + shape.x1) / 2, (shape.y0 + shape.y1) / 2
    hx, hy = shape.width * 0.35, shape.height * 0.35
    return Bbox([[cx - hx, cy - hy], [cx + hx, cy + hy]])


def _straddles(shape: Bbox, border: Bbox) -> bool:
    """``shape`` crosses one of ``border``'s sides (not merely holds the whole box)."""
    inner = Bbox([[shape.x0 + SLACK, shape.y0 + SLACK], [shape.x1 - SLACK, shape.y1 - SLACK]])
    outline = Path([(border.x0, border.y0), (border.x1, border.y0), (border.x1, border.y1),
                    (border.x0, border.y1), (border.x0, border.y0)])
    return outline.intersects_bbox(inner, filled=False)
