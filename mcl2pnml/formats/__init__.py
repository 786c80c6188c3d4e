"""Nets in the text formats of other Petri-net tools, written and read.

* :mod:`~mcl2pnml.formats.tina`: TINA's ``.net`` (time Petri nets, LAAS-CNRS);
* :mod:`~mcl2pnml.formats.lola`: LoLA's net format (P/T nets, Rostock).

PNML, the standard, lives in :mod:`mcl2pnml.pnml`. :func:`load_net` reads
any of them by the file's suffix.
"""
from __future__ import annotations

from pathlib import Path
from typing import Mapping

from lark import UnexpectedInput

from ..errors import Location, Mcl2PnmlError
from ..net import Net

#: Suffix -> what the file holds, for the messages that list them.
SUFFIXES = {".pnml": "PNML", ".xml": "PNML", ".net": "TINA", ".lola": "LoLA",
            ".llnet": "LoLA"}


def load_net(path: str | Path) -> Net:
    """A net from a PNML, TINA or LoLA file, chosen by its suffix."""
    path = Path(path)
    kind = SUFFIXES.get(path.suffix.lower())
    if kind == "PNML":
        from ..pnml.reader import load_pnml
        return load_pnml(path)
    if kind == "TINA":
        from .tina import load_tina
        return load_tina(path)
    if kind == "LoLA":
        from .lola import load_lola
        return load_lola(path)
    known = ", ".join(f"{s} ({k})" for s, k in SUFFIXES.items())
    raise Mcl2PnmlError(f"cannot tell the format of '{path.name}' from its suffix; known: "
                        f"{known}, and .mcl for missions", Location(str(path)))


def syntax_error(e: UnexpectedInput, text: str, lines: list[str], filename: str,
                 readable: Mapping[str, str]) -> Mcl2PnmlError:
    """A lark syntax error of a TINA or LoLA reader as one located message.

    ``readable`` names the grammar's terminals for people ("a name", "'->'");
    the others are shown in lower case. An error past the last line points
    at the end of the file.
    """
    line, col = getattr(e, "line", 0), getattr(e, "column", 0)
    if line is None or line < 1:
        line = max(1, len(lines))
        col = len(lines[-1]) + 1 if lines else 1
    expected = sorted({readable.get(t, t.lower()) for t in
                       (getattr(e, "expected", None) or getattr(e, "allowed", None) or ())})
    token = getattr(e, "token", None)
    at = getattr(e, "pos_in_stream", None)
    if token is not None and token.type != "$END":
        found = f"unexpected {str(token)!r}"
    elif token is None and at is not None and at < len(text):
        found = f"unexpected character {text[at]!r}"
    else:
        found = "unexpected end of file"
    hint = f"; expected {', '.join(expected[:8])}" if expected else ""
    src = lines[line - 1] if 0 < line <= len(lines) else None
    return Mcl2PnmlError(f"syntax error: {found}{hint}", Location(filename, line, col, src))
