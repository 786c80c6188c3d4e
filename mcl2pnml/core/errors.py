"""The one error type users see, and how it shows where the fault is.

Every stage (MCL parser and checker, PNML reader, the net core, the CLI)
raises :class:`Mcl2PnmlError`. The CLI catches exactly this type, prints it
and exits with status 2; anything else escaping is a bug.

Like lark's ``UnexpectedInput``, an error that knows its position renders as
``file:line:col: message`` followed by the source line and a caret under the
fault, so that a user finds the problem without opening the file.

Whatever of the input an error shows (the source line, the file's name, a
name or a value the message quotes) goes through :func:`visible` first: a
control character printed raw would act on the user's terminal (``ESC ] 0 ;
... BEL`` sets its title, ``ESC [ 2 J`` clears it) and a bidirectional
override would show text other than the file's.
"""
from __future__ import annotations

import bisect
import difflib
from dataclasses import dataclass
from typing import Iterable, Sequence


#: Source lines longer than this are shown as a window around the fault.
EXCERPT_WIDTH = 100
#: Error messages name at most this many of the valid choices.
LISTED = 20
#: "Did you mean" compares a name with at most this many choices, the nearest in
#: alphabetical order: a comparison costs tens of microseconds, and a generated mission
#: may declare hundreds of thousands of names.
COMPARED = 2_000


def _escape(char: str) -> str:
    code = ord(char)
    if char in "\t\n\r":
        return repr(char)[1:-1]
    return f"\\x{code:02x}" if code < 0x100 else \
        f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


def visible(text: str, keep: str = "") -> str:
    """``text`` safe to print: each character that is not printable as its Python escape.

    Not printable, by :meth:`str.isprintable`: the C0 and C1 controls (ESC,
    BEL, CR...), DEL, the bidirectional overrides and isolates (U+202A-202E,
    U+2066-2069) and other format characters, the line and paragraph
    separators, unpaired surrogates. They are shown as ``\\x1b``, ``\\t``,
    ``\\u202e``; ``keep`` names those left as they are (a message's own line
    breaks). A backslash is left alone, so that ordinary text reads as written;
    the result is all printable, so that escaping it again changes nothing.
    """
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() or c in keep else _escape(c) for c in text)


def line_of(lines: Sequence[str], line: int | None) -> str | None:
    """Line ``line`` (from 1) of ``lines``, or None where there is no such line."""
    return lines[line - 1] if line is not None and 0 < line <= len(lines) else None


def text_location(filename: str | None, text: str, line: int | None,
                  column: int | None = None) -> Location:
    """Where ``line`` and ``column`` (from 1) are in ``text``, with the source line.

    Total: a position past the end (a parser's "unexpected end" after the last
    newline, an empty file, a file of blanks) is shown at the end of the last
    line, where the file stops; a position before the start at 1:1.
    """
    lines = source_lines(text)
    if line is None or line < 1:
        return Location(filename, 1, 1, lines[0] if lines else "")
    if line > len(lines):
        if not lines:
            return Location(filename, 1, 1, "")
        line, column = len(lines), len(lines[-1]) + 1
    source = lines[line - 1]
    column = min(max(1, column or 1), len(source) + 1)
    return Location(filename, line, column, source)


