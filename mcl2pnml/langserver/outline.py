"""What an editor's text says, read whether or not it parses: its tokens, its declarations,
and what the cursor stands in.

The parser (:mod:`mcl2pnml.language.parser`) stops at the first syntax error, which is
where a mission being typed always is. This reading never stops: a lexer as lenient as
the grammar's terminals allow (an unclosed comment or string ends at the end of the file
or line, a character of no token is a token of its own), then the declarations found by
their keywords (``docs/mcl.md``, "Declarations"): ``const``, ``primitive``, ``task``,
``function`` and ``mission`` are reserved and can only begin a declaration, so one that
is not closed (a missing ``;``, a body without its ``}``) ends where the next begins.
On a file that parses, it finds the declarations the parser does, at the same places
(``tests/langserver/test_outline.py`` holds it to the parser on every example).

Positions are offsets in the text, and (line, column) from 0 in code points, lines cut
at ``\\n`` as lark cuts them (:func:`mcl2pnml.core.errors.source_lines`). Every walk is
one pass over the tokens: a document of a megabyte is read in a fraction of a second.
"""
from __future__ import annotations

import bisect
import re
from dataclasses import dataclass, field
from functools import cached_property

#: The reserved words that begin a declaration wherever they are (docs/mcl.md, "Lexical
#: rules"); ``property`` begins one only between declarations, being a name elsewhere.
DECLARING = ("const", "primitive", "task", "function", "mission")
#: The structures a statement may be, by their keyword (``if`` and ``while`` take a
#: condition in parentheses, as ``parallel`` and ``monitor`` take their parts).
STRUCTURES = ("parallel", "monitor", "if", "while")

_TOKENS = re.compile(r"""
    (?P<space>[ \t\f\r\n]+)
  | (?P<comment>//[^\n]*|/\*[\s\S]*?(?:\*/|\Z))
  | (?P<string>"(?:[^"\\\n]|\\.)*(?:"|(?=\n)|\Z))
  | (?P<number>[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)
  | (?P<name>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<punct>[(){};,=:])
  | (?P<other>[\s\S])
""", re.VERBOSE)


@dataclass(frozen=True)
class Token:
    """One token: its kind (``name``, ``number``, ``string``, ``comment``, ``punct``,
    ``other``), its text and where it starts (an offset, and line and column from 0)."""

    kind: str
    text: str
    start: int
    line: int
    column: int

    @property
    def end(self) -> int:
        return self.start + len(self.text)


@dataclass(frozen=True)
class Declaration:
    """A declaration as written: its keyword's token, its name's (None for the mission),
    its parameters' and, for a task, its pattern's, its primitives' and its time-out's;
    ``first`` and ``last`` index its tokens in :attr:`Outline.tokens` (comments aside),
    ``end`` is the offset just past it."""

    kind: str
    keyword: Token
    name_token: Token | None
    params: tuple[Token, ...]
    first: int
    last: int
    end: int
    pattern: Token | None = None
    primitives: tuple[Token, ...] = ()
    timeout: Token | None = None
    #: where the body opens (a function's or the mission's ``{``), as an index of the tokens
    body: int | None = None
    #: whether it ends with its ``;`` or its body's ``}`` (else it runs on to the next)
    closed: bool = False

    @property
    def name(self) -> str:
        return self.name_token.text if self.name_token is not None else self.kind

    @property
    def start(self) -> int:
        return self.keyword.start


@dataclass(frozen=True)
class Context:
    """What may be written at the cursor: ``kind`` is ``none`` (in a comment, a string, a
    name being declared), ``declaration`` (between declarations), ``pattern``,
    ``primitive`` and ``after-task`` (in a task), ``value`` (an argument: ``params`` are the
    parameters in scope), ``statement`` (in a body; ``follows`` the keyword the statement
    may go on with: ``then``, ``do`` or ``else``), ``property`` or ``atom`` (in a
    property: ``atom`` the kind of the atom whose arguments it is in, ``argument`` which)."""

    kind: str
    declaration: Declaration | None = None
    params: tuple[str, ...] = ()
    follows: tuple[str, ...] = ()
    atom: str = ""
    argument: int = 0


