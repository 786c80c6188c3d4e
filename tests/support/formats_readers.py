"""Small readers of TINA's .net and LoLA's formats, written for the tests from the
formats' published descriptions, independently of ``mcl2pnml.io.formats``.

They read what a tool would, into one plain shape to compare nets by:
``{"places": {id: tokens}, "transitions": {id: (interval or None)},
"arcs": {(source, target, kind): weight}}``, where kind is ``"normal"`` or
``"test"``, and an interval is ``(low, high or None)`` in the file's units.
"""
from __future__ import annotations

import re

# -- TINA: "formats(n)", The .net format -------------------------------------------------
#
# Declarations: net N | tr T [: L] [interval] {place[arc]} -> {place[arc]}
# | pl P [: L] [(marking)] {t[arc]} -> {t[arc]} | lb N L | nt N 0|1 A | pr ...
# Names: [A-Za-z0-9_']+ or {...} with \{ \} \\ escaped. '#' comments.
# Arcs: *k (weight), ?k (test), ?-k (inhibitor), !k, !-k (stopwatch).

_TINA_TOKEN = re.compile(r"""
    (?P<ws>\s+) | (?P<comment>\#[^\n]*)
  | (?P<interval>[\[\]]\s*\d+\s*,\s*(?:\d+|w)\s*[\[\]])
  | (?P<qname>\{(?:[^{}\\]|\\.)*\}) | (?P<arrow>->)
  | (?P<op>\?-|!-|\*|\?|!) | (?P<punct>[:()<>])
  | (?P<aname>[A-Za-z0-9_']+)
""", re.X | re.S)
KEYWORDS = {"net", "tr", "pl", "lb", "nt", "pr"}


def scan(pattern: re.Pattern, text: str, what: str):
    """The matches of ``pattern`` that cover ``text``, white space and comments left out."""
    pos = 0
    while pos < len(text):
        m = pattern.match(text, pos)
        assert m, f"{what}: cannot read {text[pos:pos + 20]!r}"
        pos = m.end()
        if m.lastgroup not in ("ws", "comment"):
            yield m


def tina_tokens(text: str) -> list[tuple[str, str]]:
    out = []
    for m in scan(_TINA_TOKEN, text, "TINA"):
        kind, value = m.lastgroup, m.group()
        if kind == "qname":
            kind, value = "name", re.sub(r"\\(.)", r"\1", value[1:-1], flags=re.S)
        elif kind == "aname":
            kind = "keyword" if value in KEYWORDS else "name"
        out.append((kind, value))
    return out


def _weight(text: str) -> int:
    return int(text[:-1]) * {"K": 1000, "M": 1000000}[text[-1]] if text[-1] in "KM" \
        else int(text)


def read_tina(text: str) -> dict:
    tokens = tina_tokens(text) + [("end", "")]
    net = {"name": None, "places": {}, "transitions": {}, "arcs": {}}
    i = 0

    def arcs_of(node: str, is_transition: bool) -> None:
        nonlocal i
        side = "in"
        while tokens[i][0] in ("name", "arrow"):
            if tokens[i][0] == "arrow":
                side = "out"
                i += 1
                continue
            other = tokens[i][1]
            i += 1
            kind, weight = "normal", 1
            if tokens[i][0] == "op":
                op = tokens[i][1]
                weight = _weight(tokens[i + 1][1])
                i += 2
                assert op in ("*", "?"), f"TINA: arc kind {op} in a test file"
                kind = "test" if op == "?" else "normal"
            place, trans = (other, node) if is_transition else (node, other)
            (net["places"] if is_transition else net["transitions"]).setdefault(
                other, 0 if is_transition else None)
            key = (place, trans, kind) if (side == "in") == is_transition else (trans, place,
                                                                                 kind)
            net["arcs"][key] = net["arcs"].get(key, 0) + weight

    while tokens[i][0] != "end":
        kind, word = tokens[i]
        assert kind == "keyword", f"TINA: a declaration starts with a keyword, not {word!r}"
        i += 1
        if word == "net":
            net["name"] = tokens[i][1]
            i += 1
        elif word in ("tr", "pl"):
            node = tokens[i][1]
            i += 1
            if tokens[i] == ("punct", ":"):
                i += 2
            if word == "tr":
                interval = None
                if tokens[i][0] == "interval":
                    text_ = re.sub(r"\s", "", tokens[i][1])
                    low, high = text_[1:-1].split(",")
                    interval = (int(low), None if high == "w" else int(high))
                    i += 1
                net["transitions"][node] = interval
            else:
                marking = 0
                if tokens[i] == ("punct", "("):
                    marking = _weight(tokens[i + 1][1])
                    i += 3
                net["places"][node] = max(marking, net["places"].get(node, 0))
            arcs_of(node, word == "tr")
        else:
            raise AssertionError(f"TINA: '{word}' in a test file")
    return net


