"""``mcl2pnml lsp``: the language server, over standard input and output (pygls).

Each document an editor opens is checked when it is opened and again at each pause in
typing (:data:`PAUSE`), in a thread of its own so that the answers do not wait, and its
diagnostics published when the text they are of is still the document's
(:mod:`mcl2pnml.langserver.reading`). Completions, hovers, definitions and symbols are
read from the outline of the text as it is at the request
(:mod:`mcl2pnml.langserver.responses`); quick fixes from the warnings' diagnostics.

Only what the editor opened is read (a request about any other file is answered with
nothing: the server never reads a file it was not given), a document over the size the
server reads is not checked, and a fault in an answer is said on standard error and
answered with nothing: the server goes on.
"""
from __future__ import annotations

import asyncio
import functools
import os
import sys
import threading
import traceback
from concurrent.futures import ThreadPoolExecutor

from lsprotocol import types
from pygls.lsp.server import LanguageServer
from pygls.uris import to_fs_path

from mcl2pnml.core.version import __version__
from mcl2pnml.langserver import outline as outlines, reading, responses
from mcl2pnml.langserver.responses import Units
from mcl2pnml.langserver.meanings import Vocabulary

#: How long typing pauses, in seconds, before the document is checked again.
PAUSE = 0.2
_SEVERITY = {"error": types.DiagnosticSeverity.Error,
             "warning": types.DiagnosticSeverity.Warning,
             "information": types.DiagnosticSeverity.Information}
#: The warnings whose fix is an edit (:func:`mcl2pnml.langserver.reading.fix`).
FIXED = ("W001", "W004")


class MclServer(LanguageServer):
    """The server's state: the documents open, their outlines, their pending checks."""

    def __init__(self, limit: int = reading.MAX_DOCUMENT_SIZE):
        super().__init__("mcl2pnml", __version__,
                         text_document_sync_kind=types.TextDocumentSyncKind.Incremental)
        self.limit = limit
        self.vocab = Vocabulary()
        self.opened: set[str] = set()
        self.shut = False       # the client asked to shut down (then exit is not an error)
        self.published: dict[str, list[types.Diagnostic]] = {}
        self._outlines: dict[str, tuple[str, outlines.Outline]] = {}
        self._pending: dict[str, asyncio.Task] = {}
        self._checks = ThreadPoolExecutor(max_workers=1, thread_name_prefix="mcl-check")

    def outline(self, uri: str) -> tuple[outlines.Outline, Units] | None:
        """The outline of an open document as it is now, read once per text; None for a
        document not open."""
        if uri not in self.opened:
            return None
        text = self.workspace.get_text_document(uri).source
        known = self._outlines.get(uri)
        if known is None or known[0] is not text:
            # past the size read, an empty outline: keywords only, nothing declared
            known = (text, outlines.read(text if reading.size_of(text) <= self.limit else ""))
            self._outlines[uri] = known
        encoding = self.workspace.position_encoding or types.PositionEncodingKind.Utf16
        return known[1], Units(known[1], encoding)

    def check_later(self, uri: str, pause: float) -> None:
        """Check the document after ``pause`` seconds without a change (a change cancels
        the check waiting)."""
        waiting = self._pending.pop(uri, None)
        if waiting is not None:
            waiting.cancel()
        self._pending[uri] = asyncio.get_running_loop().create_task(self._check(uri, pause))

    async def _check(self, uri: str, pause: float) -> None:
        await asyncio.sleep(pause)
        if uri not in self.opened:      # closed meanwhile: its file is not ours to read
            return
        document = self.workspace.get_text_document(uri)
        version, text = document.version, document.source
        loop = asyncio.get_running_loop()
        try:
            found = await loop.run_in_executor(self._checks, self._diagnose, uri, text)
        except Exception:   # noqa: BLE001 (a fault of ours: said, and the server goes on)
            traceback.print_exc(file=sys.stderr)
            return
        if uri not in self.opened:
            return
        document = self.workspace.get_text_document(uri)
        if document.version == version and document.source is text:
            self.published[uri] = found
            self.text_document_publish_diagnostics(
                types.PublishDiagnosticsParams(uri, found, version))

    def _diagnose(self, uri: str, text: str) -> list[types.Diagnostic]:
        """The diagnostics of ``text``, in the check thread."""
        found, outline = reading.diagnose(text, _filename(uri), self.limit)
        units = Units(outline, self.workspace.position_encoding
                      or types.PositionEncodingKind.Utf16)
        return [types.Diagnostic(units.range(d.start, d.end), d.message,
                                 severity=_SEVERITY[d.severity], code=d.code,
                                 source="mcl2pnml")
                for d in found]

    def closed(self, uri: str) -> None:
        waiting = self._pending.pop(uri, None)
        if waiting is not None:
            waiting.cancel()
        self.opened.discard(uri)
        self._outlines.pop(uri, None)
        self.published.pop(uri, None)
        self.text_document_publish_diagnostics(types.PublishDiagnosticsParams(uri, []))


def _filename(uri: str) -> str:
    """The name an error's location gives the document: its path, or its URI."""
    try:
        return to_fs_path(uri) or uri
    except Exception:   # noqa: BLE001 (a URI pygls cannot read: named as it is)
        return uri


def _ask(ls: MclServer, *path: str):
    """What the client said it can do of ``textDocument``'s ``path`` (None: nothing)."""
    found = ls.client_capabilities.text_document
    for name in path:
        found = getattr(found, name, None)
    return found


