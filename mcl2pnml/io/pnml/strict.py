"""Reading PNML strictly: one file, one net, the net TAPAAL's verifypn reads, or a refusal.

Every proof rests on the net read from a file, so the file must have one
meaning. This reader accepts the ISO/IEC 15909-2 P/T grammar as our writer,
the Model Checking Contest, TAPAAL's PNML export, WoPeD, ProM and pm4py write
it, and refuses, at its line and column, every construct that tools read in
different ways (docs/pnml.md has the whole list and why each is refused):

* elements outside ``<toolspecific>`` content must be in the document's one
  namespace (PNML's, or none), unprefixed, each where the grammar puts it,
  with only the attributes the grammar gives it: a prefixed arc, a node
  under ``<graphics>``, a net inside a page (WoPeD's subprocess), a second
  net, a reference node, ``weight=`` on an arc are refused;
* ``<toolspecific>`` and ``<graphics>`` content is free, but holds no element
  that a reader which matches names wherever they are (verifypn does) would
  take for a node, an arc, a net or a label's value;
* a label appears once, with exactly one ``<text>`` (a name: at most one),
  whose content is plain characters: no child element, comment, processing
  instruction or CDATA section; a number is ASCII digits, padded by ASCII
  blanks only, within what a 32-bit reader holds;
* no document type declaration (no entity is ever expanded or fetched), and
  the encoding is UTF-8.

Parallel arcs add up (as verifypn does); our own read arcs (a self-loop pair
marked ``<read/>`` in our toolspecific data) are read arcs, the same
behaviour as the pair.

The file is read as a stream (lxml's ``iterparse``): each node is checked
and turned into plain values when its end tag is read, then dropped, so that
a file of a million arcs never becomes a tree in memory.
"""
from __future__ import annotations

import io
import json
import mmap
import os
import re
from array import array
from bisect import bisect_right
from pathlib import Path

from lxml import etree

from mcl2pnml.core.errors import Location, Mcl2PnmlError, NetError, PnmlError, raise_all
from mcl2pnml.core.gcpause import without_gc
from mcl2pnml.core.bounds import MAX_SECONDS
from mcl2pnml.core.files import json_fault, open_regular
from mcl2pnml.core.net import Arc, ArcKind, Marking, Net, Place, Timing, Transition, freeze
from mcl2pnml.io import ids

PNML = "http://www.pnml.org/version-2009/grammar/pnml"
TAPAAL = "http://www.informatik.hu-berlin.de/top/pnml/ptNetb"
#: Net types of P/T nets in the 2009 standard (the core model has no markings
#: of its own type, but every tool writes P/T labels in it).
NET_TYPES = frozenset({"http://www.pnml.org/version-2009/grammar/ptnet",
                       "http://www.pnml.org/version-2009/grammar/pnmlcoremodel",
                       # the pre-standard P/T type, which WoPeD still writes
                       "http://www.informatik.hu-berlin.de/top/pntd/ptNetb"})
TOOL = "mcl2pnml"
#: The largest marking and weight: what a reader holding 32-bit numbers reads
#: (verifypn refuses markings past 2^32-1 and reads weights with ``atoi``).
MAX_MARKING = 2 ** 32 - 1
MAX_WEIGHT = 2 ** 31 - 1
#: Faults reported in one message: past them the file is not worth reading on.
MAX_FAULTS = 50

#: Names that a reader matching element names wherever they stand takes for
#: nodes, arcs, nets, pages, coloured content or a label's value.
NODE_NAMES = frozenset({
    "pnml", "net", "page", "place", "transition", "arc", "referencePlace",
    "referenceTransition", "inputArc", "outputArc", "transportArc", "inhibitorArc",
    "initialMarking", "inscription", "hlinitialMarking", "hlinscription", "declaration",
    "declarations", "variable", "queries", "query", "k-bound", "finalmarkings"})