# -- LoLA: PLACE list; MARKING p: n, ...; TRANSITION t CONSUME p: n, ...; PRODUCE ...; --
#
# Names: any characters but white space and , ; : ( ) { }. Comments { ... }.

_LOLA_TOKEN = re.compile(r"(?P<ws>\s+)|(?P<comment>\{[^}]*\})|(?P<punct>[,;:])"
                         r"|(?P<word>[^,;:(){}\s]+)")


def read_lola(text: str, decode=lambda s: s) -> dict:
    tokens = []
    for m in _LOLA_TOKEN.finditer(text):
        if m.lastgroup in ("punct", "word"):
            tokens.append(m.group())
    net = {"places": {}, "transitions": {}, "arcs": {}}
    i = 0

    def expect(word: str) -> None:
        nonlocal i
        assert tokens[i] == word, f"LoLA: expected {word}, found {tokens[i]!r}"
        i += 1

    def pairs() -> list[tuple[str, int]]:
        nonlocal i
        out = []
        while tokens[i] != ";":
            name = decode(tokens[i])
            i += 1
            count = 1
            if tokens[i] == ":":
                count = int(tokens[i + 1])
                i += 2
            out.append((name, count))
            if tokens[i] == ",":
                i += 1
        i += 1
        return out

    expect("PLACE")
    while tokens[i] != "MARKING":
        net["places"][decode(tokens[i])] = 0
        i += 1
        if tokens[i] in (",", ";"):
            i += 1
    expect("MARKING")
    for p, n in pairs():
        net["places"][p] += n
    while i < len(tokens):
        expect("TRANSITION")
        t = decode(tokens[i])
        i += 1
        net["transitions"][t] = None
        expect("CONSUME")
        for p, n in pairs():
            net["arcs"][p, t, "normal"] = net["arcs"].get((p, t, "normal"), 0) + n
        expect("PRODUCE")
        for p, n in pairs():
            net["arcs"][t, p, "normal"] = net["arcs"].get((t, p, "normal"), 0) + n
    return net


# -- DOT: graphviz's language ("The DOT Language", graphviz.org/doc/info/lang.html) -------
#
# graph: [strict] (graph|digraph) [ID] '{' stmt_list '}'; a statement is a node
# (ID [attrs]), an edge (ID -> ID ... [attrs]), defaults (node|edge|graph [attrs]),
# ID = ID, or a subgraph ([subgraph [ID]] '{' ... '}'). An ID is a name, a numeral,
# a "quoted string" (\" escapes a quote) or an <HTML string>. Comments: // /* */ #.

_DOT_TOKEN = re.compile(r"""
    (?P<ws>\s+) | (?P<comment>//[^\n]*|/\*.*?\*/|^\#[^\n]*)
  | (?P<quoted>"(?:[^"\\]|\\.)*") | (?P<html><)
  | (?P<edgeop>->|--) | (?P<punct>[{}\[\];,=:])
  | (?P<id>[A-Za-z_\x80-\uffff][A-Za-z_0-9\x80-\uffff]*|-?(?:\.\d+|\d+(?:\.\d*)?))
""", re.X | re.S | re.M)


def _html_end(text: str, start: int) -> int:
    """Where the <HTML string> opened at ``start`` ends: its '<' and '>' balance (the
    DOT language's rule; a table label nests its elements)."""
    depth = 0
    for i in range(start, len(text)):
        depth += {"<": 1, ">": -1}.get(text[i], 0)
        if depth == 0:
            return i + 1
    raise AssertionError(f"DOT: an HTML string opened at {start} is not closed")


