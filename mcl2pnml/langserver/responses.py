"""The server's answers, as the protocol's types: completions, hovers, definitions, a
document's symbols, and positions in the client's units.

Every answer is read from the document's outline (:mod:`mcl2pnml.langserver.outline`),
so that it is there while the text does not parse, and from what MCL's words mean
(:mod:`mcl2pnml.langserver.meanings`). Hovers are Markdown: what the document says in
them (its names, a declaration's text) is in a code block or escaped, never markup.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from lsprotocol import types

from mcl2pnml.core.errors import visible
from mcl2pnml.langserver.outline import Declaration, Outline, Token, context
from mcl2pnml.langserver.meanings import (ABORTED, DECLARATION_WORDS, RESULTS,
                                            STATEMENT_WORDS, STRUCTURE_TEMPLATES,
                                            TASK_WORDS, Vocabulary)

#: The longest declaration a hover shows, in characters (a function's header only).
SHOWN = 600


class Units:
    """Offsets of a document to the client's positions and back: LSP counts a line's
    characters in UTF-16 code units, unless the client and the server agreed on UTF-8 or
    UTF-32 (``positionEncoding``)."""

    def __init__(self, outline: Outline, encoding: str = types.PositionEncodingKind.Utf16):
        self.outline = outline
        self.encoding = getattr(encoding, "value", encoding)     # utf-8, utf-16, utf-32

    def _units(self, text: str) -> int:
        if text.isascii() or self.encoding == types.PositionEncodingKind.Utf32.value:
            return len(text)
        if self.encoding == types.PositionEncodingKind.Utf8.value:
            return len(text.encode("utf-8", "surrogatepass"))
        return len(text.encode("utf-16-le", "surrogatepass")) // 2

    def position(self, offset: int) -> types.Position:
        line, column = self.outline.position(offset)
        return types.Position(line, self._units(self.outline.line_text(line)[:column]))

    def range(self, start: int, end: int) -> types.Range:
        return types.Range(self.position(start), self.position(end))

    def offset(self, position: types.Position) -> int:
        text = self.outline.line_text(position.line)
        column = 0
        if text.isascii() or self.encoding == types.PositionEncodingKind.Utf32.value:
            column = position.character
        else:
            units = 0
            while column < len(text) and units < position.character:
                units += self._units(text[column])
                column += 1
        return self.outline.offset(position.line, column)


# -- Markdown ------------------------------------------------------------------------------

def _md(text: str) -> str:
    """Text shown as it is in Markdown: control characters as escapes, and the characters
    Markdown and HTML read each escaped with a backslash (CommonMark's rule)."""
    return re.sub(r"([\\`*_{}\[\]<>&|~#!])", r"\\\1", visible(text))


def _code(text: str) -> str:
    """A block of MCL, fenced by more backticks than it holds in a row."""
    longest = max((len(run) for run in re.findall("`+", text)), default=0)
    fence = "`" * max(3, longest + 1)
    return f"{fence}mcl\n{visible(text, keep=chr(10))}\n{fence}"


def _source(outline: Outline, d: Declaration) -> str:
    """A declaration as written: a function's or the mission's header only."""
    end = outline.tokens[d.body].start if d.body is not None else d.end
    text = outline.text[d.start:end].strip()
    return text if len(text) <= SHOWN else text[:SHOWN] + " ..."


# -- what a name means -----------------------------------------------------------------------

@dataclass(frozen=True)
class Meaning:
    """What the name at the cursor stands for: ``kind`` is ``parameter`` (``declaration``
    declares it, at ``token``), ``declared`` (``declaration``), ``pattern``, ``structure``
    or ``atom`` (``name``)."""

    kind: str
    name: str
    declaration: Declaration | None = None
    token: Token | None = None


def meaning(outline: Outline, offset: int, vocab: Vocabulary) -> tuple[Meaning, Token] | None:
    """What the name at ``offset`` means, and its token."""
    word = outline.word_at(offset)
    if word is None:
        return None
    name, d = word.text, outline.declaration_at(word.start)
    where = context(outline, word.start)
    if d is not None:
        own = next((p for p in d.params if p.text == name), None)
        if own is not None and (own is word or where.kind == "value"):
            return Meaning("parameter", name, d, own), word
    if where.kind == "pattern" or (d is not None and d.pattern is word):
        return (Meaning("pattern", name), word) if name in vocab.patterns else None
    declared = outline.declared().get(name)
    if declared is not None:
        return Meaning("declared", name, declared), word
    if name in vocab.patterns:
        return Meaning("pattern", name), word
    if name in STRUCTURE_TEMPLATES and where.kind == "statement":
        return Meaning("structure", name), word
    if name in vocab.atoms and where.kind in ("property", "atom"):
        return Meaning("atom", name), word
    return None


def hover(outline: Outline, offset: int, vocab: Vocabulary, units: Units,
          markup: types.MarkupKind = types.MarkupKind.Markdown) -> types.Hover | None:
    """What the name at ``offset`` is, in ``markup`` (Markdown, or as plain text for a
    client that reads no Markdown)."""
    found = meaning(outline, offset, vocab)
    if found is None:
        return None
    m, word = found
    return types.Hover(_doc(explain(outline, m, vocab), markup),
                       units.range(word.start, word.end))


def explain(outline: Outline, m: Meaning, vocab: Vocabulary) -> str:
    """The Markdown that says what ``m`` is."""
    if m.kind == "parameter":
        d = m.declaration
        return (f"{_code(m.name)}\nA parameter of {d.kind} {_md(d.name)}: each call gives "
                "its value.")
    if m.kind == "pattern":
        return _pattern_text(m.name, vocab)
    if m.kind == "structure":
        name, doc, _ = vocab.structure(m.name) or (m.name, "", None)
        return f"**{_md(m.name)}** (the structure {_md(name)}, section 2.5): {_md(doc)}."
    if m.kind == "atom":
        args = ", ".join(vocab.atoms[m.name])
        return (f"{_code(f'{m.name}({args})')}\nAn atom of a property "
                "(docs/properties.md).")
    d = m.declaration
    if d.kind == "task":
        return _task_text(outline, d, vocab)
    if d.kind == "primitive":
        return _primitive_text(outline, d, vocab)
    if d.kind == "function":
        return (f"{_code(_source(outline, d))}\nA function: a call runs its block, which "
                "ends with the result of the first statement that does not end OK.")
    return _code(_source(outline, d))


def _ends_text(pattern: str, timed: bool, vocab: Vocabulary) -> list[str]:
    """A pattern's results as list items, with or without a time-out."""
    p = vocab.patterns[pattern]
    ends = vocab.ends(pattern, timed)
    if isinstance(ends, str):
        return [f"Its results cannot be told: {_md(ends)}"]
    results, stuck = ends
    lines = [f"- **{r}**: {_md(p.results.get(r, ''))}" for r in results]
    lines.append(f"- **ABORTED**: {_md(p.results.get('ABORTED', 'aborted'))}, {ABORTED}")
    if stuck:
        lines.append("- or it may run for ever")
    never = [r for r in RESULTS[:2] if r not in results]
    if never:
        lines.append(f"- never {' or '.join(never)}"
                     + ("" if timed else " without a time-out"))
    return lines


def _pattern_text(name: str, vocab: Vocabulary) -> str:
    p = vocab.patterns[name]
    slots = f"{p.slots} primitive{'s' * (p.slots != 1)}"
    lines = [f"**{_md(name)}** (a task pattern of {slots}): {_md(p.doc)}.", "",
             "With a time-out it ends:", *_ends_text(name, True, vocab), "",
             "Without a time-out it ends:", *_ends_text(name, False, vocab)]
    return "\n".join(lines)


def _task_text(outline: Outline, d: Declaration, vocab: Vocabulary) -> str:
    lines = [_code(_source(outline, d))]
    pattern = d.pattern.text if d.pattern is not None else None
    if pattern not in vocab.patterns:
        return "\n".join(lines + [f"No task pattern {_md(pattern or '')}: the patterns are "
                                  f"{_md(', '.join(vocab.patterns))}."])
    p = vocab.patterns[pattern]
    lines.append(f"**{_md(pattern)}**: {_md(p.doc)}.")
    timed = d.timeout is not None
    if timed:
        lines.append(f"Time-out: {_md(d.timeout.text)} s, counted from when its primitive "
                     "is on.")
    else:
        waits = vocab.unbounded.get(pattern, "ends only as its pattern's net ends")
        lines.append(f"No time-out: it {_md(waits)}.")
    lines += ["", "It ends:", *_ends_text(pattern, timed, vocab)]
    return "\n".join(lines)


def _primitive_text(outline: Outline, d: Declaration, vocab: Vocabulary) -> str:
    lines = [_code(_source(outline, d))]
    sim = vocab.simulated.get(d.name)
    if sim is None:
        lines.append(f"The simulated vehicle has no primitive {_md(d.name)}: `mcl2pnml run` "
                     "on the simulator refuses a mission that uses it; a vehicle script, a "
                     "bridge or ArduSub can run it (docs/running.md).")
    else:
        lines += [f"On the simulated vehicle (`mcl2pnml run`, docs/simulator.md) it takes "
                  f"{_md(sim.arguments)}; it reports", f"- **achieved**: {_md(sim.achieves)}",
                  f"- **failed**: {_md(sim.fails)}"]
    users = [t.name for t in outline.of_kind("task") if any(p.text == d.name
                                                            for p in t.primitives)]
    lines.append("")
    lines.append(f"Its tasks: {_md(', '.join(users))}." if users else "No task uses it.")
    return "\n".join(lines)


# -- completion ----------------------------------------------------------------------------

_KINDS = {"const": types.CompletionItemKind.Constant,
          "primitive": types.CompletionItemKind.Interface,
          "task": types.CompletionItemKind.Method,
          "function": types.CompletionItemKind.Function}


def completions(outline: Outline, offset: int, vocab: Vocabulary,
                markup: types.MarkupKind = types.MarkupKind.Markdown
                ) -> list[types.CompletionItem]:
    """What may be written at ``offset``: the keywords, patterns and names that fit there
    (:func:`mcl2pnml.langserver.outline.context`), each documented in ``markup``."""
    where = context(outline, offset)
    kind = where.kind
    if kind == "declaration":
        return _keywords(DECLARATION_WORDS)
    if kind == "after-task":
        return _keywords(TASK_WORDS)
    if kind == "pattern":
        return [types.CompletionItem(name, kind=types.CompletionItemKind.Class,
                                     detail=f"task pattern: {p.doc}",
                                     documentation=_doc(_pattern_text(name, vocab), markup))
                for name, p in vocab.patterns.items()]
    if kind == "primitive":
        return _declared(outline, ("primitive",), vocab, markup)
    if kind == "value":
        items = _declared(outline, ("const",), vocab, markup)
        return items + [types.CompletionItem(p, kind=types.CompletionItemKind.Variable,
                                             detail=f"parameter of {where.declaration.name}")
                        for p in dict.fromkeys(where.params)]
    if kind == "statement":
        return (_declared(outline, ("task", "function"), vocab, markup)
                + _keywords(STATEMENT_WORDS + where.follows))
    if kind == "property":
        return _keywords(vocab.property_words) + [
            types.CompletionItem(a, kind=types.CompletionItemKind.Function,
                                 detail=f"{a}({', '.join(args)})")
            for a, args in vocab.atoms.items()]
    if kind == "atom":
        return _atom_arguments(outline, where, vocab, markup)
    return []


def _atom_arguments(outline: Outline, where, vocab: Vocabulary, markup: types.MarkupKind
                    ) -> list[types.CompletionItem]:
    args = vocab.atoms.get(where.atom, ())
    what = args[where.argument] if where.argument < len(args) else None
    if what == "primitive":
        return _declared(outline, ("primitive",), vocab, markup)
    if what == "callable":
        return _declared(outline, ("task", "function"), vocab, markup)
    if what == "result":
        return [types.CompletionItem(r, kind=types.CompletionItemKind.EnumMember)
                for r in RESULTS]
    return []


def _doc(markdown: str, markup: types.MarkupKind) -> types.MarkupContent:
    return types.MarkupContent(markup, markdown)


def _keywords(words) -> list[types.CompletionItem]:
    return [types.CompletionItem(w, kind=types.CompletionItemKind.Keyword) for w in words]


def _declared(outline: Outline, kinds: tuple[str, ...], vocab: Vocabulary,
              markup: types.MarkupKind) -> list[types.CompletionItem]:
    return [types.CompletionItem(d.name, kind=_KINDS[d.kind], detail=_source_line(outline, d),
                                 documentation=_doc(explain(outline, Meaning(
                                     "declared", d.name, d), vocab), markup))
            for d in outline.declared().values() if d.kind in kinds]


def _source_line(outline: Outline, d: Declaration) -> str:
    return " ".join(_source(outline, d).split())[:120]


# -- where things are ----------------------------------------------------------------------

def definition(outline: Outline, offset: int, vocab: Vocabulary, units: Units, uri: str
               ) -> list[types.Location]:
    """Where the name at ``offset`` is declared: in the document, or a pattern's or a
    structure's template file."""
    found = meaning(outline, offset, vocab)
    if found is None:
        return []
    m, _ = found
    if m.kind == "parameter":
        return [types.Location(uri, units.range(m.token.start, m.token.end))]
    if m.kind == "declared":
        d = m.declaration
        at = d.name_token or d.keyword
        return [types.Location(uri, units.range(at.start, at.end))]
    if m.kind == "pattern":
        return _in_template(vocab.patterns[m.name].source, "pattern", m.name)
    if m.kind == "structure":
        _, _, source = vocab.structure(m.name) or (None, None, None)
        return _in_template(source, "structure", STRUCTURE_TEMPLATES[m.name])
    return []


def _in_template(source: Path | None, kind: str, name: str) -> list[types.Location]:
    """The header of template ``name`` in its file (``pattern AchieveGoal ...``)."""
    if source is None:
        return []
    try:
        lines = source.read_text(encoding="utf-8").split("\n")
    except (OSError, UnicodeDecodeError):
        return []
    header = re.compile(rf"\s*{kind}\s+{re.escape(name)}\b")
    line = next((n for n, text in enumerate(lines) if header.match(text)), 0)
    at = types.Position(line, 0)
    return [types.Location(source.as_uri(), types.Range(at, at))]


_SYMBOLS = {"const": types.SymbolKind.Constant, "primitive": types.SymbolKind.Interface,
            "task": types.SymbolKind.Method, "function": types.SymbolKind.Function,
            "mission": types.SymbolKind.Module, "property": types.SymbolKind.Property}


def symbols(outline: Outline, units: Units, uri: str, hierarchical: bool = True
            ) -> list[types.DocumentSymbol] | list[types.SymbolInformation]:
    """Every declaration, in the order written, with its parameters (a list of
    declarations alone for a client that takes no tree)."""
    if not hierarchical:
        return [types.SymbolInformation(name=d.name, kind=_SYMBOLS[d.kind],
                                        location=types.Location(uri, units.range(d.start,
                                                                                 d.end)))
                for d in outline.declarations]
    out = []
    for d in outline.declarations:
        at = d.name_token or d.keyword
        children = [types.DocumentSymbol(p.text, types.SymbolKind.Variable,
                                         units.range(p.start, p.end), units.range(p.start, p.end))
                    for p in d.params]
        out.append(types.DocumentSymbol(d.name, _SYMBOLS[d.kind], units.range(d.start, d.end),
                                        units.range(at.start, at.end),
                                        detail=_source_line(outline, d), children=children))
    return out
