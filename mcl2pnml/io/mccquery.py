"""A compiled mission's properties in the Model Checking Contest's property language.

The contest's XML (``<property-set xmlns="http://mcc.lip6.fr/">``, one
``<property>`` with its ``<id>``, ``<description>`` and ``<formula>`` each)
is what verifypn (``-x 1,2,3``), LoLA (``--xmlformula``) and every tool of
the contest read beside a PNML file. ``compile --queries`` writes three
properties, each the question one key of ``mcl2pnml analyze`` answers
(``docs/interop.md``):

* ``NAME-deadlock``: ``EF deadlock``, a dead marking is reachable. True for
  every mission, whose proper ends are dead markings: the query other tools
  call ReachabilityDeadlock, and analyze's ``terminal_markings`` not empty.
* ``NAME-deadlock-not-an-end``: ``EF (deadlock and not end)``, false exactly
  when analyze says ``deadlock_free``.
* ``NAME-end-always-reachable``: ``AG EF end``, true exactly when analyze
  says ``final_always_reachable``.

The deadlock inside the second formula is written for the tool that will
read the file (:data:`TOOLS`): ``<deadlock/>`` for verifypn and the contest's
tools, or, for LoLA, "no transition is fireable" (``is-fireable`` of every
transition, negated), which means the same. The LoLA build checked here (the
contest's, 2021) crashes on a ``<deadlock/>`` inside any formula, and given
``EF (DEADLOCK AND ...)`` as text it answers "true" on every mission; verifypn
answers both forms alike, but its query reduction spends 30 s on the long
one, where it answers the short one in a tenth of a second.

*end* is a proper end of the mission (:mod:`mcl2pnml.analysis.behaviour`; mcl.md:
"every net returns to its initial marking plus exactly one result place"):
one token in ``mission.OK``, ``mission.FAIL`` and ``mission.ABORTED``
together, and every other place but the inputs ``mission.B`` and
``mission.A`` as in the initial marking. It is written with ``integer-le``
alone, the comparison of the contest's own queries, because LoLA refuses
``integer-eq``; ``tokens-count`` of several places is their sum, so the
places empty at rest take one atom, and a marked place one atom plus its
share of one sum (every place at least its initial tokens, and all of them
no more than the initial total: each exactly its own).

A mission's own properties (``property`` declarations, docs/properties.md)
go in the contest's categories, one file each as the contest lays them
beside a model (``compile --properties``): every property in
LTLCardinality, as the LTL formula of its pattern and scope
(:mod:`mcl2pnml.core.temporal`); those a CTL formula states exactly in
CTLCardinality; the invariants (absence, universality, globally) in
ReachabilityCardinality. Their atoms are token counts, so the fireability
categories have none.

Place and transition ids are the PNML writer's (:func:`mcl2pnml.io.ids.encode`),
so the file goes with the PNML ``compile`` writes of the same net (and with
its LoLA file, whose names are the same for a compiled mission). Formulas
are written an element a line, indented, so that a reader can follow them.
"""
from __future__ import annotations

from dataclasses import dataclass
from html import escape as _escape
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import atomic_write_text, read_bytes
from mcl2pnml.core.net import Net
from mcl2pnml.core.payloads import RESULT_PLACES, MissionPlace
from mcl2pnml.core.settings import SettingError
from mcl2pnml.core.vocabulary import CAN_END
from mcl2pnml.io import ids

if TYPE_CHECKING:
    from mcl2pnml.core.queries import Query

#: (The properties' types, core.patterns, core.temporal and core.queries, are imported where
#: a property is written or read: 12-45 ms, measured with ``python -X importtime``, which
#: the CLI would pay at every start, as cli_options reads :data:`TOOLS` from here.)


def escape(text: str) -> str:
    # &, < and > as xml.sax.saxutils.escape does, without importing it: it imports urllib,
    # http and email, and the command line imports this module at start-up
    return _escape(text, quote=False)


