"""XML ids for node ids that are not XML names.

PNML ids are of type ``xsd:ID``, that is XML NCNames: ``AchieveDepth.MTX`` is
one, but pm4py happily names a place ``({'a'}, {'b'})``. Such ids are written
with the ``_xHHHH_`` escapes of XML name encoding (the convention of
``XmlConvert.EncodeName`` and of spreadsheet XML) and decoded by our reader,
so that any id survives a round trip and the file stays valid.
"""
from __future__ import annotations

import re

_ESCAPE = re.compile(r"_x([0-9A-F]{4,6})_")
_PLAIN = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*\Z")


def _name_char(c: str, first: bool) -> bool:
    """ASCII name characters; anything else is escaped (always valid, and simple)."""
    if not c.isascii():
        return False
    if c == "_" or c.isalpha():
        return True
    return not first and (c.isdigit() or c in ".-")


def encode(node_id: str) -> str:
    """An NCName that :func:`decode` maps back to ``node_id``."""
    if _PLAIN.match(node_id) and "_x" not in node_id:
        return node_id  # the common case, at regex speed
    out = []
    for i, c in enumerate(node_id):
        # an underscore that would read as the start of an escape is escaped itself
        if c == "_" and _ESCAPE.match(node_id, i):
            out.append("_x005F_")
        elif _name_char(c, first=(i == 0)):
            out.append(c)
        else:
            out.append(f"_x{ord(c):04X}_")
    return "".join(out)


def all_plain(node_ids: list[str]) -> bool:
    """Whether :func:`encode` leaves every one of ``node_ids`` as it is.

    The same test as :func:`encode`'s first line, over all ids at once (a
    regex match per id from C, and one search of their join for ``_x``), so
    that a writer can skip encoding a net of 400,000 nodes id by id.
    """
    return all(map(_PLAIN.match, node_ids)) and "_x" not in "\n".join(node_ids)


def decode(xml_id: str) -> str:
    return _ESCAPE.sub(lambda m: chr(int(m.group(1), 16)), xml_id)
