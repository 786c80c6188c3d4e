"""The language server's reading of a document, in process: the outline finds what the parser
finds on every example, and goes on where the parser stops; the cursor's context; the
positions in the client's units; the grammar's words; the warnings' fixes."""
from __future__ import annotations

from pathlib import Path

import pytest
from lsprotocol import types

from mcl2pnml import pipeline
from mcl2pnml.language import ast
from mcl2pnml.language.parser import KEYWORDS, parse
from mcl2pnml.langserver import outline, reading
from mcl2pnml.langserver.responses import Units, hover, symbols
from mcl2pnml.langserver.meanings import (DECLARATION_WORDS, FOLLOWING_WORDS,
                                            STATEMENT_WORDS, STRUCTURE_TEMPLATES, TASK_WORDS,
                                            Vocabulary, grammar_words)

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))
KIND = {ast.Const: "const", ast.Primitive: "primitive", ast.Task: "task",
        ast.Function: "function", ast.Mission: "mission", ast.Property: "property"}


def parsed(d) -> tuple:
    """A declaration of the parser, as the outline says one."""
    timeout = getattr(d, "timeout", None)
    return (KIND[type(d)], getattr(d, "name", "mission"), (d.pos.line, d.pos.column),
            tuple(getattr(d, "params", ())), getattr(d, "pattern", None),
            tuple(p.name for p in getattr(d, "primitives", ())),
            timeout.text if timeout is not None else None)


def outlined(d: outline.Declaration) -> tuple:
    at = d.name_token or d.keyword
    return (d.kind, d.name, (at.line + 1, at.column + 1), tuple(p.text for p in d.params),
            d.pattern.text if d.pattern else None, tuple(p.text for p in d.primitives),
            d.timeout.text if d.timeout else None)


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.stem)
def test_the_outline_finds_what_the_parser_finds(example: Path):
    text = example.read_text(encoding="utf-8")
    found = outline.read(text)
    assert [outlined(d) for d in found.declarations] == \
        [parsed(d) for d in parse(text).declarations]
    # each declaration runs to its ; or its }, and the next starts after it
    for d, after in zip(found.declarations, found.declarations[1:]):
        assert text[d.end - 1] in ";}" and d.end <= after.start


def test_the_outline_goes_on_where_the_parser_stops():
    text = ('const A = (1, 2;\n'                         # a ( not closed
            'function Broken(x) {\n    Go(A);\n'         # a body not closed
            'task Go(wp) = AchieveGoal(GoTo(wp)) timeout\n'   # a time-out without its number
            'primitive GoTo(p)\n'                        # no ;
            '/* a comment not closed\n task Hidden() = AchieveGoal(P());')
    found = outline.read(text)
    assert [(d.kind, d.name) for d in found.declarations] == \
        [("const", "A"), ("function", "Broken"), ("task", "Go"), ("primitive", "GoTo")]
    go = found.declarations[2]
    assert (go.pattern.text, [p.text for p in go.primitives], go.timeout) == \
        ("AchieveGoal", ["GoTo"], None)
    # a declaration not closed runs to the next: a cursor on the blank line is in it
    assert found.declaration_at(text.index("task Go") - 1).name == "Broken"


@pytest.mark.parametrize("text, kind", [
    ("|", "declaration"),
    ("task T() = |", "pattern"),
    ("task T() = AchieveGoal(|", "primitive"),
    ("task T(w) = AchieveGoal(Go(|", "value"),
    ("task T() = AchieveGoal(P()) |", "after-task"),
    ("task T() = AchieveGoal(P()) timeout 5 |", "none"),
    ("mission { |", "statement"),
    ("mission { if (A()) |", "statement"),
    ("mission { Go(|", "value"),
    ("mission { monitor(A(), Go(W|", "value"),
    ("mission { // a comment |", "none"),
    ('mission { Say("hello |', "none"),
    ("function F(|", "none"),
    ("property P: |", "property"),
    ("property P: never enabled(|", "atom"),
    ("const C = |", "value"),
    ("const C = 1;|", "declaration"),
    ("mission { A(); }\n|", "declaration"),
])
def test_the_context_at_the_cursor(text: str, kind: str):
    at = text.index("|")
    assert outline.context(outline.read(text.replace("|", "")), at).kind == kind