def _markup(formats) -> types.MarkupKind:
    """Markdown where the client reads it, else plain text."""
    return types.MarkupKind.Markdown if formats and types.MarkupKind.Markdown in formats \
        else types.MarkupKind.PlainText


def _answering(empty):
    """A request about an open document: the handler is given its outline and units, and
    answers ``empty`` for a document not open. On a fault of ours it says it on standard
    error and answers ``empty`` too: one bad answer must not stop the server."""
    def wrap(handler):
        @functools.wraps(handler)
        def answer(ls: MclServer, params):
            read = ls.outline(params.text_document.uri)
            if read is None:
                return empty
            try:
                return handler(ls, params, *read)
            except Exception:   # noqa: BLE001 (a fault of ours: said, and the server goes on)
                traceback.print_exc(file=sys.stderr)
                return empty
        return answer
    return wrap


def initialized(ls: MclServer, params: types.InitializedParams) -> None:
    # the patterns' proofs and the simulator's table, read before the first hover asks
    threading.Thread(target=ls.vocab.warm, name="mcl-vocabulary", daemon=True).start()


def shutdown(ls: MclServer, params: None) -> None:
    ls.shut = True


def exit_(ls: MclServer, params: None) -> None:
    # at once: a check still running is of no use, and waiting for its thread (and for the
    # reader's, blocked on standard input) would hold the editor's exit up
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0 if ls.shut else 1)


def did_open(ls: MclServer, params: types.DidOpenTextDocumentParams) -> None:
    ls.opened.add(params.text_document.uri)
    ls.check_later(params.text_document.uri, 0)


def did_change(ls: MclServer, params: types.DidChangeTextDocumentParams) -> None:
    ls.check_later(params.text_document.uri, PAUSE)


def did_close(ls: MclServer, params: types.DidCloseTextDocumentParams) -> None:
    ls.closed(params.text_document.uri)


@_answering(None)
def completion(ls: MclServer, params: types.CompletionParams, outline, units: Units):
    item = _ask(ls, "completion", "completion_item")
    markup = _markup(getattr(item, "documentation_format", None))
    items = responses.completions(outline, units.offset(params.position), ls.vocab, markup)
    return types.CompletionList(is_incomplete=False, items=items)


@_answering(None)
def hover(ls: MclServer, params: types.HoverParams, outline, units: Units):
    markup = _markup(getattr(_ask(ls, "hover"), "content_format", None))
    return responses.hover(outline, units.offset(params.position), ls.vocab, units, markup)


@_answering([])
def definition(ls: MclServer, params: types.DefinitionParams, outline, units: Units):
    return responses.definition(outline, units.offset(params.position), ls.vocab, units,
                              params.text_document.uri)


@_answering([])
def document_symbol(ls: MclServer, params: types.DocumentSymbolParams, outline,
                    units: Units):
    tree = getattr(_ask(ls, "document_symbol"), "hierarchical_document_symbol_support", False)
    return responses.symbols(outline, units, params.text_document.uri, bool(tree))


@_answering([])
def code_action(ls: MclServer, params: types.CodeActionParams, outline, units: Units
                ) -> list[types.CodeAction]:
    """The edit of each warning in the request (or, if the client sent none, of those
    published that meet its range) whose fix is one."""
    uri = params.text_document.uri
    asked = params.context.diagnostics or [
        d for d in ls.published.get(uri, [])
        if d.range.start.line <= params.range.end.line
        and params.range.start.line <= d.range.end.line]
    out = []
    for d in asked:
        if d.source != "mcl2pnml" or d.code not in FIXED:
            continue
        fix = reading.fix(outline, str(d.code), units.offset(d.range.start))
        if fix is None:
            continue
        edit = types.TextEdit(units.range(fix.start, fix.end), fix.text)
        out.append(types.CodeAction(fix.title, kind=types.CodeActionKind.QuickFix,
                                    diagnostics=[d], is_preferred=True,
                                    edit=types.WorkspaceEdit(changes={uri: [edit]})))
    return out


#: Each feature: its method, its options, its handler.
FEATURES = (
    (types.INITIALIZED, None, initialized),
    (types.SHUTDOWN, None, shutdown),
    (types.EXIT, None, exit_),
    (types.TEXT_DOCUMENT_DID_OPEN, None, did_open),
    (types.TEXT_DOCUMENT_DID_CHANGE, None, did_change),
    (types.TEXT_DOCUMENT_DID_CLOSE, None, did_close),
    (types.TEXT_DOCUMENT_COMPLETION, types.CompletionOptions(trigger_characters=["(", ","]),
     completion),
    (types.TEXT_DOCUMENT_HOVER, None, hover),
    (types.TEXT_DOCUMENT_DEFINITION, None, definition),
    (types.TEXT_DOCUMENT_DOCUMENT_SYMBOL, None, document_symbol),
    (types.TEXT_DOCUMENT_CODE_ACTION,
     types.CodeActionOptions(code_action_kinds=[types.CodeActionKind.QuickFix]), code_action),
)


def make_server(limit: int = reading.MAX_DOCUMENT_SIZE) -> MclServer:
    """The server with its features (see the module's documentation)."""
    server = MclServer(limit)
    for method, options, handler in FEATURES:
        server.feature(method, options)(handler)
    return server


def serve(limit: int = reading.MAX_DOCUMENT_SIZE) -> None:
    """Serve on standard input and output until the client says exit."""
    make_server(limit).start_io()