NAMESPACE = "http://mcc.lip6.fr/"
#: The places the outside marks: no proper end is asked to leave them as they were.
INPUTS = (MissionPlace.B, MissionPlace.A)
#: The tools a file can be written for, and how each is given a deadlock inside a formula.
TOOLS = {"verifypn": "<deadlock/> (verifypn, and the contest's other tools)",
         "lola": "no transition fireable (LoLA crashes on <deadlock/> inside a formula)"}


@dataclass(frozen=True)
class Element:
    """An element of a formula: its tag, and its text or its child elements."""

    tag: str
    children: tuple["Element", ...] = ()
    text: str | None = None

    def lines(self, indent: str = "") -> list[str]:
        """The element an element a line; a short one, or one of leaves only, on one line."""
        # flat() only where it may be used: called on every element, it would write each
        # subtree again for each of its ancestors (a property of 100,000 atoms: minutes)
        if not self.children:
            return [indent + self.flat()]
        if all(not c.children for c in self.children):
            flat = self.flat()
            if len(flat) <= 96:
                return [indent + flat]
        inner = [line for c in self.children for line in c.lines(indent + "  ")]
        return [f"{indent}<{self.tag}>", *inner, f"{indent}</{self.tag}>"]

    def flat(self) -> str:
        if self.text is not None:
            return f"<{self.tag}>{escape(self.text)}</{self.tag}>"
        if not self.children:
            return f"<{self.tag}/>"
        return f"<{self.tag}>" + "".join(c.flat() for c in self.children) + f"</{self.tag}>"


@dataclass(frozen=True)
class Property:
    """One property of the file: its id, what it asks, its formula."""

    id: str
    #: what it asks, and the analysis key that answers it
    description: str
    formula: Element


def _e(tag: str, *children: Element) -> Element:
    return Element(tag, children)


def _tokens(places: list[str]) -> Element:
    return _e("tokens-count", *(Element("place", text=ids.encode(p)) for p in places))


def _int(value: int) -> Element:
    return Element("integer-constant", text=str(value))


def _and(parts: list[Element]) -> Element:
    # the contest's conjunction takes two operands or more
    return parts[0] if len(parts) == 1 else _e("conjunction", *parts)


def end_formula(net: Net) -> Element:
    """A proper end of the mission ``net`` (the module's docstring says which markings)."""
    results = [r.id for r in RESULT_PLACES]
    missing = [p for p in results + [i.id for i in INPUTS] if p not in net.place_index]
    if missing:
        raise Mcl2PnmlError(f"queries are written for a compiled mission; {net.name} has no "
                            f"place {', '.join(missing)} (a mission's places: "
                            f"{', '.join(p.id for p in MissionPlace)})", Location(net.name))
    skip = set(results) | {i.id for i in INPUTS}
    rest = [p.id for p in net.places if p.id not in skip]
    empty = [p for p in rest if not net.initial.get(p)]
    marked = [p for p in rest if net.initial.get(p)]
    parts = [_e("integer-le", _int(1), _tokens(results)),
             _e("integer-le", _tokens(results), _int(1))]
    if empty:
        parts.append(_e("integer-le", _tokens(empty), _int(0)))
    parts += [_e("integer-le", _int(net.initial[p]), _tokens([p])) for p in marked]
    if marked:
        total = sum(net.initial[p] for p in marked)
        parts.append(_e("integer-le", _tokens(marked), _int(total)))
    return _and(parts)


def dead(net: Net) -> Element:
    """No transition of ``net`` is fireable: a deadlock, in words every tool reads alike."""
    return _e("negation", _e("is-fireable", *(Element("transition", text=ids.encode(t.id))
                                              for t in net.transitions)))


