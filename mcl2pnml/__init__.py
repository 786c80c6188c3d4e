"""mcl2pnml: AUV missions in MCL, compiled to Petri nets, analysed and run.

The facade. Each pipeline stage is a module of its own (see
``docs/ARCHITECTURE.md``); this module re-exports what a user of the library
needs:

>>> from mcl2pnml import NetBuilder, save_pnml, load_pnml
"""
__version__ = "0.1.0"

from mcl2pnml.core.errors import Mcl2PnmlError, NetError, PnmlError  # noqa: E402
from mcl2pnml.core.net import (Arc, ArcKind, Marking, Net, NetBuilder, Place, Timing,  # noqa: E402
                  Transition)
from mcl2pnml.core.compose import compose, fuse, union  # noqa: E402
from mcl2pnml.io.pnml import load_pnml, parse_pnml, save_pnml, to_pnml_bytes  # noqa: E402

__all__ = [
    "__version__", "Mcl2PnmlError", "NetError", "PnmlError",
    "Arc", "ArcKind", "Marking", "Net", "NetBuilder", "Place", "Timing", "Transition",
    "compose", "fuse", "union",
    "load_pnml", "parse_pnml", "save_pnml", "to_pnml_bytes",
]
