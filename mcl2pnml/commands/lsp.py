"""``mcl2pnml lsp``: the language server of MCL for editors (docs/editors.md), over standard
input and output; :mod:`mcl2pnml.langserver` serves."""
from __future__ import annotations

from dataclasses import dataclass

from mcl2pnml.commands.common import size_text
from mcl2pnml.core.settings import size_or_none
from mcl2pnml.langserver.reading import MAX_DOCUMENT_SIZE

#: The largest document checked, as ``--max-document-size`` writes it.
DOCUMENT_SIZE = size_text(MAX_DOCUMENT_SIZE)


@dataclass(frozen=True)
class LspOptions:
    """``lsp``'s settings, by the names of its options (``--help`` says each)."""

    #: a document larger than this (bytes, or as ``--max-document-size`` takes it) is not
    #: checked: one diagnostic says so
    max_document_size: int | str = DOCUMENT_SIZE


def serve(options: LspOptions = LspOptions()) -> None:
    """``mcl2pnml lsp`` with ``options``: serves until the editor says exit."""
    limit = size_or_none(options.max_document_size, "max_document_size")
    # pygls and lsprotocol, 0.7 s: only for the server
    from mcl2pnml.langserver.server import serve as run
    run(limit)
