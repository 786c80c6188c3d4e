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
a file of a million arcs never becomes a tree in memory. The shapes writers
use are checked in few steps (the fast paths); any other shape, or any fault,
is read again the careful way, which says where and why; the tests hold the
two to the same outcome. Ids, arc ends and read arcs are checked over the
whole net at the end, and a fault found then is located by its id in the file.
"""
from __future__ import annotations

import io
import mmap
import os
import re
from array import array
from bisect import bisect_right
from pathlib import Path

from lxml import etree

from mcl2pnml.core.errors import ErrorList, Location, Mcl2PnmlError, NetError, PnmlError
from mcl2pnml.core.gcpause import without_gc
from mcl2pnml.core.bounds import MAX_SECONDS
from mcl2pnml.core.files import open_regular
from mcl2pnml.core.net import Arc, ArcKind, Marking, Net, Place, Timing, Transition
from mcl2pnml.io import ids
from mcl2pnml.io.pnml.lenient import parse_lenient
from mcl2pnml.io.pnml.source import (HIGH_LEVEL, Source, XmlError, coordinates, payload_value,
                                     read_file)

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
#: Faults said in one message, each with its line; past them faults are only counted...
MAX_FAULTS = 50
#: ... up to this many, where the file is not worth reading on.
MAX_COUNTED = 10_000
#: The fast paths on: off, every node is read the careful way (the tests hold the two
#: to the same outcome on every file they have).
FAST = True

#: Names that a reader matching element names wherever they stand takes for
#: nodes, arcs, nets, pages, coloured content or a label's value.
NODE_NAMES = frozenset({
    "pnml", "net", "page", "place", "transition", "arc", "referencePlace",
    "referenceTransition", "inputArc", "outputArc", "transportArc", "inhibitorArc",
    "initialMarking", "inscription", "hlinitialMarking", "hlinscription", "declaration",
    "declarations", "variable", "queries", "query", "k-bound", "finalmarkings"})
VALUE_NAMES = frozenset({"text", "value"})
_IN_LABEL = NODE_NAMES | VALUE_NAMES
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
    "variable": "a variable (of a coloured or a data Petri net)",
    "variables": "variables of a data Petri net",
}
_NUMBER = re.compile(r"[ \t\r\n]*([0-9]+)[ \t\r\n]*\Z")
_WEIGHT = re.compile(r"[ \t]*([0-9]+)[ \t]*\Z")   # verifypn refuses a line break here
_NOT_ASCII = re.compile(rb"[\x80-\xff]")
_ENCODING = re.compile(rb"""\A(?:\xef\xbb\xbf)?<\?xml[^>]*?encoding\s*=\s*["']([^"']*)["']""")
# an empty id, white space at either end, a control character (NUL separates the ids)
_BAD_IDS = re.compile(r"\x00(?:\x00|\s)|\s\x00|[\x01-\x1f\x7f&<>\"']")
LENIENT_HINT = ("; --lenient reads it the forgiving way, but no proof (certify --check, "
                "a certificate beside the file) ever trusts that reading")

class _Buffer:
    """The file's bytes, mapped only when a message or a rare check needs them.

    The reading itself streams; the scans before it read a chunk at a time
    (:meth:`first`), so that a large file's pages never count in the process's memory.
    """

    def __init__(self, data: bytes | None = None, fd: int | None = None, size: int = 0):
        self.data, self.fd = data, fd
        self.size = len(data) if data is not None else size
        self._map = None

    @property
    def view(self):
        if self.data is not None:
            return self.data
        if self._map is None:
            self._map = mmap.mmap(self.fd, 0, access=mmap.ACCESS_READ) if self.size else b""
        return self._map

    def read_at(self, at: int, n: int) -> bytes:
        if self.data is not None:
            return self.data[at:at + n]
        return os.pread(self.fd, n, at)

    def first(self, patterns: tuple[bytes, ...]) -> dict[bytes, int]:
        """The offset of each pattern's first occurrence (-1: none), a chunk at a time."""
        found = dict.fromkeys(patterns, -1)
        overlap = max(map(len, patterns)) - 1
        at = 0
        while at < self.size and -1 in found.values():
            chunk = self.read_at(at, _CHUNK + overlap)
            for pattern, where in found.items():
                if where < 0:
                    i = chunk.find(pattern)
                    found[pattern] = at + i if i >= 0 else -1
            at += _CHUNK
        return found

    def any_beyond_ascii(self) -> bool:
        return any(_NOT_ASCII.search(self.read_at(at, _CHUNK))
                   for at in range(0, self.size, _CHUNK))

    def close(self) -> None:
        if self._map is not None and not isinstance(self._map, bytes):
            self._map.close()


_CHUNK = 16 << 20