VALUE_NAMES = frozenset({"text", "value"})
#: Why a construct of another class of nets or another dialect is refused.
REFUSED = {
    "referencePlace": "a reference place: tools disagree on it (verifypn ignores it and "
                      "drops its arcs); replace it by the place it stands for",
    "referenceTransition": "a reference transition: tools disagree on it (verifypn ignores "
                           "it and drops its arcs); replace it by the transition it stands for",
    "inputArc": "TAPAAL's own arc element", "outputArc": "TAPAAL's own arc element",
    "transportArc": "a transport arc of a timed-arc net",
    "inhibitorArc": "an inhibitor arc (it enables its transition only while the place "
                    "is empty)",
    "declaration": "a declaration of sorts and variables: this is a coloured net",
    "declarations": "a declaration of sorts and variables: this is a coloured net",
    "hlinitialMarking": "a high-level initial marking: this is a coloured net",
    "hlinscription": "a high-level arc inscription: this is a coloured net",
    "type": "a place's sort: this is a coloured net",
    "condition": "a transition guard: this is a coloured net",
    "finalmarkings": "a final marking (ProM, pm4py): not part of a P/T net, and a reader "
                     "that matches names anywhere takes its <place> elements for places",
    "capacity": "a place capacity (PIPE): a transition that would exceed it cannot fire, "
                "which a P/T net cannot say",
    "variable": "a variable of a data Petri net",
    "variables": "variables of a data Petri net",
}
_NUMBER = re.compile(r"[ \t\r\n]*([0-9]+)[ \t\r\n]*\Z")
_WEIGHT = re.compile(r"[ \t]*([0-9]+)[ \t]*\Z")   # verifypn refuses a line break here
_NOT_ASCII = re.compile(rb"[\x80-\xff]")
_ENCODING = re.compile(rb"""\A(?:\xef\xbb\xbf)?<\?xml[^>]*?encoding\s*=\s*["']([^"']*)["']""")
# tabs and line breaks in an attribute are folded into spaces by an XML parser and kept by
# others (verifypn's), and a space at either end is trimmed by some tools: either way
# two readers would name the node differently
_BLANK_ID = re.compile(r"[\x00-\x1f\x7f]|\A\s|\s\Z")
LENIENT_HINT = ("; --lenient reads it the forgiving way, but no proof (certify --check, "
                "a certificate beside the file) ever trusts that reading")


class _Lines:
    """The lines of a buffer (bytes or a memory map), found only when a message needs one.

    A large file is never decoded and split whole: the offsets of its line
    breaks are found on the first fault, and each line decoded on demand.
    """

    def __init__(self, buffer):
        self.buffer = buffer
        self._starts: array | None = None

    def _index(self) -> array:
        if self._starts is None:
            starts = array("q", [0])
            buf, find, at = self.buffer, self.buffer.find, 0
            while True:
                at = find(b"\n", at)
                if at < 0:
                    break
                at += 1
                starts.append(at)
            if starts[-1] == len(buf) and len(starts) > 1:
                starts.pop()   # a final newline opens no line
            self._starts = starts
        return self._starts

    def __len__(self) -> int:
        return len(self._index()) if len(self.buffer) else 0

    def __getitem__(self, i: int) -> str:
        starts = self._index()
        end = starts[i + 1] - 1 if i + 1 < len(starts) else len(self.buffer)
        line = bytes(self.buffer[starts[i]:end]).decode("utf-8", "replace")
        return line[:-1] if line.endswith("\r") else line

    def line_of(self, offset: int) -> int:
        return bisect_right(self._index(), offset)


def _local(tag) -> str:
    return tag.rsplit("}", 1)[-1] if isinstance(tag, str) else ""


def _raw_name(el) -> str:
    """The element's name as the file spells it (its prefix included)."""
    return f"{el.prefix}:{_local(el.tag)}" if el.prefix else _local(el.tag)


