"""LoLA's net format: P/T nets as text (the LoLA model checker, University of Rostock).

The format, as LoLA 2's manual describes it::

    PLACE p1, p2, p3;              { optionally "SAFE k :" before a list }
    MARKING p1: 1, p3: 2;
    TRANSITION t1                  { optionally "WEAK FAIR" or "STRONG FAIR" }
      CONSUME p1: 1;
      PRODUCE p2: 1, p3: 1;

A name is any run of characters but white space and ``, ; : ( ) { }``;
a weight or a count left out is 1; ``{ ... }`` is a comment (and, as
LoLA 2 also reads them, ``/* ... */`` and ``// ...``). The keywords are
upper case: PLACE, MARKING, TRANSITION, CONSUME, PRODUCE, SAFE, WEAK,
STRONG, FAIR.

What LoLA sees of our nets (:func:`to_lola`): places, transitions, weights
and the initial marking. It has no time, so time-outs are plain
transitions (the untimed semantics of our own analysis, noted in a
comment); a read arc is a CONSUME and a PRODUCE of the same place (the
same firing rule; read back, it is that self-loop). Ids that are not LoLA
names (white space or punctuation in them, or a keyword) are written with
the ``_xHHHH_`` escapes of our PNML ids, and a ``{ ids: xml-name-escapes }``
comment tells :func:`parse_lola` to decode them.
"""
from __future__ import annotations

import re
from pathlib import Path

from lark import Lark, Token, UnexpectedInput

from mcl2pnml.core.version import __version__
from mcl2pnml.core.errors import Location, Mcl2PnmlError, source_lines
from mcl2pnml.core.files import atomic_write_text, decode_text, read_bytes
from mcl2pnml.core.net import ArcKind, Net, NetBuilder
from mcl2pnml.core.bounds import MAX_TOKENS, MAX_TOKENS_TEXT, natural_at_most
from mcl2pnml.io import ids
from mcl2pnml.io.text import syntax_error

KEYWORDS = {"PLACE", "MARKING", "TRANSITION", "CONSUME", "PRODUCE", "SAFE", "WEAK",
            "STRONG", "FAIR"}
_NAME = re.compile(r"[^,;:(){}\s]+\Z")
_ESCAPED = "{ ids: xml-name-escapes }"


def _needs_escape(node: str) -> bool:
    # "_x" would read as the start of an escape once the file says it has them
    return not _NAME.match(node) or node in KEYWORDS or node.startswith(("//", "/*")) \
        or "_x" in node


def _encode(node: str) -> str:
    """``node`` as a LoLA name that :func:`ids.decode` maps back: the XML-name escapes,
    and a keyword's first letter escaped too (a keyword is an XML name, left as it is)."""
    name = ids.encode(node)
    return f"_x{ord(name[0]):04X}_{name[1:]}" if name in KEYWORDS else name


def to_lola(net: Net) -> str:
    """The net as LoLA text (see the module's documentation)."""
    nodes = [p.id for p in net.places] + [t.id for t in net.transitions]
    escape = any(map(_needs_escape, nodes))
    out = _encode if escape else (lambda n: n)
    timed = [t.id for t in net.transitions if t.timing is not None]
    reads = sum(a.kind is ArcKind.READ for a in net.arcs)
    head = [f"{{ {_safe(net.name or 'net')}: written by mcl2pnml {__version__} }}"]
    if escape:
        head.append(_ESCAPED)
    if timed:
        head.append(f"{{ {len(timed)} timed transitions (time-outs) are untimed here: LoLA "
                    "has no time }")
    if reads:
        head.append(f"{{ {reads} read arcs are a CONSUME and a PRODUCE of one place }}")
    places = [out(p.id) for p in net.places]
    lines = [*head, "", "PLACE"]
    lines += [f"  {p}{',' if k < len(places) - 1 else ';'}" for k, p in enumerate(places)]
    if not places:
        lines[-1] += " ;"
    marked = [f"{out(p)}: {n}" for p, n in net.initial.items()]
    lines += ["", "MARKING", *(f"  {m}{',' if k < len(marked) - 1 else ''}"
                               for k, m in enumerate(marked)), "  ;", ""]
    pre, post = net.pre, net.post
    for t in net.transitions:
        consume: dict[str, int] = {}
        produce: dict[str, int] = {}
        for a in pre[t.id]:
            consume[a.source] = consume.get(a.source, 0) + a.weight
            if a.kind is ArcKind.READ:
                produce[a.source] = produce.get(a.source, 0) + a.weight
        for a in post[t.id]:
            produce[a.target] = produce.get(a.target, 0) + a.weight
        lines.append(f"TRANSITION {out(t.id)}")
        lines.append("  CONSUME " + ", ".join(f"{out(p)}: {w}" for p, w in consume.items())
                     + ";")
        lines.append("  PRODUCE " + ", ".join(f"{out(p)}: {w}" for p, w in produce.items())
                     + ";")
    return "\n".join(lines) + "\n"


