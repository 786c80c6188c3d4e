"""What both PNML readers share: the bytes of a file, XML parsed without entities or
fetches, and elements mapped back to their line and column for messages with a caret."""
from __future__ import annotations

import json
from pathlib import Path

from lxml import etree

from mcl2pnml.core.errors import Location, Mcl2PnmlError, PnmlError, source_lines
from mcl2pnml.core.files import json_fault, read_bytes
from mcl2pnml.core.net import freeze

#: Elements that only coloured (high-level) nets have, with what they are.
HIGH_LEVEL = {
    "declaration": "a declaration of sorts and variables",
    "declarations": "a declaration of sorts and variables",
    "hlinitialMarking": "a high-level initial marking",
    "hlinscription": "a high-level arc inscription",
    "condition": "a transition guard",
    "multiset": "a marking written as a multiset of coloured tokens",
}


class XmlError(PnmlError):
    """The bytes are not a well-formed, declaration-free XML document."""


def local(el) -> str:
    tag = el.tag
    if not isinstance(tag, str):  # comments, processing instructions
        return ""
    return tag.rsplit("}", 1)[-1]


class Source:
    """Maps elements back to line and column, for messages with a caret."""

    def __init__(self, filename: str, data: bytes):
        self.filename = filename
        self.lines = source_lines(data.decode("utf-8", errors="replace"))

    def at(self, line: int | None, column: int | None = None) -> Location:
        if not line or line < 1 or not self.lines:
            return Location(self.filename)
        if line > len(self.lines):
            # libxml2 puts "premature end of data" on the line after a final
            # newline: shown at the end of the last line, where the file stops
            line = len(self.lines)
            column = len(self.lines[-1]) + 1
        text = self.lines[line - 1]
        column = min(max(1, column or 1), len(text) + 1)
        return Location(self.filename, line, column, text)

    def locate(self, el) -> Location:
        line = el.sourceline
        if not line or line > len(self.lines):
            return Location(self.filename)
        return Location(self.filename, line, self._column(el, line), self.lines[line - 1])

    def _column(self, el, line: int) -> int:
        """Where ``el``'s start tag is on its line (lxml keeps no column).

        The tag with this element's id; an element without one is searched
        from its parent's tag on, when the parent starts on the same line,
        so that in a file written on one line (ProM, pm4py) the caret is
        under this arc's inscription, not the first of the line.
        """
        text = self.lines[line - 1]
        name, xml_id = local(el), el.get("id")
        parent = el.getparent()
        start = 0
        if xml_id is None and parent is not None and parent.sourceline == line:
            start = self._column(parent, line)   # 1-based: past the parent's '<'
        col = None
        while True:
            i = text.find("<", start)
            if i < 0:
                break
            j = i + 1
            while j < len(text) and (text[j].isalnum() or text[j] in ":_-."):
                j += 1
            if text[i + 1:j].rsplit(":", 1)[-1] == name:
                if col is None:
                    col = i + 1
                end = text.find(">", j)
                if xml_id is None or f'"{xml_id}"' in text[j:end if end >= 0 else None] \
                        or f"'{xml_id}'" in text[j:end if end >= 0 else None]:
                    col = i + 1
                    break
            start = j
        return col or 1


def doctype_refused(src: Source) -> XmlError:
    line = next((i for i, text in enumerate(src.lines, 1) if "<!DOCTYPE" in text), 1)
    col = src.lines[line - 1].find("<!DOCTYPE") + 1 if src.lines else 1
    return XmlError("document type declarations are refused: PNML needs none, and "
                    "entities are never expanded or fetched", src.at(line, max(col, 1)))


def parse_xml(data: bytes, src: Source):
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False,
                             dtd_validation=False, huge_tree=False, remove_comments=True,
                             remove_pis=True)
    try:
        tree = etree.fromstring(data, parser).getroottree()
    except etree.XMLSyntaxError as e:
        if b"<!DOCTYPE" in data:
            # libxml2 still weighs the declared entities (a bomb fails with
            # "maximum entity amplification" at line 1): the declaration is
            # the fault to name, where it is
            raise doctype_refused(src) from None
        line, col = getattr(e, "position", (e.lineno, None))
        msg = str(e.msg).split(f", line {line}")[0]
        where = src.at(line or 1, col) if src.lines else Location(src.filename, 1, 1, "")
        raise XmlError(f"not well-formed XML: {msg}", where) from None
    except ValueError as e:  # e.g. a str with an encoding declaration
        raise XmlError(f"cannot parse as XML: {e}", src.at(None)) from None
    if tree.docinfo.doctype or tree.docinfo.internalDTD is not None:
        raise doctype_refused(src)
    return tree


def read_file(path: str | Path) -> bytes:
    """A file's bytes, or a :class:`PnmlError` that names it (a FIFO, a device or a
    directory is refused unread: :func:`mcl2pnml.core.files.read_bytes`)."""
    try:
        return read_bytes(path)
    except Mcl2PnmlError as e:
        raise PnmlError(e.message, e.location) from None


def coordinates(position) -> tuple[float, float] | None:
    """A ``<position>``'s x and y as numbers; None where either is not one (a drawing hint
    only: a bad one is dropped, not fatal). Each reader says which numbers it keeps."""
    try:
        return float(position.get("x", "")), float(position.get("y", ""))
    except ValueError:
        return None


def payload_value(text: str | None):
    """Our toolspecific payload, its JSON text as frozen data: ``(value, None)``, or
    ``(None, fault)`` with what is wrong, for the reader to say where it is."""
    try:
        return freeze(json.loads(text or "null")), None
    except (ValueError, RecursionError) as e:
        return None, f"payload is not JSON data: {json_fault(e)}"
    except Mcl2PnmlError as e:
        return None, f"payload is not JSON data: {e}"
