"""TINA's ``.net`` format: time Petri nets as text (the Tina toolbox, LAAS-CNRS).

The format, as its manual (``formats(n)``, "The .net format") describes it:
a net is a series of declarations, each led by a keyword; spaces, tabs and
line breaks only separate; ``#`` starts a comment to the end of the line.

* ``net NAME``: the net's name;
* ``tr NAME [: LABEL] [INTERVAL] INPUTS -> OUTPUTS``: a transition, its
  static firing interval (``[a,b]``, ``[a,w[`` for no upper bound; the
  default ``[0,w[`` is an untimed transition) and its arcs. An input is
  ``p`` (one token), ``p*k`` (k tokens), ``p?k`` (a test, or read, arc),
  ``p?-k`` (an inhibitor arc), ``p!k`` and ``p!-k`` (stopwatch arcs);
* ``pl NAME [: LABEL] [(MARKING)] [INPUTS -> OUTPUTS]``: a place, its
  initial marking, and arcs seen from the place;
* ``lb NAME LABEL``, ``nt NAME 0|1 TEXT`` (a note), ``pr T... > T...``
  (priorities).

Names are ``[A-Za-z0-9_']+`` or any text in braces, where ``{``, ``}`` and
``\\`` are escaped with ``\\``. Weights and markings are integers, with an
optional ``K`` (thousands) or ``M`` (millions). Declarations superpose: a
node may be declared more than once, and arcs declared twice add up.

What TINA sees of our nets (:func:`to_tina`):

* time-outs are static intervals ``[d,d]``; bounds are integers, so a net
  whose delays are not whole seconds is written in a finer unit, stated in a
  ``# time unit`` comment that :func:`parse_tina` reads back;
* with ``urgent=True`` (what ``compile --format tina`` asks for: the
  executor's semantics), a transition that is neither timed nor fired by the
  vehicle gets ``[0,0]``: it fires as soon as it is enabled, before time
  passes, as in the executor; a transition the vehicle fires (an event)
  keeps ``[0,w[``, since the vehicle may report at any time, or never;
* read arcs are test arcs ``p?k``; names shown to people are labels;
* what TINA has no words for (interface labels, payloads: the vehicle's
  actions and events, the call sites' bindings) is written as comments,
  one before each node that has some, for the reader of the file.

:func:`parse_tina` reads any ``.net`` file into a :class:`~mcl2pnml.core.net.Net`
for ``mcl2pnml analyze``. Inhibitor and stopwatch arcs, priorities and open
time bounds (``]a,`` or ``,b[``) are beyond what our nets can say, and are
refused with their position rather than dropped.
"""
from __future__ import annotations

import json
import re
from fractions import Fraction
from pathlib import Path

from lark import Lark, Token, UnexpectedInput

from mcl2pnml.core.version import __version__
from mcl2pnml.core.bounds import MAX_SECONDS, MAX_TOKENS, MAX_TOKENS_TEXT, natural_at_most
from mcl2pnml.core.errors import Location, Mcl2PnmlError, source_lines
from mcl2pnml.core.files import atomic_write_text, decode_text, read_bytes
from mcl2pnml.core.net import ArcKind, Net, NetBuilder, Timing, thaw
from mcl2pnml.core.payloads import read_transition
from mcl2pnml.core.timing import DIGITS
from mcl2pnml.io.text import syntax_error

# -- writing ---------------------------------------------------------------------------

_ANAME = re.compile(r"[A-Za-z0-9_']+\Z")
_KEYWORDS = {"net", "tr", "pl", "lb", "nt", "pr"}


def name(text: str) -> str:
    """A name as TINA writes it: plain when it can be, else in braces, escaped."""
    if _ANAME.match(text) and text not in _KEYWORDS:
        return text
    return "{" + re.sub(r"([{}\\])", r"\\\1", text) + "}"


def time_unit(net: Net) -> int:
    """The power of ten ``d`` such that every bound, in units of 10^-d s, is whole."""
    bounds = [b for t in net.transitions if t.timing is not None
              for b in (t.timing.earliest, t.timing.latest) if b is not None]
    for digits in range(DIGITS + 1):
        if all(abs(b * 10 ** digits - round(b * 10 ** digits)) < 1e-9 for b in bounds):
            return digits
    raise Mcl2PnmlError(f"a time bound of net '{net.name}' is finer than a microsecond; "
                        "TINA's bounds are whole numbers of a unit")


def _bound(seconds: float, digits: int) -> str:
    return str(round(seconds * 10 ** digits))