def mission_properties(net: Net, tool: str = "verifypn") -> tuple[Property, ...]:
    """The three properties of the module's docstring, for the compiled mission ``net``,
    its deadlock inside a formula written for ``tool`` (a key of :data:`TOOLS`)."""
    if tool not in TOOLS:
        raise SettingError("tool", f"no tool '{tool}'; the queries are written for "
                                   f"{' or '.join(TOOLS)}")
    name = ids.encode(net.name or "net")
    end = end_formula(net)
    stuck = dead(net) if tool == "lola" else _e("deadlock")
    return (
        Property(f"{name}-deadlock",
                 "EF deadlock: a dead marking is reachable (true for every mission: its "
                 "proper ends are dead); mcl2pnml analyze: terminal_markings not empty",
                 _e("exists-path", _e("finally", _e("deadlock")))),
        Property(f"{name}-deadlock-not-an-end",
                 "EF (deadlock and not end): a dead marking that is not a proper end (one "
                 "of mission.OK, mission.FAIL, mission.ABORTED marked, every place but "
                 "mission.B and mission.A as initially) is reachable; "
                 "mcl2pnml analyze: deadlock_free is its negation",
                 _e("exists-path", _e("finally", _e("conjunction", stuck,
                                                    _e("negation", end))))),
        Property(f"{name}-end-always-reachable",
                 f"AG EF end: {CAN_END} (from every reachable marking); "
                 "mcl2pnml analyze: final_always_reachable",
                 _e("all-paths", _e("globally", _e("exists-path", _e("finally", end))))),
    )


def to_queries(properties: tuple[Property, ...]) -> str:
    """The property set as the contest writes it: one ``<property>`` each."""
    lines = ['<?xml version="1.0" encoding="utf-8"?>', f'<property-set xmlns="{NAMESPACE}">']
    for p in properties:
        lines += ["  <property>", f"    <id>{escape(p.id)}</id>",
                  f"    <description>{escape(p.description)}</description>",
                  *_e("formula", p.formula).lines("    "), "  </property>"]
    return "\n".join(lines + ["</property-set>", ""])


def write_queries(net: Net, path: str | Path, tool: str = "verifypn") -> tuple[Property, ...]:
    """Write the mission's properties for ``tool`` to ``path``, whole or not at all."""
    properties = mission_properties(net, tool)
    atomic_write_text(path, to_queries(properties))
    return properties


# -- a mission's own properties (docs/properties.md) ------------------------------------------

#: The contest's categories a property is written in, each its own file, as the contest
#: gives them beside a model: the file's suffix, and which form of the property it takes.
CATEGORIES = ("ReachabilityCardinality", "CTLCardinality", "LTLCardinality")


def _predicate(p) -> Element:
    """A predicate on places (:mod:`mcl2pnml.core.patterns`) as the contest's state formula."""
    from mcl2pnml.core.patterns import And, Const, Not, Tokens   # 12-45 ms: see the top
    if isinstance(p, Tokens):
        if not p.places:   # an empty sum is 0
            return _constant(p.at_least <= 0)
        return _e("integer-le", _int(p.at_least), _tokens(list(p.places)))
    if isinstance(p, Not):
        return _e("negation", _predicate(p.arg))
    if isinstance(p, Const):
        return _constant(p.value)
    parts = [_predicate(a) for a in p.args]
    if not parts:
        return _constant(isinstance(p, And))
    return parts[0] if len(parts) == 1 else _e(
        "conjunction" if isinstance(p, And) else "disjunction", *parts)


def _constant(value: bool) -> Element:
    """True as ``0 <= 0``, false as ``1 <= 0``: LoLA refuses the contest's ``<true/>``."""
    return _e("integer-le", _int(0 if value else 1), _int(0))


def formula_element(f) -> Element:
    """A temporal formula (:mod:`mcl2pnml.core.temporal`) as the contest's XML."""
    from mcl2pnml.core import temporal   # 12-45 ms: see the top
    if isinstance(f, temporal.State):
        return _predicate(f.predicate)
    if isinstance(f, temporal.Neg):
        return _e("negation", formula_element(f.arg))
    if isinstance(f, (temporal.Conj, temporal.Disj)):
        return _e("conjunction" if isinstance(f, temporal.Conj) else "disjunction",
                  *(formula_element(a) for a in f.args))
    if isinstance(f, temporal.Until):
        return _e("until", _e("before", formula_element(f.before)),
                  _e("reach", formula_element(f.reach)))
    tag = {temporal.Globally: "globally", temporal.Finally: "finally",
           temporal.AllPaths: "all-paths", temporal.ExistsPath: "exists-path"}[type(f)]
    return _e(tag, formula_element(f.arg))


