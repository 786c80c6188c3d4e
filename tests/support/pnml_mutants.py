"""Hostile PNML files made from real ones: XML-level mutations, each named by its operator.

A PNML reader that proves things about a net must read every file either as the
net the other tools read or not at all. The files that test this are made here,
at run time, from real files (the external corpus, ``../shared/external-nets``,
and our own templates and compiled missions): each mutant is a real file changed
by one operator (:data:`OPERATORS`), or by two in a chain, at a place drawn at
random. The operators are the ways two readers of one file part company:
namespaces and prefixes, nodes where the grammar puts none (under
``<toolspecific>``, ``<graphics>``, a label, an unknown element, another node),
labels and ids given twice, numbers and ids written with CDATA, comments, character
references, other spaces and other forms of numbers, the attributes and labels of
other dialects (TAPAAL, PIPE, ProM, WoPeD), references, entities, encodings, and
changes that keep the meaning (attribute and element order, white space), which a
reader must read as the seed.

Everything is deterministic: a mutant is a function of the seeds, its index and
the campaign's seed (:func:`mutant`), so that any mutant of a run can be made again
from its number. Bytes in, bytes out: a seed is parsed once into a small tree of
plain objects (:class:`El`) that keeps prefixes, attribute order and mixed content,
changed, and written back by :func:`serialize`, which writes exactly what the
operator asked for (a prefix, a character reference, a CDATA section), where a
general XML writer would normalise it away.
"""
from __future__ import annotations

import json
import pickle
import random
import unicodedata
import zlib
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Callable, Iterator, Sequence

from lxml import etree

PNML_NS = "http://www.pnml.org/version-2009/grammar/pnml"
OTHER_NS = "http://example.org/not-pnml"
OLD_NS = "http://www.informatik.hu-berlin.de/top/pnml/ptNetb"
XML_NS = "http://www.w3.org/XML/1998/namespace"
NODES = ("place", "transition", "arc")
LABELS = ("name", "initialMarking", "inscription")
NUMBER_LABELS = ("initialMarking", "inscription")
#: Attributes that carry a number in some dialect (TAPAAL's own format, verifypn's reader).
NUMBER_ATTRIBUTES = ("initialMarking", "inscription", "weight")
TOOLS = ("org.woped", "ProM", "TAPAAL", "PIPE", "mcl2pnml", "x")
#: Seeds larger than this are left out by default: small files make many mutants a second.
MAX_SEED_BYTES = 40_000

# -- the tree ----------------------------------------------------------------------------------


class Raw(str):
    """Markup written as it is (a CDATA section, a comment, a reference, bytes to replace)."""


@dataclass(eq=False)
class El:
    """An element: its namespace and local name, the prefix it is written with (None: the
    default namespace), its attributes ``[namespace, name, value, prefix]`` in order, its
    content (text, :class:`Raw` markup and elements, in order), namespace declarations
    written on it beyond the ones it needs, and the quote its attributes are written in."""

    ns: str | None
    name: str
    attrs: list = field(default_factory=list)
    kids: list = field(default_factory=list)
    prefix: str | None = None
    decls: dict = field(default_factory=dict)
    quote: str = '"'

    def get(self, name: str) -> str | None:
        for ns, key, value, _ in self.attrs:
            if ns is None and key == name:
                return value
        return None

    def set(self, name: str, value: str) -> None:
        for a in self.attrs:
            if a[0] is None and a[1] == name:
                a[2] = value
                return
        self.attrs.append([None, name, value, None])

    def drop(self, name: str) -> None:
        self.attrs = [a for a in self.attrs if not (a[0] is None and a[1] == name)]

    def elements(self) -> list["El"]:
        return [k for k in self.kids if isinstance(k, El)]

    def child(self, name: str) -> "El | None":
        return next((k for k in self.elements() if k.name == name), None)

    def text(self) -> str:
        return "".join(k for k in self.kids if isinstance(k, str) and not isinstance(k, Raw))


def new(like: El, name: str, attrs: Sequence[tuple[str, str]] = (), kids: Sequence = ()) -> El:
    """An element in the namespace of ``like`` (so that it needs no declaration of its own)."""
    return El(like.ns, name, [[None, k, v, None] for k, v in attrs], list(kids))


def clone(el: El) -> El:
    """A deep copy (iterative: a mutant may nest deeper than Python recurses)."""
    top = El(el.ns, el.name, [list(a) for a in el.attrs], [], el.prefix, dict(el.decls),
             el.quote)
    stack = [(el, top)]
    while stack:
        src, dst = stack.pop()
        for k in src.kids:
            if isinstance(k, El):
                c = El(k.ns, k.name, [list(a) for a in k.attrs], [], k.prefix, dict(k.decls),
                       k.quote)
                dst.kids.append(c)
                stack.append((k, c))
            else:
                dst.kids.append(k)
    return top


def walk(root: El) -> Iterator[tuple[El, El | None]]:
    """Every element with its parent, in document order."""
    stack: list[tuple[El, El | None]] = [(root, None)]
    while stack:
        el, parent = stack.pop()
        yield el, parent
        stack.extend((k, el) for k in reversed(el.elements()))


def _split(tag: str) -> tuple[str | None, str]:
    if tag.startswith("{"):
        ns, _, name = tag[1:].partition("}")
        return ns, name
    return None, tag


def from_lxml(e) -> El:
    """The tree of an lxml element (comments and processing instructions kept as markup)."""
    def convert(x) -> El:
        ns, name = _split(x.tag)
        attrs = [[*_split(k), v, None] for k, v in x.attrib.items()]
        for a in attrs:
            if a[0] is not None:
                a[3] = next((p for p, u in x.nsmap.items() if u == a[0] and p), None)
        return El(ns, name, attrs, [], x.prefix)
    top = convert(e)
    stack = [(e, top)]
    while stack:
        src, dst = stack.pop()
        if src.text:
            dst.kids.append(src.text)
        for c in src:
            if c.tag is etree.Comment:
                dst.kids.append(Raw(f"<!--{c.text or ''}-->"))
            elif c.tag is etree.PI:
                dst.kids.append(Raw(f"<?{c.target} {c.text or ''}?>"))
            elif c.tag is etree.Entity:
                dst.kids.append(Raw(f"&{c.name};"))
            else:
                k = convert(c)
                dst.kids.append(k)
                stack.append((c, k))
            if c.tail:
                dst.kids.append(c.tail)
    return top


def _escape(text: str, quote: str | None = None) -> str:
    if isinstance(text, Raw):
        return text
    text = text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    text = text.replace("\r", "&#13;")
    if quote is not None:   # attribute values keep their white space only as references
        text = text.replace(quote, "&quot;" if quote == '"' else "&apos;")
        text = text.replace("\t", "&#9;").replace("\n", "&#10;")
    return text