#: What may not appear in a ``{ }`` comment: its end, and (LoLA reads such a comment
#: within one line) line breaks and the other control characters.
_UNSAFE = str.maketrans({"{": "(", "}": ")", **{chr(c): " " for c in (*range(32), 127)}})


def _safe(text: str) -> str:
    """Text for inside a ``{ }`` comment, on one line (LoLA 2's lexer: ``"{"[^\\n\\r]*"}"``)."""
    return text.translate(_UNSAFE)


def write_lola(net: Net, path: str | Path) -> Path:
    """Write ``net`` to ``path`` as LoLA text, whole or not at all."""
    atomic_write_text(path, to_lola(net))
    return Path(path)


# -- reading ---------------------------------------------------------------------------

GRAMMAR = r"""
start: "PLACE" placelists "MARKING" [counts] ";" transition*
placelists: (placelist ";")+
placelist: [capacity] NAME ("," NAME)*
capacity: "SAFE" [NUMBER] ":"
counts: count ("," count)*
count: NAME [":" NUMBER]
transition: "TRANSITION" NAME [fairness] "CONSUME" [counts] ";" "PRODUCE" [counts] ";"
fairness: ("WEAK" | "STRONG") "FAIR"

NUMBER.2: /\d+(?![^,;:(){}\s])/
NAME: /[^,;:(){}\s]+/
COMMENT: /\{[^}]*\}/ | /\/\*(.|\n)*?\*\// | /\/\/[^\n]*/
%import common.WS
%ignore WS
%ignore COMMENT
"""

_PARSER = Lark(GRAMMAR, parser="lalr", maybe_placeholders=True)
_READABLE = {"NAME": "a name", "NUMBER": "a number", "$END": "the end of the file",
             "SEMICOLON": "';'", "COMMA": "','", "COLON": "':'",
             **{k: f"'{k}'" for k in KEYWORDS}}


def parse_lola(text: str, filename: str = "<lola>") -> Net:
    """A net from LoLA text; errors name the file, line and column."""
    lines = source_lines(text)
    try:
        tree = _PARSER.parse(text)
    except UnexpectedInput as e:
        raise syntax_error(e, text, lines, filename, _READABLE) from None
    decode = ids.decode if _ESCAPED in text else (lambda n: n)

    def at(token: Token, message: str) -> Mcl2PnmlError:
        src = lines[token.line - 1] if 0 < token.line <= len(lines) else None
        return Mcl2PnmlError(message, Location(filename, token.line, token.column, src))

    def count(n: Token | None) -> int:
        """A marking or a weight, at most :data:`MAX_TOKENS`."""
        if n is None:
            return 1
        value = natural_at_most(str(n), MAX_TOKENS)
        if value is None:
            shown = str(n) if len(n) <= 30 else f"a number of {len(n):,} digits"
            raise at(n, f"{shown} is too large: markings and weights go up to "
                        f"{MAX_TOKENS_TEXT}")
        return value

    def pairs(counts) -> list[tuple[Token, int]]:
        if counts is None:
            return []
        return [(name, count(n)) for name, n in (c.children for c in counts.children)]

    b = NetBuilder(Path(filename).stem or "net")
    places: set[str] = set()
    placelists, counts, *transitions = tree.children
    for placelist in placelists.children:
        for token in placelist.children[1:]:
            p = decode(str(token))
            if p in places:
                raise at(token, f"place '{p}' is declared twice")
            places.add(p)
            b.place(p)
    marking: dict[str, int] = {}
    for token, n in pairs(counts):
        p = decode(str(token))
        if p not in places:
            raise at(token, f"the marking names '{p}', which is not a declared place")
        marking[p] = marking.get(p, 0) + n
        if marking[p] > MAX_TOKENS:   # a place named twice: its counts add up
            raise at(token, f"place '{p}' is given more than {MAX_TOKENS_TEXT} tokens in all")
    seen: set[str] = set()
    for tr in transitions:
        token, _, consume, produce = tr.children
        t = decode(str(token))
        if t in seen or t in places:
            raise at(token, f"'{t}' is declared twice")
        seen.add(t)
        b.transition(t)
        for side, items in (("consume", consume), ("produce", produce)):
            for place, weight in pairs(items):
                p = decode(str(place))
                if p not in places:
                    where = "from" if side == "consume" else "into"
                    raise at(place, f"transition '{t}' would {side} {where} '{p}', which is "
                                    "not a declared place")
                if weight == 0:
                    continue   # an arc of weight 0 moves nothing: it is no arc
                if side == "consume":
                    b.arc(p, t, weight)
                else:
                    b.arc(t, p, weight)
    net = b.build()
    return net.with_initial({p: n for p, n in marking.items() if n})


def read_lola(path: str | Path) -> Net:
    """A net from a LoLA file."""
    return parse_lola(decode_text(read_bytes(path), str(path), "a LoLA"), str(path))
