"""The template language: the paper's nets in a text a teacher can open and edit.

A template file (``templates/*.pnt``) describes one net of the paper: a
vehicle primitive, a task pattern, the reduced task, or a control structure.
For example, the reduced task of Fig. 3::

    reduced task-reduced "The reduced model of a task (Fig. 3, section 2.3)"

    place B = 1 interface     "begin: marked by the structure above"
    place A = 1 interface     "abort"
    place MTX = 1 interface   "mutex: the task is free"
    place OK interface
    place FAIL interface
    place ABORTED interface
    place EXE                 "running"

    transition t1: B, MTX -> EXE          "start"
    transition t2: EXE -> OK, MTX         "ends OK"

Syntax, line by line (``#`` starts a comment):

* ``KIND NAME [alias NAME ...] ["doc"]`` first: KIND is ``primitive``,
  ``pattern``, ``reduced`` or ``structure``;
* ``uses primitive [P, Q]``: slots for primitives. Unnamed, the slot's
  places are the primitive's interface places as they are (``E``, ``D``...);
  named ``P``, they are prefixed (``P_E``, ``P_D``...);
* ``uses structure T1, T2``: slots for subordinate structures, whose control
  places ``T1_B``, ``T1_A``, ``T1_MTX``, ``T1_OK``, ``T1_FAIL``,
  ``T1_ABORTED`` (the paper's fusion groups 27 and 28) are declared with it;
* ``place NAME [= TOKENS] [interface] ["doc"]``: the initial marking is the
  paper's M0 for this net (equations 6, 17 and 22 start from it);
* ``transition NAME: INPUTS -> OUTPUTS [timeout] [KEY=VALUE ...] ["doc"]``:
  an input ``?P`` is a read arc (P is tested, not consumed); ``P*2`` has
  weight 2; ``timeout`` marks the task's time-out (``t03`` in the paper);
  ``KEY=VALUE`` tags (``event=achieved``) say which vehicle event fires it.

Docs and tags go into each node's payload, so they reach PNML too.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from lark import Lark, Token, Transformer, UnexpectedInput, v_args

from mcl2pnml.core import payloads
from mcl2pnml.core.errors import Location, Mcl2PnmlError, did_you_mean, raise_all
from mcl2pnml.core.payloads import PayloadError
from mcl2pnml.core.net import ArcKind, Net, NetBuilder

#: The control interface of every task and structure (the paper's Fp, section 2.5).
CONTROL = ("B", "A", "MTX", "OK", "FAIL", "ABORTED")


class TemplateKind(enum.Enum):
    """What a template is, and so how it is composed."""

    PRIMITIVE = "primitive"
    """A vehicle primitive (section 2.2, Fig. 1): its interface places are
    fused with a pattern's primitive slot."""

    PATTERN = "pattern"
    """A task pattern (section 2.4): a task net with primitive slots, such as
    AchieveGoal (Fig. 2); fused with one primitive per slot."""

    REDUCED = "reduced"
    """The reduced model of a task (section 2.3, Fig. 3): what a structure
    sees of any task or structure below it."""

    STRUCTURE = "structure"
    """A control structure (section 2.5, Fig. 4): joins subordinate
    structures through their control places T1_B ... T1_ABORTED."""


GRAMMAR = r"""
start: _NL* header (_NL+ item)* _NL*
header: KIND NAME alias* STRING?
alias: "alias" NAME
?item: uses | place | transition
uses: "uses" USEKIND [NAME ("," NAME)*]
place: "place" NAME ["=" INT] [INTERFACE] [STRING]
transition: "transition" NAME ":" [arcs] "->" [arcs] tag* [STRING]
arcs: arc ("," arc)*
arc: [READ] NAME ["*" INT]
tag: TIMEOUT | NAME "=" NAME

KIND.2: "primitive" | "pattern" | "reduced" | "structure"
USEKIND.2: "primitive" | "structure"
INTERFACE.2: "interface"
TIMEOUT.2: "timeout"
READ: "?"
NAME: /[A-Za-z_][A-Za-z0-9_\-]*/
INT: /[0-9]+/
STRING: /"[^"\n]*"/
COMMENT: /#[^\n]*/
_NL: /(\r?\n[\t ]*)+/
%ignore /[\t ]+/
%ignore COMMENT
"""

@lru_cache(maxsize=None)
def _parser() -> Lark:
    """The templates' parser, built on first use (not at import: most commands read no
    template source)."""
    return Lark(GRAMMAR, parser="lalr", propagate_positions=True, maybe_placeholders=True)