def dot_tokens(text: str) -> list[tuple[str, str]]:
    out = []
    pos = 0
    while pos < len(text):
        m = _DOT_TOKEN.match(text, pos)
        assert m, f"DOT: cannot read {text[pos:pos + 20]!r}"
        pos, value = m.end(), m.group()
        if m.lastgroup == "html":
            pos = _html_end(text, m.start())
            out.append(("id", text[m.start():pos]))
        elif m.lastgroup == "quoted":
            out.append(("id", value[1:-1].replace('\\"', '"')))
        elif m.lastgroup == "id":
            out.append(("id", value))
        elif m.lastgroup not in ("ws", "comment"):
            out.append((m.lastgroup, value))
    return out


def read_dot(text: str) -> dict:
    """{"nodes": {id: attrs}, "edges": [(a, b, attrs)], "clusters": {name: [ids]}}."""
    tokens = dot_tokens(text) + [("end", "")]
    nodes: dict[str, dict] = {}
    edges: list = []
    clusters: dict[str, list] = {}
    i = 0

    def attrs() -> dict:
        nonlocal i
        out = {}
        while tokens[i] == ("punct", "["):
            i += 1
            while tokens[i] != ("punct", "]"):
                key = tokens[i][1]
                assert tokens[i + 1] == ("punct", "="), f"DOT: {key} without a value"
                out[key] = tokens[i + 2][1]
                i += 3
                if tokens[i] in (("punct", ","), ("punct", ";")):
                    i += 1
            i += 1
        return out

    def statements(defaults: dict, inside: list[str]) -> None:
        nonlocal i
        defaults = {k: dict(v) for k, v in defaults.items()}   # a subgraph scopes them
        while tokens[i] != ("punct", "}"):
            kind, word = tokens[i]
            if kind == "punct" and word == ";":
                i += 1
                continue
            if kind == "id" and word.lower() in ("node", "edge", "graph") \
                    and tokens[i + 1] == ("punct", "["):
                i += 1
                defaults[word.lower()].update(attrs())
                continue
            if kind == "id" and word.lower() == "subgraph" or kind == "punct" and word == "{":
                name = None
                if word.lower() == "subgraph":
                    i += 1
                    if tokens[i][0] == "id":
                        name = tokens[i][1]
                        i += 1
                assert tokens[i] == ("punct", "{")
                i += 1
                members: list[str] = []
                statements(defaults, members)
                i += 1
                if name and name.startswith("cluster"):
                    clusters.setdefault(name[len("cluster_"):], []).extend(members)
                inside.extend(members)
                continue
            if kind == "id" and tokens[i + 1] == ("punct", "="):
                i += 3          # ID = ID: a graph attribute
                continue
            chain = [word]
            i += 1

            def port() -> None:
                # node_id: ID [':' ID [':' compass_pt]]: where on the node an edge ends
                nonlocal i
                while tokens[i] == ("punct", ":"):
                    i += 2

            port()
            while tokens[i][0] == "edgeop":
                chain.append(tokens[i + 1][1])
                i += 2
                port()
            given = attrs()
            if len(chain) == 1:
                node = chain[0]
                if node not in nodes:
                    nodes[node] = dict(defaults["node"])
                    inside.append(node)
                nodes[node].update(given)
            else:
                for a, b in zip(chain, chain[1:]):
                    for n in (a, b):
                        if n not in nodes:
                            nodes[n] = dict(defaults["node"])
                            inside.append(n)
                    edges.append((a, b, {**defaults["edge"], **given}))

    while tokens[i][1].lower() in ("strict", "digraph", "graph") or tokens[i][0] == "id" \
            and tokens[i + 1] == ("punct", "{"):
        i += 1
    assert tokens[i] == ("punct", "{"), "DOT: a graph's body is in braces"
    i += 1
    statements({"node": {}, "edge": {}, "graph": {}}, [])
    return {"nodes": nodes, "edges": edges, "clusters": clusters}
