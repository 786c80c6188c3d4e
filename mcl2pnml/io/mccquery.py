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

*end* is a proper end of the mission (:mod:`analysis.behaviour`; mcl.md:
"every net returns to its initial marking plus exactly one result place"):
one token in ``mission.OK``, ``mission.FAIL`` and ``mission.ABORTED``
together, and every other place but the inputs ``mission.B`` and
``mission.A`` as in the initial marking. It is written with ``integer-le``
alone, the comparison of the contest's own queries, because LoLA refuses
``integer-eq``; ``tokens-count`` of several places is their sum, so the
places empty at rest take one atom, and a marked place one atom plus its
share of one sum (every place at least its initial tokens, and all of them
no more than the initial total: each exactly its own).

Place and transition ids are the PNML writer's (:func:`mcl2pnml.io.ids.encode`),
so the file goes with the PNML ``compile`` writes of the same net (and with
its LoLA file, whose names are the same for a compiled mission). Formulas
are written an element a line, indented, so that a reader can follow them.
"""
from __future__ import annotations

from dataclasses import dataclass
from html import escape as _escape
from pathlib import Path

from mcl2pnml.core.errors import Location, Mcl2PnmlError, OptionError
from mcl2pnml.core.files import atomic_write_text
from mcl2pnml.core.net import Net
from mcl2pnml.core.payloads import RESULT_PLACES, MissionPlace
from mcl2pnml.io import ids


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
        flat = self.flat()
        if not self.children or (all(not c.children for c in self.children) and len(flat) <= 96):
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
        raise OptionError("--queries-for", f"no tool '{tool}'; the queries are written for "
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
                 "AG EF end: from every reachable marking a proper end can be reached; "
                 "mcl2pnml analyze: final_always_reachable",
                 _e("all-paths", _e("globally", _e("exists-path", _e("finally", end))))),
    )


def to_xml(properties: tuple[Property, ...]) -> str:
    """The property set as the contest writes it: one ``<property>`` each."""
    lines = ['<?xml version="1.0" encoding="utf-8"?>', f'<property-set xmlns="{NAMESPACE}">']
    for p in properties:
        lines += ["  <property>", f"    <id>{escape(p.id)}</id>",
                  f"    <description>{escape(p.description)}</description>",
                  *_e("formula", p.formula).lines("    "), "  </property>"]
    return "\n".join(lines + ["</property-set>", ""])


def save_queries(net: Net, path: str | Path, tool: str = "verifypn") -> tuple[Property, ...]:
    """Write the mission's properties for ``tool`` to ``path``, whole or not at all."""
    properties = mission_properties(net, tool)
    atomic_write_text(path, to_xml(properties))
    return properties
