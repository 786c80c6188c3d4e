"""MCL text to the AST (lark, LALR), the first stage of the compiler.

The grammar is ``docs/mcl.md``'s: declarations in any order (const,
primitive, task, function, mission), statements that are calls, blocks,
``parallel``, ``monitor``, ``if``/``then``/``else`` and ``while``/``do``; and
``property`` declarations (docs/properties.md), whose words are keywords only
inside a property.
Comments are ``// ...`` and ``/* ... */``.

A syntax error is one :class:`Mcl2PnmlError` at the first fault, with the
line, a caret, and what would have been valid there; input that is not
UTF-8 text (or is binary) is refused the same way, at the first bad byte.
"""
from __future__ import annotations

import difflib
import math
import re
from functools import lru_cache
from pathlib import Path

from lark import (Lark, Token, Transformer_NonRecursive, Tree, UnexpectedCharacters,
                  UnexpectedEOF, UnexpectedInput, UnexpectedToken)

from mcl2pnml.language import ast
from mcl2pnml.core.bounds import MAX_INTEGER, natural_at_most
from mcl2pnml.core.errors import Location, Mcl2PnmlError, line_of, source_lines
from mcl2pnml.core.files import decode_text, read_bytes
from mcl2pnml.core.gcpause import without_gc

GRAMMAR = r"""
start: declaration*

?declaration: const | primitive | task | function | mission | property

const: "const" NAME "=" value ";"
primitive: "primitive" NAME "(" [names] ")" ";"
task: "task" NAME "(" [names] ")" "=" NAME "(" primcall ("," primcall)* ")" [timeout] ";"
timeout: "timeout" NUMBER
primcall: NAME "(" [values] ")"
function: "function" NAME "(" [names] ")" block
mission: MISSION block

names: NAME ("," NAME)*
values: value ("," value)*

?value: NUMBER    -> number
      | STRING    -> string
      | NAME      -> ref
      | "(" values ")" -> tuple

block: "{" statement* "}"

?statement: call ";"
          | parallel ";"
          | monitor ";"
          | if_
          | while_
          | block

?structure: call | block | parallel | monitor

call: NAME "(" [values] ")"
parallel: "parallel" "(" structure ("," structure)+ ")"
monitor: "monitor" "(" structure "," structure ")"
if_: "if" "(" structure ")" ["then"] block ["else" block]
while_: "while" "(" structure ")" ["do"] block

// a property (docs/properties.md): its words are keywords only where they are
// expected (the contextual lexer), so no mission that names a thing "before" breaks
property: PROPERTY NAME ":" pattern [scope] ";"
pattern: "never" pexpr                   -> never
       | "always" pexpr                  -> always
       | "eventually" pexpr              -> eventually
       | "at" "most" NUMBER "times" pexpr -> at_most
       | pexpr "only" "after" pexpr      -> only_after
       | pexpr "leads" "to" pexpr        -> leads_to
// between's first expression is one term: "between a and b" has one reading
scope: "globally"                        -> globally
     | "before" pexpr                    -> before
     | "after" pexpr                     -> after
     | "between" punary "and" pexpr      -> between
     | "after" pexpr "until" pexpr       -> after_until
?pexpr: pand ("or" pand)*
?pand: punary ("and" punary)*
?punary: NOT punary -> pnot
       | patom
?patom: TRUE -> ptrue
      | FALSE -> pfalse
      | NAME "(" NAME ("," NAME)* ")" -> patom
      | "(" pexpr ")"

PROPERTY: "property"
NOT: "not"
TRUE: "true"
FALSE: "false"
MISSION: "mission"
NAME: /[A-Za-z_][A-Za-z0-9_]*/
NUMBER: /[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?/
STRING: /"([^"\\\n]|\\.)*"/
COMMENT: /\/\/[^\n]*/ | /\/\*(.|\n)*?\*\//

%import common.WS
%ignore WS
%ignore COMMENT
"""

#: A keyword's shape: a literal of the grammar that a name could be.
_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
#: The rule whose words are keywords only inside it (the contextual lexer's).
_PROPERTY_RULE = "property"