def test_then_do_and_else_follow_their_structures():
    def follows(text):
        at = text.index("|")
        return outline.context(outline.read(text.replace("|", "")), at).follows
    assert follows("mission { if (A()) |") == ("then",)
    assert follows("mission { while (monitor(A(), B())) |") == ("do",)
    assert follows("mission { if (A()) then { B(); } |") == ("else",)


def test_positions_are_in_the_clients_units():
    line = 'const S = "\U0001F41F\u00e9"; // a fish'
    read = outline.read(line + "\n")
    comment = line.index("//")
    astral = sum(1 for c in line[:comment] if ord(c) > 0xFFFF)
    wide = sum(len(c.encode("utf-8")) - 1 for c in line[:comment])
    for encoding, units in ((types.PositionEncodingKind.Utf16, comment + astral),
                            (types.PositionEncodingKind.Utf8, comment + wide),
                            (types.PositionEncodingKind.Utf32, comment)):
        u = Units(read, encoding)
        assert u.position(comment) == types.Position(0, units)
        assert u.offset(types.Position(0, units)) == comment


def test_the_words_are_the_grammars():
    words = grammar_words()
    groups = (DECLARATION_WORDS, STATEMENT_WORDS, FOLLOWING_WORDS, TASK_WORDS)
    said = {w for group in groups for w in group}
    assert said <= words and KEYWORDS <= said
    properties = set(Vocabulary().property_words)
    assert properties == words - said and not properties & KEYWORDS
    library = Vocabulary()
    assert all(library.structure(k) is not None for k in STRUCTURE_TEMPLATES)


@pytest.mark.parametrize("statement", ["monitor(A(), B());", "parallel(monitor(A(), B()), C());"])
def test_w001s_fix_ends_the_warning(statement: str):
    head = ("primitive P(); primitive Q(); primitive R(); primitive S();\n"
            "task A() = AchieveGoal(P()) timeout 9; task B() = AchieveGoal(Q()) timeout 9;\n"
            "task C() = AchieveGoal(R()) timeout 9; task D() = AchieveGoal(S()) timeout 9;\n")
    text = head + f"mission {{\n    {statement}\n    D();\n}}\n"
    (warning,), read = reading.diagnose(text, "<mcl>")
    assert warning.code == "W001" and text[warning.start:warning.end] == "monitor"
    fix = reading.fix(read, "W001", warning.start)
    fixed = text[:fix.start] + fix.text + text[fix.end:]
    assert pipeline.warnings_of(pipeline.check_source(fixed)) == []


def test_a_diagnostic_spans_the_token_it_points_at_or_nothing_past_the_end():
    text = "mission {\n    Go(Far);\n}\n"
    found, _ = reading.diagnose(text, "<mcl>")
    assert sorted(text[d.start:d.end] for d in found) == ["Far", "Go"]
    (empty,), _ = reading.diagnose("", "<mcl>")     # no mission: at the end of nothing
    assert (empty.severity, empty.start, empty.end) == ("error", 0, 0)


def test_a_client_without_markdown_or_trees_gets_plain_text_and_a_list():
    text = (ROOT / "examples" / "sauce.mcl").read_text(encoding="utf-8")
    read = outline.read(text)
    units = Units(read)
    said = hover(read, text.index("FindCross"), Vocabulary(), units, types.MarkupKind.PlainText)
    assert said.contents.kind == types.MarkupKind.PlainText and "AchieveGoal" in \
        said.contents.value
    flat = symbols(read, units, "file:///sauce.mcl", hierarchical=False)
    assert [s.name for s in flat] == [s.name for s in symbols(read, units, "file:///s.mcl")]
    assert all(isinstance(s, types.SymbolInformation) for s in flat)
