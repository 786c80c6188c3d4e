"""The language server of ``mcl2pnml lsp``: MCL in an editor (docs/editors.md).

A front end as the CLI is, beside :mod:`mcl2pnml.commands`: it reads what the editor
sends, asks the facade (:mod:`mcl2pnml.pipeline`) and the language's own words, and
answers in LSP's types. ``outline`` reads a document whether or not it parses,
``reading`` checks it through the facade, ``meanings`` says what MCL's words mean,
``responses`` builds the answers, ``server`` is the pygls server. May import the
facade and the layers under it, never the CLI nor the commands.
"""
