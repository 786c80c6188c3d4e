"""The commands of ``mcl2pnml``, one module each, over the facade (:mod:`mcl2pnml.pipeline`).

Each module holds a command's decisions and nothing of the command line: a frozen
options dataclass (its settings by name, each default written there once, that the
CLI's options take theirs from), a function that does the command (the options, the
files, a :class:`~mcl2pnml.core.progress.Notes` to say things on the way), and an
outcome with ``lines()`` (the text it prints) and ``as_json()`` (its ``--json``), with
the exit status where the command has more than one. A setting that does not fit is a
:class:`~mcl2pnml.core.settings.SettingError` naming the setting; the CLI names the
option.

``check`` and ``functional`` share :mod:`~mcl2pnml.commands.check` (both read a mission
and print it checked); the others have a module of their own, named for the command but
where a library module holds that name already: ``campaign`` is :mod:`.fly` (the runs are
:mod:`mcl2pnml.campaign`'s), ``odds`` :mod:`.weigh` (the chain is :mod:`mcl2pnml.odds`'),
``show`` :mod:`.page` (the page is :mod:`mcl2pnml.view.show`'s); the counterexamples
``analyze`` explains are told by :mod:`.witnesses`.
"""
