"""Writing nets as ISO/IEC 15909-2 PNML (P/T nets, 2009 grammar).

What a P/T net cannot say travels in ``<toolspecific tool="mcl2pnml">``,
where other tools skip it and our reader restores it:

* a place's interface label and payload: ``<interface label="B"/>``,
  ``<payload>{json}</payload>``;
* a transition's timing and payload: ``<timing earliest="300" latest="300"/>``;
* a read arc: written as the two arcs of a self-loop (so that every P/T tool
  fires it correctly), each marked ``<read/>``; our reader joins them again.
  When its transition also puts tokens into the place, the return arc
  carries them too, and our reader takes what exceeds the read arc's weight
  as that arc: two arcs from one node to another are read differently by
  each tool (verifypn adds them up, pm4py keeps one, SNAKES refuses them,
  LoLA crashes), so a file never has any.

Every arc carries its inscription, weight 1 included: the standard lets a
file leave 1 out, but WoPeD logs a warning per arc without one and PIPE
reads it as weight 0 (docs/interop.md).

One flat ``<page>`` per net, because nested pages break LoLA and SNAKES and
make pm4py silently wrong. Every node gets a ``<graphics><position>`` when
the caller hands positions (a layout: :mod:`mcl2pnml.view.layout`), or when
every node of the net already has one; writing never lays out.

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
from itertools import compress, repeat
from operator import attrgetter, is_
from pathlib import Path
from typing import Any, BinaryIO, Callable, Iterator, Mapping, Sequence

from mcl2pnml.core.version import __version__
from mcl2pnml.core.files import atomic_writer
from mcl2pnml.core.gcpause import without_gc
from mcl2pnml.core.net import ArcKind, FrozenDict, Net, Place, Timing, Transition
from mcl2pnml.io import ids
NS = "http://www.pnml.org/version-2009/grammar/pnml"
PTNET = "http://www.pnml.org/version-2009/grammar/ptnet"
TOOL = "mcl2pnml"
#: Elements per chunk handed to the output file.
CHUNK = 4096

# XML escapes as translation tables: xml.sax.saxutils.escape would do, but importing it
# imports urllib, http and email, a fifth of the start-up of a command that writes PNML
_XML = {"&": "&amp;", "<": "&lt;", ">": "&gt;"}
_TEXT = str.maketrans({**_XML, "\r": "&#13;"})  # a bare CR in text would read back as LF
_ATTR = str.maketrans({**_XML, '"': "&quot;", "\n": "&#10;", "\r": "&#13;", "\t": "&#9;"})
_SPECIAL = re.compile(r"[&<>\r]")
#: The inscription of an arc of weight 1. PNML lets a file leave it out, but WoPeD logs
#: a warning for every arc without one, and PIPE reads such an arc as weight 0.
_ONE = "<inscription><text>1</text></inscription>"


def _text(value: str) -> str:
    # most labels are plain ids: one regex scan instead of a translation
    return value.translate(_TEXT) if _SPECIAL.search(value) else value


def _attr(value: str) -> str:
    return value.translate(_ATTR)


@lru_cache(maxsize=1 << 16)   # positions repeat: layouts put nodes on a grid
def _graphics(x: float, y: float) -> str:
    return f'<graphics><position x="{_fmt(x)}" y="{_fmt(y)}"/></graphics>'


def _bend_graphics(points) -> str:
    """An arc's bend points, PNML's arc ``<graphics>``: one ``<position>`` each."""
    inner = "".join(f'<position x="{_fmt(x)}" y="{_fmt(y)}"/>' for x, y in points)
    return f"<graphics>{inner}</graphics>"


def _fmt(x: float) -> str:
    """A number in the xsd:decimal lexical form (no exponent)."""
    if x.is_integer() and abs(x) < 1e15:   # the common case: layout is on a grid
        return str(int(x))
    text = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


class _Ids:
    """Hands out XML ids: encoded node ids first, then fresh ones that clash with none.

    ``node`` maps node ids to XML ids, or is ``None`` when every node id is
    its own encoding (the compiler's always are): then ids are written as
    they are, with no lookup per arc end.
    """

    def __init__(self, net: Net):
        node_ids = [n.id for n in net.places]
        node_ids += [n.id for n in net.transitions]
        if ids.all_plain(node_ids):
            self.node: dict[str, str] | None = None
        else:
            self.node = {i: ids.encode(i) for i in node_ids}
            node_ids = list(self.node.values())
        # XML ids are names, so none holds a line break: joined one to a
        # line, they answer "is this id taken" and "which ids start so" by a
        # string search, without a set of 400,000 ids built for two questions
        self._taken = "\n" + "\n".join(node_ids) + "\n"

    def numbering(self, stem: str) -> str:
        """A stem such that ``stem`` + digits is no id handed out so far."""
        while any(rest.isdigit() for rest in re.findall(f"\n{re.escape(stem)}(.*)", self._taken)):
            stem += "_"
        return stem

    def fresh(self, stem: str) -> str:
        candidate, i = stem, 0
        while f"\n{candidate}\n" in self._taken:
            i += 1
            candidate = f"{stem}{i}"
        self._taken += candidate + "\n"
        return candidate


_TOOL_OPEN = f'<toolspecific tool="{TOOL}" version="{_attr(__version__)}">'
_READ = f"{_TOOL_OPEN}<read/></toolspecific>"


def _plain(value):
    """What ``json`` cannot serialise itself: the frozen mappings of payloads."""
    if isinstance(value, FrozenDict):
        # its own dict, not a copy: json only reads it, and copying a
        # mapping through its Python methods cost more than the encoding
        return value._data
    raise TypeError(f"payload holds a {type(value).__name__}")


def _payload(payload) -> str:
    if payload is None:
        return ""
    data = json.dumps(payload, default=_plain, sort_keys=True, separators=(",", ":"))
    return f"<payload>{_text(data)}</payload>"


def _tool(labels: str) -> str:
    return f"{_TOOL_OPEN}{labels}</toolspecific>" if labels else ""


def _place_tail(tokens: int, interface: str | None, payload) -> str:
    """What follows a place's name and position: its marking, our labels, the end tag."""
    marking = f"<initialMarking><text>{tokens}</text></initialMarking>" if tokens else ""
    labels = "" if interface is None else f'<interface label="{_attr(interface)}"/>'
    return f"{marking}{_tool(labels + _payload(payload))}</place>\n"


def _transition_tail(timing: Timing | None, payload) -> str:
    """What follows a transition's name and position: our labels, the end tag."""
    labels = ""
    if timing is not None:
        latest = "" if timing.latest is None else f' latest="{_fmt(timing.latest)}"'
        labels = f'<timing earliest="{_fmt(timing.earliest)}"{latest}/>'
    return f"{_tool(labels + _payload(payload))}</transition>\n"


def _node_lines(tag: str, nodes: tuple[Place, ...] | tuple[Transition, ...], keys: list,
                tail: Callable[[Any], str], node: dict[str, str] | None,
                pos: dict[str, tuple[float, float]]) -> Iterator[str]:
    """The lines of ``nodes`` in chunks; ``keys[i]`` says what ends node i's line.

    Nodes made from one template differ in their ids only, so the end of a
    line (marking, labels, payload) is formatted once per distinct key, from
    the first node that has it. The lines are then put together column by
    column, each column built by ``map`` or a comprehension: a compiled
    mission has 400,000 nodes, and a Python step per node per attribute is
    what writing them used to cost.
    """
    first = dict(zip(reversed(keys), reversed(nodes)))   # reversed: the first one wins
    ends = {k: tail(n) for k, n in first.items()}
    ends_ = list(map(ends.__getitem__, keys))
    ids_ = list(map(_ID, nodes))
    names = list(map(_NAME, nodes))
    if node is None:   # plain ids: no escaping, as ids or as labels
        xml = ids_
        labels = (ids_ if names.count(None) == len(names) else
                  [i if name is None else _text(name) for i, name in zip(ids_, names)])
    else:
        xml = list(map(node.__getitem__, ids_))
        labels = [_text(i if name is None else name) for i, name in zip(ids_, names)]
    if pos:
        ends_ = [ends_[k] if i not in pos else _graphics(*pos[i]) + ends_[k]
                 for k, i in enumerate(ids_)]
    for start in range(0, len(nodes), CHUNK):
        stop = start + CHUNK
        yield "".join([f'<{tag} id="{x}"><name><text>{label}</text></name>{end}'
                       for x, label, end in zip(xml[start:stop], labels[start:stop],
                                                ends_[start:stop])])


_ID, _NAME, _PAYLOAD = attrgetter("id"), attrgetter("name"), attrgetter("payload")


Positions = Mapping[str, "tuple[float, float]"]
#: (source, target) of an arc -> its bend points, from the source
Bends = Mapping["tuple[str, str]", "Sequence[tuple[float, float]]"]


def own_positions(net: Net) -> dict[str, tuple[float, float]] | None:
    """The nodes' own positions, when every node has one (a net read from a drawn file)."""
    nodes = (*net.places, *net.transitions)
    if all(n.position is not None for n in nodes):
        return {n.id: n.position for n in nodes}
    return None


def _chunks(net: Net, xid: _Ids, positions: Positions | None,
            bends: Bends | None = None) -> Iterator[str]:
    """The page, one line per place, transition and arc, in chunks of :data:`CHUNK` lines."""
    pos = own_positions(net) if positions is None else positions
    pos = pos or {}
    node = xid.node
    tokens = dict(net.initial.items())
    # Payloads are keyed by identity: call sites share their prototype's
    # payload objects, and the net keeps every payload alive (so every id
    # distinct) while it is written.
    places, transitions = net.places, net.transitions
    yield from _node_lines(
        "place", places,
        list(zip(map(tokens.get, map(_ID, places)), map(attrgetter("interface"), places),
                 map(id, map(_PAYLOAD, places)))),
        lambda p: _place_tail(tokens.get(p.id, 0), p.interface, p.payload), node, pos)
    yield from _node_lines(
        "transition", transitions,
        list(zip(map(attrgetter("timing"), transitions), map(id, map(_PAYLOAD, transitions)))),
        lambda t: _transition_tail(t.timing, t.payload), node, pos)
    # Arcs are numbered (a1, a2 ...): the line shows their ends anyway, and a
    # counter is cheaper than building and checking a name per arc. Nearly
    # every arc is a plain arc of weight 1: a run of those is formatted in one
    # comprehension, a chunk at a time, instead of one step per arc.
    stem = xid.numbering("a")
    sources, targets, weights, kinds = net.columns
    extras: Any = repeat(0)
    own = _into_read_places(sources, targets, weights, kinds)
    if own:
        # the transition's own arc into a place it reads goes with the read arc's return
        rows = [(s, d, w, k, own.get((s, d), 0))
                for s, d, w, k in zip(sources, targets, weights, kinds) if (d, s) not in own]
        sources, targets, weights, kinds, extras = map(list, zip(*rows))
    # bend points by the written arc's ends, before ids are escaped; a read arc's return
    # runs back along its line
    bent = {}
    for (a, b), pts in (bends or {}).items():
        if pts:
            bent[(a, b)] = _bend_graphics(pts)
            bent.setdefault((b, a), _bend_graphics(pts[::-1]))
    lines = list(zip(sources, targets)) if bent else None
    if node is not None:
        sources, targets = [node[s] for s in sources], [node[t] for t in targets]
    number = 0
    for start in range(0, len(sources), CHUNK):
        stop = min(start + CHUNK, len(sources))
        if (not bent and weights[start:stop].count(1) == stop - start
                and kinds[start:stop].count(ArcKind.NORMAL) == stop - start):
            yield "".join([f'<arc id="{stem}{k}" source="{a}" target="{b}">{_ONE}</arc>\n'
                           for k, a, b in zip(range(number + 1, number + 1 + stop - start),
                                              sources[start:stop], targets[start:stop])])
            number += stop - start
            continue
        chunk = []
        for k, (src, dst, weight, kind, extra) in enumerate(
                zip(sources[start:stop], targets[start:stop], weights[start:stop],
                    kinds[start:stop], extras[start:stop] if own else extras), start):
            number += 1
            inscription = f"<inscription><text>{weight}</text></inscription>"
            there = back = ""
            if bent:
                there = bent.get(lines[k], "")
                back = bent.get(lines[k][::-1], "")
            if kind is ArcKind.NORMAL:
                chunk.append(f'<arc id="{stem}{number}" source="{src}" target="{dst}">'
                             f"{inscription}{there}</arc>\n")
            else:
                # a read arc is a self-loop to P/T tools, each half marked as read
                chunk.append(f'<arc id="{stem}{number}" source="{src}" target="{dst}">'
                             f"{inscription}{there}{_READ}</arc>\n")
                number += 1
                if extra:
                    inscription = f"<inscription><text>{weight + extra}</text></inscription>"
                chunk.append(f'<arc id="{stem}{number}" source="{dst}" target="{src}">'
                             f"{inscription}{back}{_READ}</arc>\n")
        yield "".join(chunk)


def pt_arcs(net: Net) -> list[tuple[str, str, int, bool]]:
    """The arcs as a P/T tool sees them, as this writer writes them: (source, target,
    weight, read?), a read arc as the two arcs of a self-loop whose return carries also
    the tokens the transition's own arc puts back into the place (for writers of other
    dialects: :mod:`mcl2pnml.io.pipe`)."""
    sources, targets, weights, kinds = net.columns
    own = _into_read_places(sources, targets, weights, kinds)
    out = []
    for s, d, w, k in zip(sources, targets, weights, kinds):
        if (d, s) in own:
            continue    # goes with the read arc's return
        if k is ArcKind.NORMAL:
            out.append((s, d, w, False))
        else:
            out += [(s, d, w, True), (d, s, w + own.get((s, d), 0), True)]
    return out


def _into_read_places(sources, targets, weights, kinds) -> dict[tuple[str, str], int]:
    """(place, transition) -> the weight of the transition's arc into a place it reads.

    Read arcs go from a place to a transition, so every arc the other way is
    an ordinary one; a compiled mission has none of these.
    """
    # scans in C (map, compress): a mission of a million arcs pays a few milliseconds
    reads = set(compress(zip(targets, sources), map(is_, kinds, repeat(ArcKind.READ))))
    if not reads:
        return {}
    readers = {t for t, _ in reads}
    return {(d, s): w for s, d, w in compress(zip(sources, targets, weights),
                                                map(readers.__contains__, sources))
            if (s, d) in reads}


@without_gc
def stream_pnml(net: Net, out: BinaryIO, positions: Positions | None = None,
                bends: Bends | None = None) -> None:
    """Stream ``net`` as a PNML document into a binary file object.

    ``positions`` (node id -> x, y) go into ``<graphics>``; None: the nodes'
    own positions if every node has one, else no positions at all.
    ``bends`` ((source, target) of an arc -> points) go into the arc's
    ``<graphics>`` as ``<position>`` elements, the standard's bend points, in
    order from the source; a read arc's return runs back through them.
    """
    if positions is not None and not isinstance(positions, Mapping):
        # a layout engine's name belongs to the caller, which lays out: writing never does
        raise TypeError(f"positions are a mapping of node ids to (x, y), not {positions!r}")
    xid = _Ids(net)
    net_id = xid.fresh(ids.encode(net.name) if net.name else "net")
    page_id = xid.fresh("page")
    out.write(("<?xml version='1.0' encoding='UTF-8'?>\n"
               f'<pnml xmlns="{NS}">\n'
               f'<net id="{net_id}" type="{PTNET}">\n'
               f"<name><text>{_text(net.name or 'net')}</text></name>\n"
               f'<page id="{page_id}">\n').encode())
    for chunk in _chunks(net, xid, positions, bends):
        out.write(chunk.encode())
    out.write(("</page>\n"
               f'{_TOOL_OPEN}<ids encoding="xml-name-escapes"/></toolspecific>\n'
               "</net>\n</pnml>\n").encode())


def to_pnml(net: Net, positions: Positions | None = None,
            bends: Bends | None = None) -> bytes:
    buf = io.BytesIO()
    stream_pnml(net, buf, positions, bends)
    return buf.getvalue()


def write_pnml(net: Net, path: str | Path, positions: Positions | None = None,
               bends: Bends | None = None) -> Path:
    """Write ``net`` to ``path`` atomically; returns the path."""
    with atomic_writer(path) as out:
        stream_pnml(net, out, positions, bends)
    return Path(path)