@lru_cache(maxsize=None)
def grammar_words() -> tuple[frozenset[str], frozenset[str]]:
    """The grammar's keywords, read from :data:`GRAMMAR`: (every word of it, those of
    missions).

    A word is a literal of the grammar shaped as a name (``"while"``); those of
    missions are the words of the rules reached from ``start`` without entering
    a property, which alone may not be names. A property's words (``before``,
    ``never``...) are keywords only inside a property: a mission may name a
    thing ``before``. Read from the parser the first parse builds anyway.
    """
    parser = _fast_parser()
    literal = {t.name: t.pattern.value for t in parser.terminals
               if t.pattern.type == "str" and _WORD.fullmatch(t.pattern.value)}
    expansions: dict[str, list] = {}
    for rule in parser.rules:
        expansions.setdefault(rule.origin.name, []).append(rule.expansion)
    seen, todo, mission = {"start"}, ["start"], set()
    while todo:
        for expansion in expansions.get(todo.pop(), ()):
            for symbol in expansion:
                if symbol.is_term:
                    mission.update([literal[symbol.name]] if symbol.name in literal else [])
                elif symbol.name not in seen and symbol.name != _PROPERTY_RULE:
                    seen.add(symbol.name)
                    todo.append(symbol.name)
    return frozenset(literal.values()), frozenset(mission)


def keywords() -> frozenset[str]:
    """The words a mission may not use as names (:func:`grammar_words`)."""
    return grammar_words()[1]


def __getattr__(name: str):
    # KEYWORDS stays a name of this module, read from the grammar on first use: building
    # the parser at import would cost every command that reads no MCL lark's analysis
    if name == "KEYWORDS":
        return keywords()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

_READABLE = {"NAME": "a name", "NUMBER": "a number", "STRING": "a string",
             "$END": "the end of the file"}


def _describe(terminal: str) -> str:
    if terminal in _READABLE:
        return _READABLE[terminal]
    try:
        pattern = _tree_parser().get_terminal(terminal).pattern
    except KeyError:
        return terminal.lower()
    return f"'{pattern.value}'" if pattern.type == "str" else terminal.lower()


def _number_value(text: str) -> int | float | str:
    """A NUMBER's value, or why it is out of range (:mod:`mcl2pnml.core.bounds`).

    An integer is at most :data:`MAX_INTEGER` in size (judged by its length
    before it is converted: Python converts no more than 4,300 digits); a
    decimal is a finite double (``1e309`` is not).
    """
    if not any(c in text for c in ".eE"):
        sign = -1 if text.startswith("-") else 1
        value = natural_at_most(text.lstrip("+-"), MAX_INTEGER)
        if value is None:
            shown = text if len(text) <= 30 else f"an integer of {len(text):,} digits"
            return (f"{shown} is too large: an integer is at most 2^63-1 in size; a larger "
                    "number is a decimal, e.g. 1e30")
        return sign * value
    value = float(text)
    if not math.isfinite(value):
        shown = text if len(text) <= 30 else f"a number of {len(text):,} characters"
        return f"{shown} is too large: a decimal is at most 1.7976931348623157e308 in size"
    return value


class _BadString(str):
    """Why a STRING's escapes cannot be read (:func:`_string_value`)."""


def _string_value(token: str) -> str:
    """A STRING token's text, its backslash escapes read as Python reads them (``\\n``,
    ``\\x1b``, ``\\u00e9``...), or a :class:`_BadString` saying why they cannot be.

    The characters outside Latin-1 are first written as escapes themselves, so that
    ``unicode_escape`` (which reads bytes as Latin-1) gives every character back.
    """
    raw = token[1:-1]
    if "\\" not in raw:
        return raw
    try:
        return raw.encode("latin-1", "backslashreplace").decode("unicode_escape")
    except UnicodeDecodeError as e:
        return _BadString(f"a string's escape cannot be read: {e.reason}")


def _pos(item) -> ast.Pos:
    if isinstance(item, Token):
        return ast.Pos(item.line, item.column)
    meta = getattr(item, "meta", None)
    return ast.Pos(getattr(meta, "line", 0), getattr(meta, "column", 0))