@dataclass(frozen=True)
class Template:
    """A parsed template: its own net (slot places included) and its slots."""

    kind: TemplateKind
    name: str
    aliases: tuple[str, ...]
    doc: str
    net: Net
    primitives: tuple[str, ...]
    children: tuple[str, ...]
    source: str

    @property
    def names(self) -> tuple[str, ...]:
        return (self.name, *self.aliases)


def slot_places(slot: str, interface: tuple[str, ...]) -> dict[str, str]:
    """Slot place id -> the interface place it stands for (``T1_B`` -> ``B``)."""
    return {(f"{slot}_{p}" if slot else p): p for p in interface}


class _ToData(Transformer):
    """Parse tree -> plain tuples that keep their tokens (for positions)."""

    def start(self, items):
        return items

    def header(self, items):
        kind, name, *rest = items
        doc = rest[-1] if rest and isinstance(rest[-1], Token) and rest[-1].type == "STRING" else None
        aliases = [a for a in rest if not (isinstance(a, Token) and a.type == "STRING")]
        return ("header", kind, name, aliases, doc)

    def alias(self, items):
        return items[0]

    def uses(self, items):
        return ("uses", items[0], [n for n in items[1:] if n is not None])

    def place(self, items):
        name, tokens, interface, doc = items
        return ("place", name, int(tokens) if tokens else 0, interface is not None, doc)

    def transition(self, items):
        name, ins, outs, *rest = items
        doc = rest[-1] if rest and isinstance(rest[-1], Token) and rest[-1].type == "STRING" else None
        tags = [t for t in rest if isinstance(t, tuple)]
        return ("transition", name, ins or [], outs or [], tags, doc)

    def arcs(self, items):
        return items

    @v_args(inline=True)
    def arc(self, read, name, weight):
        return (read is not None, name, int(weight) if weight else 1)

    def tag(self, items):
        if len(items) == 1:
            return ("timeout", items[0], True)
        return (str(items[0]), items[0], str(items[1]))


def _describe(terminal: str) -> str:
    """A terminal as a user knows it: ``':'`` rather than ``COLON``."""
    try:
        pattern = _parser().get_terminal(terminal).pattern
    except KeyError:
        return terminal
    if pattern.type == "str":
        return f"'{pattern.value}'"
    return {"NAME": "a name", "INT": "a number", "STRING": "a \"doc string\"",
            "_NL": "end of line"}.get(terminal, terminal.lower())


def _doc(token) -> str | None:
    return token[1:-1] if token is not None else None


def _items(text: str, filename: str, lines: list[str]) -> list:
    """The template's items (:class:`_ToData`), or its one syntax error, located."""
    try:
        return _ToData().transform(_parser().parse(text if text.endswith("\n") else text + "\n"))
    except UnexpectedInput as e:
        expected = sorted({_describe(t) for t in (getattr(e, "expected", None)
                                                   or getattr(e, "allowed", None) or [])})
        hint = f"; expected {' or '.join(expected)}" if expected else ""
        src = lines[e.line - 1] if 0 < e.line <= len(lines) else None
        raise Mcl2PnmlError(f"syntax error in template{hint}",
                            Location(filename, e.line, e.column, src)) from None


