"""What the readers of text formats (TINA, LoLA) share: their syntax errors."""
from __future__ import annotations

from typing import Mapping

from lark import UnexpectedInput

from mcl2pnml.core.errors import Location, Mcl2PnmlError


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
