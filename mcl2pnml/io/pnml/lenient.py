"""Reading PNML P/T nets the forgiving way (``--lenient``): tolerant of what real tools
write, strict on what is wrong; no proof rests on it (docs/pnml.md).

Tolerated: the PNML namespace or none (pm4py writes none); the P/T and the
core-model net types; places and transitions straight under ``<net>``
(ProM without ``<page>``); several and nested pages (flattened); reference
places and transitions (resolved to the node they stand for); the older
``<value>`` form of labels (PIPE); parallel arcs (their weights add up);
unknown elements and other tools' ``<toolspecific>`` (skipped).

Arc types, written three ways by real tools (TAPAAL's ``type`` attribute,
ProM's and pm4py's ``<arctype>``, PIPE's ``<type value>``): ``normal`` is
an ordinary arc, ``read`` and ``test`` are read arcs; inhibitor and reset
arcs are refused, since a P/T reading of them would be silently wrong and
the invariants and siphons of a P/T net do not hold for them. Coloured
content (declarations, sorts, high-level markings and inscriptions, a
marking written as a multiset) is refused whatever type the net claims.
TAPAAL's own format (old HU-Berlin namespace, markings and weights as
attributes) is read with its markings and weights when it is untimed, and
refused where its time or colour would matter.

Refused, each with a message naming file, line and column: XML that is not
well-formed; a document type declaration (PNML needs none, and entities are
how XML bombs and external fetches get in: nothing is ever resolved or
fetched); duplicate ids; an arc whose end is missing or that joins two places
or two transitions; a marking that is not a natural number; a weight that is
not a positive integer; a reference that dangles or loops. All errors of a
file are reported together.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from mcl2pnml.core.errors import Location, Mcl2PnmlError, NetError, PnmlError, raise_all
from mcl2pnml.core.gcpause import without_gc
from mcl2pnml.core.bounds import MAX_SECONDS, MAX_TOKENS, MAX_TOKENS_TEXT, natural_at_most
from mcl2pnml.core.net import Arc, ArcKind, Marking, Net, Place, Timing, Transition
from mcl2pnml.io import ids
from mcl2pnml.io.pnml.tapaal import is_tapaal, parse_tapaal
from mcl2pnml.io.pnml.source import (HIGH_LEVEL, Source, coordinates, local as _local,
                                     parse_xml, payload_value, read_file)
from mcl2pnml.io.pnml.writer import TOOL

P_T_TYPES = {
    "http://www.pnml.org/version-2009/grammar/ptnet",
    "http://www.pnml.org/version-2009/grammar/pnmlcoremodel",
    "http://www.informatik.hu-berlin.de/top/pntd/ptNetb",  # pre-standard PNML
    "P/T net",  # PIPE
}


#: Arc types that are ordinary arcs, as tools spell them.
NORMAL_ARCS = frozenset({"normal", "regular", "ordinary", "default", "standard"})
#: Arc types that test a place without taking from it: our read arcs.
READ_ARCS = frozenset({"read", "test"})
#: Arc types a P/T net cannot say, with what they are.
REFUSED_ARCS = {
    "inhibitor": "an inhibitor arc (it enables its transition only while the place is empty)",
    "tapninhibitor": "an inhibitor arc (it enables its transition only while the place is "
                     "empty)",
    "reset": "a reset arc (firing empties the place)",
    "transfer": "a transfer arc (firing moves every token of the place)",
    "transport": "a transport arc of a timed-arc net",
}
#: How an arc of the file reads: an ordinary arc, a read arc of another tool, or
#: half of the self-loop pair our writer makes of a read arc.
NORMAL, READ, PAIR = "normal", "read", "pair"


def _children(el, name: str):
    return [c for c in el if _local(c) == name]


def _child(el, name: str):
    for c in el:
        if _local(c) == name:
            return c
    return None


@dataclass
class _Raw:
    """What one pass over the document found, before the net is built."""

    places: dict = field(default_factory=dict)        # id -> Place
    transitions: dict = field(default_factory=dict)   # id -> Transition
    marking: dict = field(default_factory=dict)
    refs: dict = field(default_factory=dict)          # reference id -> (target id, element)
    arcs: list = field(default_factory=list)          # (element, source, target, weight, read)
    seen: dict = field(default_factory=dict)          # xml id -> line it is first used on
    substituted: set = field(default_factory=set)     # transitions refined by a subprocess
    firing_rules: dict = field(default_factory=dict)  # (priority, timed) -> first transition
    errors: list = field(default_factory=list)


class _Reader:
    def __init__(self, src: Source, decode: bool):
        self.src = src
        self.raw = _Raw()
        self.decode = ids.decode if decode else (lambda s: s)

    def error(self, el, message: str) -> None:
        loc = self.src.locate(el) if el is not None else Location(self.src.filename)
        self.raw.errors.append(PnmlError(message, loc))

    # -- labels ----------------------------------------------------------------

    def _label_text(self, el, name: str) -> str | None:
        label = _child(el, name)
        if label is None:
            return None
        text = _child(label, "text")
        if text is not None:
            return (text.text or "").strip()
        value = _child(label, "value")  # PIPE and other pre-2009 writers
        if value is not None:
            v = (value.text or "").strip()
            if not v.startswith("Default,"):
                return v
            # PIPE's "Default,1": tokens of the default class; another class
            # ("Default,1,red,2") is a coloured marking
            classes = v.split(",")
            if len(classes) > 2 and any(n.strip() not in ("", "0") for n in classes[3::2]):
                self.error(value, f"'{v}': tokens of several classes (PIPE's colours): this "
                                  "is a coloured net; a P/T reading would drop its colours")
            return classes[1].strip()
        return None

    def _natural(self, el, label: str, minimum: int, what: str) -> int | None:
        text = self._label_text(el, label)
        if text is None:
            return None
        digits = text.strip()
        n = None
        if _plain_digits(digits):
            n = natural_at_most(digits, MAX_TOKENS)
            if n is None:
                shown = digits if len(digits) <= 30 else f"(a number of {len(digits):,} digits)"
                self.error(_child(el, label), f"{what}: {label} {shown} is too large: "
                                              f"markings and weights go up to {MAX_TOKENS_TEXT}")
                return None
        elif digits[:1] in "+-" and _plain_digits(digits[1:]) and len(digits) <= 30:
            n = int(digits)   # a sign, as int() took it: -1 is refused below, +2 is 2
        if n is None or n < minimum:
            kind = "a natural number" if minimum == 0 else "a positive integer"
            self.error(_child(el, label), f"{what}: {label} must be {kind}, not "
                                          f"'{text[:40]}{'...' if len(text) > 40 else ''}'")
            return None
        return n

    def _position(self, el) -> tuple[float, float] | None:
        g = _child(el, "graphics")
        pos = _child(g, "position") if g is not None else None
        if pos is None:
            return None
        xy = coordinates(pos)
        return xy if xy and math.isfinite(xy[0]) and math.isfinite(xy[1]) else None

    def _ours(self, el):
        return [ts for ts in _children(el, "toolspecific") if ts.get("tool") == TOOL]

    def _payload(self, el):
        for ts in self._ours(el):
            p = _child(ts, "payload")
            if p is not None:
                value, fault = payload_value(p.text)
                if fault:
                    self.error(p, fault)
                return value
        return None

    # -- nodes -----------------------------------------------------------------

    def _id(self, el) -> str | None:
        xml_id = el.get("id")
        if xml_id is None:
            self.error(el, f"<{_local(el)}> has no id")
            return None
        if xml_id in self.raw.seen:
            first = self.raw.seen[xml_id]
            self.error(el, f"duplicate id '{xml_id}' (first used on line {first})")
            return None
        # the line, not the element: a proxy kept per node would keep a
        # million of them alive in a large file
        self.raw.seen[xml_id] = el.sourceline
        return xml_id

    def _node_id(self, el) -> str | None:
        """A place's or transition's id, checked here so that the error has its line
        (the core would refuse it too, but knows no line)."""
        xml_id = self._id(el)
        if xml_id is not None and (not xml_id or xml_id != xml_id.strip()):
            self.error(el, f"{_local(el)} id {xml_id!r} must be a non-empty string without "
                           "leading or trailing white space")
            return None
        return xml_id

    def place(self, el) -> None:
        xml_id = self._node_id(el)
        if xml_id is None:
            return
        node_id = self.decode(xml_id)
        interface = None
        for ts in self._ours(el):
            i = _child(ts, "interface")
            if i is not None:
                interface = i.get("label")
        self.raw.places[xml_id] = Place(node_id, self._label_text(el, "name"), interface,
                                        self._payload(el), self._position(el))
        tokens = self._natural(el, "initialMarking", 0, f"place '{xml_id}'")
        if tokens:
            self.raw.marking[node_id] = tokens
        capacity = self._label_text(el, "capacity")   # PIPE's; 0 means none
        if capacity not in (None, "", "0"):
            self.error(_child(el, "capacity"),
                       f"place '{xml_id}' has the capacity {capacity}: a transition that would "
                       "put more tokens in it cannot fire, which a P/T net cannot say")

    def transition(self, el) -> None:
        xml_id = self._node_id(el)
        if xml_id is None:
            return
        # PIPE's priorities, and its immediate transitions that fire before timed ones
        # (GSPN): which transition may fire depends on them once they differ
        firing = (self._label_text(el, "priority") or "1", self._label_text(el, "timed") or "false")
        self.raw.firing_rules.setdefault(firing, el)
        guard = (el.get("guard") or "true").strip().lower()
        if guard != "true":   # a data Petri net (ProM, pm4py): variables decide what fires
            self.error(el, f"transition '{xml_id}' has the guard '{el.get('guard')}' (a data "
                           "Petri net): a P/T reading would let it fire whatever the data; "
                           "mcl2pnml reads P/T nets")
        timing = None
        for ts in self._ours(el):
            t = _child(ts, "timing")
            if t is not None:
                try:
                    latest = t.get("latest")
                    timing = Timing(float(t.get("earliest", "0")),
                                    None if latest is None else float(latest))
                except (ValueError, Mcl2PnmlError) as e:
                    self.error(t, f"transition '{xml_id}': bad timing: {e}")
                    continue
                longest = max(timing.earliest, timing.latest or 0.0)
                if longest > MAX_SECONDS:
                    self.error(t, f"transition '{xml_id}': bad timing: time bounds go up to "
                                  f"{MAX_SECONDS:,} s, not {longest:g}")
                    timing = None
        self.raw.transitions[xml_id] = Transition(
            self.decode(xml_id), self._label_text(el, "name"), timing,
            self._payload(el), self._position(el))

    def reference(self, el) -> None:
        xml_id = self._id(el)
        if xml_id is None:
            return
        ref = el.get("ref")
        if ref is None:
            self.error(el, f"reference node '{xml_id}' has no ref attribute")
            return
        self.raw.refs[xml_id] = (ref, el)

    def _arc_type(self, el) -> tuple[str | None, object]:
        """The arc's type as its writer spelled it, and the element that says it."""
        if el.get("type") is not None:                      # TAPAAL
            return el.get("type").strip().lower(), el
        arctype = _child(el, "arctype")                     # ProM, pm4py
        if arctype is not None:
            text = _child(arctype, "text")
            return ((text.text if text is not None else arctype.text) or "").strip().lower(), \
                arctype
        kind = _child(el, "type")                           # PIPE
        if kind is not None:
            return (kind.get("value") or kind.text or "").strip().lower(), kind
        return None, el

    def arc(self, el, scoped: bool = False) -> None:
        xml_id = el.get("id") if scoped else self._id(el)
        src, dst = el.get("source"), el.get("target")
        if src is None or dst is None:
            self.error(el, f"arc '{xml_id}' needs both a source and a target")
            return
        weight = self._natural(el, "inscription", 1, f"arc '{xml_id}'")
        kind, said_by = self._arc_type(el)
        if kind in REFUSED_ARCS:
            self.error(said_by, f"arc '{xml_id}' is {REFUSED_ARCS[kind]}: a P/T net has none, "
                                "and reading it as an ordinary arc would change what the "
                                "net does; remove it, or analyse the net with a tool for "
                                "its class")
            return
        if kind is not None and kind not in NORMAL_ARCS and kind not in READ_ARCS:
            self.error(said_by, f"arc '{xml_id}' has type '{kind}', which is not a P/T arc; "
                                "known: " + ", ".join(sorted(NORMAL_ARCS | READ_ARCS)))
            return
        if any(_child(ts, "read") is not None for ts in self._ours(el)):
            read = PAIR
        else:
            read = READ if kind in READ_ARCS else NORMAL
        self.raw.arcs.append((el, src, dst, 1 if weight is None else weight, read))

    def coloured(self, net_el) -> None:
        """Refuse what only a coloured (high-level) net has, wherever it is in the net.

        Searched by lxml in one pass (the names in any namespace); other
        tools' ``<toolspecific>`` data is theirs and skipped.
        """
        for el in net_el.iter(*(f"{{*}}{name}" for name in (*HIGH_LEVEL, "structure"))):
            name = _local(el)
            if name == "structure" and _local(el.getparent()) != "type":
                continue   # a high-level label's body: its label is reported
            if any(_local(a) == "toolspecific" for a in el.iterancestors()):
                continue
            what = HIGH_LEVEL.get(name, "a place's sort")
            self.error(el, f"<{name}> is {what}: this is a coloured (high-level) net, "
                           "whatever its type says, and a P/T reading would drop its colours "
                           "and tokens; unfold it to a P/T net first")
            return   # one message says it: the rest of the net is coloured alike

    def walk(self, net_el) -> None:
        """Every node and arc, in document order, through pages of any depth.

        A page with the id of a transition and a ``<net>`` inside is a WoPeD
        subprocess: the net that refines that transition. Its places with
        the ids of the transition's input and output places are those
        places; the subprocess is read in the transition's stead
        (substitution), so the net read is the one WoPeD runs, flattened.
        Arc ids inside a subprocess repeat the top level's and name nothing
        else, so they are not held to be unique.
        """
        handlers = {"place": self.place, "transition": self.transition, "arc": self.arc,
                    "referencePlace": self.reference, "referenceTransition": self.reference}
        # explicit: pages may nest deeper than Python recurses; True: in a subprocess
        stack = [(iter(net_el), False)]
        while stack:
            children, inside = stack[-1]
            child = next(children, None)
            if child is None:
                stack.pop()
                continue
            name = _local(child)
            sub = _child(child, "net") if name == "page" else None
            if sub is not None and child.get("id") in self.raw.transitions:
                self.raw.substituted.add(child.get("id"))
                stack.append((iter(sub), True))
            elif name == "page":
                self._id(child)
                stack.append((iter(child), inside))
            elif inside and name == "place" and child.get("id") in self.raw.places:
                continue   # the subprocess's copy of the transition's input or output place
            elif inside and name == "arc":
                self.arc(child, scoped=True)
            elif name in handlers:
                handlers[name](child)

    # -- resolution --------------------------------------------------------------

    def resolve(self, xml_id: str, el, end: str) -> str | None:
        """The node a (possibly reference) id stands for, or None after an error."""
        seen = []
        while xml_id in self.raw.refs:
            if xml_id in seen:
                self.error(el, f"arc {end} '{seen[0]}': references loop ({' -> '.join(seen)})")
                return None
            seen.append(xml_id)
            xml_id = self.raw.refs[xml_id][0]
        if xml_id not in self.raw.places and xml_id not in self.raw.transitions:
            via = f" (through reference '{seen[0]}')" if seen else ""
            self.error(el, f"arc {end} '{xml_id}'{via} is not a place or transition "
                           "of this net")
            return None
        return xml_id

    def build(self, name: str) -> Net:
        raw = self.raw
        weights: dict[tuple[str, str, bool], int] = {}
        arc_el: dict[tuple[str, str, bool], object] = {}
        for t in raw.substituted:   # its subprocess stands in its place
            del raw.transitions[t]
        if len(raw.firing_rules) > 1:
            el = list(raw.firing_rules.values())[1]
            rules = ", ".join(f"priority {p}{' timed' if timed == 'true' else ''}"
                              for p, timed in raw.firing_rules)
            self.error(el, f"transition '{el.get('id')}' differs from others in priority or "
                           f"timing ({rules}): which transition may fire depends on them, "
                           "which a P/T net cannot say")
        for el, src, dst, weight, read in raw.arcs:
            if src in raw.substituted or dst in raw.substituted:
                continue
            s, d = self.resolve(src, el, "source"), self.resolve(dst, el, "target")
            if s is None or d is None:
                continue
            s_place, d_place = s in raw.places, d in raw.places
            if s_place == d_place:
                kind = "place" if s_place else "transition"
                self.error(el, f"arc '{el.get('id')}' goes from {kind} '{s}' to {kind} "
                               f"'{d}'; an arc joins a place and a transition")
                continue
            if read == READ and not s_place:
                self.error(el, f"read arc '{el.get('id')}' goes from transition '{s}' to "
                               f"place '{d}'; a read arc tests a place for its transition")
                continue
            key = (s, d, read)
            weights[key] = weights.get(key, 0) + weight
            arc_el.setdefault(key, el)
        for (s, d, read), w in list(weights.items()):
            forward = weights.get((d, s, PAIR))
            if read == PAIR and d in raw.places and forward is not None and w > forward:
                # our writer's return half also carries the transition's own arc
                # into the place (a file has no two arcs between the same nodes)
                weights[(s, d, read)] = forward
                weights[(s, d, NORMAL)] = weights.get((s, d, NORMAL), 0) + w - forward
        arcs = []
        for (s, d, read), w in weights.items():
            if read == NORMAL:
                arcs.append(Arc(self.decode(s), self.decode(d), w))
            elif read == READ:
                arcs.append(Arc(self.decode(s), self.decode(d), w, ArcKind.READ))
            elif s in raw.places:  # a read arc is the pair (p -> t, t -> p), both marked
                if weights.get((d, s, PAIR)) != w:
                    self.error(arc_el[(s, d, read)],
                               f"read arc from '{s}' to '{d}' has no matching return arc")
                    continue
                arcs.append(Arc(self.decode(s), self.decode(d), w, ArcKind.READ))
            elif weights.get((d, s, PAIR)) != w:
                self.error(arc_el[(s, d, read)],
                           f"read arc return from '{s}' to '{d}' has no matching arc")
        raise_all(raw.errors)
        return Net(name, tuple(raw.places.values()), tuple(raw.transitions.values()),
                   tuple(arcs), Marking(raw.marking))