class _Lines:
    """The lines of a buffer (bytes or a memory map), found only when a message needs one.

    A large file is never decoded and split whole: the offsets of its line
    breaks are found on the first fault, and each line decoded on demand.
    """

    def __init__(self, source: _Buffer):
        self.source = source
        self._starts: array | None = None

    @property
    def buffer(self):
        return self.source.view

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
        return len(self._index()) if self.source.size else 0

    def __getitem__(self, i: int) -> str:
        starts = self._index()
        end = starts[i + 1] - 1 if i + 1 < len(starts) else len(self.buffer)
        line = bytes(self.buffer[starts[i]:end]).decode("utf-8", "replace")
        line = line[:-1] if line.endswith("\n") else line     # the file's final newline
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

    def __init__(self, src, lines: _Lines, careful: bool, cdata: bool):
        self.src = src            # the locator of messages, over lazy lines
        self.lines = lines
        self.cdata = cdata        # a CDATA section somewhere: each <text> looked at closer
        self.ns = None            # the document's namespace: PNML's, or "" for none
        self.errors: list[PnmlError] = []
        # plain values only, no element kept: ids are checked in bulk at the end and
        # a fault found then is located by searching the file for its id
        self.ids: list[str] = []                    # every id: nets, pages, nodes, arcs
        self.places: list = []                      # (id, name, interface, payload, position)
        self.transitions: list = []                 # (id, name, timing, payload, position)
        self.marking: dict[str, int] = {}
        self.arc_ids: list = []                     # the arcs, in four aligned columns
        self.sources: list = []
        self.targets: list = []
        self.weights: list = []
        self.read: set = set()                      # indices of arcs marked <read/>
        self.decode = False
        self.more = 0             # faults past those said: counted only
        self.refused_ids: set = set()   # ids of refused nodes, which their arcs do not name
        self.nets = 0
        self.net_name = None
        self.net_id = None
        self.fast = FAST and not careful
        # one string per name, however many arcs name it: a million arcs' ends are then
        # references to the nodes' own ids, not two million strings
        self.names: dict[str, str] = {}
        self._payloads: dict[str, object] = {}

    # -- messages ------------------------------------------------------------------------

    def error(self, el, message: str) -> None:
        if self.counted():
            loc = self.src.locate(el) if el is not None else Location(self.src.filename)
            self.errors.append(PnmlError(message, loc))

    def counted(self) -> bool:
        """One more fault: whether it is one of those said (else it is counted only)."""
        if len(self.errors) < MAX_FAULTS:
            return True
        self.more += 1
        if self.more + len(self.errors) >= MAX_COUNTED:
            raise _TooMany()
        return False

    def refuse(self, stopped: bool = False) -> None:
        """Raise the faults found, if any: those said, and how many more."""
        if len(self.errors) == 1 and not self.more:
            raise self.errors[0]
        if self.errors:
            raise _Faults(_in_order(self.errors), self.more, stopped)

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
        self.T_INTERFACE, self.T_PAYLOAD, self.T_TIMING, self.T_READ = map(
            q, ("interface", "payload", "timing", "read"))

    # -- what may stand where --------------------------------------------------------------

    def stray(self, el, where: str) -> None:
        """An element the grammar does not put here: refused with what it is."""
        name = _raw_name(el)
        local = _local(el.tag)
        coloured = HIGH_LEVEL.get(local) or ("a place's sort" if local == "type" and
                                            where.startswith("in place") else None)
        if coloured:   # one message says it: the rest of the net is coloured alike
            raise _Fatal(PnmlError(
                f"<{name}> is {coloured}: this is a coloured (high-level) net, whatever its "
                "type says, and a P/T reading would drop its colours and tokens; unfold it "
                "to a P/T net first", self.src.locate(el)))
        ns = el.tag[1:].split("}", 1)[0] if el.tag.startswith("{") else ""
        if el.prefix is not None or ns != self.ns:
            said = f"<{name}>" + (f" in the namespace '{ns}'" if ns else " in no namespace")
            self.error(el, f"{said} {where}: PNML elements are in the document's namespace "
                           f"('{self.ns or 'none'}'), written without a prefix; tools that "
                           "match names read it differently, so it is refused" + LENIENT_HINT)
        elif local in REFUSED:
            if local.startswith("reference") and el.get("id"):
                self.refused_ids.add(el.get("id"))   # its arcs go without saying
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
                       "guard": "a data Petri net's guard"}.get(key)
                if why is None:
                    self.error(el, f"<{_raw_name(el)}> has the attribute {shown}, which is not "
                                   "in the P/T grammar")
                else:
                    self.error(el, f"<{_raw_name(el)}> has the attribute {shown}: {why}; "
                                   "refused, since tools give it different meanings"
                                   + LENIENT_HINT)

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
            if child.prefix is not None and isinstance(tag, str):
                self.stray(child, f"in <{_raw_name(label)}>")
            elif tag == self.T_TEXT:
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
            if required and not any(isinstance(c.tag, str) for c in label):
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
        if weight and match is None and _NUMBER.match(text):
            self.error(label, f"{what}: the inscription's number {text.strip()!r} has a line "
                              "break around it, which verifypn refuses; write it on the line "
                              "of its <text>" + LENIENT_HINT)
            return None
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
            value, fault = payload_value(text)
            if fault:
                self.error(el, fault)
            self._payloads[text] = value
        return value

    def position(self, graphics):
        """A node's position, None if it has none or a bad one (a drawing hint only:
        dropped), _NO if a <position> lacks a coordinate."""
        for child in graphics:
            if child.tag == self.T_POSITION and (child.get("x") is None or child.get("y") is None):
                return _NO
        for child in graphics:
            if child.tag == self.T_POSITION:
                xy = coordinates(child)
                return xy if xy and abs(xy[0]) < 1e300 and abs(xy[1]) < 1e300 else None
        return None

    # -- nodes -----------------------------------------------------------------------------

    def node_id(self, el) -> str | None:
        """The element's id, kept for the checks of all ids at the end (:meth:`check_ids`)."""
        xml_id = el.get("id")
        if xml_id is None:
            self.error(el, f"<{_raw_name(el)}> has no id")
            return None
        self.ids.append(xml_id)
        return xml_id

    def placed(self, el) -> bool:
        """Is a node (or page) where the grammar puts it: in a page or straight in the net?"""
        parent = el.getparent()
        if parent is not None and parent.tag not in self.containers and any(
                _local(a.tag) in REFUSED for a in el.iterancestors()):
            return False   # inside a construct refused for what it is (a final marking)
        if parent is None or parent.tag not in self.containers:
            self.stray(el, f"in <{_raw_name(parent)}>" if parent is not None else "at the top")
            return False
        if el.prefix is not None:
            self.stray(el, f"in <{_raw_name(parent)}>")
            return False
        return True

    def place(self, el) -> None:
        self.node(el, place=True)

    def transition(self, el) -> None:
        self.node(el, place=False)

    def node(self, el, place: bool) -> None:
        """A place or a transition the careful way: every child checked, every fault said.
        A place may have its marking and our fusion label, a transition our timing."""
        if not self.placed(el):
            return
        self.attributes(el, _ID_ONLY)
        xml_id = self.node_id(el)
        kind = "place" if place else "transition"
        ours = "interface" if place else "timing"
        name = extra = payload = position = None
        tokens = 0
        seen: set = set()
        for child in el:
            tag = child.tag
            if child.prefix is not None and isinstance(tag, str):
                self.stray(child, f"in {kind} '{xml_id}'")
            elif tag == self.T_NAME:
                if self.once(el, seen, child):
                    name = self.text_of(child, required=False)
            elif place and tag == self.T_MARKING:
                if self.once(el, seen, child):
                    tokens = self.number(child, f"place '{xml_id}'", weight=False) or 0
            elif tag == self.T_TOOL:
                self.free(child, in_label=False)
                if self.ours(child):
                    for inner in child:
                        if _local(inner.tag) == ours:
                            extra = inner.get("label") if place else self.timing(inner, xml_id)
                        elif _local(inner.tag) == "payload":
                            payload = self.payload(inner)
            elif tag == self.T_GRAPHICS:
                if self.once(el, seen, child):
                    self.free(child, in_label=False)
                    position = self.position(child)
                    if position is _NO:
                        position = None
                        self.error(child, f"a <position> without both x and y in {kind} "
                                          f"'{xml_id}': verifypn's reader crashes on it; give "
                                          "both or none")
            elif isinstance(tag, str):
                self.stray(child, f"in {kind} '{xml_id}'")
        self.mixed(el)
        if xml_id is not None:
            xml_id = self.names.setdefault(xml_id, xml_id)
            (self.places if place else self.transitions).append(
                (xml_id, name, extra, payload, position))
            if tokens:
                self.marking[xml_id] = tokens

    def timing(self, el, xml_id) -> Timing | None:
        timing = _timing_value(el)
        if timing is not None:
            return timing
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
            if child.prefix is not None and isinstance(tag, str):
                self.stray(child, f"in arc '{xml_id}'")
            elif tag == self.T_INSCRIPTION:
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
        if xml_id is not None and weight is not None:
            self.add_arc(xml_id, source, target, weight, read)

    def add_arc(self, xml_id: str, source: str, target: str, weight: int, read: bool) -> None:
        if read:
            self.read.add(len(self.arc_ids))
        self.arc_ids.append(xml_id)
        self.sources.append(self.names.setdefault(source, source))
        self.targets.append(self.names.setdefault(target, target))
        self.weights.append(weight)

    # -- the fast paths: the shapes writers use, checked in few steps; anything else (or
    # anything wrong) is left to the careful methods above, which say where and why

    def fast_text(self, label):
        """The plain text of a simple label, None if it has no <text>, _NO if it is not
        simple (the careful :meth:`text_of` then reads it, or says what is wrong)."""
        text = label.text
        if (text is not None and text.strip()) or label.keys():
            return _NO
        found = None
        for child in label:
            tag = child.tag
            tail = child.tail
            if tail is not None and tail.strip():
                return _NO
            if tag == self.T_TEXT:
                if found is not None or len(child) or child.keys():
                    return _NO
                found = child
            elif tag == self.T_GRAPHICS or tag == self.T_TOOL:
                if not _free_ok(child, True):
                    return _NO
            elif isinstance(tag, str):
                return _NO
        return None if found is None else (found.text or "")

    def plain(self, label):
        """:meth:`fast_text` of the common label, one plain <text> and nothing else, in the
        fewest steps (a name per node: 400,000 of them in a large mission)."""
        if len(label) == 1 and label.text is None:
            inner = label[0]
            if inner.tag == self.T_TEXT and not len(inner) and inner.tail is None \
                    and not label.keys() and not inner.keys():
                return inner.text or ""
        return self.fast_text(label)

    def fast_common(self, child, tag, state: list) -> bool:
        """A node's name, graphics or other tools' data; False where not simple."""
        if tag == self.T_NAME:
            if state[0] is not _UNSET:
                return False
            state[0] = self.plain(child)
            return state[0] is not _NO
        if tag == self.T_GRAPHICS:
            if state[1] is not _UNSET or not _free_ok(child, False):
                return False
            state[1] = self.position(child)
            return state[1] is not _NO
        return False

    def fast_place(self, el) -> bool:
        return self.fast_node(el, place=True)

    def fast_transition(self, el) -> bool:
        return self.fast_node(el, place=False)

    def fast_node(self, el, place: bool) -> bool:
        """A place or a transition in few steps, as :meth:`node` reads it; False where it
        is not of the simple shapes (the careful way then reads it, or says what is wrong)."""
        if el.keys() != _ID_KEYS:    # (no prefix: the fast paths run where none is declared)
            return False
        text = el.text
        if text is not None and text.strip():
            return False
        state = [_UNSET, _UNSET]
        tokens = extra = payload = None    # extra: a place's fusion label, a transition's timing
        ours = self.T_INTERFACE if place else self.T_TIMING
        for child in el:
            tail = child.tail
            if tail is not None and tail.strip():
                return False
            tag = child.tag
            if place and tag == self.T_MARKING:
                if tokens is not None:
                    return False
                text = self.plain(child)
                match = _NUMBER.match(text) if isinstance(text, str) else None
                if match is None or len(match.group(1)) > 10:
                    return False
                tokens = int(match.group(1))
                if tokens > MAX_MARKING:
                    return False
            elif tag == self.T_TOOL:
                if child.get("tool") == TOOL:
                    for inner in child:
                        name = inner.tag
                        if name == ours and extra is None and not len(inner):
                            extra = inner.get("label") if place else _timing_value(inner)
                            if extra is None and not place:
                                return False
                        elif name == self.T_PAYLOAD and payload is None and not len(inner):
                            payload = self.payload(inner)
                        elif isinstance(name, str):
                            return False
                elif not _free_ok(child, False):
                    return False
            elif not self.fast_common(child, tag, state) and isinstance(tag, str):
                return False
        xml_id = el.get("id")
        self.ids.append(xml_id)
        xml_id = self.names.setdefault(xml_id, xml_id)
        name, position = state
        (self.places if place else self.transitions).append(
            (xml_id, None if name is _UNSET else name, extra, payload,
             None if position is _UNSET else position))
        if tokens:
            self.marking[xml_id] = tokens
        return True

    def fast_arc_of(self):
        """The fast path of arcs, a closure over what it needs: a million arcs make every
        attribute lookup count."""
        T_INSCRIPTION, T_TEXT, T_TOOL, T_READ = (self.T_INSCRIPTION, self.T_TEXT, self.T_TOOL,
                                                 self.T_READ)
        weight_match, fast_text, common = _WEIGHT.match, self.fast_text, self.fast_common
        add_id, add_arc_id = self.ids.append, self.arc_ids.append
        add_source, add_target, add_weight = (self.sources.append, self.targets.append,
                                              self.weights.append)
        name = self.names.setdefault
        read_arcs, arc_ids = self.read, self.arc_ids

        def fast_arc(el) -> bool:
            # (no prefix to look for: the fast paths run only in a file that declares none)
            if el.keys() != _ARC_KEYS:
                return False
            text = el.text
            if text is not None and text.strip():
                return False
            weight = None
            read = False
            state = None
            for child in el:
                tail = child.tail
                if tail is not None and tail.strip():
                    return False
                tag = child.tag
                if tag == T_INSCRIPTION and weight is None:
                    # the common label: one plain <text>, nothing else
                    if len(child) == 1 and child.text is None and not child.keys():
                        inner = child[0]
                        if inner.tag != T_TEXT or len(inner) or inner.tail is not None \
                                or inner.keys():
                            return False
                        text = inner.text or ""
                    else:
                        text = fast_text(child)
                        if not isinstance(text, str):
                            return False
                    match = weight_match(text)
                    if match is None or len(match.group(1)) > 10:
                        return False
                    weight = int(match.group(1))
                    if not 0 < weight <= MAX_WEIGHT:
                        return False
                elif tag == T_TOOL:
                    if child.get("tool") == TOOL:
                        for inner in child:
                            if inner.tag == T_READ and not len(inner):
                                read = True
                            elif isinstance(inner.tag, str):
                                return False
                    elif not _free_ok(child, False):
                        return False
                elif isinstance(tag, str):
                    if state is None:
                        state = [_UNSET, _UNSET]
                    if not common(child, tag, state):
                        return False
            xml_id, source, target = el.values()     # in the order of _ARC_KEYS
            add_id(xml_id)
            if read:
                read_arcs.add(len(arc_ids))
            add_arc_id(xml_id)
            add_source(name(source, source))
            add_target(name(target, target))
            add_weight(weight or 1)
            return True
        return fast_arc

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
            if child.prefix is not None and isinstance(tag, str):
                self.stray(child, f"in <{_raw_name(el)}> '{el.get('id')}'")
            elif tag == self.T_NAME:
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
        """The net: ids checked, arcs added up by their ends as verifypn adds parallel arcs.

        Our read arc is the pair (p -> t, t -> p), both halves marked, whose
        return may also carry the transition's own arc into the place (one
        arc per pair of ends in a file): read as a read arc when every arc
        between the two is marked and the return is at least the take.
        Anything else marked read is read as the arcs it is, which is what
        it does.
        """
        self.check_ids()
        place_ids = [p[0] for p in self.places]
        transition_ids = [t[0] for t in self.transitions]
        places, transitions = set(place_ids), set(transition_ids)
        if self.errors:
            self.say_bad_arcs(places, transitions)
            self.refuse()
        rename = self.renaming(place_ids + transition_ids)
        sources, targets, weights = self.sources, self.targets, self.weights
        if rename:
            sources = list(map(rename.get, sources, sources))
            targets = list(map(rename.get, targets, targets))
            places = {rename.get(p, p) for p in places}
        # as written: the core checks in C that every arc joins a place and a transition
        # and that no two join the same ends; where it does not hold, the arcs are said
        # one by one, or added up
        arcs = list(map(Arc, sources, targets, weights))
        if self.read:
            arcs = self.joined(arcs, places)
        try:
            return self.net(arcs, rename)
        except NetError:
            pass
        self.say_bad_arcs(places if not rename else set(place_ids), transitions)
        self.refuse()
        return self.net(self.summed(list(zip(sources, targets)), weights, places), rename)

    def net(self, arcs: list, rename: dict) -> Net:
        if rename:
            get = rename.get
            nodes = ([Place(get(i, i), *rest) for i, *rest in self.places],
                     [Transition(get(i, i), *rest) for i, *rest in self.transitions])
            marking = Marking({get(p, p): n for p, n in self.marking.items()})
        else:
            nodes = ([Place(*p) for p in self.places], [Transition(*t) for t in self.transitions])
            marking = Marking(self.marking)
        return Net(self.net_name or self.net_id or "net", tuple(nodes[0]), tuple(nodes[1]),
                   tuple(arcs), marking)

    def summed(self, pairs: list, weights: list, places: set) -> list:
        """Arcs between the same ends added up, and our read arcs joined again."""
        take: dict[tuple[str, str], int] = {}     # (place, transition) -> tokens taken
        give: dict[tuple[str, str], int] = {}     # (transition, place) -> tokens given
        marked: set = set()                       # (place, transition) pairs marked read
        plain: set = set()                        # ... with an unmarked arc between them
        read = self.read
        for k, ((s, d), w) in enumerate(zip(pairs, weights)):
            if s in places:
                take[(s, d)] = take.get((s, d), 0) + w
                pair = (s, d)
            else:
                give[(s, d)] = give.get((s, d), 0) + w
                pair = (d, s)
            (marked if k in read else plain).add(pair)
        arcs = []
        for (p, t), w in take.items():
            back = give.get((t, p))
            if back is not None and back >= w and (p, t) in marked and (p, t) not in plain:
                arcs.append(Arc(p, t, w, ArcKind.READ))
                if back > w:
                    arcs.append(Arc(t, p, back - w))
                give[(t, p)] = 0
            else:
                arcs.append(Arc(p, t, w))
        arcs += [Arc(t, p, w) for (t, p), w in give.items() if w]
        return arcs

    def joined(self, arcs: list, places: set) -> list:
        """Our read arcs joined again, in a net with no two arcs between the same ends:
        both halves of a pair are then marked (:meth:`summed` says the rule)."""
        marked = {(arcs[k].source, arcs[k].target): k for k in self.read}
        drop, out = set(), []
        for (s, d), k in marked.items():
            back = marked.get((d, s))
            w = arcs[k].weight
            # which end is the place: the one that is a place in the net
            if back is None or s not in places or arcs[back].weight < w:
                continue
            drop.update((k, back))
            out.append(Arc(s, d, w, ArcKind.READ))
            if arcs[back].weight > w:
                out.append(Arc(d, s, arcs[back].weight - w))
        if not drop:
            return arcs
        return [a for k, a in enumerate(arcs) if k not in drop] + out

    def check_ids(self) -> None:
        """Every id of the file: unique, and read alike by every reader (checked over all
        ids at once; a fault is then found and located id by id)."""
        ids = self.ids
        joined = "\x00" + "\x00".join(ids) + "\x00"    # XML has no NUL: a safe separator
        if _BAD_IDS.search(joined):
            for xml_id in ids:
                if not xml_id or _BAD_IDS.search(f"\x00{xml_id}\x00"):
                    self.error_id(xml_id, f"the id {xml_id!r} {_id_fault(xml_id)}")
        if len(set(ids)) != len(ids):
            first: set = set()
            for xml_id in ids:
                if xml_id in first:
                    self.error_id(xml_id, f"duplicate id '{xml_id}' (first used on line "
                                          f"{self.line_of_id(xml_id)})", nth=2)
                first.add(xml_id)
        # an XML parser folds a tab or a line break in an attribute into a space, a reader
        # of bytes keeps it: an id with a space must be written with spaces only
        # (an arc's end with a space names a node only if a node's id has one)
        spaced = [i for i in (*ids, *self.sources, *self.targets) if " " in i] \
            if " " in joined else []
        for value in dict.fromkeys(spaced):
            if not self.written_as_is(value):
                self.error_id(value, f"the id {value!r} is written with a tab or a line "
                                     "break (or a character reference) where it reads a "
                                     "space: readers of bytes keep them, XML parsers fold "
                                     "them, so the two name different nodes")

    def written_as_is(self, value: str) -> bool:
        quoted = [f'"{value}"'.encode(), f"'{value}'".encode()]
        buffer = self.lines.buffer
        return any(buffer.find(q) >= 0 for q in quoted)

    def renaming(self, node_ids: list) -> dict:
        """Our writer's escaped ids (``_xHHHH_``) decoded, where the file says it escapes
        them; two ids that decode to one are refused where the second is."""
        if not self.decode:
            return {}
        rename = {i: ids.decode(i) for i in node_ids if "_x" in i}
        rename = {k: v for k, v in rename.items() if k != v}
        if rename:
            seen: dict[str, str] = {}
            for raw in node_ids:
                name = rename.get(raw, raw)
                if name in seen:
                    self.error_id(raw, f"the id '{raw}' reads as '{name}' once its escapes "
                                       f"are decoded (the file says its ids are escaped), as "
                                       f"'{seen[name]}' does: two nodes of one name")
                seen.setdefault(name, raw)
            self.refuse()
        return rename

    def say_bad_arcs(self, places: set, transitions: set) -> None:
        for xml_id, s, d in zip(self.arc_ids, self.sources, self.targets):
            s_place, d_place = s in places, d in places
            if s in self.refused_ids or d in self.refused_ids:
                continue
            for end, name in (("source", s), ("target", d)):
                if name not in places and name not in transitions:
                    self.error_id(xml_id, f"arc '{xml_id}': its {end} '{name}' is not a place "
                                          "or transition of this net")
                    break
            else:
                if s_place == d_place:
                    kind = "place" if s_place else "transition"
                    self.error_id(xml_id, f"arc '{xml_id}' goes from {kind} '{s}' to {kind} "
                                          f"'{d}'; an arc joins a place and a transition")

    def line_of_id(self, xml_id: str, nth: int = 1) -> int | None:
        at = self.find_id(xml_id, nth)
        return None if at is None else self.lines.line_of(at[0])

    def find_id(self, xml_id: str, nth: int = 1):
        """Where the ``nth`` element with this id starts in the file: (offset, column).
        The id as the file may write it (:func:`_written_id`): a fault is located only once
        found, so this slower search runs only where there is one."""
        buffer = self.lines.buffer
        pattern, at = _written_id(xml_id), -1
        for _ in range(nth):
            match = pattern.search(buffer, at + 1)
            if match is None:
                return None
            at = match.start()
        tag = buffer.rfind(b"<", 0, at)
        return (tag if tag >= 0 else at), None

    def error_id(self, xml_id: str, message: str, nth: int = 1) -> None:
        """A fault found once the file was read, at the element with this id."""
        if not self.counted():
            return
        at = self.find_id(xml_id, nth)
        if at is None:
            self.errors.append(PnmlError(message, self.src.at(None)))
            return
        line = self.lines.line_of(at[0])
        column = at[0] - self.lines._index()[line - 1] + 1
        self.errors.append(PnmlError(message, self.src.at(line, column)))

    def error_at(self, line: int | None, message: str) -> None:
        if self.counted():
            self.errors.append(PnmlError(message, self.src.at(line)))

    def net_end(self, el, root) -> None:
        """A net's end tag: the one net of the file, straight under <pnml>."""
        parent = el.getparent()
        self.nets += parent is root
        if parent is not None and parent.tag == self.T_PAGE:
            raise _Fatal(PnmlError(
                f"a <net> inside <page> '{parent.get('id')}' (a WoPeD subprocess): tools read "
                "it as a separate net, as part of this one, or as the refinement of a "
                "transition; flatten it into one page" + LENIENT_HINT, self.src.locate(el)))
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


