"""MCL highlighted by Pygments (mcl2pnml.language.highlight): found through the installed
entry point, its words the grammar's, and every mission of the repository (the examples,
the docs' ```mcl blocks) lexed without an error token."""
from __future__ import annotations

import re
import subprocess
import sys
from importlib.metadata import entry_points

import pytest
from pygments.lexers import get_lexer_by_name, get_lexer_for_filename
from pygments.token import Error, Keyword, Name, String, Token

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.language.declared_properties import ATOMS, RESULTS
from mcl2pnml.language.highlight import MclLexer
from mcl2pnml.language.library import default_library
from mcl2pnml.language.parser import KEYWORDS, parse
from mcl2pnml.language.template_parser import TemplateKind

from helpers import ROOT

FILES = sorted((ROOT / "examples").glob("*.mcl")) + sorted((ROOT / "examples").glob("*.props"))
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```(\S*)[^\n]*\n(.*?)^```", re.M | re.S)


def blocks(label: str | None) -> list[tuple[str, str]]:
    """The docs' fenced blocks labelled ``label`` (None: unlabelled), each where it is."""
    out = []
    for doc in DOCS:
        text = doc.read_text(encoding="utf-8")
        for m in FENCE.finditer(text):
            if m.group(1) == (label or ""):
                where = f"{doc.relative_to(ROOT)}:{text[:m.start()].count(chr(10)) + 1}"
                out.append((where, m.group(2)))
    return out


def tokens(text: str) -> list[tuple[Token, str]]:
    return [(t, v) for t, v in MclLexer().get_tokens(text) if v.strip()]


def errors(text: str) -> list[str]:
    return [v for t, v in tokens(text) if t in Error]


def test_pygments_finds_the_lexer_through_the_installed_entry_point():
    found = [e for e in entry_points(group="pygments.lexers") if e.name == "mcl"]
    assert [e.value for e in found] == ["mcl2pnml.language.highlight:MclLexer"]
    assert type(get_lexer_by_name("mcl")) is MclLexer
    assert type(get_lexer_for_filename("survey.mcl")) is MclLexer


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_every_example_lexes_without_an_error_token(path):
    assert errors(path.read_text(encoding="utf-8")) == []


def test_every_mcl_block_of_the_docs_lexes_without_an_error_token():
    found = blocks("mcl")
    assert len(found) > 20   # docs/mcl.md's own
    assert {where: errors(body) for where, body in found if errors(body)} == {}


def test_every_unlabelled_block_the_parser_reads_is_labelled_mcl():
    """A block of MCL left unlabelled is not highlighted: whatever the parser reads is."""
    def reads(body: str) -> bool:
        try:
            parse(body)
        except Mcl2PnmlError:
            return False
        return bool(parse(body).declarations)
    assert [where for where, body in blocks(None) if reads(body)] == []


def test_the_reserved_words_are_keywords_and_the_patterns_builtins():
    source = ("task Dive(d) = AchieveGoal(KeepDepth(d)) timeout 60;\nmission {\n"
              "  if (monitor(Dive(1), Dive(2))) then { Dive(3); } else { Dive(4); }\n"
              "  while (Dive(5)) do { parallel(Dive(6), Dive(7)); }\n}\n")
    parse(source)   # valid MCL
    found = tokens(source)
    assert {v for t, v in found if t in Keyword and t is not Keyword.Declaration} == KEYWORDS \
        - {"const", "primitive", "task", "function", "mission"}
    assert (Name.Builtin, "AchieveGoal") in found and (Name.Function, "Dive") in found
    patterns = {n for t in default_library().unique() if t.kind is TemplateKind.PATTERN
                for n in t.names if n not in KEYWORDS}
    assert {v for t, v in tokens(" ".join(patterns)) if t is Name.Builtin} == patterns


def test_a_property_s_words_are_keywords_only_inside_a_property():
    source = ("primitive P();\ntask before() = AchieveGoal(P());\nmission { before(); }\n"
              "property X: true leads to running(before) before not false and outcome(OK);\n")
    parse(source)   # valid MCL: "before" names a task
    found = tokens(source)
    names = [t for t, v in found if v == "before"]
    assert names[:2] == [Name.Function, Name.Function]
    assert names[2:] == [Name, Keyword]   # the atom's argument; the scope
    assert (Keyword.Constant, "true") in found and (Keyword.Constant, "false") in found
    assert (Name.Builtin, "running") in found and (Name.Constant, "OK") in found
    atoms = " ".join(f"{a}(X)" for a in ATOMS)
    inside = tokens(f"property P: never {atoms} or outcome({', '.join(RESULTS)});")
    assert {v for t, v in inside if t is Name.Builtin} == set(ATOMS)
    assert {v for t, v in inside if t is Name.Constant} == set(RESULTS)
    outside = tokens("const leads = 1; mission { to(leads); }")
    assert (Name.Constant, "leads") in outside and (Name.Function, "to") in outside


@pytest.mark.parametrize("source", ['mission { Go("open); }', "mission { Go(); } /* open",
                                    "mission { Gö(); }"])
def test_what_the_parser_refuses_is_an_error_token(source):
    with pytest.raises(Mcl2PnmlError):
        parse(source)
    assert errors(source)


def test_a_string_and_a_comment_are_the_grammar_s():
    found = tokens('// a comment\nconst Name = "a \\"quoted\\" string"; /* two\nlines */')
    assert [v for t, v in found if t in String] == ['"a \\"quoted\\" string"']
    assert [t for t, v in found if v.startswith(("//", "/*"))] == [Token.Comment] * 2


def test_importing_the_lexer_reads_no_grammar():
    """Pygments imports every plugin whenever it looks up a name it does not know."""
    out = subprocess.run([sys.executable, "-c", "import sys, mcl2pnml.language.highlight; "
                          "print('lark' in sys.modules)"], capture_output=True, text=True,
                         timeout=60, check=True)
    assert out.stdout.strip() == "False"