class _Build(Transformer_NonRecursive):
    """Parse tree to AST nodes, each with the position of its first token."""

    def __default_token__(self, token):
        return token

    def start(self, items):
        return tuple(items)

    def names(self, items):
        return tuple(str(t) for t in items)

    def values(self, items):
        return tuple(items)

    def number(self, items):
        (tok,) = items
        text = str(tok)
        value = _number_value(text)
        if isinstance(value, str):
            # out of range: the slow path locates it (:func:`_check_nesting`)
            raise ValueError(value)
        return ast.Number(value, text, _pos(tok))

    def string(self, items):
        (tok,) = items
        value = _string_value(str(tok))
        if isinstance(value, _BadString):   # the slow path locates it (:func:`_check_nesting`)
            raise ValueError(value)
        return ast.String(value, _pos(tok))

    def ref(self, items):
        (tok,) = items
        return ast.Ref(str(tok), _pos(tok))

    def tuple(self, items):
        (values,) = items
        first = values[0].pos if values else ast.Pos(0, 0)
        return ast.Tuple(tuple(values), ast.Pos(first.line, max(1, first.column - 1)))

    def const(self, items):
        name, value = items
        return ast.Const(str(name), value, _pos(name))

    def primitive(self, items):
        name, params = items
        return ast.Primitive(str(name), params or (), _pos(name))

    def timeout(self, items):
        return self.number(items)

    def primcall(self, items):
        name, args = items
        return ast.PrimCall(str(name), args or (), _pos(name))

    def task(self, items):
        name, params, pattern, *rest = items
        timeout = rest[-1] if rest and isinstance(rest[-1], ast.Number) else None
        calls = tuple(c for c in rest if isinstance(c, ast.PrimCall))
        return ast.Task(str(name), params or (), str(pattern), calls, timeout, _pos(name),
                        _pos(pattern))

    def function(self, items):
        name, params, body = items
        return ast.Function(str(name), params or (), body, _pos(name))

    def mission(self, items):
        keyword, body = items
        return ast.Mission(body, _pos(keyword))

    # -- properties --------------------------------------------------------------

    def property(self, items):
        _, name, (pattern, p, s, bound), scope = items
        kind, q, r = scope or ("globally", None, None)
        return ast.Property(str(name), pattern, p, s, bound, kind, q, r, _pos(name))

    def never(self, items):
        return ("never", items[0], None, None)

    def always(self, items):
        return ("always", items[0], None, None)

    def eventually(self, items):
        return ("eventually", items[0], None, None)

    def at_most(self, items):
        bound, p = items
        return ("at most", p, None, self.number([bound]))

    def only_after(self, items):
        return ("only after", items[0], items[1], None)

    def leads_to(self, items):
        return ("leads to", items[0], items[1], None)

    def globally(self, items):
        return ("globally", None, None)

    def before(self, items):
        return ("before", None, items[0])

    def after(self, items):
        return ("after", items[0], None)

    def between(self, items):
        return ("between", items[0], items[1])

    def after_until(self, items):
        return ("after until", items[0], items[1])

    def pexpr(self, items):
        return ast.PropOr(tuple(items), items[0].pos)

    def pand(self, items):
        return ast.PropAnd(tuple(items), items[0].pos)

    def pnot(self, items):
        keyword, arg = items
        return ast.PropNot(arg, _pos(keyword))

    def ptrue(self, items):
        return ast.PropTruth(True, _pos(items[0]))

    def pfalse(self, items):
        return ast.PropTruth(False, _pos(items[0]))

    def patom(self, items):
        kind, *args = items
        return ast.PropAtom(str(kind), tuple(str(a) for a in args), _pos(kind),
                            tuple(_pos(a) for a in args))

    def block(self, items):
        return ast.Block(tuple(items), ast.Pos(0, 0))

    def call(self, items):
        name, args = items
        return ast.Call(str(name), args or (), _pos(name))

    def parallel(self, items):
        return ast.Parallel(tuple(items), items[0].pos if items else ast.Pos(0, 0))

    def monitor(self, items):
        return ast.Monitor(items[0], items[1], items[0].pos)

    def if_(self, items):
        cond, then, otherwise = items
        return ast.If(cond, then, otherwise, cond.pos)

    def while_(self, items):
        cond, body = items
        return ast.While(cond, body, cond.pos)


def decode(data: bytes, filename: str) -> str:
    """MCL source as text; not UTF-8, or binary, is an error at the first bad byte."""
    return decode_text(data, filename, "an MCL")


class _Suspect(Exception):
    """Raised while parsing straight to the AST at what the checks on the tree must judge."""