def serialize(root: El) -> str:
    """The element as XML text: each element with the prefix it names, a namespace
    declared where its own differs from the one in scope, attributes in their order.

    Iterative, so that the deep-nesting operators can nest as deep as they like.
    """
    out: list[str] = []
    stack: list = [(root, {None: None, "xml": XML_NS})]
    while stack:
        item, scope = stack.pop()
        if isinstance(item, tuple):          # a closing tag
            out.append(f"</{item[0]}>")
            continue
        if not isinstance(item, El):
            out.append(_escape(item))
            continue
        el, inner, decl = item, dict(scope), {}

        def need(prefix, uri):
            if inner.get(prefix, None if prefix is None else "") != uri:
                decl[prefix] = uri
                inner[prefix] = uri
        if el.prefix:
            need(el.prefix, el.ns or OTHER_NS)
            tag = f"{el.prefix}:{el.name}"
        else:
            need(None, el.ns)
            tag = el.name
        attrs = []
        for k, (ns, name, value, prefix) in enumerate(el.attrs):
            if ns == XML_NS:
                attrs.append((f"xml:{name}", value))
            elif ns:
                p = prefix or f"a{k}"
                need(p, ns)
                attrs.append((f"{p}:{name}", value))
            else:
                attrs.append((name, value))
        for p, uri in el.decls.items():
            decl[p] = uri
            inner[p] = uri if p is not None else uri or None   # xmlns="": no namespace
        q = el.quote
        head = [tag] + [f'xmlns={q}{_escape(u or "", q)}{q}' if p is None
                        else f"xmlns:{p}={q}{_escape(u, q)}{q}" for p, u in decl.items()]
        head += [f"{n}={q}{_escape(v, q)}{q}" for n, v in attrs]
        if not el.kids:
            out.append("<" + " ".join(head) + "/>")
            continue
        out.append("<" + " ".join(head) + ">")
        stack.append(((tag,), None))
        stack.extend((k, inner) for k in reversed(el.kids))
    return "".join(out)


@dataclass(eq=False)
class Doc:
    """A document being mutated: the tree, what stands before and after it, and how it
    becomes bytes (its encoding, a byte-order mark, byte-level edits after encoding)."""

    root: El
    original: bytes
    decl: str = '<?xml version="1.0" encoding="UTF-8"?>\n'
    doctype: str = ""
    tail: str = "\n"
    encoding: str = "utf-8"
    bom: bytes = b""
    post: list = field(default_factory=list)
    as_is: bool = False      # the seed's own bytes, untouched

    def to_bytes(self) -> bytes:
        if self.as_is:
            data = self.original
        else:
            text = self.decl + self.doctype + serialize(self.root) + self.tail
            data = self.bom + text.encode(self.encoding, errors="xmlcharrefreplace")
        for edit in self.post:
            data = edit(data)
        return data

    def net(self) -> El | None:
        return next((e for e, _ in walk(self.root) if e.name == "net"), None)


# -- seeds -------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Seed:
    """A real file mutants are made from: its name (where it comes from) and bytes."""

    name: str
    data: bytes


def corpus_seeds(max_bytes: int = MAX_SEED_BYTES) -> list[Seed]:
    """The external corpus's files (tests/data/external/corpus.json) of at most
    ``max_bytes``, each checked against its SHA-256; none where the corpus is absent."""
    import pytest
    from test_external import ROWS, corpus_file
    out = []
    for row in ROWS:
        try:
            path = corpus_file(row)
        except pytest.skip.Exception:
            continue
        if path.stat().st_size <= max_bytes:
            out.append(Seed(f"corpus:{row['file']}", path.read_bytes()))
    return out


def template_seeds() -> list[Seed]:
    """The paper's template nets as our writer writes them (read arcs as marked pairs,
    payloads, the ids marker): the files our own tools exchange."""
    from mcl2pnml import pipeline
    out = []
    for name, *_ in pipeline.templates():
        name = name.split(",")[0]
        out.append(Seed(f"template:{name}", pipeline.to_pnml_bytes(
            pipeline.template_net(name), "none")))
    return out


def seeds(max_bytes: int = MAX_SEED_BYTES) -> list[Seed]:
    """The seeds of a campaign: the corpus's small files and the templates."""
    return corpus_seeds(max_bytes) + template_seeds()


@lru_cache(maxsize=256)
def _parsed(data: bytes) -> bytes | El:
    """The seed's tree, pickled: unpickling makes a fresh copy several times faster than
    :func:`clone` (a mission's net is thousands of elements, copied for each mutant); a
    tree nested deeper than pickling recurses is kept as it is, cloned each time."""
    parser = etree.XMLParser(resolve_entities=False, huge_tree=True, no_network=True)
    tree = from_lxml(etree.fromstring(data, parser))
    try:
        return pickle.dumps(tree, protocol=pickle.HIGHEST_PROTOCOL)
    except RecursionError:
        return tree


def parse(seed: Seed) -> Doc:
    """A fresh document of the seed (its tree parsed once per process)."""
    tree = _parsed(seed.data)
    return Doc(clone(tree) if isinstance(tree, El) else pickle.loads(tree), seed.data)


# -- operators ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Operator:
    """One way of changing a file: ``apply`` changes the document and says whether it
    could (a seed without arcs has no arc to turn round); ``family`` groups operators in
    reports; ``preserves``: the file means what the seed meant, so that a reader must read
    the seed's net from it or refuse both; ``late``: it works on the bytes (an encoding,
    a cut), so that in a chain it comes last."""

    name: str
    family: str
    apply: Callable[[Doc, random.Random], bool]
    preserves: bool = False
    late: bool = False


OPERATORS: dict[str, Operator] = {}


def operator(name: str, family: str, preserves: bool = False, late: bool = False):
    def register(f: Callable[[Doc, random.Random], bool]):
        OPERATORS[name] = Operator(name, family, f, preserves, late)
        return f
    return register


def _all(doc: Doc, *names: str) -> list[tuple[El, El]]:
    return [(e, p) for e, p in walk(doc.root) if e.name in names and p is not None]


def _pick(doc: Doc, rng: random.Random, *names: str) -> tuple[El | None, El | None]:
    found = _all(doc, *names)
    return rng.choice(found) if found else (None, None)


def _subtree(el: El) -> set[int]:
    return {id(e) for e, _ in walk(el)}


def _insert(parent: El, el: El, rng: random.Random) -> None:
    parent.kids.insert(rng.randint(0, len(parent.kids)), el)


def _ids(doc: Doc) -> set[str]:
    return {e.get("id") for e, _ in walk(doc.root) if e.get("id") is not None}


def _fresh(doc: Doc, stem: str, taken: set[str] | None = None) -> str:
    """An id ``stem`` + a number that no element of ``doc`` has (``taken``: its ids, if
    known already)."""
    taken, k = _ids(doc) if taken is None else taken, 0
    while f"{stem}{k}" in taken:
        k += 1
    return f"{stem}{k}"


def _arcs_of(doc: Doc, node_id: str) -> list[El]:
    return [e for e, _ in walk(doc.root)
            if e.name in ("arc", "inputArc", "outputArc", "inhibitorArc")
            and node_id in (e.get("source"), e.get("target"))]


def _renamed(doc: Doc, old: str, new_id, node: El, arcs: str, rng: random.Random) -> None:
    """Node ``node`` (id ``old``) given the id ``new_id``; its arcs' ends too when
    ``arcs`` is "all", or "some" of them, or "none"."""
    node.set("id", new_id)
    for a in _arcs_of(doc, old):
        if arcs == "all" or (arcs == "some" and rng.random() < 0.5):
            for end in ("source", "target"):
                if a.get(end) == old:
                    a.set(end, new_id)


@operator("identity", "baseline", preserves=True)
def _identity(doc, rng):
    """The seed's own bytes: where the readers already part, every mutant of it will too."""
    doc.as_is = True
    return True


@operator("reserialized", "baseline", preserves=True)
def _reserialized(doc, rng):
    """The seed as this module writes it back, nothing changed."""
    return True


# -- namespaces

@operator("ns-prefix-element", "namespace")
def _prefix_element(doc, rng):
    """One element written with a prefix bound to its namespace (PNML's if it had none):
    the same element to a namespace-aware reader, an unknown ``pnml:place`` to one that
    compares names."""
    el, _ = _pick(doc, rng, *NODES, "page", "net", "text", "value", *LABELS, "toolspecific")
    if el is None:
        return False
    el.prefix = rng.choice(["pnml", "p", "x"])
    el.ns = el.ns or PNML_NS
    return True