@dataclass
class Outline:
    """A text's tokens (no blanks) and declarations, with the positions between them."""

    text: str
    tokens: list[Token] = field(default_factory=list)      # comments left out
    comments: list[Token] = field(default_factory=list)    # comments only
    declarations: list[Declaration] = field(default_factory=list)

    @cached_property
    def line_starts(self) -> list[int]:
        return [0] + [m.end() for m in re.finditer("\n", self.text)]

    @cached_property
    def _starts(self) -> list[int]:
        return [t.start for t in self.tokens]

    def position(self, offset: int) -> tuple[int, int]:
        """(line, column) from 0 of an offset."""
        line = bisect.bisect_right(self.line_starts, offset) - 1
        return line, offset - self.line_starts[line]

    def offset(self, line: int, column: int) -> int:
        """The offset of (line, column) from 0, within the text: past the end of a line is
        its end, past the last line the text's end."""
        if line >= len(self.line_starts):
            return len(self.text)
        start = self.line_starts[max(line, 0)]
        stop = (self.line_starts[line + 1] - 1 if line + 1 < len(self.line_starts)
                else len(self.text))
        return min(start + max(column, 0), stop)

    def line_text(self, line: int) -> str:
        """Line ``line`` (from 0) without its end."""
        if not 0 <= line < len(self.line_starts):
            return ""
        stop = self.line_starts[line + 1] - 1 if line + 1 < len(self.line_starts) \
            else len(self.text)
        return self.text[self.line_starts[line]:stop]

    def index_before(self, offset: int) -> int:
        """The index of the last token that starts before ``offset`` (-1 if none)."""
        return bisect.bisect_left(self._starts, offset) - 1

    def token_at(self, offset: int) -> Token | None:
        """The token the offset is in, or just after the end of (the word a cursor ends)."""
        i = self.index_before(offset + 1)
        if i >= 0 and self.tokens[i].start <= offset <= self.tokens[i].end:
            return self.tokens[i]
        return None

    def word_at(self, offset: int) -> Token | None:
        """The name at the offset (under it, or just before it), if one is."""
        for at in (offset, offset - 1):
            token = self.token_at(at) if at >= 0 else None
            if token is not None and token.kind == "name":
                return token
        return None

    @cached_property
    def _comment_starts(self) -> list[int]:
        return [c.start for c in self.comments]

    def in_comment(self, offset: int) -> bool:
        """Whether the offset is inside a comment (after its first character)."""
        i = bisect.bisect_left(self._comment_starts, offset) - 1
        if i < 0:
            return False
        c = self.comments[i]
        # a line comment runs to its line's end, a cursor there still in it
        return c.start < offset < c.end or (offset == c.end and c.text.startswith("//"))

    @cached_property
    def _declaration_starts(self) -> list[int]:
        return [d.start for d in self.declarations]

    def declaration_at(self, offset: int) -> Declaration | None:
        """The declaration the offset is in: before its ``;`` or ``}``, or before the next
        declaration when it is not closed (at its end, where a word is typed)."""
        i = bisect.bisect_right(self._declaration_starts, offset) - 1
        if i < 0:
            return None
        d = self.declarations[i]
        return d if offset < d.end or (offset == d.end and not d.closed) else None

    def declared(self) -> dict[str, Declaration]:
        """The declarations by name, the first of each name (the checker says of the next
        that it is a duplicate); the mission and the properties have their own names."""
        out: dict[str, Declaration] = {}
        for d in self.declarations:
            if d.kind in DECLARING[:4] and d.name_token is not None:
                out.setdefault(d.name, d)
        return out

    def of_kind(self, kind: str) -> list[Declaration]:
        return [d for d in self.declared().values() if d.kind == kind]


def read(text: str) -> Outline:
    """The outline of ``text``: tokens and declarations, whatever the text is."""
    outline = Outline(text)
    starts = outline.line_starts
    line = 0
    for m in _TOKENS.finditer(text):
        kind = m.lastgroup
        if kind == "space":
            continue
        start = m.start()
        while line + 1 < len(starts) and starts[line + 1] <= start:
            line += 1
        token = Token(kind, m.group(), start, line, start - starts[line])
        (outline.comments if kind == "comment" else outline.tokens).append(token)
    outline.declarations = _Declarations(outline.tokens, len(text)).run()
    return outline