class _StrictReader:
    """One pass over the stream: checks each node and keeps its plain values."""

    def __init__(self, src, lines: _Lines, cdata: bool):
        self.src = src            # the lenient reader's locator, over lazy lines
        self.lines = lines
        self.cdata = cdata        # the file has a CDATA section somewhere: look closer
        self.ns = None            # the document's namespace: PNML's, or "" for none
        self.errors: list[PnmlError] = []
        self.seen: dict[str, int] = {}              # xml id -> its line
        self.places: list = []                      # (id, name, interface, payload, pos, el line)
        self.transitions: list = []                 # (id, name, timing, payload, pos)
        self.marking: dict[str, int] = {}
        self.arcs: list = []                        # (source, target, weight, read?, line)
        self.node_kind: dict[str, bool] = {}        # xml id -> is a place
        self.decode = False
        self.nets = 0
        self.net_name = None
        self.net_id = None
        self._payloads: dict[str, object] = {}

    # -- messages ------------------------------------------------------------------------

    def error(self, el, message: str) -> None:
        if len(self.errors) < MAX_FAULTS:
            loc = self.src.locate(el) if el is not None else Location(self.src.filename)
            self.errors.append(PnmlError(message, loc))
        if len(self.errors) >= MAX_FAULTS:
            raise _TooMany()

    def tags(self, ns: str) -> None:
        """The names of the grammar's elements in the document's namespace."""
        self.ns = ns
        q = (lambda name: f"{{{ns}}}{name}") if ns else (lambda name: name)
        (self.T_NET, self.T_PAGE, self.T_PLACE, self.T_TRANSITION, self.T_ARC, self.T_NAME,
         self.T_TEXT, self.T_MARKING, self.T_INSCRIPTION, self.T_GRAPHICS, self.T_TOOL,
         self.T_POSITION, self.T_ARCTYPE) = map(q, (
             "net", "page", "place", "transition", "arc", "name", "text", "initialMarking",
             "inscription", "graphics", "toolspecific", "position", "arctype"))
        self.containers = {self.T_NET, self.T_PAGE}

    # -- what may stand where --------------------------------------------------------------

    def stray(self, el, where: str) -> None:
        """An element the grammar does not put here: refused with what it is."""
        name = _raw_name(el)
        local = _local(el.tag)
        ns = el.tag[1:].split("}", 1)[0] if el.tag.startswith("{") else ""
        if el.prefix is not None or ns != self.ns:
            said = f"<{name}>" + (f" in the namespace '{ns}'" if ns else " in no namespace")
            self.error(el, f"{said} {where}: PNML elements are in the document's namespace "
                           f"('{self.ns or 'none'}'), written without a prefix; tools that "
                           "match names read it differently, so it is refused" + LENIENT_HINT)
        elif local in REFUSED:
            self.error(el, f"<{name}> is {REFUSED[local]}; mcl2pnml reads P/T nets"
                           + LENIENT_HINT * (local in ("finalmarkings",)))
        elif local == "net" and where.startswith("in <page"):
            self.error(el, f"a <net> inside <page> '{el.getparent().get('id')}' (a WoPeD "
                           "subprocess): tools read it as a separate net, as part of this "
                           "one, or as the refinement of a transition; flatten it into one "
                           "page" + LENIENT_HINT)
        elif local == "value" and where.startswith("in <"):
            self.error(el, f"<value> {where} is the pre-standard form of a label's value "
                           "(PIPE's): tools read 'Default,1' as 1, as 0, or not at all; "
                           "write <text>" + LENIENT_HINT)
        else:
            self.error(el, f"<{name}> {where} is not part of a P/T net in PNML "
                           "(ISO/IEC 15909-2)")

    def attributes(self, el, allowed: frozenset) -> None:
        for key in el.keys():
            if key not in allowed:
                shown = key if not key.startswith("{") else \
                    f"{key.split('}', 1)[1]} (namespace '{key[1:].split('}', 1)[0]}')"
                why = {"weight": "TAPAAL reads it as the arc's weight",
                       "initialMarking": "TAPAAL reads it as the place's tokens",
                       "invariant": "TAPAAL's age invariant of a timed-arc net",
                       "name": "TAPAAL's own format names nodes in attributes",
                       "inscription": "TAPAAL reads it as the arc's time interval",
                       "guard": "a data Petri net's guard"}.get(key, "not in the P/T grammar")
                self.error(el, f"<{_raw_name(el)}> has the attribute {shown}: {why}; "
                               "refused, since tools give it different meanings" + LENIENT_HINT)

    def mixed(self, el) -> None:
        """Character data between elements of the grammar (only <text> holds any)."""
        text = el.text
        if text and text.strip():
            self.error(el, f"<{_raw_name(el)}> holds the text {text.strip()[:30]!r} outside "
                           "any <text>: not part of PNML")
        for child in el:
            tail = child.tail
            if tail and tail.strip():
                self.error(child, f"text {tail.strip()[:30]!r} after <{_raw_name(child)}> is "
                                  "outside any <text>: not part of PNML")

    def free(self, el, in_label: bool) -> None:
        """``<toolspecific>`` or ``<graphics>`` content: anything but what a name-matching
        reader takes for a node, an arc, a net, or (in a label) the label's value."""
        for inner in el.iter():
            tag = inner.tag
            if not isinstance(tag, str) or inner is el:
                continue
            local = _local(tag)
            if local in NODE_NAMES or (in_label and local in VALUE_NAMES):
                what = "a label's value" if local in VALUE_NAMES else "a node, arc or net"
                self.error(inner, f"<{_raw_name(inner)}> inside <{_raw_name(el)}>: a reader "
                                  f"that matches names anywhere (verifypn) takes it for {what}, "
                                  "others skip it; refused")

    # -- labels --------------------------------------------------------------------------

    def text_of(self, label, required: bool) -> str | None:
        """The one ``<text>`` of a label, checked to be plain characters."""
        found = None
        for child in label:
            tag = child.tag
            if tag == self.T_TEXT:
                if found is not None:
                    self.error(child, f"a second <text> in <{_raw_name(label)}>: tools read "
                                      "the first or the last; refused")
                    return None
                found = child
            elif tag == self.T_GRAPHICS or tag == self.T_TOOL:
                self.free(child, in_label=True)
            elif isinstance(tag, str):
                self.stray(child, f"in <{_raw_name(label)}>")
        self.attributes(label, frozenset())
        self.mixed(label)
        if found is None:
            if required:
                self.error(label, f"<{_raw_name(label)}> has no <text>")
            return None
        self.attributes(found, frozenset())
        if len(found):
            what = "a comment" if found[0].tag is etree.Comment else (
                "a processing instruction" if found[0].tag is etree.PI else
                f"the element <{_raw_name(found[0])}>")
            self.error(found, f"<text> of <{_raw_name(label)}> holds {what}: tools read the "
                              "characters before it, after it, or all of them; refused")
            return None
        text = found.text or ""
        if self.cdata and b"<![CDATA[" in etree.tostring(found):
            self.error(found, f"<text> of <{_raw_name(label)}> holds a CDATA section: some "
                              "readers skip it (verifypn reads 0); write plain characters")
            return None
        return text

    def number(self, label, what: str, weight: bool) -> int | None:
        text = self.text_of(label, required=True)
        if text is None:
            return None
        match = (_WEIGHT if weight else _NUMBER).match(text)
        limit = MAX_WEIGHT if weight else MAX_MARKING
        if match is None or (weight and int(match.group(1)) == 0):
            kind = "a positive integer" if weight else "a natural number"
            blanks = "spaces and tabs" if weight else "spaces, tabs and line breaks"
            shown = text if len(text) <= 40 else text[:40] + "..."
            self.error(label, f"{what}: {_local(label.tag)} must be {kind} in ASCII digits "
                              f"(with {blanks} around it at most), not {shown!r}")
            return None
        digits = match.group(1)
        if len(digits) > 12 or int(digits) > limit:
            shown = digits if len(digits) <= 30 else f"(a number of {len(digits):,} digits)"
            self.error(label, f"{what}: {_local(label.tag)} {shown} is too large: at most "
                              f"{limit:,}, what 32-bit readers (verifypn) hold")
            return None
        return int(digits)

    def once(self, el, seen: set, child) -> bool:
        tag = child.tag
        if tag in seen:
            self.error(child, f"a second <{_raw_name(child)}> in <{_raw_name(el)}> "
                              f"'{el.get('id')}': tools read the first or the last; refused")
            return False
        seen.add(tag)
        return True

    # -- our own toolspecific data --------------------------------------------------------------

    def ours(self, ts) -> bool:
        return ts.get("tool") == TOOL

    def payload(self, el):
        text = el.text or ""
        value = self._payloads.get(text, self)
        if value is self:
            try:
                value = freeze(json.loads(text or "null"))
            except (ValueError, RecursionError) as e:
                self.error(el, f"payload is not JSON data: {json_fault(e)}")
                value = None
            except Mcl2PnmlError as e:
                self.error(el, f"payload is not JSON data: {e}")
                value = None
            self._payloads[text] = value
        return value

    def position(self, graphics):
        for child in graphics:
            if child.tag == self.T_POSITION:
                try:
                    x, y = float(child.get("x", "")), float(child.get("y", ""))
                except ValueError:
                    return None   # a drawing hint only: a bad one is dropped
                return (x, y) if abs(x) < 1e300 and abs(y) < 1e300 else None
        return None

    # -- nodes -----------------------------------------------------------------------------

    def node_id(self, el) -> str | None:
        xml_id = el.get("id")
        if xml_id is None:
            self.error(el, f"<{_raw_name(el)}> has no id")
            return None
        if not xml_id or _BLANK_ID.search(xml_id):
            self.error(el, f"{_local(el.tag)} id {xml_id!r} is empty, starts or ends with white "
                           "space, or holds a tab, a line break or a control character, which "
                           "readers keep, trim or fold differently")
            return None
        if xml_id in self.seen:
            self.error(el, f"duplicate id '{xml_id}' (first used on line {self.seen[xml_id]})")
            return None
        self.seen[xml_id] = el.sourceline
        return xml_id

    def placed(self, el) -> bool:
        """Is a node (or page) where the grammar puts it: in a page or straight in the net?"""
        parent = el.getparent()
        if parent is None or parent.tag not in self.containers:
            self.stray(el, f"in <{_raw_name(parent)}>" if parent is not None else "at the top")
            return False
        if el.prefix is not None:
            self.stray(el, f"in <{_raw_name(parent)}>")
            return False
        return True

    def place(self, el) -> None:
        if not self.placed(el):
            return
        self.attributes(el, _ID_ONLY)
        xml_id = self.node_id(el)
        name = interface = payload = position = None
        tokens = 0
        seen: set = set()
        for child in el:
            tag = child.tag
            if tag == self.T_NAME:
                if self.once(el, seen, child):
                    name = self.text_of(child, required=False)
            elif tag == self.T_MARKING:
                if self.once(el, seen, child):
                    tokens = self.number(child, f"place '{xml_id}'", weight=False) or 0
            elif tag == self.T_TOOL:
                self.free(child, in_label=False)
                if self.ours(child):
                    for inner in child:
                        if _local(inner.tag) == "interface":
                            interface = inner.get("label")
                        elif _local(inner.tag) == "payload":
                            payload = self.payload(inner)
            elif tag == self.T_GRAPHICS:
                if self.once(el, seen, child):
                    self.free(child, in_label=False)
                    position = self.position(child)
            elif isinstance(tag, str):
                self.stray(child, f"in place '{xml_id}'")
        self.mixed(el)
        if xml_id is not None:
            self.node_kind[xml_id] = True
            self.places.append((xml_id, name, interface, payload, position))
            if tokens:
                self.marking[xml_id] = tokens

    def transition(self, el) -> None:
        if not self.placed(el):
            return
        self.attributes(el, _ID_ONLY)
        xml_id = self.node_id(el)
        name = timing = payload = position = None
        seen: set = set()
        for child in el:
            tag = child.tag
            if tag == self.T_NAME:
                if self.once(el, seen, child):
                    name = self.text_of(child, required=False)
            elif tag == self.T_TOOL:
                self.free(child, in_label=False)
                if self.ours(child):
                    for inner in child:
                        if _local(inner.tag) == "timing":
                            timing = self.timing(inner, xml_id)
                        elif _local(inner.tag) == "payload":
                            payload = self.payload(inner)
            elif tag == self.T_GRAPHICS:
                if self.once(el, seen, child):
                    self.free(child, in_label=False)
                    position = self.position(child)
            elif isinstance(tag, str):
                self.stray(child, f"in transition '{xml_id}'")
        self.mixed(el)
        if xml_id is not None:
            self.node_kind[xml_id] = False
            self.transitions.append((xml_id, name, timing, payload, position))

    def timing(self, el, xml_id) -> Timing | None:
        try:
            latest = el.get("latest")
            timing = Timing(float(el.get("earliest", "0")),
                            None if latest is None else float(latest))
        except (ValueError, Mcl2PnmlError) as e:
            self.error(el, f"transition '{xml_id}': bad timing: {e}")
            return None
        longest = max(timing.earliest, timing.latest or 0.0)
        if longest > MAX_SECONDS:
            self.error(el, f"transition '{xml_id}': bad timing: time bounds go up to "
                           f"{MAX_SECONDS:,} s, not {longest:g}")
            return None
        return timing

    def arc(self, el) -> None:
        if not self.placed(el):
            return
        self.attributes(el, _ARC_ATTRIBUTES)
        xml_id = self.node_id(el)
        kind = el.get("type")     # TAPAAL's export: "normal", or "inhibitor"
        if kind is not None and kind != "normal":
            self.error(el, f"arc '{xml_id}' has type={kind[:30]!r}: only 'normal' arcs are "
                           "P/T arcs (inhibitor, transport and timed arcs belong to other "
                           "classes of nets; read as ordinary arcs, they would change what "
                           "the net does)")
        source, target = el.get("source"), el.get("target")
        weight, read = 1, False
        seen: set = set()
        for child in el:
            tag = child.tag
            if tag == self.T_INSCRIPTION:
                if self.once(el, seen, child):
                    weight = self.number(child, f"arc '{xml_id}'", weight=True)
            elif tag == self.T_TOOL:
                self.free(child, in_label=False)
                if self.ours(child) and any(_local(i.tag) == "read" for i in child):
                    read = True
            elif tag == self.T_GRAPHICS or tag == self.T_NAME:
                if self.once(el, seen, child):
                    if tag == self.T_NAME:
                        self.text_of(child, required=False)
                    else:
                        self.free(child, in_label=False)
            elif tag == self.T_ARCTYPE:    # ProM's and pm4py's: only an ordinary arc is P/T
                if self.once(el, seen, child):
                    kind = (self.text_of(child, required=True) or "").strip()
                    if kind != "normal":
                        self.error(child, f"arc '{xml_id}' has the type '{kind[:30]}': only "
                                          "'normal' arcs are P/T arcs (a read, inhibitor or "
                                          "reset arc is another class of nets, and tools that "
                                          "ignore <arctype> read it as an ordinary arc)")
            elif isinstance(tag, str):
                self.stray(child, f"in arc '{xml_id}'")
        self.mixed(el)
        if source is None or target is None:
            self.error(el, f"arc '{xml_id}' needs both a source and a target")
            return
        for end in (source, target):
            if not end or _BLANK_ID.search(end):
                self.error(el, f"arc '{xml_id}' names {end!r}, which is no id")
                return
        if xml_id is not None and weight is not None:
            self.arcs.append((source, target, weight, read, el.sourceline))

    def page(self, el) -> None:
        if self.placed(el):
            self.attributes(el, _ID_ONLY)
            self.node_id(el)
            self.rest(el, "page")
        # its nodes were read and dropped as they ended; what is left goes with it

    def rest(self, el, kind: str) -> None:
        """What is left of a page or net at its end tag, once its nodes were read and
        dropped: its name, toolspecific data, graphics, and anything that is not PNML."""
        seen: set = set()
        for child in el:
            tag = child.tag
            if tag == self.T_NAME:
                if self.once(el, seen, child):
                    text = self.text_of(child, required=False)
                    if kind == "net":
                        self.net_name = text
            elif tag == self.T_TOOL:
                self.free(child, in_label=False)
                if kind == "net" and self.ours(child) and any(
                        _local(i.tag) == "ids" for i in child):
                    self.decode = True
            elif tag == self.T_GRAPHICS and kind == "page":
                if self.once(el, seen, child):
                    self.free(child, in_label=False)
            elif tag is etree.Comment or tag is etree.PI:
                continue
            elif isinstance(tag, str):
                self.stray(child, f"in <{_raw_name(el)}> '{el.get('id')}'")
        self.mixed(el)

    # -- the net -------------------------------------------------------------------------------

    def build(self) -> Net:
        """The net: arcs added up by their ends, as verifypn adds parallel arcs.

        Our read arc is the pair (p -> t, t -> p), both halves marked, whose
        return may also carry the transition's own arc into the place (one
        arc per pair of ends in a file): read as a read arc when every arc
        between the two is marked and the return is at least the take.
        Anything else marked read is read as the arcs it is, which is what
        it does.
        """
        decode = ids.decode if self.decode else (lambda s: s)
        kinds = self.node_kind
        take: dict[tuple[str, str], int] = {}     # (place, transition) -> tokens taken
        give: dict[tuple[str, str], int] = {}     # (transition, place) -> tokens given
        marked: set = set()                       # (place, transition) pairs marked read
        plain: set = set()                        # ... with an unmarked arc between them
        for source, target, weight, read, line in self.arcs:
            s_place, t_place = kinds.get(source), kinds.get(target)
            if s_place is None or t_place is None:
                missing = source if s_place is None else target
                end = "source" if s_place is None else "target"
                self.error_at(line, f"arc {end} '{missing}' is not a place or transition of "
                                    "this net")
                continue
            if s_place == t_place:
                kind = "place" if s_place else "transition"
                self.error_at(line, f"arc from {kind} '{source}' to {kind} '{target}': an arc "
                                    "joins a place and a transition")
                continue
            if s_place:
                take[(source, target)] = take.get((source, target), 0) + weight
                pair = (source, target)
            else:
                give[(source, target)] = give.get((source, target), 0) + weight
                pair = (target, source)
            (marked if read else plain).add(pair)
        raise_all(_in_order(self.errors))
        arcs = []
        for (p, t), w in take.items():
            back = give.get((t, p))
            if back is not None and back >= w and (p, t) in marked and (p, t) not in plain:
                arcs.append(Arc(decode(p), decode(t), w, ArcKind.READ))
                if back > w:
                    arcs.append(Arc(decode(t), decode(p), back - w))
                give[(t, p)] = 0
            else:
                arcs.append(Arc(decode(p), decode(t), w))
        arcs += [Arc(decode(t), decode(p), w) for (t, p), w in give.items() if w]
        places = [Place(decode(i), n, f, p, pos) for i, n, f, p, pos in self.places]
        transitions = [Transition(decode(i), n, t, p, pos)
                       for i, n, t, p, pos in self.transitions]
        marking = Marking({decode(p): n for p, n in self.marking.items()})
        return Net(self.net_name or self.net_id or "net", tuple(places), tuple(transitions),
                   tuple(arcs), marking)

    def error_at(self, line: int | None, message: str) -> None:
        if len(self.errors) < MAX_FAULTS:
            self.errors.append(PnmlError(message, self.src.at(line)))
        if len(self.errors) >= MAX_FAULTS:
            raise _TooMany()

    def net(self, el, root) -> None:
        """A net's end tag: the one net of the file, straight under <pnml>."""
        parent = el.getparent()
        self.nets += parent is root
        if parent is not root or el.prefix is not None:
            self.stray(el, f"in <{_raw_name(parent)}>")
        elif self.nets > 1:
            self.error(el, "a second <net> in this file: tools read the first, all of them "
                           "as one, or one chosen; one file holds one net here" + LENIENT_HINT)
        else:
            self.attributes(el, _NET_ATTRIBUTES)
            self.net_id = self.node_id(el)
            net_type = el.get("type")
            if net_type is not None and net_type not in NET_TYPES:   # none: SNAKES
                self.error(el, f"net type {net_type!r} is not a P/T net of PNML; readable: "
                               + ", ".join(sorted(NET_TYPES)))
            self.rest(el, "net")