@operator("ns-prefix-all", "namespace")
def _prefix_all(doc, rng):
    """Every element written with one prefix, declared on the root."""
    prefix = rng.choice(["pnml", "pn"])
    for el, _ in walk(doc.root):
        el.ns = el.ns or PNML_NS
        el.prefix = prefix
    return True


@operator("ns-move-element", "namespace")
def _move_ns(doc, rng):
    """One element (alone, or with its subtree) put in another namespace or in none."""
    el, _ = _pick(doc, rng, *NODES, "page", "net", "text", "value", *LABELS, "graphics",
                  "toolspecific")
    if el is None:
        return False
    target = rng.choice([OTHER_NS, None, OLD_NS, PNML_NS + "/", PNML_NS.upper()])
    if target == el.ns:
        target = OTHER_NS
    for e, _ in (walk(el) if rng.random() < 0.5 else [(el, None)]):
        e.ns = target
        if target is None:
            e.prefix = None
    return True


@operator("ns-redeclare-default", "namespace")
def _redeclare(doc, rng):
    """The default namespace declared again on a subtree: to the same one (nothing
    changes), to another, or to none (``xmlns=""``)."""
    el, _ = _pick(doc, rng, *NODES, "page", "net", *LABELS, "text")
    if el is None:
        return False
    same = rng.random() < 0.3
    target = el.ns if same else rng.choice([OTHER_NS, None, OLD_NS])
    for e, _ in walk(el):
        if e.prefix is None:
            e.ns = target
    if same:
        el.decls[None] = target or ""
    return True


@operator("ns-prefixed-attribute", "namespace")
def _prefixed_attribute(doc, rng):
    """An attribute (id, source, target, type, ref...) moved to a namespace, or a twin of
    it in a namespace with another value beside the plain one."""
    cands = [(e, a) for e, _ in walk(doc.root) for a in e.attrs
             if a[0] is None and a[1] in ("id", "source", "target", "type", "ref", "tool")]
    if not cands:
        return False
    el, attr = rng.choice(cands)
    ns = rng.choice([PNML_NS, OTHER_NS, XML_NS])
    if rng.random() < 0.5:
        attr[0], attr[3] = ns, (None if ns == XML_NS else rng.choice(["pnml", "p"]))
    else:
        others = sorted(v for v in _ids(doc) if v != attr[2]) or ["zz"]
        el.attrs.insert(rng.randint(0, len(el.attrs)),
                        [ns, attr[1], rng.choice(others), None if ns == XML_NS else "p"])
    return True


@operator("ns-unused-declarations", "namespace", preserves=True)
def _unused_decls(doc, rng):
    """Namespace declarations that nothing uses (a prefix for PNML's namespace, another
    namespace's), on the root or any element."""
    for _ in range(rng.randint(1, 3)):
        el, _ = _pick(doc, rng, *NODES, "page", "net", *LABELS)
        el = el or doc.root
        el.decls[rng.choice(["pnml", "p", "other", "xsi"])] = rng.choice([PNML_NS, OTHER_NS])
    return True


# -- nodes where the grammar puts none

def _moved_node(doc, rng) -> tuple[El | None, El | None]:
    el, parent = _pick(doc, rng, *NODES, "referencePlace", "referenceTransition")
    if el is None:
        return None, None
    parent.kids.remove(el)
    return el, parent


def _host(doc: Doc, rng: random.Random, el: El, parent: El, names: Sequence[str]) -> El:
    """An existing element named in ``names`` outside ``el`` (or ``parent``)."""
    inside = _subtree(el)
    found = [e for e, _ in walk(doc.root) if e.name in names and id(e) not in inside]
    return rng.choice(found) if found else parent


@operator("move-into-toolspecific", "move")
def _into_toolspecific(doc, rng):
    """A place, transition or arc moved under a ``<toolspecific>`` (another tool's data)."""
    el, parent = _moved_node(doc, rng)
    if el is None:
        return False
    existing = [e for e, _ in walk(doc.root) if e.name == "toolspecific"]
    if existing and rng.random() < 0.4:
        rng.choice(existing).kids.append(el)
        return True
    ts = new(parent, "toolspecific", [("tool", rng.choice(TOOLS)), ("version", "1")], [el])
    _insert(_host(doc, rng, el, parent, (parent.name, "net", *NODES)), ts, rng)
    return True


@operator("move-into-graphics", "move")
def _into_graphics(doc, rng):
    """A node moved under a ``<graphics>`` (of another node, of a label, or a new one)."""
    el, parent = _moved_node(doc, rng)
    if el is None:
        return False
    host = _host(doc, rng, el, parent, ("graphics",))
    if host.name != "graphics":
        host = new(parent, "graphics", (), [])
        _insert(parent, host, rng)
    host.kids.append(el)
    return True


@operator("move-into-label", "move")
def _into_label(doc, rng):
    """A node moved under a label (a name, a marking, an inscription) or its ``<text>``."""
    el, parent = _moved_node(doc, rng)
    if el is None:
        return False
    host = _host(doc, rng, el, parent, (*LABELS, "text"))
    if host is parent:
        host = new(parent, "name", (), [new(parent, "text", (), ["n"])])
        _insert(parent, host, rng)
    _insert(host, el, rng)
    return True


@operator("move-into-unknown", "move")
def _into_unknown(doc, rng):
    """A node wrapped in an element no grammar has."""
    el, parent = _pick(doc, rng, *NODES)
    if el is None:
        return False
    wrapper = new(parent, rng.choice(["group", "layer", "foo", "nodes", "pages"]), (), [el])
    parent.kids[parent.kids.index(el)] = wrapper
    return True


@operator("move-into-node", "move")
def _into_node(doc, rng):
    """A node moved inside another place, transition or arc."""
    el, parent = _moved_node(doc, rng)
    if el is None:
        return False
    host = _host(doc, rng, el, parent, NODES)
    _insert(host, el, rng)
    return True


@operator("move-out-of-page", "move")
def _out_of_page(doc, rng):
    """A node moved out of its page: straight under ``<net>`` (ProM writes that), under
    ``<pnml>``, or into a new page of its own."""
    el, parent = _moved_node(doc, rng)
    if el is None:
        return False
    where = rng.choice(["net", "root", "page"])
    if where == "net" and doc.net() is not None:
        _insert(doc.net(), el, rng)
    elif where == "root":
        _insert(doc.root, el, rng)
    else:
        page = new(parent, "page", [("id", _fresh(doc, "pg"))], [el])
        _insert(doc.net() or parent, page, rng)
    return True


# -- things given twice

def _number_of(el: El) -> int:
    text = el.text().strip().split(",")[-1].strip()
    return int(text) if text.isdigit() and text.isascii() and len(text) < 12 else 1


def _value_el(label: El) -> El | None:
    return label.child("text") or label.child("value")


@operator("dup-label", "duplicate")
def _dup_label(doc, rng):
    """A label given twice, the copy (before or after) saying another value."""
    el, parent = _pick(doc, rng, *LABELS)
    if el is None:
        return False
    copy = clone(el)
    value = _value_el(copy)
    if value is not None:
        n = _number_of(value)
        value.kids = [str(rng.choice([n + 1, 0, 2 * n + 3, 7])) if el.name in NUMBER_LABELS
                      else value.text() + "2"]
    at = parent.kids.index(el)
    parent.kids.insert(at + (rng.random() < 0.6), copy)
    return True