def property_queries(props) -> dict[str, tuple[Property, ...]]:
    """Each category's queries for a mission's properties (``core.properties.Property``):
    every property in LTL; in CTL where a CTL formula means the same; in reachability
    where it is an invariant (:mod:`mcl2pnml.core.temporal`). The query's id is the
    property's name, the same in every category, and its description says what it is."""
    from mcl2pnml.core import temporal   # 12-45 ms: see the top
    forms = {"ReachabilityCardinality": temporal.reachability, "CTLCardinality": temporal.ctl,
             "LTLCardinality": temporal.ltl}
    out: dict[str, tuple[Property, ...]] = {}
    for category, form in forms.items():
        queries = []
        for prop in props:
            f = form(prop)
            if f is not None:
                where = f" ({prop.location.prefix()})" if prop.location else ""
                text = " ".join(prop.text.split()) or prop.name
                queries.append(Property(prop.name, f"{text}{where}: {temporal.show(f)}",
                                        formula_element(f)))
        if queries:
            out[category] = tuple(queries)
    return out


def property_query_files(stem: str | Path) -> dict[str, Path]:
    """Each category's file, ``STEM.CATEGORY.xml``: all that may be written, for checking
    them against the command's inputs first."""
    stem = Path(stem)
    return {category: stem.with_name(f"{stem.name}.{category}.xml") for category in CATEGORIES}


def write_property_queries(props, stem: str | Path) -> list[tuple[Path, tuple[Property, ...]]]:
    """Write each category's queries to ``STEM.CATEGORY.xml``, whole or not at all; the
    files written, with their queries."""
    files = property_query_files(stem)
    written = []
    for category, queries in property_queries(props).items():
        path = files[category]
        atomic_write_text(path, to_queries(queries))
        written.append((path, queries))
    return written


# -- reading the contest's files ----------------------------------------------------------------

#: The largest property file read, in bytes (the contest's are some tens of kilobytes).
MAX_QUERIES = 16 << 20
#: The deepest formula read (the contest's nest about 20 deep).
MAX_DEPTH = 400


class QueryError(Mcl2PnmlError):
    """A property file that is not the contest's language, or asks what we cannot say."""


def read_queries(path: str | Path) -> tuple[Query, ...]:
    """The queries of a contest property file (``<property-set>``), each with its location.

    Every element the contest's 2021 files use is read with its meaning; any
    other is refused, at its line and column, never guessed."""
    data = read_bytes(path, "property file", MAX_QUERIES)
    return parse_queries(data, str(path))


def parse_queries(data: bytes, filename: str = "<queries>") -> tuple[Query, ...]:
    """The queries of a contest property file's bytes (:func:`read_queries`)."""
    # the queries' types (12-45 ms: see the top) and lxml with the PNML reader's source
    # (15 ms): only when a property file is read
    from mcl2pnml.core import queries
    from mcl2pnml.io.pnml.source import Source, local, parse_xml
    src = Source(filename, data)
    return _QueryReader(src, local, queries).property_set(parse_xml(data, src).getroot())