class _TemplateReader:
    """One template's items into its net: the places declared, the slots, and every error
    found on the way (all of them said at once, :func:`raise_all`)."""

    def __init__(self, name: str, filename: str, lines: list[str],
                 primitive_interface: tuple[str, ...]):
        self.filename, self.lines = filename, lines
        self.primitive_interface = primitive_interface
        self.errors: list[Mcl2PnmlError] = []
        self.b = NetBuilder(name)
        self.declared: dict[str, Token] = {}
        self.slots_p: list[str] = []
        self.slots_c: list[str] = []

    def loc(self, token) -> Location:
        line = getattr(token, "line", None)
        col = getattr(token, "column", None)
        src = self.lines[line - 1] if line and 0 < line <= len(self.lines) else None
        return Location(self.filename, line, col, src)

    def declare(self, name: str, token, tokens: int = 0, interface: bool = False, doc=None):
        if name in self.declared:
            self.errors.append(Mcl2PnmlError(f"'{name}' is declared twice (first on line "
                                             f"{self.declared[name].line})", self.loc(token)))
            return
        self.declared[name] = token
        self.b.place(name, tokens, interface=name if interface else None,
                     payload=payloads.place_payload(doc))

    def places(self, items: list) -> None:
        """The places: a slot's (``uses``) and the template's own, in the file's order."""
        for item in items:
            if item[0] == "uses":
                self.uses(*item[1:])
            elif item[0] == "place":
                _, name, tokens, interface, pdoc = item
                self.declare(str(name), name, tokens, interface, _doc(pdoc))

    def uses(self, what, names) -> None:
        """A ``uses primitive`` or ``uses structure`` line: its slots and their places."""
        if what == "primitive":
            if not self.primitive_interface:
                self.errors.append(Mcl2PnmlError("'uses primitive' needs the primitive "
                                                 "template", self.loc(what)))
            for slot in names or [""]:
                self.slots_p.append(str(slot))
                for place in slot_places(str(slot), self.primitive_interface):
                    self.declare(place, slot or what, interface=True)
        else:
            if not names:
                self.errors.append(Mcl2PnmlError("'uses structure' names its slots, e.g. "
                                                 "T1, T2", self.loc(what)))
            for slot in names:
                self.slots_c.append(str(slot))
                for place in slot_places(str(slot), CONTROL):
                    self.declare(place, slot, interface=True)

    def transition(self, name, ins, outs, tags, tdoc) -> None:
        """A transition, its payload from its tags, and its arcs to declared places."""
        if str(name) in self.declared:
            self.errors.append(Mcl2PnmlError(f"'{name}' names a place already", self.loc(name)))
            return
        try:
            # read through the payload records: a tag they know with a bad
            # value (``event=arrived``) is an error of the template, here
            payload = payloads.tagged(_doc(tdoc), [(key, value) for key, _, value in tags])
        except PayloadError as e:
            self.errors.append(Mcl2PnmlError(e.message, self.loc(name)))
            return
        try:
            self.b.transition(str(name), payload=payload.to_json())
        except Mcl2PnmlError as e:
            self.errors.append(Mcl2PnmlError(e.message, self.loc(name)))
            return
        for (read, place, weight), direction in [(a, "in") for a in ins] + [(a, "out") for a in outs]:
            if str(place) not in self.declared:
                self.errors.append(Mcl2PnmlError(
                    f"undeclared place '{place}'" + did_you_mean(str(place), self.declared,
                                                                "declared places"),
                    self.loc(place)))
                continue
            if direction == "out":
                if read:
                    self.errors.append(Mcl2PnmlError("'?' (read) is for inputs only",
                                                     self.loc(place)))
                self.b.arc(str(name), str(place), weight)
            else:
                self.b.arc(str(place), str(name), weight,
                           ArcKind.READ if read else ArcKind.NORMAL)

    def of_its_kind(self, kind: TemplateKind, name_tok) -> None:
        """What the kind asks: the control places but of a primitive, primitives used by a
        pattern only, structures by a structure only."""
        if kind is not TemplateKind.PRIMITIVE:
            missing = [p for p in CONTROL if p not in self.declared]
            if missing:
                self.errors.append(Mcl2PnmlError(
                    f"a {kind.value} needs the control places {', '.join(CONTROL)}; missing: "
                    f"{', '.join(missing)}", self.loc(name_tok)))
        if kind is not TemplateKind.PATTERN and self.slots_p:
            self.errors.append(Mcl2PnmlError(f"only a pattern uses primitives, not a "
                                             f"{kind.value}", self.loc(name_tok)))
        if kind is not TemplateKind.STRUCTURE and self.slots_c:
            self.errors.append(Mcl2PnmlError(f"only a structure uses structures, not a "
                                             f"{kind.value}", self.loc(name_tok)))


def parse_template(text: str, filename: str = "<template>",
                   primitive_interface: tuple[str, ...] = ()) -> Template:
    """Parse one template file. ``primitive_interface`` lists the places a
    ``uses primitive`` slot declares (the primitive template's interface)."""
    lines = text.splitlines()
    items = _items(text, filename, lines)
    _, kind_tok, name_tok, aliases, doc = items[0]
    kind = TemplateKind(str(kind_tok))
    reader = _TemplateReader(str(name_tok), filename, lines, primitive_interface)
    reader.places(items[1:])
    for item in items[1:]:
        if item[0] == "transition":
            reader.transition(*item[1:])
    reader.of_its_kind(kind, name_tok)
    raise_all(reader.errors)
    try:
        net = reader.b.build()
    except Mcl2PnmlError as e:
        raise Mcl2PnmlError(e.message, Location(filename)) from None
    return Template(kind, str(name_tok), tuple(str(a) for a in aliases), _doc(doc) or "",
                    net, tuple(reader.slots_p), tuple(reader.slots_c), filename)


def load_template(path: str | Path, primitive_interface: tuple[str, ...] = ()) -> Template:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise Mcl2PnmlError(f"cannot read template: {e}", Location(str(path))) from None
    return parse_template(text, str(path), primitive_interface)
