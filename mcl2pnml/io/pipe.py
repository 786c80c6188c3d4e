"""PIPE's own dialect of PNML: our nets as the PIPE editor opens them.

PIPE (the Platform Independent Petri net Editor, used in teaching) reads only
its own older PNML-like format, not ISO/IEC 15909-2 PNML: no namespace, no
``<page>``, ``<value>`` where the standard has ``<text>``, each transition's
``rate``, ``timed``, ``priority`` and ``infiniteServer`` given, and no
``<toolspecific>`` (it takes any on a transition for its own). It reads an
arc without an inscription as weight 0. So this writer says what PIPE can
show, in PIPE's terms: the places with their markings, the transitions, the
arcs with their weights always written, the positions and bend points
(``<arcpath>``, from the source's centre to the target's). A read arc is
the two arcs of a self-loop, as in our PNML (:func:`~mcl2pnml.io.pnml.writer
.pt_arcs`).

What PIPE cannot say is said in the file and returned to the caller, for the
command's message:

* a time-out's fixed delay: PIPE's timed transitions are exponential (a
  GSPN's), not a delay of so many seconds. A time-out is written as an
  immediate transition, like every other, and its delay is said on the canvas
  (an annotation, PIPE's ``<labels>``) and in a comment;
* the payloads (a call's bindings, the actions and events of the
  Architecture Abstraction Layer): a PIPE file is a P/T net to look at,
  play and analyse, not a mission to run.

mcl2pnml reads such a file back (its PNML reader reads PIPE's dialect) as the
same untimed P/T net, ids, arcs, weights and marking.
"""
from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

from lxml import etree

from mcl2pnml.core.files import atomic_write_bytes
from mcl2pnml.core.net import Net
from mcl2pnml.io import ids
from mcl2pnml.io.pnml.writer import own_positions, pt_arcs

Positions = Mapping[str, tuple[float, float]]
Bends = Mapping[tuple[str, str], Sequence[tuple[float, float]]]


def _value(parent, tag: str, value) -> etree._Element:
    element = etree.SubElement(parent, tag)
    etree.SubElement(element, "value").text = str(value)
    return element


def _position(parent, xy: tuple[float, float] | None) -> None:
    graphics = etree.SubElement(parent, "graphics")
    if xy is not None:
        etree.SubElement(graphics, "position", x=_number(xy[0]), y=_number(xy[1]))


def _number(x: float) -> str:
    return f"{float(x):.1f}"


def _seconds(x: float) -> str:
    return f"{x:g} s"


def to_pipe(net: Net, positions: Positions | None = None,
            bends: Bends | None = None) -> tuple[bytes, list[str]]:
    """The file's bytes, and what PIPE cannot say of ``net`` (in words, one line each:
    empty when nothing was left out)."""
    pos = (own_positions(net) if positions is None else positions) or {}
    plain = ids.all_plain([n.id for n in (*net.places, *net.transitions)])

    def xid(node: str) -> str:
        return node if plain else ids.encode(node)

    root = etree.Element("pnml")
    page = etree.SubElement(root, "net", id=ids.encode(net.name or "net"), type="P/T net")
    said: list[str] = []
    timed = [t for t in net.transitions if t.timing is not None]
    if timed:
        lines = [f"{t.id}: after {_seconds(t.timing.earliest)}"
                 + ("" if t.timing.latest == t.timing.earliest else
                    f" to {_seconds(t.timing.latest)}" if t.timing.latest is not None
                    else " or later")
                 for t in timed]
        text = ("Time-outs, written as immediate transitions (PIPE's timed transitions are "
                "exponential, not fixed delays): " + "; ".join(lines))
        page.append(etree.Comment(" " + text.replace("--", "- -") + " "))
        xs = [p[0] for p in pos.values()] or [0.0]
        ys = [p[1] for p in pos.values()] or [0.0]
        label = etree.SubElement(page, "labels", x=str(int(min(xs))), y=str(int(min(ys)) - 60),
                                 width="600", height=str(20 * (len(lines) + 1)),
                                 border="true")
        etree.SubElement(label, "text").text = text
        said.append(f"{len(timed)} time-out{'s' if len(timed) > 1 else ''} written as "
                    "immediate transitions, their delays in a note on the canvas (PIPE's "
                    "timed transitions are exponential)")
    if any(n.payload is not None for n in (*net.places, *net.transitions)):
        said.append("the payloads (bindings, actions, events) left out: a PIPE file is a "
                    "P/T net to look at, not a mission to run")
    tokens = dict(net.initial.items())
    for p in net.places:
        place = etree.SubElement(page, "place", id=xid(p.id))
        _position(place, pos.get(p.id))
        _value(place, "name", p.name or p.id)
        _value(place, "initialMarking", tokens.get(p.id, 0))
        _value(place, "capacity", 0)        # PIPE's "no capacity"
    for t in net.transitions:
        transition = etree.SubElement(page, "transition", id=xid(t.id))
        _position(transition, pos.get(t.id))
        _value(transition, "name", t.name or t.id)
        _value(transition, "orientation", 0)
        _value(transition, "rate", "1.0")
        _value(transition, "timed", "false")
        _value(transition, "infiniteServer", "false")
        _value(transition, "priority", 1)
    # arcs are numbered as in our PNML, from a stem no node id continues with digits
    stem = "a"
    while any(n.id.startswith(stem) and n.id[len(stem):].isdigit()
              for n in (*net.places, *net.transitions)):
        stem += "_"
    bent = {}
    for (a, b), points in (bends or {}).items():
        bent[(a, b)] = list(points)
        bent.setdefault((b, a), list(points)[::-1])
    for k, (source, target, weight, _) in enumerate(pt_arcs(net), 1):
        arc = etree.SubElement(page, "arc", id=f"{stem}{k}", source=xid(source),
                               target=xid(target))
        _value(arc, "inscription", weight)
        path = [pos[source]] if source in pos else []
        path += bent.get((source, target), [])
        path += [pos[target]] if target in pos else []
        for i, (x, y) in enumerate(path if len(path) >= 2 else []):
            etree.SubElement(arc, "arcpath", id=f"{i:03d}", x=str(round(x)), y=str(round(y)),
                             curvePoint="false")
        etree.SubElement(arc, "type", value="normal")
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8",
                          pretty_print=True), said


def write_pipe(net: Net, path: str | Path, positions: Positions | None = None,
               bends: Bends | None = None) -> list[str]:
    """Write ``net`` to ``path`` in PIPE's dialect, whole or not at all; returns what PIPE
    cannot say of it (:func:`to_pipe`)."""
    data, said = to_pipe(net, positions, bends)
    atomic_write_bytes(path, data)
    return said
