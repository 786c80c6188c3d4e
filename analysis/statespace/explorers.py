"""The explorers of a net's reachable markings, one table entry each (``analyze --explorer``).

Each :class:`Explorer` names the module and the function that explore, and
is imported only when used: this table loads no numpy, so the command line
can list the explorers without paying for it. Every
explorer takes the same arguments (the net's
:class:`~mcl2pnml.core.structure.Structure`, the initial marking as counts,
the state limit, the error to raise at it, the progress callback) and
returns a :class:`~mcl2pnml.analysis.statespace.general.StateSpace`; one that explores
safe nets only raises :class:`~mcl2pnml.analysis.statespace.packedmarkings.NotSafe` at the
first second token, and the counter explorer (or, under ``auto`` without
the loops in C, the general one) takes over; the counter explorer raises
:class:`~mcl2pnml.analysis.statespace.counters.NotBounded` when the net may be unbounded,
and the general one (Karp-Miller) takes over. Each also says what a
marking costs it in bytes (``footprint``), so that a memory budget becomes
a number of markings; at its limit an explorer sets ``explored`` (markings
found) and ``deadlocks`` (dead markings among those expanded, or None) on
the error it raises. An explorer built on the loops names the backend of
:class:`~mcl2pnml.analysis.statespace.loops.interface.Loops` it runs on
(``loops``): ``c`` (built at install), or ``chosen``, C where it was built
and the plain-Python reference elsewhere; the function then takes it as
``loops=``.
:func:`mcl2pnml.analysis.statespace.explore.explore` chooses among them.

Adding an explorer is one module with such a function and one entry in
:data:`EXPLORERS`; the chooser, ``analyze --explorer`` and the shared test
suite (tests/analysis/test_statespace.py, run against every entry) take it from
here.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class Explorer:
    """One way to explore the markings of a net."""

    #: the name ``--explorer`` and ``explore(backend=)`` take
    name: str
    #: what it is, for the help
    doc: str
    #: the module implementing it
    module: str
    #: its function ``(structure, m0, max_states, limit_error, progress) -> StateSpace``
    function: str
    #: it explores safe nets only (unit weights, at most one token a place)
    safe_only: bool = False
    #: the module's function saying whether it can run here (None: always)
    available: str | None = None
    #: the module's function ``(structure) -> bytes`` a marking costs at most while
    #: exploring, which turns a memory budget into a number of markings
    footprint: str = "footprint"
    #: the loops it runs on: ``c``, ``chosen`` (C where built, else the Python
    #: reference), or None (numpy, or Python of its own)
    loops: str | None = None

    def _get(self, name: str) -> Callable:
        return getattr(importlib.import_module(self.module), name)

    def can_run(self) -> bool:
        return self.available is None or self._get(self.available)()

    def bytes_per_marking(self, s) -> int:
        return self._get(self.footprint)(s)

    def explore(self, s, m0, max_states: int, limit_error, progress=None, loops=None):
        """Explore ``s`` from ``m0``; ``loops`` (a backend of the loops' interface) in
        place of the one the entry names, for an explorer built on them."""
        explore = self._get(self.function)
        if loops is None:
            return explore(s, m0, max_states, limit_error, progress)
        return explore(s, m0, max_states, limit_error, progress, loops=loops)


EXPLORERS: dict[str, Explorer] = {e.name: e for e in (
    Explorer("native", "C code for safe nets, built at install (fastest; loads at once)",
             "mcl2pnml.analysis.statespace.compiled", "explore_native", safe_only=True,
             available="native_available", loops="c"),
    Explorer("packed", "numpy for safe nets, a breadth-first frontier at a time",
             "mcl2pnml.analysis.statespace.packed", "explore_packed", safe_only=True),
    Explorer("counters", "compiled code for bounded nets: counters packed into words",
             "mcl2pnml.analysis.statespace.counters", "explore_counters", loops="chosen"),
    Explorer("general", "any net: the reachability or Karp-Miller coverability graph",
             "mcl2pnml.analysis.statespace.general", "explore_general"),
)}

#: What ``backend=`` accepts: ``auto`` (the policy of :func:`mcl2pnml.analysis.statespace.explore.explore`)
#: or an explorer of the table.
CHOICES: tuple[str, ...] = ("auto", *EXPLORERS)
