"""Which explorer builds the state space: :func:`explore` and its ``backend``.

Three explorers (:data:`BACKENDS`) share one interface, the
:class:`~analysis.generalspace.StateSpace` they return, and one test suite:

* ``"compiled"``, :mod:`analysis.compiledspace`, for safe nets: markings as
  packed bits, the textbook queue-and-hash-set loop compiled by numba (a
  few nanoseconds a firing: over a million markings a second);
* ``"packed"``, :mod:`analysis.packedspace`, for safe nets: the same packed
  markings, a whole breadth-first frontier fired at once in numpy. Both
  give the same :class:`~analysis.packedmarkings.PackedStateSpace`, whose
  edges are recomputed when needed rather than stored;
* ``"general"``, :mod:`analysis.generalspace`, for every net: the
  reachability graph, or the Karp-Miller coverability graph (Murata 1989,
  section V-A) when the net is unbounded, with markings as tuples of counts.

The safe-net explorers are tried when every weight is 1 and M0 is 0/1; the
first firing that would put a second token in a place hands over to the
general one. ``"auto"`` (the default) takes the compiled explorer when its
machine code is loaded in this process, and otherwise the numpy one, which
hands over to the compiled one past :data:`HANDOVER` markings: loading the
compiled code takes most of a second in a fresh process (importing numba,
reading its cache), more than a small state space takes to explore.

This module sits on top of the explorers and imports them; none imports it.
The names the callers use with :func:`explore` (:class:`StateSpace`,
:data:`OMEGA`, :data:`Progress`) are importable from here too.
"""
from __future__ import annotations

from typing import Sequence

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.structure import Structure, structure as make_structure

from analysis import compiledspace
from analysis.explorers import CHOICES, EXPLORERS
from analysis.generalspace import OMEGA, Progress, StateSpace, explore_general
from analysis.packedmarkings import KeyCollision, NotSafe
from analysis.packedspace import explore_packed

__all__ = ["BACKENDS", "HANDOVER", "OMEGA", "ExplorationLimit", "Progress", "StateSpace",
           "explore"]


class ExplorationLimit(Mcl2PnmlError):
    """The exploration met its state limit before it finished."""


BACKENDS = CHOICES
"""The explorers :func:`explore` can be asked for: ``auto`` or a name of
:data:`analysis.explorers.EXPLORERS`."""

HANDOVER = 500_000
"""Markings after which ``"auto"`` leaves the numpy explorer for the compiled one."""


class _HandOver(Exception):
    """The numpy explorer passed :data:`HANDOVER` markings: the compiled one starts again."""


def explore(net_or_structure, initial: dict[str, int] | None = None, *,
            max_states: int = 5_000_000, progress: Progress | None = None,
            backend: str = "auto") -> StateSpace:
    """Explore the markings reachable from ``initial`` (default: the net's M0).

    ``backend`` is one of :data:`BACKENDS`; a safe-net explorer asked for a
    net that is not safe hands over to ``"general"``, as ``"auto"`` does.
    """
    if backend not in BACKENDS:
        raise Mcl2PnmlError(f"unknown explorer '{backend}'; known: {', '.join(BACKENDS)}")
    s = (net_or_structure if isinstance(net_or_structure, Structure)
         else make_structure(net_or_structure))
    if initial is None:
        m0 = s.initial_vector()
    else:
        unknown = [p for p in initial if p not in s.place_index]
        if unknown:
            raise Mcl2PnmlError(f"initial marking names unknown places: {', '.join(unknown)}")
        m0 = tuple(initial.get(p, 0) for p in s.places)
    unit = all(w == 1 for arcs in (*s.pre, *s.read, *s.post) for w in arcs.values())
    if unit and all(n <= 1 for n in m0):
        try:
            if backend == "auto":
                backend = _auto(s, m0, max_states, progress)
                if isinstance(backend, StateSpace):
                    return backend
            chosen = EXPLORERS[backend]
            if chosen.safe_only:
                if not chosen.can_run():
                    raise Mcl2PnmlError(f"the {backend} explorer needs numba, which is not "
                                        "installed; known explorers: " + ", ".join(BACKENDS))
                return chosen.explore(s, m0, max_states, _limit(max_states), progress)
        except (NotSafe, KeyCollision):
            pass   # not safe after all, or (once in 2^64) two markings share a key
    return _explore_general(s, m0, max_states, progress)


def _auto(s: Structure, m0, max_states: int, progress) -> "str | StateSpace":
    """The explorer ``auto`` picks for a safe net, or the state space it already built.

    The compiled explorer when its code is loaded; otherwise numpy, which
    hands over to the compiled one past :data:`HANDOVER` markings.
    """
    if compiledspace.loaded():
        return "compiled"
    if compiledspace.available() and max_states > HANDOVER:
        try:
            return explore_packed(s, m0, HANDOVER, _HandOver(), progress)
        except _HandOver:
            return "compiled"
    return "packed"


def _limit(max_states: int) -> ExplorationLimit:
    return ExplorationLimit(f"the state space has more than {max_states:,} markings; "
                            "raise the limit (--max-states) or analyse a smaller net")


def _explore_general(s: Structure, m0: Sequence[int], max_states: int,
                     progress: Progress | None) -> StateSpace:
    """The general explorer, with this module's limit error."""
    return explore_general(s, m0, max_states, _limit(max_states), progress)
