"""mcl2pnml: AUV missions in MCL, compiled to Petri nets, analysed and run.

What a user of the library needs, from the layers below (``docs/ARCHITECTURE.md``): the
net core (:mod:`mcl2pnml.core`), and the thin library calls of the facade
(:mod:`mcl2pnml.pipeline`) that compile missions, load and save nets in every format,
analyse and run them. The commands of ``mcl2pnml`` are :mod:`mcl2pnml.commands`'.

>>> from mcl2pnml import NetBuilder, save_pnml, load_pnml
"""
from importlib import import_module

from mcl2pnml.core.version import __version__
from mcl2pnml.core.errors import Mcl2PnmlError, NetError, PnmlError
from mcl2pnml.core.net import Arc, ArcKind, Marking, Net, NetBuilder, Place, Timing, Transition
from mcl2pnml.core.compose import compose, fuse, union

#: Where each name of the facade comes from, imported when it is first asked for: every
#: command imports this package first (``python -m mcl2pnml``), and the PNML reader alone
#: loads lxml (10 ms, measured with ``python -X importtime -m mcl2pnml --version``), the
#: runtime its vehicles, which ``--version`` and most commands never use.
_LAZY = {
    "load_pnml": "mcl2pnml.io.pnml.reader", "parse_pnml": "mcl2pnml.io.pnml.reader",
    "RunOptions": "mcl2pnml.runtime.session",
    **dict.fromkeys(["analyze", "check_file", "check_source", "compile_file", "compile_source",
                     "functional_form", "load_net", "run_mission", "save_net", "save_pnml",
                     "save_show_page", "show_nets", "template_net", "templates",
                     "to_pnml_bytes", "validate_pnml"], "mcl2pnml.pipeline"),
}

__all__ = [
    "__version__", "Mcl2PnmlError", "NetError", "PnmlError",
    "Arc", "ArcKind", "Marking", "Net", "NetBuilder", "Place", "Timing", "Transition",
    "compose", "fuse", "union",
    "load_pnml", "parse_pnml", "save_pnml", "to_pnml_bytes",
    "check_file", "check_source", "compile_file", "compile_source", "functional_form",
    "load_net", "save_net", "template_net", "templates", "validate_pnml", "analyze",
    "run_mission", "RunOptions", "show_nets", "save_show_page",
]


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(module), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