_ID_KEYS = ["id"]
_ARC_KEYS = ["id", "source", "target"]
_UNSET = object()     # a label not met yet
_NO = object()        # a shape the fast path leaves to the careful one


def _free_ok(el, in_label: bool) -> bool:
    """Whether free content (:meth:`_StrictReader.free`) holds nothing to refuse."""
    forbidden = _IN_LABEL if in_label else NODE_NAMES
    for inner in el.iter():
        tag = inner.tag
        if isinstance(tag, str) and inner is not el and \
                tag.rsplit("}", 1)[-1] in forbidden:
            return False
    return True


def _timing_value(el) -> Timing | None:
    """Our timing data, or None where it is not a good one (said by the careful path)."""
    try:
        latest = el.get("latest")
        timing = Timing(float(el.get("earliest", "0")), None if latest is None else float(latest))
    except (ValueError, Mcl2PnmlError):
        return None
    return timing if max(timing.earliest, timing.latest or 0.0) <= MAX_SECONDS else None


#: The entities XML predefines, by the character each stands for.
_NAMED = {"&": b"amp", "<": b"lt", ">": b"gt", '"': b"quot", "'": b"apos"}


def _written_id(xml_id: str) -> "re.Pattern[bytes]":
    """``id="..."`` as it may be written for ``xml_id``: each character as itself, as a
    character reference (decimal or hexadecimal), as a predefined entity, or, for a
    space, as the white space an XML parser folds into one."""
    parts = []
    for c in xml_id:
        hexa = "".join(f"[{d}{d.upper()}]" if d.isalpha() else d for d in f"{ord(c):x}")
        options = [re.escape(c.encode()), b"&#0*" + str(ord(c)).encode() + b";",
                   b"&#x0*" + hexa.encode() + b";"]
        if c in _NAMED:
            options.append(b"&" + _NAMED[c] + b";")
        if c == " ":
            options.append(rb"[\t\n\r]")
        parts.append(b"(?:" + b"|".join(options) + b")")
    # XML lets white space stand on either side of the '=' (its production Eq)
    return re.compile(rb"""\bid[ \t\r\n]*=[ \t\r\n]*(?:"|')""" + b"".join(parts)
                      + rb"""(?:"|')""")


