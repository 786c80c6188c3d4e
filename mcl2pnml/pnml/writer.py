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
:mod:`mcl2pnml.layout` unless all nodes already have one (or the layout
engine is ``none``, the default above 100,000 nodes).

The document is generated as text, one line per place, transition and arc
(``grep`` finds a node with its whole definition), and streamed in chunks,
so memory stays flat on nets of a million arcs. Text is generated rather
than built as lxml elements because every element here has one fixed shape:
building and serialising five small elements per node cost ten times more
(a 10,000-call mission took 20 s to write). The escaping is the standard
library's; the tests hold every written file to the official RELAX NG
grammar and read it back with lxml, SNAKES and pm4py. Files are written
atomically: a file is there whole or not at all.
"""
from __future__ import annotations

import io
import json
import re
from functools import lru_cache
from pathlib import Path
from typing import BinaryIO, Iterator
from xml.sax.saxutils import escape

from .. import __version__
from ..files import atomic_writer
from ..gcpause import without_gc
from ..net import ArcKind, FrozenDict, Net, Place, Transition
from ..layout import layout
from . import ids

NS = "http://www.pnml.org/version-2009/grammar/pnml"
PTNET = "http://www.pnml.org/version-2009/grammar/ptnet"
TOOL = "mcl2pnml"
#: Elements per chunk handed to the output file.
CHUNK = 4096

_TEXT = {"\r": "&#13;"}  # a bare CR in text would read back as LF
_ATTR = {'"': "&quot;", "\n": "&#10;", "\r": "&#13;", "\t": "&#9;"}
_SPECIAL = re.compile(r"[&<>\r]")


def _text(value: str) -> str:
    # most labels are plain ids: one regex scan instead of four replacements
    return escape(value, _TEXT) if _SPECIAL.search(value) else value


def _attr(value: str) -> str:
    return escape(value, _ATTR)


@lru_cache(maxsize=1 << 16)   # positions repeat: layouts put nodes on a grid
def _graphics(x: float, y: float) -> str:
    return f'<graphics><position x="{_fmt(x)}" y="{_fmt(y)}"/></graphics>'


def _fmt(x: float) -> str:
    """A number in the xsd:decimal lexical form (no exponent)."""
    if x.is_integer() and abs(x) < 1e15:   # the common case: layout is on a grid
        return str(int(x))
    text = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


class _Ids:
    """Hands out XML ids: encoded node ids first, then fresh ones that clash with none."""

    def __init__(self, net: Net):
        self.node = {n.id: ids.encode(n.id) for n in (*net.places, *net.transitions)}
        self.taken = set(self.node.values())

    def numbering(self, stem: str) -> str:
        """A stem such that ``stem`` + digits is no id handed out so far."""
        while any(i.startswith(stem) and i[len(stem):].isdigit() for i in self.taken):
            stem += "_"
        return stem

    def fresh(self, stem: str) -> str:
        candidate, i = stem, 0
        while candidate in self.taken:
            i += 1
            candidate = f"{stem}{i}"
        self.taken.add(candidate)
        return candidate


_TOOL_OPEN = f'<toolspecific tool="{TOOL}" version="{_attr(__version__)}">'
_READ = f"{_TOOL_OPEN}<read/></toolspecific>"


def _plain(value):
    """What ``json`` cannot serialise itself: the frozen mappings of payloads."""
    if isinstance(value, FrozenDict):
        return dict(value)
    raise TypeError(f"payload holds a {type(value).__name__}")


class _Payloads:
    """``<payload>`` elements, each serialised once: nodes of one template share them."""

    def __init__(self) -> None:
        self._done: dict[int, tuple[object, str]] = {}

    def __call__(self, payload) -> str:
        if payload is None:
            return ""
        hit = self._done.get(id(payload))
        if hit is not None and hit[0] is payload:
            return hit[1]
        data = json.dumps(payload, default=_plain, sort_keys=True, separators=(",", ":"))
        text = f"<payload>{_text(data)}</payload>"
        self._done[id(payload)] = (payload, text)  # the payload is kept alive: ids stay unique
        return text


def _lines(net: Net, xid: _Ids, layout_engine: str) -> Iterator[str]:
    """The lines of the page: one per place, transition and arc."""
    positioned = all(n.position is not None for n in (*net.places, *net.transitions))
    pos = ({n.id: n.position for n in (*net.places, *net.transitions)} if positioned
           else layout(net, layout_engine))
    payload = _Payloads()

    def line(tag: str, n: Place | Transition, standard: str, tool: str) -> str:
        """One node: its name and position, then PNML's own labels, then ours."""
        tool += payload(n.payload)
        tool = f"{_TOOL_OPEN}{tool}</toolspecific>" if tool else ""
        at = pos.get(n.id)
        graphics = "" if at is None else _graphics(*at)
        label = _text(n.id if n.name is None else n.name)
        return (f'<{tag} id="{xid.node[n.id]}"><name><text>{label}</text></name>'
                f"{graphics}{standard}{tool}</{tag}>\n")

    initial = net.initial
    for p in net.places:
        tokens = initial[p.id]
        yield line("place", p,
                   f"<initialMarking><text>{tokens}</text></initialMarking>" if tokens else "",
                   "" if p.interface is None else f'<interface label="{_attr(p.interface)}"/>')
    for t in net.transitions:
        timing = ""
        if t.timing is not None:
            latest = "" if t.timing.latest is None else f' latest="{_fmt(t.timing.latest)}"'
            timing = f'<timing earliest="{_fmt(t.timing.earliest)}"{latest}/>'
        yield line("transition", t, "", timing)
    # Arcs are numbered (a1, a2 ...): the line shows their ends anyway, and a
    # counter is cheaper than building and checking a name per arc. Nearly
    # every arc is a plain arc of weight 1: a run of those is formatted in one
    # comprehension, a chunk at a time, instead of one generator step per arc.
    node, stem = xid.node, xid.numbering("a")
    sources, targets, weights, kinds = net.columns
    number = 0
    for start in range(0, len(sources), CHUNK):
        stop = min(start + CHUNK, len(sources))
        if (weights[start:stop].count(1) == stop - start
                and kinds[start:stop].count(ArcKind.NORMAL) == stop - start):
            yield "".join([f'<arc id="{stem}{k}" source="{node[a]}" target="{node[b]}"/>\n'
                           for k, a, b in zip(range(number + 1, number + 1 + stop - start),
                                              sources[start:stop], targets[start:stop])])
            number += stop - start
            continue
        for source, target, weight, kind in zip(sources[start:stop], targets[start:stop],
                                                weights[start:stop], kinds[start:stop]):
            src, dst = node[source], node[target]
            number += 1
            inscription = (f"<inscription><text>{weight}</text></inscription>"
                           if weight != 1 else "")
            if kind is ArcKind.NORMAL:
                yield (f'<arc id="{stem}{number}" source="{src}" target="{dst}">'
                       f"{inscription}</arc>\n" if inscription else
                       f'<arc id="{stem}{number}" source="{src}" target="{dst}"/>\n')
            else:
                # a read arc is a self-loop to P/T tools, each half marked as read
                yield (f'<arc id="{stem}{number}" source="{src}" target="{dst}">'
                       f"{inscription}{_READ}</arc>\n")
                number += 1
                yield (f'<arc id="{stem}{number}" source="{dst}" target="{src}">'
                       f"{inscription}{_READ}</arc>\n")


