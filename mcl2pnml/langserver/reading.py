"""A document's diagnostics and the fixes of its warnings, as ``mcl2pnml check`` finds them.

The text is checked by the facade as a file is (:func:`mcl2pnml.pipeline.check_source`:
the parser, then the checker, which gives every error of the file at once) and, when it
checks, its warnings are found (:func:`mcl2pnml.pipeline.warnings_of`, docs/warnings.md),
each with its code and its fix. Every diagnostic spans the token its message points at
(:mod:`mcl2pnml.langserver.outline`).

A document over the size the server reads is not checked (one diagnostic says so), and
whatever goes wrong inside the checker is one diagnostic too, never a server that stops:
an editor sends whatever is typed.

Two warnings have a fix that is an edit, the one docs/warnings.md gives: W001's monitor
becomes the condition of an ``if`` (the statements after it then always run), and
W004's condition a statement before the block (a sequence stops at its FAIL).
"""
from __future__ import annotations

import sys
import traceback
from dataclasses import dataclass

from mcl2pnml import pipeline
from mcl2pnml.core.errors import SHOWN_ERRORS, ErrorList, Location, Mcl2PnmlError, visible
from mcl2pnml.langserver.outline import Outline, Token, read

#: The largest document the server checks, in bytes (``mcl2pnml lsp --max-document-size``):
#: a mission of a megabyte is checked in about a second, and an editor asks again at each
#: pause in typing.
MAX_DOCUMENT_SIZE = 1 << 20


@dataclass(frozen=True)
class Diagnostic:
    """One diagnostic: ``severity`` is ``error``, ``warning`` or ``information``; its range
    runs from ``start`` to ``end``, offsets in the text; ``code`` a warning's (W001...)."""

    severity: str
    start: int
    end: int
    message: str
    code: str | None = None


@dataclass(frozen=True)
class Fix:
    """An edit that applies a warning's fix: ``text`` in place of ``start`` to ``end``."""

    title: str
    start: int
    end: int
    text: str


def diagnose(text: str, filename: str, limit: int = MAX_DOCUMENT_SIZE
             ) -> tuple[list[Diagnostic], Outline]:
    """Every error of the document, or its warnings when it has none; and the outline
    their offsets are in (of nothing, for a document over ``limit`` bytes)."""
    size = size_of(text)
    if size > limit:
        return [Diagnostic("information", 0, 0,
                           f"this document is {size:,} bytes, over the {limit:,} the language "
                           "server checks (mcl2pnml lsp --max-document-size): it is not "
                           "checked here; `mcl2pnml check` checks it")], read("")
    outline = read(text)
    try:
        checked = pipeline.check_source(text, filename)
        warnings = pipeline.warnings_of(checked)
    except ErrorList as e:
        return _errors(outline, e.errors), outline
    except Mcl2PnmlError as e:
        return _errors(outline, [e]), outline
    except Exception as e:   # noqa: BLE001 (a fault of ours: said, and the server goes on)
        traceback.print_exc(file=sys.stderr)
        return [Diagnostic("error", 0, 0, "mcl2pnml could not check this document "
                           f"(an internal error: {type(e).__name__}: {visible(str(e))})")
                ], outline
    return [Diagnostic("warning", *_span(outline, w.location),
                       f"{visible(w.message)}\nfix: {visible(w.fix)}", w.code)
            for w in warnings], outline


def size_of(text: str) -> int:
    """A document's size in bytes, as it is in a file (UTF-8)."""
    return len(text.encode("utf-8", "surrogatepass"))


def _errors(outline: Outline, errors) -> list[Diagnostic]:
    out = [Diagnostic("error", *_span(outline, e.location), visible(e.message, keep="\n"))
           for e in errors[:SHOWN_ERRORS]]
    if len(errors) > SHOWN_ERRORS:
        at = out[-1].start
        out.append(Diagnostic("information", at, at,
                              f"... and {len(errors) - SHOWN_ERRORS:,} more errors (the "
                              f"first {SHOWN_ERRORS} are shown)"))
    return out


def _span(outline: Outline, location: Location | None) -> tuple[int, int]:
    """The offsets of the token a location points at: all of a name, a number, a string;
    one character of anything else; none at the end of a line or of the text."""
    if location is None or location.line is None:
        return 0, 0
    at = outline.offset(location.line - 1, (location.column or 1) - 1)
    token = outline.token_at(at)
    if token is not None and token.start == at:
        return at, token.end
    line_end = outline.text.find("\n", at)
    return at, at if at == len(outline.text) or at == line_end else at + 1


# -- the fixes --------------------------------------------------------------------------

def fix(outline: Outline, code: str | None, offset: int) -> Fix | None:
    """The edit for warning ``code`` at ``offset`` (where its diagnostic starts), if it
    has one."""
    i = outline.index_before(offset + 1)
    if i < 0 or outline.tokens[i].start != offset:
        return None
    if code == "W001":
        return _monitor_tested(outline, i)
    if code == "W004":
        return _condition_first(outline, i)
    return None


def _closing(tokens: list[Token], opening: int) -> int | None:
    """The index of the ``)`` that closes the ``(`` at ``opening``."""
    depth = 0
    for k in range(opening, len(tokens)):
        if tokens[k].kind == "punct" and tokens[k].text == "(":
            depth += 1
        elif tokens[k].kind == "punct" and tokens[k].text == ")":
            depth -= 1
            if depth == 0:
                return k
        elif tokens[k].kind == "punct" and tokens[k].text in "{};":
            return None
    return None


def _is(tokens: list[Token], i: int, text: str) -> bool:
    return 0 <= i < len(tokens) and tokens[i].kind != "string" and tokens[i].text == text


def _monitor_tested(outline: Outline, i: int) -> Fix | None:
    """W001: ``monitor(S1, S2);`` becomes ``if (monitor(S1, S2)) then { }``; a monitor that
    is a part of a structure, ``{ if (monitor(S1, S2)) then { } }``."""
    t = outline.tokens
    if not (_is(t, i, "monitor") and _is(t, i + 1, "(")):
        return None
    close = _closing(t, i + 1)
    if close is None:
        return None
    monitor = outline.text[t[i].start:t[close].end]
    if _is(t, close + 1, ";"):
        end, text = t[close + 1].end, f"if ({monitor}) then {{ }}"
    else:
        end, text = t[close].end, f"{{ if ({monitor}) then {{ }} }}"
    return Fix("Test the monitor: if (monitor(...)) then { }, so that what follows it "
               "always runs (W001)", t[i].start, end, text)


def _condition_first(outline: Outline, i: int) -> Fix | None:
    """W004: ``if (C) then { B }`` becomes ``C; { B }``: a FAIL of C stops the sequence."""
    t = outline.tokens
    if not (_is(t, i, "if") and _is(t, i + 1, "(")):
        return None
    close = _closing(t, i + 1)
    if close is None or close == i + 2:
        return None
    block = close + 2 if _is(t, close + 1, "then") else close + 1
    if not _is(t, block, "{"):
        return None
    condition = outline.text[t[i + 2].start:t[close - 1].end]
    ends = "" if _is(t, close - 1, "}") else ";"
    return Fix("Stop at the condition's failure: run it as a statement before the block "
               "(W004)", t[i].start, t[block].start, f"{condition}{ends} ")
