"""Which explorer builds the state space: :func:`explore` and its ``backend``.

Four explorers (:data:`BACKENDS`) share one interface, the
:class:`~mcl2pnml.analysis.statespace.general.StateSpace` they return, and one test suite:

* ``"native"``, :mod:`mcl2pnml.analysis.statespace.compiled` with the loops in C
  (``analysis/statespace/loops/_native.c``, built when mcl2pnml is installed), for safe
  nets: markings as packed bits, the textbook queue-and-hash-set loop (a few
  nanoseconds a firing: over a million markings a second), loaded in a
  millisecond;
* ``"packed"``, :mod:`mcl2pnml.analysis.statespace.packed`, for safe nets: the same packed
  markings, a whole breadth-first frontier fired at once in numpy. Both
  give the same :class:`~mcl2pnml.analysis.statespace.packedmarkings.PackedStateSpace`, whose
  edges are recomputed when needed rather than stored;
* ``"counters"``, :mod:`mcl2pnml.analysis.statespace.counters`, for bounded nets: counters
  packed into words, as wide as the P-invariants prove, the same loop (in C
  where it was built, else the plain-Python reference of the loops'
  interface, :mod:`mcl2pnml.analysis.statespace.loops.backends`); it raises
  :class:`~mcl2pnml.analysis.statespace.counters.NotBounded` on a net that may be unbounded;
* ``"general"``, :mod:`mcl2pnml.analysis.statespace.general`, for every net: the
  reachability graph, or the Karp-Miller coverability graph (Murata 1989,
  section V-A) when the net is unbounded, with markings as tuples of counts.

``"auto"`` (the default) chooses by the net's kind. A safe net (every weight
1, M0 0/1) gets the native explorer where it was built (and the state space
is then asked again in C too), else the numpy one. A net that is not safe
(or a safe-net explorer's first second token) gets the counter explorer
where the loops in C were built, else the general one; a net the counter
explorer finds possibly unbounded gets the general one, Karp-Miller.

Every exploration has a memory budget in bytes (``max_memory``, default
:func:`default_memory`): each explorer's bytes per marking turn it into a
number of markings, and the exploration stops there with
:class:`MemoryLimit` (how many markings were found, and how many dead ones
were met) rather than being killed by the kernel.

This module sits on top of the explorers and imports them; none imports it.
The names the callers use with :func:`explore` (:class:`StateSpace`,
:data:`OMEGA`, :data:`Progress`) are importable from here too.
"""
from __future__ import annotations

from mcl2pnml.core.bounds import MAX_STATES
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.memory import default_memory, resident, size_text
from mcl2pnml.core.structure import Structure, structure as make_structure

from mcl2pnml.analysis.statespace.explorers import CHOICES, EXPLORERS
from mcl2pnml.analysis.statespace.general import (OMEGA, FoundMarkings, Progress, StateSpace,
                                                explore_general)
from mcl2pnml.analysis.statespace.counters import NotBounded
from mcl2pnml.analysis.statespace.loops.backends import c_loops
from mcl2pnml.analysis.statespace.packedmarkings import KeyCollision, NotSafe

__all__ = ["BACKENDS", "OMEGA", "ExplorationLimit", "MemoryLimit", "Progress",
           "StateSpace", "default_memory", "explore", "resident"]


class ExplorationLimit(Mcl2PnmlError):
    """The exploration met its state limit before it finished.

    ``explored`` is how many markings were found, ``deadlocks`` how many dead
    markings were met among those expanded (None when the explorer cannot tell), and
    ``found`` the markings themselves where the explorer keeps them packed
    (:class:`~mcl2pnml.analysis.statespace.general.FoundMarkings`: each reachable, for
    witnesses; None from the general explorer). Whoever catches the error drops it
    soon: ``found`` holds the whole queue.
    """

    explored: int | None = None
    deadlocks: int | None = None
    found: "FoundMarkings | None" = None


class MemoryLimit(ExplorationLimit):
    """The exploration would have gone past its memory budget (``max_memory``)."""


BACKENDS = CHOICES
"""The explorers :func:`explore` can be asked for: ``auto`` or a name of
:data:`mcl2pnml.analysis.statespace.explorers.EXPLORERS`."""