def _id_fault(xml_id: str) -> str:
    """What is wrong with an id that :data:`_BAD_IDS` finds."""
    if not xml_id:
        return "is empty"
    if xml_id != xml_id.strip():
        return "starts or ends with white space, which some tools trim and others keep"
    if re.search(r"[&<>\"']", xml_id):
        return ("holds one of & < > \" ', which tools write back unescaped, breaking their own "
                "files")
    return "holds a control character, which readers keep or fold differently"


def _in_order(errors: list) -> list:
    """Faults in the order of the file (an element is checked at its end tag, so that a
    page's fault would otherwise follow its nodes')."""
    return sorted(errors, key=lambda e: (e.location.line or 0, e.location.column or 0)
                  if e.location else (0, 0))


class _TooMany(Exception):
    """Enough faults for one message: stop reading."""


class _Faults(ErrorList):
    """The faults of a file: the first :data:`MAX_FAULTS` with their lines, and how many
    more were counted (at least, where reading stopped at :data:`MAX_COUNTED`)."""

    def __init__(self, errors: list, more: int, stopped: bool):
        self.more, self.stopped = more, stopped
        super().__init__(errors)

    def __str__(self) -> str:
        lines = [str(e) for e in self.errors]
        if self.more:
            lines.append(f"... and {'at least ' if self.stopped else ''}{self.more:,} more "
                         f"errors (the first {len(self.errors)} are shown)")
        return "\n".join(lines)