@dataclass(frozen=True)
class Location:
    """A position in a source file; line and column count from 1."""

    file: str | None = None
    line: int | None = None
    column: int | None = None
    source_line: str | None = None

    def prefix(self) -> str:
        parts = [visible(self.file or "<input>")]
        if self.line is not None:
            parts.append(str(self.line))
            parts.append(str(self.column if self.column is not None else 1))
        return ":".join(parts)

    def excerpt(self) -> str:
        """The source line with a caret under the column, or ``""``.

        A tab is shown as one space; every other character that is not printable
        as its escape (:func:`visible`), the caret under the escape of the
        character it points at.
        """
        if self.source_line is None or self.line is None:
            return ""
        line = self.source_line.rstrip("\r\n")
        col = max(1, self.column or 1)
        # the characters around the fault first (each shows as one or more), so that a
        # line of megabytes is not escaped whole
        low, high = max(0, col - 1 - EXCERPT_WIDTH), col - 1 + EXCERPT_WIDTH
        text, col = line[low:high].replace("\t", " "), col - low
        if not text.isprintable():
            shown = [visible(c) for c in text]
            col = len("".join(shown[:col - 1])) + 1 + max(0, col - 1 - len(shown))
            text = "".join(shown)
        # a window around the fault, marked as cut
        start = max(0, min(col - 1 - EXCERPT_WIDTH // 2, len(text) - EXCERPT_WIDTH))
        left = "..." if start or low else ""
        right = "..." if start + EXCERPT_WIDTH < len(text) or high < len(line) else ""
        text = left + text[start:start + EXCERPT_WIDTH] + right
        col = col - start + len(left)
        return f"    {text}\n    {' ' * (col - 1)}^"


def source_lines(text: str) -> list[str]:
    """The lines of a source as lark and libxml2 number them: cut at ``\n`` only.

    ``str.splitlines`` also cuts at form feeds, ``\r``, ``\x85``, U+2028 and
    more, so that its line n is not the parser's line n and an excerpt would
    show the wrong line. A final newline opens no line; a ``\r`` before a
    newline is dropped, so that an excerpt cannot return the cursor.
    """
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return [line[:-1] if line.endswith("\r") else line for line in lines]


class Mcl2PnmlError(Exception):
    """A user-facing error: bad MCL, bad PNML, a bad net, a bad argument.

    ``message`` says what is wrong and, where there is a choice, what is valid.
    """

    def __init__(self, message: str, location: Location | None = None):
        super().__init__(message)
        self.message = message
        self.location = location

    def __str__(self) -> str:
        # what a message quotes of the input is shown visibly; its own line breaks kept
        message = visible(self.message, keep="\n")
        if self.location is None:
            return message
        head = f"{self.location.prefix()}: {message}"
        excerpt = self.location.excerpt()
        return f"{head}\n{excerpt}" if excerpt else head


class NetError(Mcl2PnmlError):
    """A net that breaks the rules of the core (dangling arc, duplicate id...)."""


class PnmlError(Mcl2PnmlError):
    """A PNML document that cannot be read as a P/T net."""


#: The most errors of one file shown at once: a file broken everywhere (a net of
#: 10^5 bad arcs) is a screenful and a count, not 150,000 lines.
SHOWN_ERRORS = 50


def shown(errors: Sequence[object], what: str = "errors") -> list[str]:
    """The errors (or warnings) as lines to print: the first :data:`SHOWN_ERRORS`, then
    how many more."""
    lines = [str(e) for e in errors[:SHOWN_ERRORS]]
    if len(errors) > SHOWN_ERRORS:
        lines.append(f"... and {len(errors) - SHOWN_ERRORS:,} more {what} "
                     f"(the first {SHOWN_ERRORS} are shown)")
    return lines


class ErrorList(Mcl2PnmlError):
    """Several errors found in one file, reported together (the first
    :data:`SHOWN_ERRORS` of them, and how many more)."""

    def __init__(self, errors: Sequence[Mcl2PnmlError]):
        self.errors = tuple(errors)
        super().__init__(str(self))

    def __str__(self) -> str:
        return "\n".join(shown(self.errors))


def raise_all(errors: Iterable[Mcl2PnmlError]) -> None:
    """Raise the errors collected by a checking pass, if there are any."""
    errors = list(errors)
    if len(errors) == 1:
        raise errors[0]
    if errors:
        raise ErrorList(errors)


def did_you_mean(name: str, valid: Iterable[str], what: str) -> str:
    """``"; did you mean 'Go'? declared tasks: Go, Stop"`` for error messages."""
    valid = sorted(set(valid))
    at = bisect.bisect(valid, name)
    near = valid[max(0, at - COMPARED // 2):at + COMPARED // 2]
    close = difflib.get_close_matches(name, near, n=1)
    hint = f"; did you mean '{visible(close[0])}'?" if close else ""
    listing = ", ".join(map(visible, valid[:LISTED])) if valid else "none"
    if len(valid) > LISTED:
        listing += f", ... ({len(valid) - LISTED:,} more)"
    return f"{hint} {what}: {listing}" if hint else f"; {what}: {listing}"