def explore(net_or_structure, initial: dict[str, int] | None = None, *,
            max_states: int = MAX_STATES, progress: Progress | None = None,
            backend: str = "auto", max_memory: int | None = None,
            held: int = 0) -> StateSpace:
    """Explore the markings reachable from ``initial`` (default: the net's M0).

    ``backend`` is one of :data:`BACKENDS`; a safe-net explorer asked for a
    net that is not safe hands over to ``"counters"``, which hands over to
    ``"general"`` on a net that may be unbounded, as ``"auto"`` does. ``max_memory`` is a budget in bytes
    (default :func:`default_memory`): each explorer's bytes per marking turn
    it into a number of markings, and past it :class:`MemoryLimit` is raised
    (past ``max_states``, :class:`ExplorationLimit`). ``held``: bytes of the
    budget the caller already holds (the net, the analysis so far).
    """
    if backend not in BACKENDS:
        raise Mcl2PnmlError(f"unknown explorer '{backend}'; known: {', '.join(BACKENDS)}")
    s = (net_or_structure if isinstance(net_or_structure, Structure)
         else make_structure(net_or_structure))
    m0 = _initial(s, initial)
    budget = _Budget(max_states, default_memory() if max_memory is None else max_memory,
                     held)
    unit = all(w == 1 for arcs in (*s.pre, *s.read, *s.post) for w in arcs.values())
    # the packed explorers hold a few dense masks a transition, a word per 64
    # places each: on a wide net (400,000 places and transitions: 120 GB) they
    # alone would be over budget, and the general explorer is left
    wide = _mask_bytes(s) > budget.free // 2
    try:
        if unit and all(n <= 1 for n in m0) and not wide:
            try:
                return _explore_safe(s, m0, backend, budget, progress)
            except (NotSafe, KeyCollision):
                pass   # not safe after all, or (once in 2^64) two markings share a key
        if backend != "general" and not wide and (backend != "auto" or c_loops()):
            # auto leaves a net that is not safe to the general explorer where the
            # loops in C were not built: Python's counters would be no faster
            try:
                return budget.run(EXPLORERS["counters"], s, m0, progress)
            except NotBounded:
                pass   # perhaps unbounded: Karp-Miller decides
        return budget.run(EXPLORERS["general"], s, m0, progress)
    except ExplorationLimit as e:
        if e.explored is None:
            e.explored = budget.states
        raise


def _mask_bytes(s: Structure) -> int:
    """What the packed explorers' transition masks take: eight arrays of a row a
    transition, a 64-bit word per 64 places (counters: per 8)."""
    return 8 * len(s.transitions) * 8 * max(1, -(-len(s.places) * 8 // 64))


def _initial(s: Structure, initial: dict[str, int] | None) -> tuple[int, ...]:
    if initial is None:
        return s.initial_vector()
    unknown = [p for p in initial if p not in s.place_index]
    if unknown:
        raise Mcl2PnmlError(f"initial marking names unknown places: {', '.join(unknown)}")
    return tuple(initial.get(p, 0) for p in s.places)


class _Budget:
    """The two limits of one exploration, as a number of markings for each explorer."""

    def __init__(self, max_states: int, max_memory: int, held: int = 0):
        self.max_states, self.max_memory = max_states, max_memory
        self.free = max_memory - held
        self.states = max_states

    def run(self, explorer, s: Structure, m0, progress):
        per = explorer.bytes_per_marking(s)
        self.states = min(self.max_states, max(1, self.free // per))
        return explorer.explore(s, m0, self.states, self._error(per), progress)

    def _error(self, per: int) -> ExplorationLimit:
        if self.states < self.max_states:
            return MemoryLimit(
                f"the exploration stopped at {self.states:,} markings, its memory budget of "
                f"{size_text(self.max_memory)} ({per:,} bytes a marking); raise the budget "
                "(--max-memory) or analyse a smaller net")
        return _limit(self.max_states)


def _explore_safe(s: Structure, m0, backend: str, budget: _Budget, progress) -> StateSpace:
    """A safe-net explorer (raises NotSafe at a second token in a place)."""
    if backend == "auto":
        # the loops in C where they were built; else numpy, faster than Python's loops
        backend = "native" if EXPLORERS["native"].can_run() else "packed"
    chosen = EXPLORERS[backend]
    if not chosen.can_run():
        raise Mcl2PnmlError(f"the {backend} explorer needs its C code, built when mcl2pnml "
                            "is installed on a machine with a C compiler; known explorers: "
                            + ", ".join(BACKENDS))
    if not chosen.safe_only:
        raise NotSafe   # the counter or general explorer, asked for by name
    return budget.run(chosen, s, m0, progress)


def _limit(max_states: int) -> ExplorationLimit:
    return ExplorationLimit(f"the state space has more than {max_states:,} markings; "
                            "raise the limit (--max-states) or analyse a smaller net")


def _explore_general(s: Structure, m0, max_states: int,
                     progress: Progress | None) -> StateSpace:
    """The general explorer, with this module's limit error (what the tests compare with)."""
    return explore_general(s, m0, max_states, _limit(max_states), progress)