class _Fatal(Exception):
    """A fault that says all there is to say of the file (coloured content)."""

    def __init__(self, error: PnmlError):
        super().__init__(error.message)
        self.error = error


#: Another tool's own dialect, told by the head of the file: (pattern, what it is).
DIALECTS = (
    (re.compile(rb"""xmlns\s*=\s*["']http://www\.informatik\.hu-berlin\.de/top/pnml/ptNetb["']"""
                rb"""|<place\b[^>]*\sinitialMarking\s*=|<(?:input|output|transport|inhibitor)Arc\b"""),
     "TAPAAL's own format (a timed-arc net, its markings and weights in attributes), which "
     "P/T tools read differently (verifypn refuses its timed arcs); export PNML from TAPAAL, "
     "or read it"),
    (re.compile(rb"""<net\b[^>]*\btype\s*=\s*["']P/T net["']"""),
     "PIPE's own dialect of PNML (net type 'P/T net', labels in <value>: 'Default,1'), which "
     "P/T tools read differently (verifypn reads every marking as 0); export standard PNML, "
     "or read it"),
)
_STANDARD = re.compile(rb"""<pnml\b[^>]*\bxmlns\s*=\s*["']http://www\.pnml\.org/version-2009/grammar/pnml["']""")
#: The largest dialect file read the forgiving way to say what it holds that a P/T net
#: cannot (past it, the dialect alone is named).
DIALECT_EXPLAINED = 64 << 20