class _Declarations:
    """One pass over the tokens, declaration by declaration (see the module's documentation)."""

    def __init__(self, tokens: list[Token], size: int):
        self.t = tokens
        self.size = size
        self.i = 0
        self.closed = False     # whether the declaration read last ended with its ; or }

    def run(self) -> list[Declaration]:
        out = []
        while self.i < len(self.t):
            token = self.t[self.i]
            if token.kind == "name" and (token.text in DECLARING or token.text == "property"
                                         and self._is("name", 1)):
                out.append(self._declaration())
            else:
                self.i += 1         # a stray token between declarations: passed over
        return out

    def _is(self, kind: str, ahead: int = 0, text: str | None = None) -> bool:
        at = self.i + ahead
        return at < len(self.t) and self.t[at].kind == kind and \
            (text is None or self.t[at].text == text)

    def _stops(self) -> bool:
        """Whether the next token begins another declaration, or there is none."""
        return self.i >= len(self.t) or (self.t[self.i].kind == "name"
                                         and self.t[self.i].text in DECLARING)

    def _declaration(self) -> Declaration:
        first = self.i
        self.closed = False
        keyword = self.t[first]
        kind = keyword.text
        self.i += 1
        name = None
        if kind != "mission" and self._is("name") and self.t[self.i].text not in DECLARING:
            name = self.t[self.i]
            self.i += 1
        params = self._params() if kind in ("primitive", "task", "function") else ()
        task: dict = {}
        if kind == "task" and self._is("punct", 0, "="):
            self.i += 1
            task = self._task_body()
        body = None
        if kind in ("function", "mission"):
            body = self._block()
        else:
            self._to_semicolon()
        last = max(first, self.i - 1)
        # one not closed runs on to the next declaration: a cursor after it is still in it
        end = self.t[last].end if self.closed else \
            self.t[self.i].start if self.i < len(self.t) else self.size
        return Declaration(kind, keyword, name, params, first, last, end, body=body,
                           closed=self.closed, **task)

    def _params(self) -> tuple[Token, ...]:
        """``( NAME, ... )``: the names, up to the ``)`` or to what cannot be in the list."""
        if not self._is("punct", 0, "("):
            return ()
        self.i += 1
        names = []
        while not self._stops():
            token = self.t[self.i]
            if token.kind == "name":
                names.append(token)
            elif token.text == ")":
                self.i += 1
                break
            elif token.text != ",":
                break
            self.i += 1
        return tuple(names)

    def _task_body(self) -> dict:
        """``PATTERN(PRIM(args), ...) [timeout N]``, as far as it is written."""
        out: dict = {}
        if not self._is("name") or self._stops():
            return out
        out["pattern"] = self.t[self.i]
        self.i += 1
        prims = []
        depth = 0
        while not self._stops():
            token = self.t[self.i]
            if token.text == "(":
                depth += 1
            elif token.text == ")":
                depth -= 1
            elif token.text in ";{}" or depth <= 0:
                break
            elif depth == 1 and token.kind == "name" and self._is("punct", 1, "("):
                prims.append(token)
            self.i += 1
            if depth == 0:
                break
        out["primitives"] = tuple(prims)
        if self._is("name", 0, "timeout") and self._is("number", 1):
            out["timeout"] = self.t[self.i + 1]
            self.i += 2
        return out

    def _to_semicolon(self) -> None:
        """On to the ``;`` that ends the declaration, at no depth, past it; or to the next
        declaration."""
        depth = 0
        while not self._stops():
            text = self.t[self.i].text
            self.i += 1
            if text in "({" and self.t[self.i - 1].kind == "punct":
                depth += 1
            elif text in ")}" and self.t[self.i - 1].kind == "punct":
                depth = max(0, depth - 1)
            elif text == ";" and depth == 0:
                self.closed = True
                return

    def _block(self) -> int | None:
        """A body: to its ``{``, then to the ``}`` that closes it (or to the next
        declaration); the index of the ``{``."""
        while not self._stops() and not self._is("punct", 0, "{"):
            if self._is("punct", 0, ";"):
                return None
            self.i += 1
        if self._stops():
            return None
        opened, depth = self.i, 0
        while not self._stops():
            token = self.t[self.i]
            self.i += 1
            if token.kind != "punct":
                continue
            if token.text == "{":
                depth += 1
            elif token.text == "}":
                depth -= 1
                if depth == 0:
                    self.closed = True
                    break
        return opened