def _name(token: Token) -> Token:
    """The lexer's check of every name: a keyword lets the tree's checks say what is wrong."""
    if token in keywords():
        raise _Suspect
    return token


#: Parses straight to the AST: :class:`_Build`'s methods run as the rules are
#: reduced, so no tree is built, nor walked again to transform it and to
#: check it (a 10,000-call mission parsed in half the time). Whatever is in
#: doubt, from a syntax error to a keyword used as a name, is parsed again
#: by :func:`_parse_tree`, as every file was before, so that errors are
#: found and reported exactly as they were. Built on the first parse, not at import:
#: a command that parses no MCL (analyzing a PNML file) does not pay lark's grammar
#: analysis.
@lru_cache(maxsize=None)
def _fast_parser() -> Lark:
    return Lark(GRAMMAR, parser="lalr", maybe_placeholders=True, transformer=_Build(),
                lexer_callbacks={"NAME": _name})


@lru_cache(maxsize=None)
def _tree_parser() -> Lark:
    """The parser that builds a tree with positions, for the checks and the error messages."""
    return Lark(GRAMMAR, parser="lalr", propagate_positions=True, maybe_placeholders=True)


def grammar() -> Lark:
    """The grammar as lark analysed it, its terminals and rules: what the highlighter
    reads its words from (:mod:`mcl2pnml.language.highlight`)."""
    return _tree_parser()


@without_gc
def parse(text: str, filename: str = "<mcl>") -> ast.Program:
    """Parse MCL source into a :class:`~mcl2pnml.language.ast.Program` (no checks beyond syntax)."""
    try:
        declarations = _fast_parser().parse(text)
    except Exception:   # any fault, or doubt: the tree says which, and where
        declarations = None
    if declarations is None or _deepest(declarations) > MAX_NESTING:
        declarations = _parse_tree(text, filename)
    return ast.Program(declarations, filename, text)


def _parse_tree(text: str, filename: str) -> tuple[ast.Declaration, ...]:
    """Parse to a tree, check it, then build the AST: the slow way, that locates every error."""
    lines = source_lines(text)
    try:
        tree = _tree_parser().parse(text)
    except UnexpectedInput as e:
        raise _syntax_error(e, text, lines, filename) from None
    _check_nesting(tree, lines, filename)
    return _Build().transform(tree)


def _syntax_error(e: UnexpectedInput, text: str, lines: list[str],
                  filename: str) -> Mcl2PnmlError:
    """The one message of a syntax error: a repair that lets the parse go on where there is
    one (:func:`_repair`), else what was found and what would have been valid there."""
    repaired = None if isinstance(e, UnexpectedCharacters) else _repair(e, text)
    if repaired is not None:
        message, line, col = repaired
        return Mcl2PnmlError(f"syntax error: {message}",
                             Location(filename, line, col, line_of(lines, line)))
    line, col = e.line, e.column
    if isinstance(e, UnexpectedEOF) or line < 1:
        line = max(1, len(lines))
        col = len(lines[-1]) + 1 if lines else 1
    expected = sorted({_describe(t) for t in (getattr(e, "expected", None)
                                              or getattr(e, "allowed", None) or ())})
    if isinstance(e, UnexpectedCharacters):
        found = f"unexpected character {text[e.pos_in_stream]!r}"
    elif isinstance(e, UnexpectedEOF) or e.token.type == "$END":
        found = "unexpected end of file"
    else:
        tok = e.token
        found = (f"'{tok}' is a keyword" if str(tok) in keywords() and "a name" in expected
                 else f"unexpected {_describe(tok.type) if tok.type != 'NAME' else repr(str(tok))}")
    hint = f"; expected {', '.join(expected[:-1])} or {expected[-1]}" if len(expected) > 1 \
        else (f"; expected {expected[0]}" if expected else "")
    return Mcl2PnmlError(f"syntax error: {found}{hint}",
                         Location(filename, line, col, line_of(lines, line)))


#: The most words of a statement tried as misspelled keywords, from the fault backwards.
_TRIED = 8
#: How far past the fault a guess is parsed (characters): far enough to see the parse go on.
_PAST = 200
#: What the guesses parse in all, at most (characters): each parses the file from its start
#: to a little past the fault, so that a fault deep in a generated mission of megabytes gets
#: the plain message at once rather than after minutes of guessing.
_GUESSED = 2_000_000