@operator("dup-text", "duplicate")
def _dup_text(doc, rng):
    """A label with a second value: another ``<text>`` or ``<value>`` beside the first,
    or inside its ``<graphics>`` or a ``<toolspecific>`` of the label."""
    el, _ = _pick(doc, rng, *NUMBER_LABELS) if rng.random() < 0.8 else _pick(doc, rng, "name")
    if el is None:
        return False
    value = _value_el(el)
    n = _number_of(value) if value is not None else 1
    other = str(rng.choice([n + 1, 0, 9, 2 * n + 2]))
    extra = new(el, rng.choice(["text", "text", "value"]), (), [other])
    how = rng.choice(["after", "before", "graphics", "toolspecific", "nested"])
    if how == "after":
        el.kids.append(extra)
    elif how == "before":
        el.kids.insert(0, extra)
    elif how == "graphics":
        el.kids.append(new(el, "graphics", (), [extra]))
    elif how == "toolspecific":
        el.kids.append(new(el, "toolspecific", [("tool", rng.choice(TOOLS)),
                                                 ("version", "1")], [extra]))
    elif value is not None:
        value.kids.append(extra)
    else:
        return False
    return True


@operator("dup-node", "duplicate")
def _dup_node(doc, rng):
    """A place, transition or arc given twice: with its id, or with a fresh one (a
    parallel arc, a place that nothing uses), beside it or in another page."""
    el, parent = _pick(doc, rng, *NODES)
    if el is None:
        return False
    copy = clone(el)
    if rng.random() < 0.5:
        copy.set("id", _fresh(doc, (el.get("id") or "n") + "_"))
    pages = [e for e, _ in walk(doc.root) if e.name == "page"]
    host = rng.choice(pages) if pages and rng.random() < 0.3 else parent
    _insert(host, copy, rng)
    return True


@operator("dup-net", "duplicate")
def _dup_net(doc, rng):
    """The net, or a page, given twice (same id or a fresh one), before or after it."""
    el, parent = _pick(doc, rng, "net", "page")
    if el is None:
        return False
    copy = clone(el)
    if rng.random() < 0.5:
        copy.set("id", _fresh(doc, el.name))
    at = parent.kids.index(el)
    parent.kids.insert(at + (rng.random() < 0.7), copy)
    return True


@operator("dup-id", "duplicate")
def _dup_id(doc, rng):
    """One element given the id of another: a place and a transition alike, two places,
    an arc and a place, a page and a node."""
    cands = [e for e, _ in walk(doc.root) if e.get("id") is not None
             and e.name in (*NODES, "page", "net")]
    if len(cands) < 2:
        return False
    a, b = rng.sample(cands, 2)
    a.set("id", b.get("id"))
    return True


@operator("wrap-net", "duplicate")
def _wrap(doc, rng):
    """The net (or a page, or the whole document) wrapped in an element of no grammar,
    in ``<toolspecific>``, or in a second ``<net>``."""
    el, parent = _pick(doc, rng, "net", "page")
    if el is None:
        return False
    name = rng.choice(["nets", "foo", "toolspecific", "net", "document"])
    wrapper = new(parent, name, [("tool", "x"), ("version", "1")] if name == "toolspecific"
                  else [("id", _fresh(doc, "w"))] if name == "net" else [], [el])
    parent.kids[parent.kids.index(el)] = wrapper
    return True


# -- numbers and ids written otherwise

def _number_spot(doc: Doc, rng: random.Random, attributes: bool = True):
    """A number to rewrite: the value element of a marking or an inscription, or (when
    ``attributes``) an attribute that holds one; with its present value."""
    spots = [("el", v) for e, _ in walk(doc.root) if e.name in NUMBER_LABELS
             for v in e.elements() if v.name in ("text", "value")]
    if attributes:
        spots += [("attr", a) for e, _ in walk(doc.root) for a in e.attrs
                  if a[0] is None and a[1] in NUMBER_ATTRIBUTES]
    if not spots:
        return None, None, 1
    kind, spot = rng.choice(spots)
    text = (spot.text() if kind == "el" else spot[2]).strip().split(",")[-1].strip()
    n = int(text) if text.isdigit() and text.isascii() and len(text) < 12 else 1
    return kind, spot, n


def _write_number(kind: str, spot, value: str, raw: bool = False) -> None:
    """``value`` in the place of the number at ``spot`` (PIPE's ``Default,`` kept before
    it); ``raw``: markup, written as it is."""
    if kind == "el":
        prefix = "".join(p + "," for p in spot.text().split(",")[:-1])
        spot.kids = [Raw(_escape(prefix) + value) if raw else prefix + value]
    else:
        spot[2] = Raw(value) if raw else value


def _number_operator(name: str, doc: str, forms: Callable[[int, random.Random], list[str]],
                     raw: bool = False, attributes: bool = True) -> None:
    """An operator writing a marking's or a weight's number (N) in one of ``forms(N)``."""
    def apply(doc, rng):
        kind, spot, n = _number_spot(doc, rng, attributes)
        if spot is None:
            return False
        _write_number(kind, spot, rng.choice(forms(n, rng)), raw)
        return True
    apply.__doc__ = doc
    operator(name, "number")(apply)


def _halves(n: int) -> tuple[str, str]:
    s = str(n) if n >= 10 else f"1{n}"
    k = len(s) // 2
    return s[:k], s[k:]


_number_operator(
    "num-cdata", "A number with a CDATA section in it, around it or beside it.",
    lambda n, r: [f"<![CDATA[{n}]]>", "{0}<![CDATA[{1}]]>".format(*_halves(n)),
                  f" <![CDATA[ {n} ]]> ", f"<![CDATA[]]>{n}", f"<![CDATA[{n}]]><![CDATA[0]]>"],
    raw=True, attributes=False)
_number_operator(
    "num-comment", "A number with a comment before, after or inside it.",
    lambda n, r: [f"<!-- c -->{n}", f"{n}<!-- c -->", "<!--{0}-->{1}".format(*_halves(n)),
                  "{0}<!-- -->{1}".format(*_halves(n)), f"<!--{n}-->"],
    raw=True, attributes=False)
_number_operator(
    "num-pi", "A number with a processing instruction before, after or inside it.",
    lambda n, r: [f"<?pi x?>{n}", f"{n}<?pi?>", "{0}<?x y?>{1}".format(*_halves(n))],
    raw=True, attributes=False)
_number_operator(
    "num-charref", "A number's digits, or white space around it, as character references.",
    lambda n, r: ["".join(f"&#{ord(c)};" for c in str(n)),
                  "".join(f"&#x{ord(c):x};" for c in str(n)), f"&#32;{n}", f"{n}&#10;",
                  f"&#9;{n}", f"&#160;{n}", f"{n}&#13;", f"&#x0A;{n}&#x0A;"],
    raw=True)
#: White space of every kind: ASCII's, the no-break and typographic spaces, a zero-width
#: space and a byte-order mark, the next-line control, vertical tab and form feed.
SPACES = (" ", "\t", "\n", "\r\n", "\u00a0", "\u2002", "\u2009", "\u3000", "\ufeff",
          "\u0085", "\u1680", "\u200b", "\v", "\f", "  \n  ")
_number_operator(
    "num-space", "A number with white space around or inside it: ASCII's and other scripts'.",
    lambda n, r: [r.choice([f"{sp}{n}", f"{n}{sp}", f"{sp}{n}{sp}",
                            "{0}{sp}{1}".format(*_halves(n), sp=sp)]) for sp in SPACES])
_number_operator(
    "num-sign", "A number with a sign: +N, -N, -0, a doubled or trailing sign, a minus sign.",
    lambda n, r: [f"+{n}", f"-{n}", "-0", "+0", f"+ {n}", f"--{n}", f"+-{n}", f"{n}+",
                  f"\u2212{n}"])
_number_operator(
    "num-leading-zeros", "A number with leading zeros (a C reader of octal reads 010 as 8).",
    lambda n, r: [f"0{n}", f"00{n}", "0" * 30 + str(n), "00", f"0{n:o}" if n > 7 else f"0{n}"])