def _dialect(buffer: _Buffer, filename: str) -> None:
    """Refuse another tool's dialect: with the forgiving reader's own refusal where it
    finds what a P/T net cannot say (colours, inhibitor arcs, time), else as the dialect."""
    head = buffer.read_at(0, 1 << 16)
    if _STANDARD.search(head):
        return   # in PNML's namespace: what another dialect would mean there is said strictly
    for pattern, what in DIALECTS:
        match = pattern.search(head)
        if match is None:
            continue
        if buffer.size <= DIALECT_EXPLAINED:
            try:
                parse_lenient(buffer.read_at(0, buffer.size), filename)
            except PnmlError as e:   # what it finds, with advice the strict reading keeps
                for fault in getattr(e, "errors", [e]):
                    fault.message = fault.message.replace("with --net ID",
                                                          "with --lenient --net ID")
                raise
        line = head.count(b"\n", 0, match.start()) + 1
        column = match.start() - (head.rfind(b"\n", 0, match.start()) + 1) + 1
        src_line = head.split(b"\n")[line - 1].decode("utf-8", "replace")
        raise PnmlError(f"this is {what} with --lenient, which no proof trusts",
                        Location(filename, line, column, src_line))


def _prolog_faults(buffer: _Buffer, filename: str) -> None:
    """What is refused before parsing: another encoding, a document type declaration."""
    head = buffer.read_at(0, 4)
    if head[:2] in (b"\xff\xfe", b"\xfe\xff") or b"\x00" in head:
        raise PnmlError("the file is not UTF-8 (it looks like UTF-16 or UTF-32): readers "
                        "that take bytes as UTF-8 read it differently; save it as UTF-8",
                        Location(filename, 1, 1))
    declared = _ENCODING.match(buffer.read_at(0, 512))
    if declared and declared.group(1).decode("ascii", "replace").lower() not in (
            "utf-8", "utf8", "us-ascii", "ascii") and buffer.any_beyond_ascii():
        name = declared.group(1).decode("ascii", "replace")
        raise PnmlError(f"the file declares the encoding '{name}' and holds characters "
                        "beyond ASCII: readers that take bytes as UTF-8 read them "
                        "differently; save it as UTF-8", 
                        Location(filename, 1, 1))


