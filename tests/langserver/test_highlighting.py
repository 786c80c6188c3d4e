"""The TextMate grammar of docs/editors/ and its page: the grammar's keywords are exactly
the words of the parser's lark grammar, its task patterns the template library's, its
atoms and results the properties'; the VS Code extension's files are what VS Code reads;
README.md leads to the page."""
from __future__ import annotations

import json
import re
from pathlib import Path

from mcl2pnml.language.declared_properties import ATOMS
from mcl2pnml.language.library import default_library
from mcl2pnml.language.template_parser import TemplateKind
from mcl2pnml.langserver.meanings import RESULTS, grammar_words

ROOT = Path(__file__).resolve().parents[2]
EDITORS = ROOT / "docs" / "editors"
GRAMMAR = json.loads((EDITORS / "mcl.tmLanguage.json").read_text(encoding="utf-8"))
#: The scopes of a keyword, in TextMate's naming.
KEYWORD_SCOPES = ("keyword.", "storage.type.", "constant.language.")


def nodes(node, *keys: str):
    """Every object of the grammar, nested ones too, that has one of ``keys``."""
    if isinstance(node, dict):
        if any(key in node for key in keys):
            yield node
        for value in node.values():
            yield from nodes(value, *keys)
    elif isinstance(node, list):
        for value in node:
            yield from nodes(value, *keys)


def rules(grammar):
    return nodes(grammar, "match", "begin")


def words(scope: str | tuple[str, ...]) -> set[str]:
    """The words of the rules of ``scope``, each written ``\\b(?:w1|w2|...)\\b``."""
    out = set()
    for rule in rules(GRAMMAR):
        if rule.get("name", "").startswith(scope):
            found = re.fullmatch(r"\\b\(\?:(\w+(?:\|\w+)*)\)\\b", rule["match"])
            assert found, rule
            out |= set(found.group(1).split("|"))
    return out


def test_its_keywords_are_the_parsers():
    assert words(KEYWORD_SCOPES) == grammar_words()


def test_its_patterns_atoms_and_results_are_the_projects():
    patterns = {t.name for t in default_library().unique() if t.kind is TemplateKind.PATTERN}
    assert words("support.class.pattern.") == patterns
    assert words("support.function.atom.") == set(ATOMS)
    assert words("support.constant.result.") == set(RESULTS)


def test_every_rule_reads_and_every_include_is_there():
    for rule in rules(GRAMMAR):
        for key in ("match", "begin", "end"):
            if key in rule:
                re.compile(rule[key])
    included = {i["include"][1:] for i in nodes(GRAMMAR, "include")}
    assert included <= set(GRAMMAR["repository"])
    assert GRAMMAR["scopeName"] == "source.mcl"


def test_the_vscode_extension_names_the_grammar_and_the_server():
    package = json.loads((EDITORS / "vscode" / "package.json").read_text(encoding="utf-8"))
    (grammar,) = package["contributes"]["grammars"]
    assert grammar["scopeName"] == GRAMMAR["scopeName"]
    assert Path(grammar["path"]).name == "mcl.tmLanguage.json"
    config = package["contributes"]["languages"][0]["configuration"]
    json.loads((EDITORS / "vscode" / Path(config).name).read_text(encoding="utf-8"))
    assert package["contributes"]["configuration"]["properties"]["mcl.server.command"][
        "default"][1:] == ["lsp"]


def test_the_page_is_linked_and_names_what_is_there():
    assert "](docs/editors.md)" in (ROOT / "README.md").read_text(encoding="utf-8")
    page = (ROOT / "docs" / "editors.md").read_text(encoding="utf-8")
    for editor in ("VS Code", "Neovim", "Helix", "Emacs"):
        assert f"## {editor}" in page
    for link in re.findall(r"\]\((editors/[^)]+)\)", page):
        assert (ROOT / "docs" / link).exists(), link
