"""Validation of PNML P/T nets: our schema, the official grammar where given, the reader's rules.

Three judges, in this order:

1. mcl2pnml's own RELAX NG schema of ISO/IEC 15909-2 P/T nets (``ptnet.rng``
   beside this module, shipped with the package), always;
2. the official 2009 grammar (AFNOR's RELAX NG files, not shipped with
   mcl2pnml), when it is given: the directory given explicitly (``mcl2pnml
   validate --grammar DIR``), else the one in the environment variable
   ``MCL2PNML_PNML_GRAMMAR`` (``none``: our schema alone). It is never looked
   for: a file's verdict does not depend on the folders above the working
   directory or the package (a checkout passes ``--grammar ../shared/pnml-grammar``
   where that is, as its tests and ``make demo`` do). A directory given must
   hold ``ptnet.pntd`` and the files it includes (``pnmlcoremodel.rng``,
   ``conventions.rng``, ``anyElement.rng``) with local ``include`` references,
   as pnml.org's ``grammar.zip`` unpacked and pointed at its own files; one
   that does not, or that lxml cannot compile, is an error;
3. the reader's own rules (:func:`mcl2pnml.io.pnml.reader.parse_pnml`), which
   no RELAX NG schema can express: an arc from a place to a place passes
   both schemas.

A file is valid only when every judge applied finds it so. The two schemas
admit the same documents (``tests/io/test_schema.py`` holds them side by side on
every file we write, a corpus and its mutations), but for some orders of a
page's children that the standard admits and libxml2, checking the official
grammar, refuses; where both reject an element, one message says so, naming
both, in our schema's words.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

from lxml import etree

from mcl2pnml.core.errors import ErrorList, Location, Mcl2PnmlError, PnmlError
from mcl2pnml.io.pnml.reader import parse_pnml
from mcl2pnml.io.pnml.source import Source, XmlError, parse_xml, read_file
from mcl2pnml.io.pnml.writer import NS, PTNET

ENV = "MCL2PNML_PNML_GRAMMAR"
ENTRY = "ptnet.pntd"
#: The value of ``$MCL2PNML_PNML_GRAMMAR`` that applies our schema alone.
NONE = "none"
#: Our schema, package data of :mod:`mcl2pnml.io.pnml`.
SCHEMA = "ptnet.rng"
OURS = "mcl2pnml's ISO/IEC 15909-2 schema"
OFFICIAL = "official 2009 grammar"
CORE_MODEL = "http://www.pnml.org/version-2009/grammar/pnmlcoremodel"
#: How a schema message says which schema gave it.
_SAID_BY = {frozenset({OURS}): "schema", frozenset({OFFICIAL}): "official grammar",
            frozenset({OURS, OFFICIAL}): "schema and official grammar"}
#: libxml2's message for an IDREF that names no id: it comes without a node.
_UNKNOWN_ID = re.compile(r'IDREF attribute (\S+) references an unknown ID "(.*)"')
#: libxml2's messages that blame an element's attributes, naming the element.
_ATTRIBUTES = re.compile(r"Element (\S+) failed to validate attributes|"
                         r"Invalid attribute \S+ for element (\S+)")
#: A step of a libxml2 path with a namespace prefix.
_PREFIXED = re.compile(r"([A-Za-z_][\w.-]*):([A-Za-z_][\w.-]*)")
#: What is valid, for the faults where libxml2 says only that something is not:
#: (the element at fault, what libxml2 says of it, what to add).
_HINTS = (
    ("pnml", re.compile(r"Expecting a namespace for element"),
     f'PNML elements are in the namespace "{NS}"'),
    ("net", re.compile(r"Element net failed to validate attributes"),
     f"a net has an id and the type {PTNET} (or the core model's, {CORE_MODEL})"),
    ("net", re.compile(r"Expecting an element, got nothing"), "a net has one page at least"),
)


def find_grammar(explicit: str | Path | None = None) -> Path | None:
    """The directory of the official PNML grammar given (``explicit``, else
    ``$MCL2PNML_PNML_GRAMMAR``), or ``None`` when none is given (or the variable says
    ``none``): it is never looked for.

    A directory given that has no ``ptnet.pntd`` is a :class:`PnmlError` saying how to
    get the grammar.
    """
    given = explicit if explicit is not None else os.environ.get(ENV) or None
    if given is None or explicit is None and given == NONE:
        return None
    if (Path(given) / ENTRY).is_file():
        return Path(given)
    source = "--grammar" if explicit is not None else ENV
    raise PnmlError(
        f"PNML grammar: no {ENTRY} in {given} (from {source}); unpack pnml.org's "
        f"version-2009 grammar.zip (ptnet.pntd and the .rng files it includes) and pass "
        f"--grammar DIR or set {ENV}=DIR")


def schema_text() -> bytes:
    """Our schema's text, from the installed package (a wheel or a checkout alike)."""
    return resources.files(__package__).joinpath(SCHEMA).read_bytes()