def _parse(source, buffer, filename: str, net_id: str | None) -> Net:
    """The net of the document in ``buffer`` (read from ``source``), read strictly
    (docs/pnml.md): its prolog and dialect first, then its elements as a stream."""
    _prolog_faults(buffer, filename)
    _dialect(buffer, filename)
    lines = _Lines(buffer)
    src = Source.__new__(Source)
    src.filename, src.lines = filename, lines
    first = buffer.first((b"<!DOCTYPE", b"<![CDATA[", b"xmlns:"))
    doctype = first[b"<!DOCTYPE"]
    if doctype >= 0:
        line = lines.line_of(doctype)
        raise XmlError("document type declarations are refused: PNML needs none, and "
                       "entities are never expanded or fetched",
                       src.at(line, doctype - lines._index()[line - 1] + 1))
    etree.clear_error_log()   # this thread's log: from here on, this parse's faults only
    # a prefix must be declared to be used: where none is, no element has one, and the
    # fast paths need not look; a CDATA section can hide in any <text>
    cdata = first[b"<![CDATA["] >= 0
    reader = _StrictReader(src, lines, careful=cdata or first[b"xmlns:"] >= 0, cdata=cdata)
    root = None
    try:
        root = _stream(source, reader, src)
    except etree.XMLSyntaxError as e:
        raise _not_well_formed(e, src, lines, filename) from None
    except _TooMany:
        reader.refuse(stopped=True)
    except _Fatal as fatal:
        raise fatal.error from None
    if reader.nets == 0 and not reader.errors:
        raise PnmlError("no <net> in this document", src.locate(root))
    if net_id is not None and reader.net_id is not None and net_id != reader.net_id \
            and not reader.errors:
        raise PnmlError(f"no net with id '{net_id}'; the net in this file: {reader.net_id}",
                        src.at(reader.line_of_id(reader.net_id)))
    try:
        return reader.build()
    except _TooMany:
        reader.refuse(stopped=True)
        raise
    except NetError as e:   # a rule of the core, e.g. a name with a control character
        raise PnmlError(e.message, Location(filename)) from None


