"""Writing nets as ISO/IEC 15909-2 PNML (P/T nets, 2009 grammar).

What a P/T net cannot say travels in ``<toolspecific tool="mcl2pnml">``,
where other tools skip it and our reader restores it:

* a place's interface label and payload: ``<interface label="B"/>``,
  ``<payload>{json}</payload>``;
* a transition's timing and payload: ``<timing earliest="300" latest="300"/>``;
* a read arc: written as the two arcs of a self-loop (so that every P/T tool
  fires it correctly), each marked ``<read/>``; our reader joins them again.

One flat ``<page>`` per net, because nested pages break LoLA and SNAKES and
make pm4py silently wrong. Every node gets a ``<graphics><position>`` from
:mod:`mcl2pnml.layout` unless all nodes already have one.

The document is streamed with ``lxml.etree.xmlfile``, one node at a time, so
memory stays flat on nets of 100,000 nodes, and written atomically: a file is
there whole or not at all.
"""
from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Iterator

from lxml import etree

from .. import __version__
from ..files import atomic_write_bytes
from ..net import ArcKind, Net, thaw
from ..layout import layout
from . import ids

NS = "http://www.pnml.org/version-2009/grammar/pnml"
PTNET = "http://www.pnml.org/version-2009/grammar/ptnet"
TOOL = "mcl2pnml"


def _fmt(x: float) -> str:
    """A number in the xsd:decimal lexical form (no exponent)."""
    text = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


class _Ids:
    """Hands out XML ids: encoded node ids first, then fresh ones that clash with none."""

    def __init__(self, net: Net):
        self.node = {n.id: ids.encode(n.id) for n in (*net.places, *net.transitions)}
        self.taken = set(self.node.values())

    def fresh(self, stem: str) -> str:
        candidate, i = stem, 0
        while candidate in self.taken:
            i += 1
            candidate = f"{stem}{i}"
        self.taken.add(candidate)
        return candidate


def _E(tag: str, attrib: dict | None = None, text: str | None = None, *children):
    el = etree.Element(tag, attrib or {})
    if text is not None:
        el.text = text
    for child in children:
        if child is not None:
            el.append(child)
    return el


def _name(label: str):
    return _E("name", None, None, _E("text", None, label))


def _graphics(pos: tuple[float, float]):
    return _E("graphics", None, None,
              _E("position", {"x": _fmt(pos[0]), "y": _fmt(pos[1])}))


def _toolspecific(*children):
    children = [c for c in children if c is not None]
    if not children:
        return None
    return _E("toolspecific", {"tool": TOOL, "version": __version__}, None, *children)


def _payload(payload):
    if payload is None:
        return None
    return _E("payload", None, json.dumps(thaw(payload), sort_keys=True, separators=(",", ":")))


def _elements(net: Net, xid: _Ids, layout_engine: str) -> Iterator[etree._Element]:
    positioned = all(n.position is not None for n in (*net.places, *net.transitions))
    pos = ({n.id: n.position for n in (*net.places, *net.transitions)} if positioned
           else layout(net, layout_engine))
    for p in net.places:
        el = _E("place", {"id": xid.node[p.id]}, None, _name(p.label), _graphics(pos[p.id]))
        if net.initial[p.id]:
            el.append(_E("initialMarking", None, None, _E("text", None, str(net.initial[p.id]))))
        interface = None if p.interface is None else _E("interface", {"label": p.interface})
        ts = _toolspecific(interface, _payload(p.payload))
        if ts is not None:
            el.append(ts)
        yield el
    for t in net.transitions:
        el = _E("transition", {"id": xid.node[t.id]}, None, _name(t.label), _graphics(pos[t.id]))
        timing = None
        if t.timing is not None:
            attrs = {"earliest": _fmt(t.timing.earliest)}
            if t.timing.latest is not None:
                attrs["latest"] = _fmt(t.timing.latest)
            timing = _E("timing", attrs)
        ts = _toolspecific(timing, _payload(t.payload))
        if ts is not None:
            el.append(ts)
        yield el
    for a in net.arcs:
        src, dst = xid.node[a.source], xid.node[a.target]
        pairs = [(src, dst)] if a.kind is ArcKind.NORMAL else [(src, dst), (dst, src)]
        for s, d in pairs:
            el = _E("arc", {"id": xid.fresh(f"{s}-{d}" if a.kind is ArcKind.NORMAL
                                            else f"{s}-{d}-read"),
                            "source": s, "target": d})
            if a.weight != 1:
                el.append(_E("inscription", None, None, _E("text", None, str(a.weight))))
            if a.kind is ArcKind.READ:
                el.append(_toolspecific(_E("read")))
            yield el


def write_pnml(net: Net, out: io.BufferedIOBase, layout_engine: str = "auto") -> None:
    """Stream ``net`` as a PNML document into a binary file object."""
    xid = _Ids(net)
    net_id = xid.fresh(ids.encode(net.name) if net.name else "net")
    page_id = xid.fresh("page")
    with etree.xmlfile(out, encoding="UTF-8") as xf:
        xf.write_declaration()
        with xf.element("pnml", nsmap={None: NS}):
            with xf.element("net", {"id": net_id, "type": PTNET}):
                xf.write(_name(net.name or "net"), pretty_print=True)
                with xf.element("page", {"id": page_id}):
                    for el in _elements(net, xid, layout_engine):
                        xf.write(el, pretty_print=True)
                xf.write(_toolspecific(_E("ids", {"encoding": "xml-name-escapes"})),
                         pretty_print=True)


def to_pnml_bytes(net: Net, layout_engine: str = "auto") -> bytes:
    buf = io.BytesIO()
    write_pnml(net, buf, layout_engine)
    return buf.getvalue()


def save_pnml(net: Net, path: str | Path, layout_engine: str = "auto") -> Path:
    """Write ``net`` to ``path`` atomically; returns the path."""
    return atomic_write_bytes(path, to_pnml_bytes(net, layout_engine))