_ID_ONLY = frozenset({"id"})
_ARC_ATTRIBUTES = frozenset({"id", "source", "target", "type"})
_NET_ATTRIBUTES = frozenset({"id", "type"})


def _in_order(errors: list) -> list:
    """Faults in the order of the file (an element is checked at its end tag, so that a
    page's fault would otherwise follow its nodes')."""
    return sorted(errors, key=lambda e: (e.location.line or 0, e.location.column or 0)
                  if e.location else (0, 0))


class _TooMany(Exception):
    """Enough faults for one message: stop reading."""


def _prolog_faults(buffer, filename: str) -> None:
    """What is refused before parsing: another encoding, a document type declaration."""
    head = bytes(buffer[:4])
    if head[:2] in (b"\xff\xfe", b"\xfe\xff") or b"\x00" in head:
        raise PnmlError("the file is not UTF-8 (it looks like UTF-16 or UTF-32): readers "
                        "that take bytes as UTF-8 read it differently; save it as UTF-8",
                        Location(filename, 1, 1))
    declared = _ENCODING.match(bytes(buffer[:512]))
    if declared and declared.group(1).decode("ascii", "replace").lower() not in (
            "utf-8", "utf8", "us-ascii", "ascii") and _NOT_ASCII.search(buffer):
        name = declared.group(1).decode("ascii", "replace")
        raise PnmlError(f"the file declares the encoding '{name}' and holds characters "
                        "beyond ASCII: readers that take bytes as UTF-8 read them "
                        "differently; save it as UTF-8", 
                        Location(filename, 1, 1))