@without_gc
def write_pnml(net: Net, out: BinaryIO, layout_engine: str = "auto") -> None:
    """Stream ``net`` as a PNML document into a binary file object."""
    xid = _Ids(net)
    net_id = xid.fresh(ids.encode(net.name) if net.name else "net")
    page_id = xid.fresh("page")
    out.write(("<?xml version='1.0' encoding='UTF-8'?>\n"
               f'<pnml xmlns="{NS}">\n'
               f'<net id="{net_id}" type="{PTNET}">\n'
               f"<name><text>{_text(net.name or 'net')}</text></name>\n"
               f'<page id="{page_id}">\n').encode())
    chunk: list[str] = []
    for line in _lines(net, xid, layout_engine):
        chunk.append(line)
        if len(chunk) >= CHUNK:
            out.write("".join(chunk).encode())
            chunk.clear()
    out.write("".join(chunk).encode())
    out.write(("</page>\n"
               f'{_TOOL_OPEN}<ids encoding="xml-name-escapes"/></toolspecific>\n'
               "</net>\n</pnml>\n").encode())


def to_pnml_bytes(net: Net, layout_engine: str = "auto") -> bytes:
    buf = io.BytesIO()
    write_pnml(net, buf, layout_engine)
    return buf.getvalue()


def save_pnml(net: Net, path: str | Path, layout_engine: str = "auto") -> Path:
    """Write ``net`` to ``path`` atomically; returns the path."""
    with atomic_writer(path) as out:
        write_pnml(net, out, layout_engine)
    return Path(path)