class _Guesses:
    """Edits of the text around a syntax error, each held to the parser: does the parse go
    past the fault with it? Each parses the text up to :data:`_PAST` characters past the
    fault (an end there is no fault of the edit), within :data:`_GUESSED` in all."""

    def __init__(self, text: str, fault: int, fault_end: int):
        self.text, self.fault, self.fault_end = text, fault, fault_end
        self.left = _GUESSED

    def helps(self, start: int, end: int, new: str) -> bool:
        """Whether writing ``new`` over ``text[start:end]`` lets the parse go past the
        fault's token (False once the guesses have parsed what they may)."""
        shift = len(new) - (end - start)
        cut = min(len(self.text), self.fault_end + _PAST)
        edited = self.text[:start] + new + self.text[end:cut]
        if len(edited) > self.left:
            return False
        self.left -= len(edited)
        at = _fault_at(edited)
        if at is None or at >= len(edited) and cut < len(self.text):
            return True          # parsed, or stopped by the cut only
        return (at - shift if at >= start + len(new) else at) >= max(self.fault + 1,
                                                                     self.fault_end)


def _fault_at(text: str) -> int | None:
    """The offset where the parser first fails on ``text`` (an unexpected end: the text's
    length), or None when it parses."""
    try:
        _tree_parser().parse(text)
    except UnexpectedEOF:
        return len(text)
    except UnexpectedToken as e:
        return len(text) if e.token.type == "$END" else e.token.start_pos
    except UnexpectedInput as e:
        return e.pos_in_stream
    return None


def _repair(e: UnexpectedInput, text: str) -> tuple[str, int, int] | None:
    """A misspelled keyword or a missing ``;`` that explains the syntax error ``e``, as
    (message, line, column) where the fix goes; None when neither does.

    A word of the statement the fault is in (from the fault backwards) that is close to a
    keyword of the grammar (difflib's ratio) is that keyword misspelled if, the keyword
    written in its place, the parse goes past the fault: ``paralel(Dive(1), Dive(2))``
    fails at the second ``(``, ``parallel(...)`` parses. Otherwise a ``;`` is missing at
    the end of the token before the fault if, inserted there, the parse goes past it.
    Each guess is held to the parser (:class:`_Guesses`), so none is offered that would
    not help.
    """
    at_end = isinstance(e, UnexpectedEOF) or e.token.type == "$END"
    fault = len(text) if at_end else e.token.start_pos
    guesses = _Guesses(text, fault, len(text) if at_end else e.token.end_pos)
    tokens = []
    try:
        for token in _tree_parser().lex(text[:fault]):
            tokens.append(token)
    except UnexpectedInput:   # a character no token begins with: the tokens before it
        pass
    statement = next((i + 1 for i in range(len(tokens) - 1, -1, -1)
                      if tokens[i].type in ("SEMICOLON", "LBRACE", "RBRACE")), 0)
    words, _ = grammar_words()
    for token in [*([] if at_end else [e.token]), *reversed(tokens[statement:])][:_TRIED]:
        if not _WORD.fullmatch(token) or token in words:
            continue
        for word in difflib.get_close_matches(str(token), words, n=3, cutoff=0.5):
            if guesses.helps(token.start_pos, token.end_pos, word):
                return (f"unexpected '{token}'; did you mean '{word}'?", token.line,
                        token.column)
    if tokens and guesses.helps(tokens[-1].end_pos, tokens[-1].end_pos, ";"):
        last = tokens[-1]
        where = "" if at_end else \
            f" before '{e.token}'" + (f" (line {e.token.line})"
                                       if e.token.line != last.end_line else "")
        return f"missing ';'{where}", last.end_line, last.end_column
    return None


#: How deep blocks, structures, calls and tuples may nest. Missions people
#: write nest a handful of levels; the limit keeps every later stage (some
#: of which walk the program recursively) far from Python's stack limit.
MAX_NESTING = 100
_NESTING = {"block", "parallel", "monitor", "if_", "while_", "call", "primcall", "tuple",
            "pexpr", "pand", "pnot"}
_PROPERTY_NESTING = {"pexpr", "pand", "pnot"}