def _json(payload) -> str:
    return json.dumps(thaw(payload), sort_keys=True, separators=(",", ":"))


def _comment(text: str) -> str:
    return "# " + " ".join(text.split())


def to_tina(net: Net, *, urgent: bool = False) -> str:
    """The net as TINA ``.net`` text (see the module's documentation)."""
    digits = time_unit(net)
    unit = "1 s" if digits == 0 else f"{Fraction(1, 10 ** digits)} s"
    lines = [f"# {net.name or 'net'}: written by mcl2pnml {__version__}",
             f"# time unit: {unit} (every time bound below counts this unit)"]
    if urgent:
        lines.append("# untimed transitions that the vehicle does not fire are [0,0]: "
                     "they fire as soon as they are enabled")
    lines += [f"net {name(net.name or 'net')}", ""]
    for p in net.places:
        notes = []
        if p.interface is not None:
            notes.append(f"interface {p.interface}")
        if p.payload:
            notes.append(f"payload {_json(p.payload)}")
        if notes:
            lines.append(_comment(f"{p.id}: " + "; ".join(notes)))
        label = f" : {name(p.name)}" if p.name is not None else ""
        tokens = net.initial[p.id]
        lines.append(f"pl {name(p.id)}{label}" + (f" ({tokens})" if tokens else ""))
    lines.append("")
    pre, post = net.pre, net.post
    for t in net.transitions:
        if t.payload:
            lines.append(_comment(f"{t.id}: payload {_json(t.payload)}"))
        label = f" : {name(t.name)}" if t.name is not None else ""
        if t.timing is not None:
            hi = "w[" if t.timing.latest is None else _bound(t.timing.latest, digits) + "]"
            interval = f" [{_bound(t.timing.earliest, digits)},{hi}"
        elif urgent and read_transition(t).event is None:
            interval = " [0,0]"
        else:
            interval = ""
        inputs = [name(a.source) + ("?" + str(a.weight) if a.kind is ArcKind.READ
                                    else "" if a.weight == 1 else f"*{a.weight}")
                  for a in pre[t.id]]
        outputs = [name(a.target) + ("" if a.weight == 1 else f"*{a.weight}")
                   for a in post[t.id]]
        lines.append(f"tr {name(t.id)}{label}{interval} {' '.join(inputs)} -> "
                     f"{' '.join(outputs)}".rstrip())
    return "\n".join(lines) + "\n"


def write_tina(net: Net, path: str | Path, *, urgent: bool = False) -> Path:
    """Write ``net`` to ``path`` as TINA ``.net``, whole or not at all."""
    atomic_write_text(path, to_tina(net, urgent=urgent))
    return Path(path)


# -- reading ---------------------------------------------------------------------------

GRAMMAR = r"""
start: decl*
?decl: net | tr | pl | lb | nt | pr
net: "net" name
tr: "tr" name label? INTERVAL? arcs?
pl: "pl" name label? marking? arcs?
lb: "lb" name name
nt: "nt" name name name    // the middle one is 0 or 1: a name here, as names may be digits
pr: "pr" name+ (LT | GT) name+
label: ":" name
marking: "(" NUMBER ")"
arcs: arc* ARROW arc*
arc: name (STAR NUMBER | TEST NUMBER | INHIBIT NUMBER | STOPWATCH NUMBER | STOPINH NUMBER)?
?name: ANAME | QNAME

ARROW: "->"
STAR: "*"
TEST: "?"
INHIBIT: "?-"
STOPWATCH: "!"
STOPINH: "!-"
LT: "<"
GT: ">"
INTERVAL: /[\[\]][ \t\r\n]*\d+[ \t\r\n]*,[ \t\r\n]*(\d+|w)[ \t\r\n]*[\[\]]/
NUMBER: /\d+[KM]?/
ANAME: /[A-Za-z0-9_']+/
QNAME: /\{([^{}\\]|\\.)*\}/s
COMMENT: /#[^\n]*/
%import common.WS
%ignore WS
%ignore COMMENT
"""

_PARSER = Lark(GRAMMAR, parser="lalr", propagate_positions=True, maybe_placeholders=False)

_READABLE = {"ANAME": "a name", "QNAME": "a name in braces", "NUMBER": "a number",
             "INTERVAL": "a time interval", "ARROW": "'->'", "$END": "the end of the file",
             "NET": "'net'", "TR": "'tr'", "PL": "'pl'", "LB": "'lb'", "NT": "'nt'",
             "PR": "'pr'", "STAR": "'*'", "TEST": "'?'", "INHIBIT": "'?-'",
             "STOPWATCH": "'!'", "STOPINH": "'!-'", "LPAR": "'('", "RPAR": "')'",
             "COLON": "':'", "LT": "'<'", "GT": "'>'"}