def _stream(source, reader: "_StrictReader", src: Source):
    """Read the document as a stream of its nodes, pages and nets as each ends, every other
    element checked inside the one that holds it; the document's root."""
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
            never = lambda el: False      # noqa: E731  (the careful way only)
            on = reader.fast
            # tag -> (its fast path, its careful one)
            handlers = {
                reader.T_PLACE: (reader.fast_place if on else never, reader.place),
                reader.T_TRANSITION: (reader.fast_transition if on else never,
                                      reader.transition),
                reader.T_ARC: (reader.fast_arc_of() if on else never, reader.arc),
                reader.T_PAGE: (never, reader.page)}
            containers = reader.containers
        handler = handlers.get(el.tag)
        if handler is not None:
            parent = el.getparent()
            if parent.tag not in containers or not handler[0](el):
                handler[1](el)            # the careful way: it says what is wrong
            parent.remove(el)             # read: dropped, so the stream stays small
        elif el.tag == reader.T_NET:
            reader.net_end(el, root)
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
    return root


def _not_well_formed(e: etree.XMLSyntaxError, src: Source, lines: "_Lines",
                     filename: str) -> XmlError:
    """libxml2's syntax error as one message at the first fault of this parse."""
    line, col = getattr(e, "position", (e.lineno, None))
    msg = str(e.msg).split(f", line {line}")[0]
    # the first fault of this parse, where it is
    logged = [x for x in e.error_log if x.line and x.domain == etree.ErrorDomains.PARSER]
    if logged and (not line or logged[0].line < line):
        line, col, msg = logged[0].line, logged[0].column, logged[0].message
    if not line:   # no element at all: said where the file ends
        line = max(1, len(lines))
        col = len(lines[line - 1]) + 1 if len(lines) else 1
    where = src.at(line, col) if len(lines) else Location(filename, 1, 1, "")
    return XmlError(f"not well-formed XML: {msg}", where)


def _root(root, reader, src):
    """The document's root, which must be <pnml>: its namespace is the document's."""
    if root is None or _local(root.tag) != "pnml" or root.prefix is not None:
        name = _raw_name(root) if root is not None else "nothing"
        raise PnmlError(f"the root element is <{name}>, not <pnml>",
                        src.locate(root) if root is not None else src.at(1))
    ns = root.tag[1:].split("}", 1)[0] if root.tag.startswith("{") else ""
    if ns == TAPAAL:   # written with a prefix, past the head: the dialect all the same
        raise PnmlError("this is TAPAAL's own format (a timed-arc net, its markings and "
                        "weights in attributes), which P/T tools read differently (verifypn "
                        "refuses its timed arcs); export PNML from TAPAAL" + LENIENT_HINT,
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
    return _parse(io.BytesIO(data), _Buffer(data), filename, net_id)


@without_gc
def read_strict(path: str | Path, net_id: str | None = None) -> Net:
    """Read one P/T net from a PNML file, strictly, as a stream (never whole in memory)."""
    try:
        fd = open_regular(path)
    except Mcl2PnmlError as e:
        raise PnmlError(e.message, e.location) from None
    with os.fdopen(fd, "rb") as f:
        size = os.fstat(f.fileno()).st_size
        if size == 0:
            return parse_strict(read_file(path), str(path), net_id)
        buffer = _Buffer(fd=f.fileno(), size=size)
        try:
            return _parse(f, buffer, str(path), net_id)
        finally:
            buffer.close()
