"""``mcl2pnml show``: a net as one self-contained HTML page, to play the token game.

The page is for teaching Petri-net supervisors: it draws the net where its
PNML ``<graphics>`` put it (:mod:`mcl2pnml.view.layout`), boxes the nodes of each
instance (a task, a structure, a call site: :func:`~mcl2pnml.io.dot.instance_clusters`)
and highlights the fusion places where they meet; a student clicks an
enabled transition to fire it, steps back, resets, and sees the marking and
every P-invariant's value at each step (each must keep its value at M0: a
broken one would be a bug of ours, and is shown in red). A recorded run (the
JSON-lines log of ``mcl2pnml run --log``) can be followed step by step, with
the vehicle's actions and events beside the firings; and a mission or a
task can be switched to its reduced model (Fig. 3 of the paper: every task
started by B, ending in OK, FAIL or ABORTED, without its primitive).

Everything the page needs is inside it: the data as JSON, the script and
the style; it fetches nothing, so it opens from a file, offline, in any
browser. The page itself is ``show_page.html`` beside this module.
"""
from __future__ import annotations

import json
from importlib import resources
from pathlib import Path
from typing import Any, Iterable

from mcl2pnml.io.dot import border_out, instance_clusters
from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import atomic_write_text, read_text
from mcl2pnml.view.layout import layout
from mcl2pnml.core.net import Net, thaw
from mcl2pnml.core.payloads import doc_of, read_transition

#: Above this many nodes the page would be a heap nobody can read: refused.
MAX_NODES = 5_000
#: How many P-invariants the page checks at each step, at most.
MAX_INVARIANTS = 400


def variant(net: Net, label: str) -> dict[str, Any]:
    """One net as the page draws it: nodes with positions, arcs by index, boxes, invariants."""
    from analysis.invariants import p_invariant_basis
    from mcl2pnml.core.structure import structure

    nodes = len(net.places) + len(net.transitions)
    if nodes > MAX_NODES:
        raise Mcl2PnmlError(f"net '{net.name}' has {nodes:,} nodes; a page draws at most "
                            f"{MAX_NODES:,} (compile it to PNML or DOT instead)")
    pos = layout(net, "auto")
    boxes = instance_clusters(net)
    kept = border_out(net, boxes)
    box_of = {n: name for name, members in kept.items() for n in members}
    index = {p.id: k for k, p in enumerate(net.places)}
    # the places a box had and border_out took out: where boxes meet
    border = {n for members in boxes.values() for n in members} - set(box_of)
    places = [{"id": p.id, "label": p.label, "x": pos[p.id][0], "y": pos[p.id][1],
               "tokens": net.initial[p.id], "interface": p.interface,
               "fusion": p.id in border, "group": box_of.get(p.id),
               "doc": thaw(doc_of(p.payload))} for p in net.places]
    transitions = []
    for t in net.transitions:
        payload = read_transition(t)
        kind = ("event" if payload.event is not None else "timeout" if t.timing is not None
                else "action" if payload.actions else "call" if payload.entry is not None
                else "")
        transitions.append({
            "id": t.id, "label": t.label, "x": pos[t.id][0], "y": pos[t.id][1],
            "timing": str(t.timing) if t.timing is not None else None, "kind": kind,
            "group": box_of.get(t.id), "doc": thaw(payload.doc),
            "pre": [[index[a.source], a.weight] for a in net.pre[t.id]
                    if a.kind.value == "normal"],
            "read": [[index[a.source], a.weight] for a in net.pre[t.id]
                     if a.kind.value == "read"],
            "post": [[index[a.target], a.weight] for a in net.post[t.id]]})
    basis = p_invariant_basis(structure(net))[:MAX_INVARIANTS]
    invariants = [{"terms": [[index[p], c] for p, c in y.items()],
                   "value": sum(c * net.initial[p] for p, c in y.items())} for y in basis]
    return {"label": label, "name": net.name, "places": places, "transitions": transitions,
            "groups": sorted(kept), "invariants": invariants}


def read_run(path: str | Path) -> list[dict[str, Any]]:
    """The entries of a JSON-lines run log (``mcl2pnml run --log``); bad lines are errors."""
    entries = []
    text = read_text(path, "run log")
    for n, line in enumerate(text.split("\n"), 1):
        if not line.strip():
            continue
        try:
            entry = json.loads(line)
        except json.JSONDecodeError as e:
            raise Mcl2PnmlError(f"not a JSON line: {e.msg}",
                                Location(str(path), n, e.colno, line)) from None
        if not isinstance(entry, dict):
            raise Mcl2PnmlError("a run log's line is a JSON object",
                                Location(str(path), n, 1, line))
        entries.append(entry)
    return entries


def check_run(net: Net, entries: Iterable[dict[str, Any]], path: str) -> None:
    """Every transition a run log fires must be one of the net's."""
    for n, entry in enumerate(entries, 1):
        fired = entry.get("fire")
        if fired is not None and fired not in net.transition_index:
            raise Mcl2PnmlError(f"the run fires '{fired}', which is no transition of "
                                f"'{net.name}': a log of another mission?", Location(path))


def page(title: str, variants: list[dict[str, Any]],
         run: list[dict[str, Any]] | None = None) -> str:
    """The HTML page: the template with the data inside it."""
    data = json.dumps({"title": title, "variants": variants, "run": run},
                      separators=(",", ":"))
    # inside <script>, "</" would end the element: written as "<\/" in JSON strings
    data = data.replace("</", "<\\/")
    html = resources.files("mcl2pnml.view").joinpath("show_page.html").read_text("utf-8")
    return html.replace("__TITLE__", _escape(title)).replace("__DATA__", data)


def _escape(text: str) -> str:
    return (text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
            .replace('"', "&quot;"))


def save_page(path: str | Path, title: str, variants: list[dict[str, Any]],
              run: list[dict[str, Any]] | None = None) -> Path:
    """Write the page, whole or not at all."""
    atomic_write_text(path, page(title, variants, run))
    return Path(path)