def _parse(source, buffer, filename: str, net_id: str | None) -> Net:
    from mcl2pnml.io.pnml.reader import XmlError, _Source
    _prolog_faults(buffer, filename)
    lines = _Lines(buffer)
    src = _Source.__new__(_Source)
    src.filename, src.lines = filename, lines
    doctype = buffer.find(b"<!DOCTYPE")
    if doctype >= 0:
        line = lines.line_of(doctype)
        raise XmlError("document type declarations are refused: PNML needs none, and "
                       "entities are never expanded or fetched",
                       src.at(line, doctype - lines._index()[line - 1] + 1))
    reader = _StrictReader(src, lines, cdata=buffer.find(b"<![CDATA[") >= 0)
    try:
        # end tags only, of the elements read as they end: everything else is checked
        # inside the node, page or net that holds it
        events = etree.iterparse(
            source, events=("end",), remove_comments=False, remove_pis=False,
            strip_cdata=False, resolve_entities=False, load_dtd=False, no_network=True,
            huge_tree=False, tag=("{*}net", "{*}page", "{*}place", "{*}transition", "{*}arc"))
        root = handlers = None
        for _, el in events:
            if root is None:
                root = _root(el.getroottree().getroot(), reader, src)
                handlers = {reader.T_PLACE: reader.place, reader.T_TRANSITION: reader.transition,
                            reader.T_ARC: reader.arc, reader.T_PAGE: reader.page}
            handler = handlers.get(el.tag)
            if handler is not None:
                handler(el)
                el.getparent().remove(el)     # read: dropped, so the stream stays small
            elif el.tag == reader.T_NET:
                reader.net(el, root)
            elif not _inside_free(el, reader):
                # a node's name in another namespace: said where it stands
                parent = el.getparent()
                reader.stray(el, f"in <{_raw_name(parent)}>" if parent is not None
                             else "at the top")
        if root is None:
            root = _root(events.root, reader, src)
        reader.mixed(root)
        for child in root:
            if isinstance(child.tag, str) and child.tag != reader.T_NET:
                reader.stray(child, "in <pnml>")
    except etree.XMLSyntaxError as e:
        line, col = getattr(e, "position", (e.lineno, None))
        msg = str(e.msg).split(f", line {line}")[0]
        raise XmlError(f"not well-formed XML: {msg}", src.at(line, col)) from None
    except _TooMany:
        raise_all(_in_order(reader.errors))
    if reader.nets == 0 and not reader.errors:
        raise PnmlError("no <net> in this document", src.locate(root))
    if net_id is not None and reader.net_id is not None and net_id != reader.net_id:
        raise PnmlError(f"no net with id '{net_id}'; the net in this file: {reader.net_id}",
                        src.at(reader.seen.get(reader.net_id)))
    try:
        return reader.build()
    except _TooMany:
        raise_all(_in_order(reader.errors))
        raise
    except NetError as e:   # a rule of the core, e.g. a name with a control character
        raise PnmlError(e.message, Location(filename)) from None