class _QueryReader:
    """The contest's property language read from one file's elements, each fault at its
    line and column (:meth:`fail`)."""

    def __init__(self, src, local: Callable[[object], str], queries) -> None:
        # (``local``: an element's name without its namespace, the PNML reader's, which
        # comes with lxml; ``queries``: :mod:`mcl2pnml.core.queries`, imported by the caller)
        self.src, self.local, self.q = src, local, queries
        #: the contest's unary connectives and operators, by their elements
        self.unary = {"negation": queries.Neg, "next": queries.Next,
                      "globally": queries.Globally, "finally": queries.Finally,
                      "all-paths": queries.AllPaths, "exists-path": queries.ExistsPath}

    def fail(self, message: str, el) -> QueryError:
        return QueryError(message, self.src.locate(el))

    @staticmethod
    def children(el) -> list:
        return [c for c in el if isinstance(c.tag, str)]

    def text(self, el) -> str:
        value = (el.text or "").strip()
        if not value or self.children(el):
            raise self.fail(f"<{self.local(el)}> holds a name or a number, and nothing else", el)
        return value

    def names(self, el, tag: str) -> tuple[str, ...]:
        found = []
        for c in self.children(el):
            if self.local(c) != tag:
                raise self.fail(f"<{self.local(el)}> holds <{tag}> elements, not "
                                f"<{self.local(c)}>", c)
            found.append(self.text(c))
        if not found:
            raise self.fail(f"<{self.local(el)}> names no {tag}", el)
        return tuple(found)

    def integer(self, el):
        tag = self.local(el)
        if tag == "integer-constant":
            value = self.text(el)
            if not value.isdigit() or len(value) > 18:
                raise self.fail(f"'{value[:40]}' is not a natural number", el)
            return self.q.IntConst(int(value))
        if tag == "tokens-count":
            return self.q.TokensCount(self.names(el, "place"))
        raise self.fail(f"<{tag}> is not an integer expression; one of <integer-constant>, "
                        "<tokens-count>", el)

    def one(self, el):
        kids = self.children(el)
        if len(kids) != 1:
            raise self.fail(f"<{self.local(el)}> holds one formula, not {len(kids)}", el)
        return kids[0]

    def formula(self, el, depth: int = 0):
        if depth > MAX_DEPTH:
            raise self.fail(f"a formula nested more than {MAX_DEPTH} deep", el)
        tag = self.local(el)
        if tag in self.unary:
            return self.unary[tag](self.formula(self.one(el), depth + 1))
        if tag in ("conjunction", "disjunction"):
            args = tuple(self.formula(c, depth + 1) for c in self.children(el))
            if not args:
                raise self.fail(f"<{tag}> of nothing", el)
            return (self.q.Conj if tag == "conjunction" else self.q.Disj)(args)
        if tag == "until":
            parts = {self.local(c): c for c in self.children(el)}
            if set(parts) != {"before", "reach"} or len(self.children(el)) != 2:
                raise self.fail("<until> holds <before> and <reach>", el)
            return self.q.Until(self.formula(self.one(parts["before"]), depth + 1),
                           self.formula(self.one(parts["reach"]), depth + 1))
        if tag == "integer-le":
            kids = self.children(el)
            if len(kids) != 2:
                raise self.fail(f"<integer-le> compares two integers, not {len(kids)}", el)
            return self.q.IntLe(self.integer(kids[0]), self.integer(kids[1]))
        if tag == "is-fireable":
            return self.q.Fireable(self.names(el, "transition"))
        if tag == "deadlock":
            return self.q.Deadlock()
        if tag in ("true", "false"):
            return self.q.BoolConst(tag == "true")
        raise self.fail(f"<{tag}> is not an element of the contest's property language we "
                        "read", el)

    def property_set(self, root) -> tuple[Query, ...]:
        if self.local(root) != "property-set":
            raise self.fail(f"the root element is <{self.local(root)}>, not <property-set>",
                            root)
        out, seen = [], set()
        for prop in self.children(root):
            if self.local(prop) != "property":
                raise self.fail(f"<property-set> holds <property> elements, not "
                                f"<{self.local(prop)}>", prop)
            parts = {}
            for c in self.children(prop):
                if self.local(c) in parts:
                    raise self.fail(f"a second <{self.local(c)}> in one property", c)
                parts[self.local(c)] = c
            if "id" not in parts or "formula" not in parts:
                raise self.fail("a <property> has an <id> and a <formula>", prop)
            pid = self.text(parts["id"])
            if pid in seen:
                raise self.fail(f"a second property '{pid}'", parts["id"])
            seen.add(pid)
            body = self.one(parts["formula"])
            if self.local(body) == "place-bound":
                asks = self.q.PlaceBound(self.names(body, "place"))
            else:
                asks = self.formula(body)
            out.append(self.q.Query(pid, asks, self.src.locate(prop)))
        return tuple(out)