@without_gc  # a large file is millions of small objects, all alive (see gcpause)
def parse_lenient(data: bytes, filename: str = "<input>", net_id: str | None = None) -> Net:
    """Read one P/T net from PNML bytes, the forgiving way (this module's docstring)."""
    src = Source(filename, data)
    root = parse_xml(data, src).getroot()
    if _local(root) != "pnml":
        raise PnmlError(f"the root element is <{_local(root)}>, not <pnml>", src.locate(root))
    if is_tapaal(root):
        try:
            return parse_tapaal(root, src, net_id)
        except NetError as e:  # an arc to nowhere, say
            raise PnmlError(e.message, Location(filename)) from None
    nets = _children(root, "net")
    if not nets:
        raise PnmlError("no <net> in this document", src.locate(root))
    if net_id is not None:
        chosen = [n for n in nets if n.get("id") == net_id]
        if not chosen:
            listing = ", ".join(str(n.get("id")) for n in nets)
            raise PnmlError(f"no net with id '{net_id}'; nets in this file: {listing}",
                            src.locate(root))
        net_el = chosen[0]
    elif len(nets) > 1:
        listing = ", ".join(str(n.get("id")) for n in nets)
        raise PnmlError(f"this file holds {len(nets)} nets ({listing}); choose one with "
                        "--net ID",
                        src.locate(nets[1]))
    else:
        net_el = nets[0]
    net_type = net_el.get("type")
    if net_type is not None and net_type not in P_T_TYPES:
        raise PnmlError(f"net type '{net_type}' is not a place/transition net; readable: "
                        + ", ".join(sorted(P_T_TYPES)), src.locate(net_el))
    ours = [ts for ts in _children(net_el, "toolspecific") if ts.get("tool") == TOOL]
    decode = any(_child(ts, "ids") is not None for ts in ours)
    reader = _Reader(src, decode)
    reader._id(net_el)
    reader.coloured(net_el)
    reader.walk(net_el)
    name_el = _child(net_el, "name")
    name = reader._label_text(net_el, "name") if name_el is not None else None
    try:
        return reader.build(name or net_el.get("id") or "net")
    except NetError as e:  # a rule of the core, e.g. reading and consuming one place
        raise PnmlError(e.message, Location(filename)) from None


def _plain_digits(text: str) -> bool:
    """ASCII decimal digits only (``str.isdigit`` also takes other scripts' digits)."""
    return text.isdigit() and text.isascii()


def read_lenient(path: str | Path, net_id: str | None = None) -> Net:
    """Read one P/T net from a PNML file, the forgiving way."""
    return parse_lenient(read_file(path), str(path), net_id)