@lru_cache(maxsize=1)
def our_schema() -> etree.RelaxNG:
    """Our schema, compiled once."""
    return etree.RelaxNG(etree.fromstring(schema_text()))


@lru_cache(maxsize=4)
def official_grammar(directory: str) -> etree.RelaxNG:
    """The official grammar in ``directory``, compiled once, or a located :class:`PnmlError`."""
    path = os.path.join(directory, ENTRY)
    parser = etree.XMLParser(no_network=True, resolve_entities=False)
    try:
        return etree.RelaxNG(etree.parse(path, parser))
    except (OSError, etree.LxmlError) as e:
        # the first complaint with a line is the cause (a missing include, say);
        # the later ones are its consequences (references left without a definition)
        log = list(getattr(e, "error_log", None) or ())
        entry = next((x for x in log if x.line), log[0] if log else None)
        where = Location(entry.filename or path, entry.line or None, entry.column or None) \
            if entry is not None else Location(path)
        raise PnmlError(f"the PNML grammar in {directory} cannot be used: "
                        f"{entry.message if entry is not None else e}; give the directory of "
                        f"pnml.org's version-2009 grammar.zip unpacked, or set {ENV}={NONE} "
                        "to apply mcl2pnml's schema alone", where) from None


@dataclass(frozen=True)
class SchemaVerdict:
    """What one schema made of a document."""

    schema: str
    valid: bool


@dataclass(frozen=True)
class Verdict:
    """The outcome of :func:`validate`: the problems found, and which schemas judged."""

    file: str
    errors: tuple[Mcl2PnmlError, ...]
    schemas: tuple[SchemaVerdict, ...] = ()

    @property
    def valid(self) -> bool:
        return not self.errors

    def judges(self) -> str:
        """``"mcl2pnml's ISO/IEC 15909-2 schema; official 2009 grammar: valid"``: who judged.

        Our schema is named alone when the file is valid (it always applies);
        each schema's own verdict is given as soon as one differs or fails.
        """
        if self.valid:
            first, *rest = self.schemas
            return "; ".join([first.schema, *(f"{s.schema}: valid" for s in rest)])
        return "; ".join(f"{s.schema}: {'valid' if s.valid else 'invalid'}"
                         for s in self.schemas)


def validate(path: str | Path, grammar: str | Path | None = None,
             net_id: str | None = None) -> Verdict:
    """Check a PNML file against our schema, the official grammar where it is, and the
    reader's rules. ``net_id``: the net the reader's rules are checked on, of a file
    that holds several."""
    return validate_bytes(read_file(path), str(path), grammar, net_id)