_number_operator(
    "num-forms", "A number in another form: exponent, decimal point, hexadecimal, other digits.",
    lambda n, r: [f"{n}e0", f"{n}E0", f"{n}.0", f"{n}.", f".{n}", f"{n}e1", f"0x{n:x}",
                  f"0X{n:X}", f"{n}.5", f"{n / 10:g}e1", "inf", "NaN", f"{n}L", f"{n}u",
                  "".join(chr(0xFF10 + int(c)) for c in str(n)),    # fullwidth digits
                  "".join(chr(0x0660 + int(c)) for c in str(n)),    # Arabic-Indic digits
                  "\u00b2", "\u2163", f"{n}_0", f"1_{n}"])
_number_operator(
    "num-huge", "A number past 2^31, 2^32, 2^63 and 2^64, and one of hundreds of digits.",
    lambda n, r: [str(v) for v in (2**31 - 1, 2**31, 2**31 + n, 2**32 - 1, 2**32, 2**32 + n,
                                   2**53 + 1, 2**63 - 1, 2**63, 2**64 - 1, 2**64, 2**64 + n,
                                   10**30, 10**100)] + ["9" * 400])
_number_operator(
    "num-negative", "A negative number (some wrap round to a natural one in 32 or 64 bits).",
    lambda n, r: ["-1", f"-{n}", str(-(2**32) + n), str(-(2**64) + n), "-4294967295",
                  "-2147483648", str(-(2**63))])
_number_operator(
    "num-junk", "A number followed or replaced by something else: letters, another number...",
    lambda n, r: [f"{n}abc", f"{n} {n}", f"{n},0", f"{n}/1", "", " ", "n", f"{n}\x7f",
                  f"{n};", f"{n}%", f"{n}\u0301", f"{n}[0,inf)", "true", f"{n}-{n}"])


def _id_node(doc: Doc, rng: random.Random) -> El | None:
    el, _ = _pick(doc, rng, "place", "transition")
    return el


@operator("id-charref", "id", preserves=True)
def _id_charref(doc, rng):
    """A node's id written with character references (the same id, decoded), in the node
    and at some of its arcs' ends."""
    el = _id_node(doc, rng)
    if el is None or not el.get("id"):
        return False
    value = el.get("id")

    def written() -> Raw:
        return Raw("".join(_escape(c, '"') if rng.random() < 0.5 else
                           rng.choice([f"&#{ord(c)};", f"&#x{ord(c):X};", f"&#x{ord(c):04x};"])
                           for c in value))
    el.set("id", written())
    for a in _arcs_of(doc, value):
        for end in ("source", "target"):
            if a.get(end) == value:
                a.set(end, written() if rng.random() < 0.5 else value)
    return True


@operator("id-space", "id")
def _id_space(doc, rng):
    """A node's id with white space around or in it, written literally (which XML
    normalises to spaces in an attribute) or as references (which it keeps), in the
    node, in its arcs, or in both."""
    el = _id_node(doc, rng)
    if el is None or not el.get("id"):
        return False
    old = el.get("id")
    sp = rng.choice([" ", "\t", "\n", "&#9;", "&#10;", "&#13;", "&#32;", "\u00a0", "&#160;",
                     "\r\n"])
    new_id = Raw(rng.choice([sp + _escape(old, '"'), _escape(old, '"') + sp,
                             _escape(old[:1], '"') + sp + _escape(old[1:], '"')]))
    where = rng.choice(["node and arcs", "node and arcs", "node", "arcs", "some arcs"])
    _renamed(doc, old, new_id, el, {"node": "none", "some arcs": "some"}.get(where, "all"),
             rng)
    if where in ("arcs", "some arcs"):      # only the arcs say it so
        el.set("id", old)
    return True


@operator("id-unicode", "id")
def _id_unicode(doc, rng):
    """A node's id with characters beyond ASCII: accented (composed in the node and
    decomposed at its arcs, or alike), spaces of other scripts, a zero-width space."""
    el = _id_node(doc, rng)
    if el is None or not el.get("id"):
        return False
    old = el.get("id")
    extra = rng.choice(["\u00e9", "\u00a0", "\u200b", "\u0130", "\ufb01", "\U0001f600",
                        "\u212b", "\u00c5"])
    new_id = old + extra
    el.set("id", new_id)
    other = unicodedata.normalize(rng.choice(["NFC", "NFD", "NFKC"]), new_id)
    for a in _arcs_of(doc, old):
        for end in ("source", "target"):
            if a.get(end) == old:
                a.set(end, other if rng.random() < 0.5 else new_id)
    return True


@operator("id-entity", "id")
def _id_entity(doc, rng):
    """A node's id with the predefined entities (``&amp;`` ``&lt;`` ``&quot;``...), or a
    reference to one undeclared, in the node and its arcs alike."""
    el = _id_node(doc, rng)
    if el is None or not el.get("id"):
        return False
    old = el.get("id")
    # never a reference that decodes to another (``&amp;amp;``): verifypn writes the ids it
    # read back unescaped, and its net, read back, would not say the id it holds
    ent = rng.choice(["&amp;", "&lt;", "&gt;", "&quot;", "&apos;", "&nbsp;"])
    _renamed(doc, old, Raw(_escape(old, '"') + ent), el, "all", rng)
    return True


# -- dialects: meanings other tools give

@operator("attr-weight", "dialect")
def _attr_weight(doc, rng):
    """An arc with a ``weight=`` attribute (TAPAAL's reader takes it before the
    inscription), agreeing with the inscription or not."""
    el, _ = _pick(doc, rng, "arc")
    if el is None:
        return False
    label = el.child("inscription")
    n = _number_of(_value_el(label)) if label is not None and _value_el(label) else 1
    el.set("weight", str(rng.choice([n, n + 1, 0, 5, -1])) if rng.random() < 0.9 else "x")
    return True


@operator("attr-initialMarking", "dialect")
def _attr_marking(doc, rng):
    """A place with an ``initialMarking=`` attribute (TAPAAL's own format), with the label
    or without it, agreeing or not."""
    el, _ = _pick(doc, rng, "place")
    if el is None:
        return False
    el.set("initialMarking", str(rng.choice([0, 1, 2, 5, 1000])))
    if rng.random() < 0.3 and el.child("initialMarking") is not None:
        el.kids.remove(el.child("initialMarking"))
    return True


ARC_TYPES = ("normal", "read", "test", "inhibitor", "timed", "transport", "tapnInhibitor",
             "reset", "Normal", "INHIBITOR", " normal", "", "regular", "default")


@operator("attr-arc-type", "dialect")
def _attr_type(doc, rng):
    """An arc with ``type=`` (TAPAAL's): normal, read, test, inhibitor, timed, transport,
    and other spellings."""
    el, _ = _pick(doc, rng, "arc", "inputArc", "outputArc")
    if el is None:
        return False
    el.set("type", rng.choice(ARC_TYPES))
    return True


@operator("attr-inscription", "dialect")
def _attr_inscription(doc, rng):
    """An arc with an ``inscription=`` attribute (TAPAAL's own format: a weight or an
    interval), beside its label or instead of it."""
    el, _ = _pick(doc, rng, "arc")
    if el is None:
        return False
    el.set("inscription", rng.choice(["1", "2", "[0,inf)", "0", "3"]))
    if rng.random() < 0.3 and el.child("inscription") is not None:
        el.kids.remove(el.child("inscription"))
    return True