def _root(root, reader, src):
    """The document's root, which must be <pnml>: its namespace is the document's."""
    if root is None or _local(root.tag) != "pnml" or root.prefix is not None:
        name = _raw_name(root) if root is not None else "nothing"
        raise PnmlError(f"the root element is <{name}>, not <pnml>",
                        src.locate(root) if root is not None else src.at(1))
    ns = root.tag[1:].split("}", 1)[0] if root.tag.startswith("{") else ""
    if ns == TAPAAL:
        raise PnmlError("this is TAPAAL's own format (a timed-arc net, its markings and "
                        "weights in attributes), which P/T tools read differently (verifypn "
                        "refuses its timed arcs); export PNML from TAPAAL" + LENIENT_HINT
                        + " (read as the untimed P/T net it draws, where time cannot matter)",
                        src.locate(root))
    if ns not in (PNML, ""):
        raise PnmlError(f"<pnml> is in the namespace '{ns}', not PNML's ({PNML})",
                        src.locate(root))
    reader.tags(ns)
    reader.attributes(root, frozenset())
    return root


def _inside_free(el, reader) -> bool:
    """Whether ``el`` stands in ``<toolspecific>`` or ``<graphics>`` content, where the
    content's own check (at the end of its node) refuses it with its reason."""
    for anc in el.iterancestors():
        if anc.tag == reader.T_TOOL or anc.tag == reader.T_GRAPHICS:
            return True
    return False


@without_gc   # a large file is millions of small objects, all alive (see gcpause)
def parse_strict(data: bytes, filename: str = "<input>", net_id: str | None = None) -> Net:
    """Read one P/T net from PNML bytes, strictly (this module's docstring)."""
    return _parse(io.BytesIO(data), data, filename, net_id)


@without_gc
def load_strict(path: str | Path, net_id: str | None = None) -> Net:
    """Read one P/T net from a PNML file, strictly, as a stream (never whole in memory)."""
    from mcl2pnml.io.pnml.reader import read_file
    try:
        fd = open_regular(path)
    except Mcl2PnmlError as e:
        raise PnmlError(e.message, e.location) from None
    with os.fdopen(fd, "rb") as f:
        if os.fstat(f.fileno()).st_size == 0:
            return parse_strict(read_file(path), str(path), net_id)
        with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as buffer:
            return _parse(f, buffer, str(path), net_id)