def validate_bytes(data: bytes, filename: str, grammar: str | Path | None = None,
                   net_id: str | None = None) -> Verdict:
    """:func:`validate` on a document's bytes; ``filename`` names it in messages."""
    judges = [(OURS, our_schema())]
    official = find_grammar(grammar)
    if official is not None:
        judges.append((OFFICIAL, official_grammar(str(official))))
    src = Source(filename, data)
    try:
        doc = parse_xml(data, src)
    except XmlError as e:   # no schema can judge what is not XML
        return Verdict(filename, (e,), tuple(SchemaVerdict(name, False) for name, _ in judges))
    # the element at fault -> what each schema says of it: one message per element, in
    # our schema's words where it has some (the official grammar's interleaves add a
    # line per enclosing element that ours, written as sequences, does not)
    found: dict[Location, dict[str, str]] = {}
    schemas = []
    for name, rng in judges:
        valid = rng.validate(doc)
        schemas.append(SchemaVerdict(name, valid))
        for where, message in ([] if valid else _schema_errors(rng.error_log, doc, src)):
            found.setdefault(where, {})[name] = message
    errors: list[Mcl2PnmlError] = [
        PnmlError(f"{_SAID_BY[frozenset(said)]}: {said.get(OURS) or said[OFFICIAL]}", where)
        for where, said in found.items()]
    try:
        parse_pnml(data, filename, net_id)
    except ErrorList as e:
        errors.extend(e.errors)
    except PnmlError as e:
        errors.append(e)
    return Verdict(filename, tuple(errors), tuple(schemas))


def _schema_errors(log, doc, src: Source) -> list[tuple[Location, str]]:
    """libxml2's complaints, one message per element at fault, located at its start tag.

    libxml2 logs a fault from the inside out: details without a node
    ("Extra element text in interleave"), then the element that failed,
    then each enclosing element that failed because of it. The details go
    with the element they precede; an element that only failed because of
    a descendant already reported is not reported again.
    """
    groups: dict[object, list[str]] = {}   # element -> its messages, in the log's order
    pending: list[str] = []
    for entry in log:
        message = entry.message.strip().replace("element , ", "element, ")  # a name left blank
        if message not in pending:
            pending.append(message)
        node = _node(doc, entry.path, message) if entry.path else _referrer(doc, message)
        if node is not None:
            groups.setdefault(node, [])
            groups[node] += [m for m in pending if m not in groups[node]]
            pending = []
    if pending:   # nothing in the log names an element: the document as a whole
        groups.setdefault(doc.getroot(), []).extend(pending)
    reported: list = []
    out = []
    for node, messages in groups.items():
        if any(node in r.iterancestors() for r in reported):
            continue
        reported.append(node)
        local = etree.QName(node).localname
        messages += [hint for name, pattern, hint in _HINTS
                     if name == local and any(pattern.search(m) for m in messages)]
        out.append((src.locate(node), "; ".join(messages)))
    return out


def _node(doc, path: str, message: str):
    """The element libxml2's ``path`` names, or the one its ``message`` blames.

    The path is where libxml2 stood: for a fault of content, the child that
    did not fit (the place to show); for a fault of attributes, sometimes a
    child of the element whose attributes are wrong, which the message names.
    A step in another namespace is written with the document's prefix, which
    XPath does not know: it is matched by its local name.
    """
    path = _PREFIXED.sub(r"*[local-name()='\2']", path)
    try:
        found = doc.xpath(path)
    except etree.XPathError:
        return None
    node = found[0] if found and isinstance(found[0], etree._Element) else None
    blamed = _ATTRIBUTES.search(message)
    if node is not None and blamed:
        name = blamed.group(1) or blamed.group(2)
        owner = next((el for el in (node, *node.iterancestors())
                      if etree.QName(el).localname == name), None)
        node = owner if owner is not None else node
    return node


def _referrer(doc, message: str):
    """The element whose IDREF names an id that does not exist, from libxml2's message."""
    m = _UNKNOWN_ID.fullmatch(message)
    if m is None:
        return None
    attribute, value = m.groups()
    return next((el for el in doc.iter() if el.get(attribute) == value), None)