@operator("pipe-value", "dialect")
def _pipe_value(doc, rng):
    """Labels in PIPE's form: ``<value>`` for ``<text>``, ``Default,N`` markings, a
    capacity; or both forms in one label."""
    el, _ = _pick(doc, rng, *NUMBER_LABELS)
    if el is None:
        return False
    value = _value_el(el)
    n = _number_of(value) if value is not None else 1
    how = rng.choice(["value", "default", "both", "classes", "capacity"])
    if how == "capacity":
        node = next((p for p, _ in walk(doc.root) if el in p.kids), None)
        if node is None:
            return False
        node.kids.append(new(node, "capacity", (), [new(node, "value", (),
                                                         [str(rng.choice([0, 1, n]))])]))
        return True
    text = {"value": str(n), "default": f"Default,{n}", "both": str(n),
            "classes": f"Default,{n},red,{rng.choice([0, 2])}"}[how]
    kids = [new(el, "value", (), [text])]
    if how == "both":
        kids.insert(rng.randint(0, 1), new(el, "text", (), [str(rng.choice([n, n + 1]))]))
    el.kids = [k for k in el.kids if not (isinstance(k, El) and k.name in ("text", "value"))]
    el.kids += kids
    return True


@operator("prom-arctype", "dialect")
def _prom_arctype(doc, rng):
    """An arc with ProM's ``<arctype>`` label (read, inhibitor, reset...), or PIPE's
    ``<type value=...>``."""
    el, _ = _pick(doc, rng, "arc")
    if el is None:
        return False
    kind = rng.choice(ARC_TYPES)
    if rng.random() < 0.6:
        label = new(el, "arctype", (), [new(el, "text", (), [kind])] if rng.random() < 0.8
                    else [kind])
    else:
        label = new(el, "type", [("value", kind)])
    _insert(el, label, rng)
    return True


@operator("tapaal-elements", "dialect")
def _tapaal_elements(doc, rng):
    """An arc renamed to one of TAPAAL's own elements (``inputArc``, ``outputArc``,
    ``inhibitorArc``, ``transportArc``)."""
    el, _ = _pick(doc, rng, "arc")
    if el is None:
        return False
    el.name = rng.choice(["inputArc", "outputArc", "inhibitorArc", "transportArc"])
    if el.name == "transportArc":
        el.set("transition", el.get("target") or "")
    return True


@operator("high-level-labels", "dialect")
def _high_level(doc, rng):
    """Coloured content: ``<hlinitialMarking>``, ``<hlinscription>``, a sort on a place,
    a declaration in the net."""
    el, _ = _pick(doc, rng, "place", "arc", "net")
    if el is None:
        return False
    structure = new(el, "structure", (), [new(el, "numberof", (), [
        new(el, "subterm", (), [new(el, "numberconstant", [("value", "2")])]),
        new(el, "subterm", (), [new(el, "dotconstant")])])])
    label = {"place": rng.choice(["hlinitialMarking", "type"]), "arc": "hlinscription",
             "net": "declaration"}[el.name]
    _insert(el, new(el, label, (), [new(el, "text", (), ["2'dot"]), structure]), rng)
    return True


# -- references and WoPeD's subprocesses

@operator("reference-node", "reference")
def _reference(doc, rng):
    """A reference place or transition (in a new page, or beside its node) standing for a
    node, some or all of whose arcs are moved to it; or a reference that dangles, loops,
    chains, or stands for a node of the other kind."""
    el, parent = _pick(doc, rng, "place", "transition")
    if el is None or not el.get("id"):
        return False
    kind = "referencePlace" if el.name == "place" else "referenceTransition"
    ref_id = _fresh(doc, "ref")
    how = rng.choice(["plain", "plain", "chain", "loop", "dangling", "wrong kind", "marked"])
    target = el.get("id")
    if how == "dangling":
        target = "nowhere"
    elif how == "wrong kind":
        other = [e for e, _ in walk(doc.root)
                 if e.name in ("place", "transition") and e.name != el.name and e.get("id")]
        target = rng.choice(other).get("id") if other else "nowhere"
    refs = [new(parent, kind, [("id", ref_id), ("ref", target)])]
    if how in ("chain", "loop"):
        second = _fresh(doc, "refb")
        refs[0].set("ref", second)
        refs.append(new(parent, kind, [("id", second), ("ref", ref_id if how == "loop"
                                                         else target)]))
    if how == "marked":
        refs[0].kids.append(new(parent, "initialMarking", (), [new(parent, "text", (), ["3"])]))
    if rng.random() < 0.5:
        host = new(parent, "page", [("id", _fresh(doc, "pg"))], refs)
        _insert(doc.net() or parent, host, rng)
    else:
        for r in refs:
            _insert(parent, r, rng)
    arcs = _arcs_of(doc, el.get("id"))
    for a in arcs if rng.random() < 0.5 else arcs[:1]:
        for end in ("source", "target"):
            if a.get(end) == el.get("id"):
                a.set(end, ref_id)
    return True


@operator("woped-subprocess", "reference")
def _subprocess(doc, rng):
    """A WoPeD subprocess: a page with a transition's id holding a ``<net>`` that refines
    it, its input and output places repeated inside; or such a page for no transition,
    with a marked place inside, or with arcs to the outer net."""
    el, parent = _pick(doc, rng, "transition")
    if el is None or not el.get("id"):
        return False
    t = el.get("id")
    ins = [a.get("source") for a in _arcs_of(doc, t) if a.get("target") == t]
    outs = [a.get("target") for a in _arcs_of(doc, t) if a.get("source") == t]
    how = rng.choice(["plain", "plain", "no transition", "marked", "outer arc"])
    page_id = t if how != "no transition" else _fresh(doc, "sub")
    inner = _fresh(doc, f"{t}_s")
    kids = [new(parent, "place", [("id", p)]) for p in dict.fromkeys(ins + outs) if p]
    kids.append(new(parent, "transition", [("id", inner)]))
    kids += [new(parent, "arc", [("id", f"{inner}_i{k}"), ("source", p), ("target", inner)])
             for k, p in enumerate(ins) if p]
    kids += [new(parent, "arc", [("id", f"{inner}_o{k}"), ("source", inner), ("target", p)])
             for k, p in enumerate(outs) if p]
    if how == "marked":
        kids.append(new(parent, "place", [("id", _fresh(doc, "sp"))], [new(
            parent, "initialMarking", (), [new(parent, "text", (), ["1"])])]))
    if how == "outer arc":
        others = [e.get("id") for e, _ in walk(doc.root) if e.name == "place" and e.get("id")]
        if others:
            kids.append(new(parent, "arc", [("id", _fresh(doc, "oa")), ("source", inner),
                                            ("target", rng.choice(others))]))
    page = new(parent, "page", [("id", page_id)], [new(parent, "net", (), kids)])
    parent.kids.insert(parent.kids.index(el) + 1, page)
    return True


# -- entities and document types

def _entity_spot(doc: Doc, rng: random.Random, ref: str) -> bool:
    """``ref`` (an entity reference) put in a number, a name or an id."""
    where = rng.choice(["number", "name", "id"])
    if where == "number":
        kind, spot, _ = _number_spot(doc, rng, attributes=False)
        if spot is not None:
            _write_number(kind, spot, ref, raw=True)
            return True
    if where == "id":
        el = _id_node(doc, rng)
        if el is not None and el.get("id"):
            _renamed(doc, el.get("id"), Raw(_escape(el.get("id"), '"') + ref), el, "all", rng)
            return True
    label, _ = _pick(doc, rng, "name")
    value = _value_el(label) if label is not None else None
    if value is None:
        return False
    value.kids = [Raw(_escape(value.text()) + ref)]
    return True


@operator("entity-internal", "entity")
def _entity_internal(doc, rng):
    """A document type declaring an internal entity, used in a number, a name or an id."""
    value = rng.choice(["7", "1", "", "p", "<text>5</text>", "&#49;"])
    doc.doctype = f'<!DOCTYPE {doc.root.name} [\n<!ENTITY e "{value}">\n]>\n'
    return _entity_spot(doc, rng, "&e;")


