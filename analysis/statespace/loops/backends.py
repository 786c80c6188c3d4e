"""Which backend of :class:`~mcl2pnml.analysis.statespace.loops.interface.Loops` runs here.

The loops in C (:mod:`mcl2pnml.analysis.statespace.loops.c`) where they were
built when mcl2pnml was installed, else the plain-Python reference
(:mod:`mcl2pnml.analysis.statespace.loops.python`). The environment variable
:data:`SWITCH` set to ``python`` takes the reference even where C was built:
how a machine without a C compiler is tried on one that has one.
"""
from __future__ import annotations

import os

from mcl2pnml.analysis.statespace.loops import python as python_loops
from mcl2pnml.analysis.statespace.loops.interface import Loops

try:
    from mcl2pnml.analysis.statespace.loops import c as _c_loops
except ImportError:     # installed without a C compiler: the extension was not built
    _c_loops = None

#: The environment variable that, set to ``python``, leaves the loops in C aside.
SWITCH = "MCL2PNML_LOOPS"


def c_loops() -> Loops | None:
    """The loops in C, or None where they were not built (or :data:`SWITCH` leaves them)."""
    if os.environ.get(SWITCH) == "python":
        return None
    return _c_loops   # type: ignore[return-value]


def chosen() -> Loops:
    """The loops that run here: C where it was built, else the Python reference."""
    return c_loops() or python_loops   # type: ignore[return-value]


def named(name: str) -> Loops | None:
    """The backend called ``name`` (``c`` or ``python``), or None if it cannot run here."""
    return {"c": c_loops(), "python": python_loops}[name]   # type: ignore[return-value]