# -- what the cursor stands in -------------------------------------------------------------

def context(outline: Outline, offset: int) -> Context:
    """What may be written at ``offset`` (see :class:`Context`)."""
    token = outline.token_at(offset)
    if outline.in_comment(offset) or (token is not None and token.kind == "string"
                                      and token.start < offset):
        return Context("none")
    d = outline.declaration_at(offset)
    if d is None or offset <= d.start:
        return Context("declaration")
    # the tokens of the declaration before the cursor, less the word being typed
    stop = outline.index_before(offset)
    if stop >= 0 and outline.tokens[stop].kind == "name" and \
            outline.tokens[stop].end >= offset:
        stop -= 1
    before = outline.tokens[d.first:min(stop, d.last) + 1]
    if d.kind == "const":
        return Context("value", d) if any(t.text == "=" for t in before[1:]) else Context("none")
    if d.kind == "task":
        return _in_task(d, before)
    if d.kind in ("function", "mission"):
        return _in_body(d, before)
    if d.kind == "property":
        return _in_property(d, before)
    return Context("none")      # a primitive: names its parameters


def _in_task(d: Declaration, before: list[Token]) -> Context:
    equals = next((k for k, t in enumerate(before) if t.text == "=" and t.kind == "punct"),
                  None)
    if equals is None:
        return Context("none")
    depth, closed = 0, False
    for t in before[equals + 1:]:
        if t.kind == "punct" and t.text == "(":
            depth += 1
        elif t.kind == "punct" and t.text == ")":
            depth -= 1
            closed = closed or depth == 0
    if closed and depth <= 0:
        timed = any(t.text == "timeout" for t in before[equals + 1:])
        return Context("none" if timed else "after-task", d)
    if depth == 0:
        return Context("pattern", d) if len(before) == equals + 1 else Context("none", d)
    if depth == 1:
        return Context("primitive", d)
    return Context("value", d, tuple(p.text for p in d.params))


def _in_body(d: Declaration, before: list[Token]) -> Context:
    if d.body is None or d.first + len(before) - 1 < d.body:
        return Context("none", d)       # its name, its parameters
    opened: list[Token | None] = []          # each open bracket's token before it
    prev: Token | None = None
    for t in before[d.body - d.first:]:
        if t.kind == "punct" and t.text in "({":
            opened.append(prev if t.text == "(" else None)
        elif t.kind == "punct" and t.text in ")}" and opened:
            opened.pop()
        prev = t
    params = tuple(p.text for p in d.params)
    head = opened[-1] if opened else None
    if head is not None and head.kind == "name" and head.text not in STRUCTURES:
        return Context("value", d, params)
    follows: tuple[str, ...] = ()
    if prev is not None and prev.text == ")":
        follows = _closing(before, len(before) - 1)
    elif prev is not None and prev.text == "}":
        follows = ("else",)
    return Context("statement", d, params, follows)


def _closing(tokens: list[Token], at: int) -> tuple[str, ...]:
    """``then`` or ``do`` when the ``)`` at ``at`` closes an ``if``'s or a ``while``'s
    condition."""
    depth = 0
    for k in range(at, -1, -1):
        text = tokens[k].text
        if tokens[k].kind == "punct" and text == ")":
            depth += 1
        elif tokens[k].kind == "punct" and text == "(":
            depth -= 1
            if depth == 0:
                word = tokens[k - 1].text if k > 0 else ""
                return {"if": ("then",), "while": ("do",)}.get(word, ())
    return ()


def _in_property(d: Declaration, before: list[Token]) -> Context:
    if not any(t.text == ":" for t in before):
        return Context("none", d)
    opened: list[tuple[Token | None, int]] = []   # each open parenthesis: its word, commas
    prev: Token | None = None
    for t in before:
        if t.kind == "punct" and t.text == "(":
            opened.append((prev, 0))
        elif t.kind == "punct" and t.text == ")" and opened:
            opened.pop()
        elif t.kind == "punct" and t.text == "," and opened:
            word, commas = opened[-1]
            opened[-1] = (word, commas + 1)
        prev = t
    if opened and opened[-1][0] is not None and opened[-1][0].kind == "name":
        word, commas = opened[-1]
        return Context("atom", d, atom=word.text, argument=commas)
    return Context("property", d)