@operator("entity-external", "entity")
def _entity_external(doc, rng):
    """An external entity (a local file, a URL) or parameter entity, used or declared."""
    system = rng.choice(["file:///etc/hostname", "/etc/passwd", "http://127.0.0.1:9/x.dtd",
                         "pnml.ent"])
    if rng.random() < 0.3:
        doc.doctype = f'<!DOCTYPE {doc.root.name} [\n<!ENTITY % p SYSTEM "{system}">\n%p;\n]>\n'
        return True
    doc.doctype = f'<!DOCTYPE {doc.root.name} [\n<!ENTITY e SYSTEM "{system}">\n]>\n'
    return _entity_spot(doc, rng, "&e;")


@operator("entity-billion-laughs", "entity")
def _laughs(doc, rng):
    """Entities that expand exponentially, used once."""
    levels = rng.choice([3, 6, 10])
    decls = ['<!ENTITY l0 "ha">'] + [f'<!ENTITY l{i} "{f"&l{i - 1};" * 10}">'
                                     for i in range(1, levels)]
    doc.doctype = f"<!DOCTYPE {doc.root.name} [\n" + "\n".join(decls) + "\n]>\n"
    return _entity_spot(doc, rng, f"&l{levels - 1};")


@operator("entity-doctype", "entity")
def _doctype(doc, rng):
    """A document type declaration with nothing used from it, or one whose attribute
    defaults would give arcs a type or places a marking, or an undeclared entity."""
    root = doc.root.name
    how = rng.choice(["empty", "system", "public", "attlist", "fixed", "undeclared"])
    if how == "undeclared":
        return _entity_spot(doc, rng, rng.choice(["&e;", "&nbsp;", "&copy;"]))
    doc.doctype = {
        "empty": f"<!DOCTYPE {root}>\n",
        "system": f'<!DOCTYPE {root} SYSTEM "pnml.dtd">\n',
        "public": f'<!DOCTYPE {root} PUBLIC "-//X//DTD PNML//EN" "http://127.0.0.1:9/p.dtd">\n',
        "attlist": f"<!DOCTYPE {root} [\n<!ATTLIST arc type CDATA \"inhibitor\">\n"
                   "<!ATTLIST place initialMarking CDATA \"5\">\n]>\n",
        "fixed": f"<!DOCTYPE {root} [\n<!ATTLIST arc weight CDATA #FIXED \"3\">\n]>\n",
    }[how]
    return True


# -- encodings (on the bytes)

def _non_ascii(doc: Doc, rng: random.Random) -> None:
    """Some non-ASCII text where it shows: a name, or an id (node and arcs alike)."""
    el = _id_node(doc, rng)
    if el is not None and el.get("id") and rng.random() < 0.5:
        _renamed(doc, el.get("id"), el.get("id") + "\u00e9", el, "all", rng)
        return
    label, _ = _pick(doc, rng, "name")
    value = _value_el(label) if label is not None else None
    if value is not None:
        value.kids = [value.text() + "\u00fc\u00df"]


def _declared(doc: Doc, encoding: str | None) -> None:
    doc.decl = "" if encoding is None else f'<?xml version="1.0" encoding="{encoding}"?>\n'


@operator("enc-utf16", "encoding", late=True)
def _utf16(doc, rng):
    """UTF-16 with a byte-order mark, declared or not, big- or little-endian."""
    _non_ascii(doc, rng)
    _declared(doc, rng.choice(["UTF-16", None]))
    big = rng.random() < 0.5
    doc.encoding = "utf-16-be" if big else "utf-16-le"
    doc.bom = b"\xfe\xff" if big else b"\xff\xfe"
    return True


@operator("enc-utf16-no-bom", "encoding", late=True)
def _utf16_nobom(doc, rng):
    """UTF-16 without a byte-order mark (declared, or not at all)."""
    _declared(doc, rng.choice(["UTF-16", "UTF-16LE", None]))
    doc.encoding = "utf-16-le"
    return True


@operator("enc-latin1", "encoding", late=True)
def _latin1(doc, rng):
    """Latin-1 bytes, declared as ISO-8859-1 (PIPE declares it), with non-ASCII text."""
    _non_ascii(doc, rng)
    _declared(doc, rng.choice(["ISO-8859-1", "iso-8859-1", "latin1", "windows-1252"]))
    doc.encoding = "latin-1"
    return True


@operator("enc-bom", "encoding", late=True, preserves=True)
def _bom(doc, rng):
    """A UTF-8 byte-order mark, with the declaration or without."""
    doc.bom = b"\xef\xbb\xbf"
    if rng.random() < 0.3:
        _declared(doc, None)
    return True


@operator("enc-invalid-utf8", "encoding", late=True)
def _invalid(doc, rng):
    """Bytes that are no UTF-8 (a lone 0xFF, a cut sequence, an overlong slash, a
    surrogate) in a name, an id or a number."""
    marker = "\ue000"
    bad = rng.choice([b"\xff", b"\xc3", b"\xc0\xaf", b"\xed\xa0\x80", b"\xe2\x82", b"\x80"])
    if not _entity_spot(doc, rng, marker):
        return False
    doc.post.append(lambda data: data.replace(marker.encode(), bad))
    return True


@operator("enc-mismatch", "encoding", late=True)
def _mismatch(doc, rng):
    """A declaration that says another encoding than the bytes are in (UTF-16 over
    UTF-8, ASCII over non-ASCII, one that does not exist)."""
    _non_ascii(doc, rng)
    _declared(doc, rng.choice(["UTF-16", "US-ASCII", "ISO-8859-1", "EBCDIC-US", "nonsense",
                               "UTF-32"]))
    return True


# -- meaning kept: order and white space

@operator("order-attributes", "order", preserves=True)
def _order_attributes(doc, rng):
    """Every element's attributes in another order, some in single quotes."""
    for el, _ in walk(doc.root):
        rng.shuffle(el.attrs)
        if rng.random() < 0.3:
            el.quote = "'"
    return True


@operator("order-children", "order", preserves=True)
def _order_children(doc, rng):
    """The children of each page or net (nodes, arcs, pages) and of each node (labels,
    graphics) in another order, the text between them where it was."""
    for el, _ in walk(doc.root):
        if el.name in ("net", "page", *NODES):
            slots = [k for k, x in enumerate(el.kids) if isinstance(x, El)]
            kids = [el.kids[k] for k in slots]
            rng.shuffle(kids)
            for k, x in zip(slots, kids):
                el.kids[k] = x
    return True


@operator("order-whitespace", "order", preserves=True)
def _whitespace(doc, rng):
    """White space between elements taken out, or more of it put in (never inside a
    label's text)."""
    strip = rng.random() < 0.5
    for el, _ in walk(doc.root):
        if not el.elements():
            continue
        kids = [k for k in el.kids if not (isinstance(k, str) and not isinstance(k, Raw)
                                           and not k.strip())]
        if not strip:
            spaced = []
            for k in kids:
                spaced += ["\n" + " " * rng.randint(0, 4), k] if isinstance(k, El) else [k]
            kids = spaced + ["\n"]
        el.kids = kids
    return True


# -- deep nesting

@operator("deep-pages", "deep")
def _deep_pages(doc, rng):
    """A page's content moved into a chain of pages nested ``d`` deep."""
    el, _ = _pick(doc, rng, "page", "net")
    if el is None:
        return False
    depth = rng.choice([2, 5, 50, 200, 254, 255, 256, 300, 1000])
    content, el.kids = el.kids, []
    # the ids in the document (the content taken out) gathered once and kept up to date:
    # walking the whole tree for each new page made a thousand-deep chain cost seconds
    taken = _ids(doc)
    inner = el
    for k in range(depth):
        page = new(el, "page", [("id", _fresh(doc, f"deep{k}_", taken))])
        taken.add(page.get("id"))
        inner.kids.append(page)
        inner = page
    inner.kids = content
    return True


