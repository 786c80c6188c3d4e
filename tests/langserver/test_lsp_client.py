"""``mcl2pnml lsp`` as an editor meets it: started as a process and spoken to in LSP by a
real client (pytest-lsp), with Visual Studio Code's capabilities; one server for the
module.

What the server answers is held to what the project computes: the errors' places to
where the test wrote each mistake, the warnings to the lint's, the completions to the
checked program's names and the template library's patterns, the hovers to the patterns'
proofs and the simulator's table, the definitions and symbols to the parser's positions.
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest
import pytest_lsp
from lsprotocol import types
from pytest_lsp import ClientServerConfig, LanguageClient, client_capabilities

from mcl2pnml import pipeline
from mcl2pnml.language.library import default_library
from mcl2pnml.language.template_parser import TemplateKind

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))
#: Small, so that a document over it is cheap to send.
LIMIT = 64 << 10
SERVER = [sys.executable, "-m", "mcl2pnml", "lsp", "--stdio", "--max-document-size",
          f"{LIMIT >> 10}K"]
PUBLISH = types.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS
pytestmark = pytest.mark.asyncio(loop_scope="module")


@pytest_lsp.fixture(config=ClientServerConfig(server_command=SERVER), scope="module")
async def client(lsp_client: LanguageClient):
    await lsp_client.initialize_session(types.InitializeParams(
        capabilities=client_capabilities("visual-studio-code")))
    yield
    await lsp_client.shutdown_session()


# -- talking to it -------------------------------------------------------------------------

def uri_of(name: str) -> str:
    """A document's URI: the editor's buffer need not be a file."""
    return (ROOT / "tests" / "langserver" / f"{name}.mcl").as_uri()


async def published(client: LanguageClient, uri: str) -> list[types.Diagnostic]:
    """The diagnostics the server publishes next for ``uri``. The client keeps the last of
    each document; it is looked at before each wait, since two notifications read at once
    wake one waiter."""
    while uri not in client.diagnostics:
        await client.wait_for_notification(PUBLISH)
    return list(client.diagnostics[uri])


async def opened(client: LanguageClient, uri: str, text: str) -> list[types.Diagnostic]:
    client.diagnostics.pop(uri, None)
    client.text_document_did_open(types.DidOpenTextDocumentParams(
        types.TextDocumentItem(uri, "mcl", 1, text)))
    return await published(client, uri)


async def changed(client: LanguageClient, uri: str, version: int, text: str
                  ) -> list[types.Diagnostic]:
    client.diagnostics.pop(uri, None)
    client.text_document_did_change(types.DidChangeTextDocumentParams(
        types.VersionedTextDocumentIdentifier(version=version, uri=uri),
        [types.TextDocumentContentChangeWholeDocument(text)]))
    return await published(client, uri)


def closed(client: LanguageClient, uri: str) -> None:
    client.text_document_did_close(types.DidCloseTextDocumentParams(
        types.TextDocumentIdentifier(uri)))


async def labels(client: LanguageClient, uri: str, line: int, character: int) -> set[str]:
    found = await client.text_document_completion_async(types.CompletionParams(
        types.TextDocumentIdentifier(uri), types.Position(line, character)))
    items = found.items if isinstance(found, types.CompletionList) else found or []
    return {item.label for item in items}


async def hover_text(client: LanguageClient, uri: str, line: int, character: int) -> str:
    found = await client.text_document_hover_async(types.HoverParams(
        types.TextDocumentIdentifier(uri), types.Position(line, character)))
    assert found is not None, (line, character)
    assert found.contents.kind == types.MarkupKind.Markdown
    return re.sub(r"\\(.)", r"\1", found.contents.value)   # Markdown's escapes read back


def at(pos) -> tuple[int, int]:
    """An AST position (from 1) as LSP's (from 0); the examples are ASCII, so that a
    column in code points is one in UTF-16 units."""
    return pos.line - 1, pos.column - 1


def errors(diagnostics) -> list[types.Diagnostic]:
    return [d for d in diagnostics if d.severity == types.DiagnosticSeverity.Error]


def written(lines: list[str]) -> str:
    return "\n".join(lines) + "\n"


# -- diagnostics ---------------------------------------------------------------------------

class Mistakes:
    """A mission written line by line, each mistake's place noted as it is written: each
    line with the word that is wrong in it, or None."""

    def __init__(self, lines: list[tuple[str, str | None]]) -> None:
        self.lines = [line for line, _ in lines]
        self.places = [(n, line.index(wrong), line.index(wrong) + len(wrong))
                       for n, (line, wrong) in enumerate(lines) if wrong is not None]


async def test_every_error_of_a_file_is_reported_at_once_where_it_is(client):
    m = Mistakes([
        ("const WP1 = (1.0, 2.0, 3.0);", None),
        ("primitive GoToWayPoint(waypoint); primitive KeepDepth(depth);", None),
        ("task Go(wp) = AchieveGoal(GoToWaypont(wp)) timeout 60;", "GoToWaypont"),
        ("task Hold(d) = KeepGoel(KeepDepth(d)) timeout 20;", "KeepGoel"),
        ("mission {", None), ("    Go(WP1);", None),
        ("    Dive(3);", "Dive"), ("    Go(WP1, 2);", "Go"), ("    Hold(Depth9);", "Depth9"),
        ("}", None)])
    uri = uri_of("mistakes")
    found = await opened(client, uri, written(m.lines))
    assert all(d.source == "mcl2pnml" for d in found)
    assert sorted((d.range.start.line, d.range.start.character, d.range.end.character)
                  for d in errors(found)) == sorted(m.places)
    assert len(found) == len(m.places)

    # a syntax error as it is typed: a missing ';' is reported where it is missing
    broken = m.lines[:5] + ["    Go(WP1)", "    Hold(2);", "}"]
    found = await changed(client, uri, 2, written(broken))
    assert [(d.range.start.line, d.range.start.character) for d in errors(found)] == \
        [(5, len(broken[5]))]
    # what the document declares is still offered where a statement goes
    assert {"Go", "Hold", "if", "monitor"} <= await labels(client, uri, 6, 4)
    closed(client, uri)


async def fixed(client: LanguageClient, name: str, lines: list[str], code: str, word: str):
    """Open a mission with warning ``code`` at ``word``, apply the quick fix the server
    offers, and return the diagnostics of the fixed text and the text."""
    uri = uri_of(name)
    found = await opened(client, uri, written(lines))
    line = next(n for n, text in enumerate(lines) if word in text)
    warned = [d for d in found if d.code == code]
    assert [(d.severity, d.range.start.line, d.range.start.character) for d in warned] == \
        [(types.DiagnosticSeverity.Warning, line, lines[line].index(word))]
    actions = await client.text_document_code_action_async(types.CodeActionParams(
        types.TextDocumentIdentifier(uri), warned[0].range,
        types.CodeActionContext(warned)))
    assert [a.kind for a in actions] == [types.CodeActionKind.QuickFix]
    (edit,) = actions[0].edit.changes[uri]
    text = apply(written(lines), edit)
    after = await changed(client, uri, 2, text)
    closed(client, uri)
    return after, text


def apply(text: str, edit: types.TextEdit) -> str:
    lines = text.split("\n")
    start = sum(len(line) + 1 for line in lines[:edit.range.start.line]) + \
        edit.range.start.character
    end = sum(len(line) + 1 for line in lines[:edit.range.end.line]) + edit.range.end.character
    return text[:start] + edit.new_text + text[end:]


HEAD = ["primitive P();", "primitive Q();", "primitive R();",
        "task A() = AchieveGoal(P()) timeout 10;", "task B() = AchieveGoal(Q()) timeout 10;",
        "task C() = AchieveGoal(R()) timeout 10;"]


#: Each warning with a fix: its code, a mission's body that has it, the word it is at.
FIXED = [("W001", ["    monitor(A(), B());", "    C();"], "monitor"),
         ("W004", ["    if (A()) then { B(); }", "    C();"], "if")]


async def test_a_warning_is_fixed_by_its_quick_fix(client):
    for code, body, word in FIXED:
        lines = HEAD + ["mission {", *body, "}"]
        after, text = await fixed(client, code.lower(), lines, code, word)
        assert after == [], code
        checked = pipeline.check_source(text)       # the fixed mission checks, with no warning
        assert pipeline.warnings_of(checked) == [], code


async def test_a_bad_or_huge_document_is_a_diagnostic_and_the_server_goes_on(client):
    huge = uri_of("huge")
    (said,) = await opened(client, huge, "// padding\n" * (LIMIT // 10))
    assert said.severity == types.DiagnosticSeverity.Information
    assert f"{LIMIT:,}" in said.message
    hostile = {"binary": "\x00\x01\x1b]0;x\x07" * 1000 + '"open string\n/* open comment',
               "nested": "mission { " + "{" * 5000 + "}" * 5000 + " }",
               "calls": "mission { " + "A(" * 3000 + ")" * 3000 + "; }"}
    for name, text in hostile.items():
        found = await opened(client, uri_of(name), text)
        assert len(errors(found)) == 1 and found[0].range.start.line == 0, name
        assert "\x1b" not in found[0].message
    closed(client, huge)
    example = EXAMPLES[0]
    await opened(client, example.as_uri(), example.read_text(encoding="utf-8"))
    assert await labels(client, example.as_uri(), 0, 0) >= {"mission", "task"}
    closed(client, example.as_uri())


async def test_completion_reads_a_document_that_does_not_parse(client):
    text = (ROOT / "examples" / "sauce.mcl").read_text(encoding="utf-8")
    head = text[:text.index("mission {")]
    checked = pipeline.check_file(ROOT / "examples" / "sauce.mcl")
    uri = uri_of("typing")
    typed = head + "task Rise() = \nmission {\n    if (Survey()) then {\n        Achie"
    found = await opened(client, uri, typed)
    assert errors(found)
    lines = typed.split("\n")
    last = len(lines) - 1
    assert set(checked.tasks) | set(checked.functions) <= \
        await labels(client, uri, last, len(lines[-1]))
    rise = next(n for n, line in enumerate(lines) if line.startswith("task Rise"))
    patterns = {t.name for t in default_library().unique() if t.kind is TemplateKind.PATTERN}
    assert await labels(client, uri, rise, len(lines[rise])) == patterns
    closed(client, uri)


# -- every example ---------------------------------------------------------------------------

async def test_every_example_is_diagnosed_completed_explained_and_outlined(client):
    # one test, not one per example: its tests in few items keep the module on one test
    # process (and one server) when the suite is spread over several
    for example in EXAMPLES:
        try:
            await example_holds(client, example)
        except AssertionError as e:
            raise AssertionError(f"{example.name}: {e}") from e


async def example_holds(client: LanguageClient, example: Path) -> None:
    uri, text = example.as_uri(), example.read_text(encoding="utf-8")
    found = await opened(client, uri, text)
    checked = pipeline.check_file(example)
    assert [(d.code, d.range.start.line + 1, d.range.start.character + 1) for d in found] == \
        [(w.code, w.location.line, w.location.column) for w in pipeline.warnings_of(checked)]

    statement = checked.mission.body.body[0].pos
    assert set(checked.tasks) | set(checked.functions) | {"parallel", "monitor", "if",
                                                          "while"} <= \
        await labels(client, uri, *at(statement))
    patterns = {t.name for t in default_library().unique() if t.kind is TemplateKind.PATTERN}
    for task in checked.tasks.values():
        assert await labels(client, uri, *at(task.pattern_pos)) == patterns
        for call in task.primitives:
            assert await labels(client, uri, *at(call.pos)) == set(checked.primitives)
        await task_is_explained(client, uri, task)
    simulated = {row[0]: row for row in pipeline.simulated_primitives()}
    for prim in checked.primitives.values():
        said = await hover_text(client, uri, *at(prim.pos))
        row = simulated.get(prim.name)
        assert (row[2] in said and row[3] in said) if row else "has no primitive" in said
    await definitions_and_symbols_hold(client, uri, checked)
    closed(client, uri)


async def task_is_explained(client: LanguageClient, uri: str, task) -> None:
    """A task's hover: its pattern, its time-out, and the results its pattern's proof
    gives it, with ABORTED."""
    said = await hover_text(client, uri, *at(task.pos))
    ends, _ = pipeline.pattern_ends(task.pattern, task.timeout is not None)
    assert task.pattern in said
    assert (f"Time-out: {task.timeout.text} s" if task.timeout else "No time-out") in said
    told = re.findall(r"^- \*\*(\w+)\*\*", said, re.MULTILINE)
    assert told == [*ends, "ABORTED"]


async def definitions_and_symbols_hold(client: LanguageClient, uri: str, checked) -> None:
    """Each call of the mission leads to its declaration, a pattern to its template; the
    symbols are the declarations, at the parser's positions."""
    declared = {d.name: d for d in checked.program.declarations if hasattr(d, "name")}
    for call in [s for s in walk(checked.mission.body) if hasattr(s, "args")]:
        (where,) = await client.text_document_definition_async(types.DefinitionParams(
            types.TextDocumentIdentifier(uri), types.Position(*at(call.pos))))
        assert (where.uri, where.range.start.line, where.range.start.character) == \
            (uri, *at(declared[call.name].pos))
    task = next(iter(checked.tasks.values()))
    (template,) = await client.text_document_definition_async(types.DefinitionParams(
        types.TextDocumentIdentifier(uri), types.Position(*at(task.pattern_pos))))
    assert template.uri == Path(str(default_library().get(task.pattern).source)).as_uri()

    symbols = await client.text_document_document_symbol_async(types.DocumentSymbolParams(
        types.TextDocumentIdentifier(uri)))
    program = checked.program.declarations
    assert [s.name for s in symbols] == [getattr(d, "name", "mission") for d in program]
    assert [(s.selection_range.start.line, s.selection_range.start.character)
            for s in symbols] == [at(d.pos) for d in program]


def walk(statement):
    """Every statement under ``statement``, itself too."""
    yield statement
    for name in ("body", "items", "watched", "watcher", "condition", "then", "otherwise"):
        child = getattr(statement, name, None)
        for c in (child if isinstance(child, tuple) else (child,)):
            if c is not None and not isinstance(c, str):
                yield from walk(c)