def _token_fault(token: Token) -> str | None:
    """Why a number is out of range or a string's escapes cannot be read, or None."""
    if token.type == "NUMBER":
        value = _number_value(str(token))
        return value if isinstance(value, str) else None
    if token.type == "STRING":
        value = _string_value(str(token))
        return value if isinstance(value, _BadString) else None
    return None


def _check_nesting(tree: Tree, lines: list[str], filename: str) -> None:
    """Refuse nesting deeper than :data:`MAX_NESTING`, keywords used as names, numbers
    out of range (:func:`_number_value`) and strings whose escapes cannot be read.

    One walk in source order, with a stack rather than recursion (a file
    nested 3,000 deep must get this message, not overflow Python's stack);
    the first fault in the file is the one reported.
    """
    stack: list[tuple[Tree | Token, int]] = [(tree, 0)]
    while stack:
        node, depth = stack.pop()
        if isinstance(node, Token):
            fault = _token_fault(node)
            if fault is not None:
                src = line_of(lines, node.line)
                raise Mcl2PnmlError(fault, Location(filename, node.line, node.column, src))
            if node.type == "NAME" and str(node) in keywords():
                # the contextual lexer lets a keyword through as a name
                src = line_of(lines, node.line)
                raise Mcl2PnmlError(f"'{node}' is a keyword and cannot be used as a name",
                                    Location(filename, node.line, node.column, src))
            continue
        if node.data in _NESTING:
            depth += 1
            if depth > MAX_NESTING:
                line, col = node.meta.line, node.meta.column
                src = line_of(lines, line)
                what = (f"more than {MAX_NESTING} levels of operators in a property; "
                        "write it more simply, or as several properties"
                        if node.data in _PROPERTY_NESTING else
                        f"more than {MAX_NESTING} levels of blocks, structures, calls and "
                        "tuples; split the mission into functions")
                raise Mcl2PnmlError(f"nested too deeply: {what}",
                                    Location(filename, line, col, src))
        stack.extend((child, depth) for child in reversed(node.children)
                     if isinstance(child, (Tree, Token)))


def _deepest(declarations: tuple[ast.Declaration, ...]) -> int:
    """How deep the AST's blocks, structures, calls and tuples nest: the tree's depth.

    Each of those rules builds one AST node, which holds what the rule's
    tree node holds, so the depths are the same; this walk is what the
    fast path pays to know that :func:`_check_nesting` has nothing to say.
    """
    deepest = 0
    stack: list[tuple[object, int]] = [(d, 0) for d in declarations]
    while stack:
        node, depth = stack.pop()
        children = _CHILDREN.get(type(node))
        if children is None:
            continue
        if type(node) in _NESTED:
            depth += 1
            deepest = max(deepest, depth)
        stack.extend((child, depth) for child in children(node) if child is not None)
    return deepest


_NESTED = {ast.Block, ast.Parallel, ast.Monitor, ast.If, ast.While, ast.Call, ast.PrimCall,
           ast.Tuple, ast.PropOr, ast.PropAnd, ast.PropNot}
_CHILDREN = {
    ast.Const: lambda n: (n.value,), ast.Task: lambda n: n.primitives,
    ast.PrimCall: lambda n: n.args, ast.Function: lambda n: (n.body,),
    ast.Mission: lambda n: (n.body,), ast.Block: lambda n: n.body,
    ast.Parallel: lambda n: n.items, ast.Monitor: lambda n: (n.watched, n.watcher),
    ast.If: lambda n: (n.condition, n.then, n.otherwise),
    ast.While: lambda n: (n.condition, n.body), ast.Call: lambda n: n.args,
    ast.Tuple: lambda n: n.items,
    ast.Property: lambda n: (n.p, n.s, n.q, n.r), ast.PropOr: lambda n: n.args,
    ast.PropAnd: lambda n: n.args, ast.PropNot: lambda n: (n.arg,),
}


def parse_file(path: str | Path, what: str | None = None, limit: int | None = None,
               option: str | None = None) -> ast.Program:
    """Parse the MCL file at ``path``; ``what`` names it in a message that it cannot be
    read, and a file over ``limit`` bytes is refused before it is read, ``option``
    raising the limit (:func:`mcl2pnml.core.files.read_bytes`)."""
    path = Path(path)
    return parse(decode(read_bytes(path, what, limit, option), str(path)), str(path))
