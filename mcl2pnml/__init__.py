"""mcl2pnml: AUV missions in MCL, compiled to Petri nets, analysed and run.

What a user of the library needs, from the layers below (``docs/ARCHITECTURE.md``): the
net core (:mod:`mcl2pnml.core`), and the thin library calls of the facade
(:mod:`mcl2pnml.pipeline`, docs/api.md) that check and compile missions, load and save nets
in every format, analyse, certify and run them, and give their odds. The commands of
``mcl2pnml`` are :mod:`mcl2pnml.commands`'. Imported under IPython (Jupyter), it shows
nets, missions and results as drawings and verdicts (:mod:`mcl2pnml.notebook`).

>>> from mcl2pnml import NetBuilder, save_pnml, load_pnml
"""
import sys
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
                     "compile_checked", "functional_form", "load_net", "run_mission",
                     "save_net", "save_pnml", "save_show_page", "show_nets", "template_net",
                     "templates", "to_pnml_bytes", "validate_pnml", "warnings_of",
                     "properties_of", "check_properties", "timed_ends",
                     "check_properties_timed", "certify_file", "exact_odds"],
                    "mcl2pnml.pipeline"),
}

__all__ = [
    "__version__", "Mcl2PnmlError", "NetError", "PnmlError",
    "Arc", "ArcKind", "Marking", "Net", "NetBuilder", "Place", "Timing", "Transition",
    "compose", "fuse", "union",
    "load_pnml", "parse_pnml", "save_pnml", "to_pnml_bytes",
    "check_file", "check_source", "compile_file", "compile_source", "compile_checked",
    "functional_form", "load_net", "save_net", "template_net", "templates", "validate_pnml",
    "analyze", "warnings_of", "properties_of", "check_properties", "timed_ends",
    "check_properties_timed", "certify_file", "exact_odds",
    "run_mission", "RunOptions", "show_nets", "save_show_page",
]


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(module), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


def _shown_in_notebooks() -> None:
    """Under IPython (Jupyter) our values are shown as drawings and verdicts
    (:func:`mcl2pnml.notebook.register`); anywhere else nothing more is imported."""
    if "IPython" in sys.modules:
        from mcl2pnml.notebook import register   # html and base64 alone: under IPython only
        register()


_shown_in_notebooks()