_UNIT = re.compile(r"#\s*time unit:\s*(\d+)(?:/(\d+))?\s*s\b")


def _text(token: Token) -> str:
    if token.type == "QNAME":
        return re.sub(r"\\(.)", r"\1", token[1:-1], flags=re.S)
    return str(token)


def _number(token: Token) -> int | None:
    """A marking or weight (``3``, ``2K``, ``5M``); None past :data:`MAX_TOKENS`."""
    text = str(token)
    scale = {"K": 1_000, "M": 1_000_000}.get(text[-1], 1)
    value = natural_at_most(text.rstrip("KM"), MAX_TOKENS)
    return None if value is None or value * scale > MAX_TOKENS else value * scale


class _Reader:
    """Superposes the declarations of one file into a net."""

    def __init__(self, text: str, filename: str):
        self.text, self.filename = text, filename
        self.lines = source_lines(text)
        self.name = Path(filename).stem or "net"
        self.kinds: dict[str, str] = {}          # node -> "place" | "transition"
        self.order: list[str] = []
        self.labels: dict[str, str] = {}
        self.marking: dict[str, int] = {}
        self.timing: dict[str, Timing | None] = {}
        self.arcs: dict[tuple[str, str, ArcKind], int] = {}
        match = _UNIT.search(text)
        self.unit: Fraction | int = 1
        if match:
            # a unit of absurd size is no unit of ours: counted in seconds, as TINA does
            num, den = (natural_at_most(match.group(1), MAX_SECONDS),
                        natural_at_most(match.group(2) or "1", MAX_SECONDS))
            if num and den:
                self.unit = Fraction(num, den)

    def at(self, item, message: str) -> Mcl2PnmlError:
        line = getattr(item, "line", None) or getattr(getattr(item, "meta", None), "line", None)
        col = getattr(item, "column", None) or getattr(getattr(item, "meta", None), "column",
                                                       None)
        src = self.lines[line - 1] if line and 0 < line <= len(self.lines) else None
        return Mcl2PnmlError(message, Location(self.filename, line, col, src))

    def node(self, token: Token, kind: str) -> str:
        node = _text(token)
        seen = self.kinds.get(node)
        if seen is None:
            self.kinds[node] = kind
            self.order.append(node)
        elif seen != kind:
            raise self.at(token, f"'{node}' is declared as a {seen} and used as a {kind}")
        return node

    def number(self, token: Token, what: str) -> int:
        """A marking or an arc weight, at most :data:`MAX_TOKENS`."""
        value = _number(token)
        if value is None:
            shown = f" {token}" if len(token) <= 30 else f", a number of {len(token):,} digits,"
            raise self.at(token, f"{what}{shown} is too large: markings and weights go up "
                                 f"to {MAX_TOKENS_TEXT}")
        return value

    def arc(self, place: str, transition: str, kind: ArcKind, weight: int,
            into_transition: bool, where) -> None:
        key = (place, transition, kind) if into_transition else (transition, place, kind)
        total = self.arcs.get(key, 0) + weight
        if total > MAX_TOKENS:   # arcs of one pair add up
            raise self.at(where, f"the arcs between '{place}' and '{transition}' weigh more "
                                 f"than {MAX_TOKENS_TEXT} together")
        self.arcs[key] = total

    def weighted(self, arc) -> tuple[Token, ArcKind, int]:
        target, *rest = arc.children
        if not rest:
            return target, ArcKind.NORMAL, 1
        op, count = rest
        weight = self.number(count, "the weight")
        if weight == 0:
            raise self.at(count, "an arc's weight must be at least 1")
        if op.type in ("INHIBIT", "STOPWATCH", "STOPINH"):
            what = {"INHIBIT": "inhibitor", "STOPWATCH": "stopwatch",
                    "STOPINH": "stopwatch-inhibitor"}[op.type]
            raise self.at(op, f"{what} arcs ('{op}') are not part of a P/T net; mcl2pnml "
                              "reads nets with normal and test arcs only")
        return target, (ArcKind.READ if op.type == "TEST" else ArcKind.NORMAL), weight

    def declare(self, tree) -> None:
        kind = tree.data
        if kind == "net":
            self.name = _text(tree.children[0])
        elif kind in ("lb", "nt"):
            if kind == "lb":
                node, label = tree.children
                self.labels[_text(node)] = _text(label)
        elif kind == "pr":
            raise self.at(tree, "priorities ('pr') are not part of a P/T net; mcl2pnml "
                                "cannot analyse them")
        elif kind == "tr":
            self.transition(tree)
        else:
            self.place(tree)

    def transition(self, tree) -> None:
        head, *rest = tree.children
        t = self.node(head, "transition")
        for item in rest:
            if isinstance(item, Token):          # the interval
                self.interval(t, item)
            elif item.data == "label":
                self.labels[t] = _text(item.children[0])
            else:
                inputs = True
                for arc in item.children:
                    if isinstance(arc, Token):   # the arrow
                        inputs = False
                        continue
                    target, kind, weight = self.weighted(arc)
                    if kind is ArcKind.READ and not inputs:
                        raise self.at(arc, "a test arc ('?') goes from a place to a "
                                           "transition: put it before '->'")
                    self.arc(self.node(target, "place"), t, kind, weight, inputs, arc)

    def place(self, tree) -> None:
        head, *rest = tree.children
        p = self.node(head, "place")
        for item in rest:
            if item.data == "label":
                self.labels[p] = _text(item.children[0])
            elif item.data == "marking":
                tokens = self.number(item.children[0], "the marking")
                if p in self.marking and self.marking[p] != tokens:
                    raise self.at(item, f"place '{p}' is given {self.marking[p]} and then "
                                        f"{tokens} tokens")
                if tokens:
                    self.marking[p] = tokens
            else:
                inputs = True       # transitions that give to p, then those that take
                for arc in item.children:
                    if isinstance(arc, Token):
                        inputs = False
                        continue
                    target, kind, weight = self.weighted(arc)
                    if kind is ArcKind.READ and inputs:
                        raise self.at(arc, "a test arc ('?') goes from a place to a "
                                           "transition: put it after '->'")
                    self.arc(p, self.node(target, "transition"), kind, weight, not inputs,
                             arc)

    def interval(self, t: str, token: Token) -> None:
        text = re.sub(r"\s", "", str(token))
        low, high = text[1:-1].split(",")
        if text[0] == "]" or (text[-1] == "[" and high != "w") or (high == "w" and
                                                                  text[-1] == "]"):
            raise self.at(token, f"the interval {text} has an open bound; mcl2pnml's "
                                 "timings are closed intervals ([a,b] or [a,w[)")
        bounds = [natural_at_most(b, MAX_SECONDS * 10 ** DIGITS) for b in (low, high)
                  if b != "w"]
        if None in bounds or any(b * self.unit > MAX_SECONDS for b in bounds):
            shown = text if len(text) <= 40 else f"of {len(text) - 3:,} characters"
            raise self.at(token, f"the interval {shown} is too long: time bounds go up "
                                 f"to {MAX_SECONDS:,} s")
        lo = Fraction(bounds[0]) * self.unit
        hi = None if high == "w" else Fraction(bounds[1]) * self.unit
        if hi is not None and hi < lo:
            raise self.at(token, f"the interval {text} is empty")
        self.timing[t] = None if (lo == 0 and hi is None) else Timing(float(lo), None if hi is None
                                                                     else float(hi))

    def net(self) -> Net:
        b = NetBuilder(self.name)
        for node in self.order:
            label = self.labels.get(node)
            if self.kinds[node] == "place":
                b.place(node, self.marking.get(node, 0), name=label)
            else:
                b.transition(node, name=label, timing=self.timing.get(node))
        for (source, target, kind), weight in self.arcs.items():
            b.arc(source, target, weight, kind)
        return b.build()


def parse_tina(text: str, filename: str = "<tina>") -> Net:
    """A net from TINA ``.net`` text; errors name the file, line and column."""
    reader = _Reader(text, filename)
    try:
        tree = _PARSER.parse(text)
    except UnexpectedInput as e:
        raise syntax_error(e, text, reader.lines, filename, _READABLE) from None
    for decl in tree.children:
        reader.declare(decl)
    try:
        return reader.net()
    except Mcl2PnmlError as e:   # e.g. a transition that reads and takes one place
        raise Mcl2PnmlError(e.message, Location(filename)) from None


def read_tina(path: str | Path) -> Net:
    """A net from a TINA ``.net`` file."""
    return parse_tina(decode_text(read_bytes(path), str(path), "a TINA"), str(path))