@operator("deep-unknown", "deep")
def _deep_unknown(doc, rng):
    """A node wrapped in ``d`` nested elements of no grammar."""
    el, parent = _pick(doc, rng, *NODES)
    if el is None:
        return False
    depth = rng.choice([1, 3, 50, 255, 300])
    wrapper = el
    for _ in range(depth):
        wrapper = new(parent, "g", (), [wrapper])
    parent.kids[parent.kids.index(el)] = wrapper
    return True


# -- taken out, turned round, cut

@operator("delete-element", "delete")
def _delete_element(doc, rng):
    """One element taken out (a label, its text, a node, a page, the net's type...)."""
    found = [(e, p) for e, p in walk(doc.root) if p is not None]
    if not found:
        return False
    el, parent = rng.choice(found)
    parent.kids.remove(el)
    return True


@operator("delete-attribute", "delete")
def _delete_attribute(doc, rng):
    """One attribute taken out (an id, an arc's end, the net's type, a tool's name)."""
    found = [(e, a) for e, _ in walk(doc.root) for a in e.attrs]
    if not found:
        return False
    el, attr = rng.choice(found)
    el.attrs.remove(attr)
    return True


@operator("swap-arc-ends", "swap")
def _swap_arc(doc, rng):
    """An arc turned round (its source and target exchanged), or every arc."""
    arcs = [e for e, _ in walk(doc.root) if e.name == "arc"]
    if not arcs:
        return False
    for a in arcs if rng.random() < 0.1 else [rng.choice(arcs)]:
        s, t = a.get("source"), a.get("target")
        if s is not None and t is not None:
            a.set("source", t)
            a.set("target", s)
    return True


@operator("swap-ids", "swap")
def _swap_ids(doc, rng):
    """Two nodes' ids exchanged, their arcs left as they were."""
    nodes = [e for e, _ in walk(doc.root) if e.name in ("place", "transition") and e.get("id")]
    if len(nodes) < 2:
        return False
    a, b = rng.sample(nodes, 2)
    ia, ib = a.get("id"), b.get("id")
    a.set("id", ib)
    b.set("id", ia)
    return True


@operator("truncate", "cut", late=True)
def _truncate(doc, rng):
    """The file cut short at a random byte (perhaps just after the root's end tag)."""
    def cut(data: bytes) -> bytes:
        end = data.rfind(b">") + 1
        return data[:rng.choice([rng.randrange(len(data)), end, max(0, end - 1)])]
    doc.post.append(cut)
    return True


@operator("trailing", "cut", late=True)
def _trailing(doc, rng):
    """Something after the root element: a second root, text, a NUL byte, a comment, a
    stray end tag, another copy of the document."""
    junk = rng.choice([b"<pnml/>", b"junk", b"\x00", b"<!-- after -->", b"</pnml>",
                       b"<?pi after?>", None])
    doc.post.append(lambda data: data + (junk if junk is not None else data))
    return True


# -- the document around the net

NET_TYPES = ("http://www.pnml.org/version-2009/grammar/ptnet",
             "http://www.pnml.org/version-2009/grammar/pnmlcoremodel",
             "http://www.pnml.org/version-2009/grammar/symmetricnet",
             "http://www.pnml.org/version-2009/grammar/highlevelnet", "P/T net", "",
             "http://www.pnml.org/version-2009/grammar/ptnet ",
             "HTTP://WWW.PNML.ORG/VERSION-2009/GRAMMAR/PTNET",
             "http://www.informatik.hu-berlin.de/top/pntd/ptNetb")


@operator("net-type", "document")
def _net_type(doc, rng):
    """The net's type changed: the other P/T spellings, a coloured type, none."""
    net = doc.net()
    if net is None:
        return False
    if rng.random() < 0.15:
        net.drop("type")
    else:
        net.set("type", rng.choice(NET_TYPES))
    return True


@operator("xml-declaration", "document")
def _xml_declaration(doc, rng):
    """The XML declaration changed: none, version 1.1 (other characters allowed), a
    standalone flag, white space or a comment before it, a processing instruction."""
    doc.decl = rng.choice([
        "", '<?xml version="1.1" encoding="UTF-8"?>\n', '<?xml version="1.0" standalone="yes"?>\n',
        '\n<?xml version="1.0"?>\n', '<!-- c --><?xml version="1.0"?>\n',
        '<?xml version="1.0"?>\n<?xml-stylesheet href="x.xsl"?>\n', "<?xml version='1.0'?>",
        '<?xml version="2.0"?>\n', '<?xml  version = "1.0"  ?>\n'])
    return True


# -- the campaign's mutants --------------------------------------------------------------------

@dataclass(frozen=True)
class Mutant:
    """A hostile file: its number in the campaign, the operator (or chain, ``a+b``) that
    made it, the seed it was made from, and its bytes."""

    index: int
    operator: str
    seed: str
    data: bytes


#: Of every ``CYCLE`` mutants, the last ``CHAINS`` are chains of two operators.
CHAINS = 4


def _chain(rng: random.Random) -> list[str]:
    early = [n for n, o in OPERATORS.items() if not o.late and n != "identity"]
    second = [n for n in OPERATORS if n != "identity"]
    return [rng.choice(early), rng.choice(second)]


def plan(index: int, names: Sequence[str] | None = None) -> list[str] | None:
    """The operator(s) mutant ``index`` is made with: each operator in turn, then a chain
    (None: drawn from the mutant's own random source); ``names`` to restrict to some."""
    names = sorted(OPERATORS) if names is None else list(names)
    cycle = len(names) + (CHAINS if len(names) > 1 else 0)
    k = index % cycle
    return [names[k]] if k < len(names) else None


def mutant(pool: Sequence[Seed], index: int, seed: int = 0,
           names: Sequence[str] | None = None) -> Mutant | None:
    """Mutant ``index`` of a campaign with random seed ``seed`` over the seeds ``pool``:
    always the same bytes for the same arguments. None if its operator applies to no
    seed drawn (twenty tries)."""
    rng = random.Random(zlib.crc32(f"{seed}/{index}".encode()))
    chosen = plan(index, names)
    for _ in range(20):
        ops = chosen or _chain(rng)
        base = rng.choice(pool)
        doc = parse(base)
        if all(OPERATORS[name].apply(doc, rng) for name in ops):
            return Mutant(index, "+".join(ops), base.name, doc.to_bytes())
    return None


def family(label: str) -> str:
    """The row of a report a mutant's label is counted in: the operator, or "chain"."""
    return "chain" if "+" in label else label


def describe() -> str:
    """Every operator, its family and its docstring's first line (for ``--list``)."""
    lines = []
    for name in sorted(OPERATORS, key=lambda n: (OPERATORS[n].family, n)):
        op = OPERATORS[name]
        doc = (op.apply.__doc__ or "").strip().split("\n")[0]
        lines.append(f"{op.family:10} {name:24} {'(keeps meaning) ' if op.preserves else ''}"
                     f"{doc}")
    return "\n".join(lines)


def labelled(m: Mutant) -> str:
    """A mutant's label, as a file name and a report's line both show it."""
    return json.dumps({"index": m.index, "operator": m.operator, "seed": m.seed})


def save(m: Mutant, folder: Path, note: str) -> Path:
    """The mutant written to ``folder`` as ``INDEX-OPERATOR.pnml``, beside a ``.txt`` with
    its label and ``note`` (what went wrong)."""
    folder.mkdir(parents=True, exist_ok=True)
    stem = f"{m.index:07d}-{m.operator.replace('+', '_')}"
    path = folder / f"{stem}.pnml"
    path.write_bytes(m.data)
    (folder / f"{stem}.txt").write_text(labelled(m) + "\n" + note + "\n")
    return path
