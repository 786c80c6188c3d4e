"""mcl2pnml: AUV missions in MCL, compiled to Petri nets, analysed and run.

The facade: what a user of the library needs, from the layers below
(``docs/ARCHITECTURE.md``): the net core (:mod:`mcl2pnml.core`), and the
pipeline (:mod:`mcl2pnml.pipeline`) that compiles missions, loads and saves
nets in every format, analyses and runs them.

>>> from mcl2pnml import NetBuilder, save_pnml, load_pnml
"""
from mcl2pnml.core.version import __version__
from mcl2pnml.core.errors import Mcl2PnmlError, NetError, PnmlError
from mcl2pnml.core.net import Arc, ArcKind, Marking, Net, NetBuilder, Place, Timing, Transition
from mcl2pnml.core.compose import compose, fuse, union
from mcl2pnml.io.pnml.reader import load_pnml, parse_pnml
from mcl2pnml.pipeline import (analyze, check_file, check_source, compile_file,
                               compile_source, functional_form, load_net, run_mission,
                               save_net, save_pnml, save_show_page, show_nets, template_net,
                               templates, to_pnml_bytes, validate_pnml)

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
    # RunOptions comes with the runtime, imported only by what runs a mission
    if name == "RunOptions":
        from mcl2pnml.runtime.session import RunOptions
        return RunOptions
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
