"""Random walks: markings reached deep in a net, fast, where a breadth-first exploration
stops at its limit near the initial marking.

Many walkers start at M0 together; at each step each fires one of its enabled transitions
chosen at random, and a walker with none starts over from M0. Every marking a walker is
in is reachable (the walk is its run), so a marking met is a witness as a found marking
is (:class:`~mcl2pnml.analysis.statespace.general.FoundMarkings`); a walk proves nothing
by what it does not meet. The contest's tools use walks so (ITS-Tools' and verifypn's
random walks; Thierry-Mieg, "Structural reductions revisited", 2020).

The walkers move as one array: a step tests every input arc of every walker at once (a
column per arc), counts each transition's missing inputs by a sparse product, and fires
the chosen transitions by adding their rows of the incidence matrix.
"""
from __future__ import annotations

import time
from typing import Iterator

import numpy as np

from mcl2pnml.core.structure import Structure

from mcl2pnml.analysis.structure.state_equation import incidence_matrix

#: Walkers moving together.
WALKERS = 256
#: Steps between two batches handed back, at most.
STEPS = 32
#: The largest batch, in bytes: fewer steps a batch on a wide net.
BATCH_BYTES = 32 << 20
#: What the walkers' markings may take, in bytes: fewer walkers on a wide net.
WALKER_BYTES = 32 << 20
#: What :func:`runs` may hold of its walkers' runs, in bytes.
RUN_BYTES = 256 << 20


def _fewer(walkers: int, places: int) -> int:
    """As many walkers as asked, or as :data:`WALKER_BYTES` holds of ``places`` counts."""
    return max(1, min(walkers, WALKER_BYTES // (8 * max(1, places))))


class _Stepper:
    """The walkers' one step: each fires one of its enabled transitions at random; one
    with none is dead (its marking is the last of its run)."""

    def __init__(self, s: Structure, seed: int):
        from scipy.sparse import csr_matrix   # scipy: only for a walk
        self.transitions = len(s.transitions)
        arc_place, arc_weight, arc_transition = [], [], []
        for j in range(self.transitions):
            need: dict[int, int] = dict(s.pre[j])
            for p, w in s.read[j].items():
                need[p] = need.get(p, 0) + w
            for p, w in need.items():
                arc_place.append(p)
                arc_weight.append(w)
                arc_transition.append(j)
        self.at = np.asarray(arc_place, dtype=np.int64)
        self.aw = np.asarray(arc_weight, dtype=np.int64)
        # transitions x arcs: a transition's count of missing inputs is its row's sum
        self.inputs = csr_matrix((np.ones(len(self.at), dtype=np.float32),
                                  (np.asarray(arc_transition, dtype=np.int64),
                                   np.arange(len(self.at)))),
                                 shape=(self.transitions, len(self.at)))
        self.change = incidence_matrix(s)[0].T.tocsr().astype(np.int64)   # a row each
        self.rng = np.random.default_rng(seed)

    def step(self, marking: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The walkers' markings after one firing each, and which of them moved (the
        others are dead: their marking is left as it was)."""
        missing = self.inputs @ (marking[:, self.at] < self.aw).T.astype(np.float32)
        enabled = missing == 0                                  # transitions x walkers
        chosen = (self.rng.random(enabled.shape) * enabled).argmax(axis=0)
        moving = enabled[chosen, np.arange(len(marking))]
        after = np.where(moving[:, None], marking + self.change[chosen].toarray(), marking)
        return after, moving


def random_walks(s: Structure, seconds: float, walkers: int = WALKERS, seed: int = 0
                 ) -> Iterator[np.ndarray]:
    """Batches of reached markings (rows of counts, a column per place), each the markings
    of up to :data:`STEPS` steps of every walker (:data:`BATCH_BYTES` at most), until
    ``seconds`` have passed (checked between batches); a dead walker starts over at M0."""
    places = len(s.places)
    m0 = np.asarray(s.initial_vector(), dtype=np.int64)
    if len(s.transitions) == 0 or places == 0:
        return
    stepper = _Stepper(s, seed)
    walkers = _fewer(walkers, places)
    steps = max(1, min(STEPS, BATCH_BYTES // (8 * walkers * places)))
    marking = np.tile(m0, (walkers, 1))
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        batch = np.empty((steps * walkers, places), dtype=np.int64)
        for k in range(steps):
            after, moving = stepper.step(marking)
            if not moving.any() and (marking == m0).all():
                return                                  # M0 is dead: nothing to walk
            marking = np.where(moving[:, None], after, m0[None, :])
            batch[k * walkers:(k + 1) * walkers] = marking
        yield batch


#: The longest run :func:`runs` follows before it starts a walker over.
DEPTH = 1_000


def runs(s: Structure, seconds: float, walkers: int = 16, seed: int = 0
         ) -> Iterator[tuple[np.ndarray, int | None]]:
    """Runs of random walkers that close: ``(markings, back)``, the markings from M0 on,
    and the position the last one's successor returns to (a cycle, the run's lasso), or
    None where the last is dead (a maximal run). Until ``seconds`` have passed; a walker
    past :data:`DEPTH` firings (fewer on a wide net, :data:`RUN_BYTES`) starts over."""
    places = len(s.places)
    m0 = np.asarray(s.initial_vector(), dtype=np.int64)
    if places == 0:
        return
    if len(s.transitions) == 0:
        yield m0[None, :], None
        return
    stepper = _Stepper(s, seed)
    walkers = _fewer(walkers, places)
    # a run's markings are held as rows, found again by their hash: the depth shrinks on
    # a wide net
    depth = max(1, min(DEPTH, RUN_BYTES // (8 * walkers * places)))
    marking = np.tile(m0, (walkers, 1))
    start = hash(m0.tobytes())
    paths: list[list[np.ndarray]] = [[m0] for _ in range(walkers)]
    seen: list[dict[int, int]] = [{start: 0} for _ in range(walkers)]
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        after, moving = stepper.step(marking)
        for w in range(walkers):
            if moving[w]:
                key = hash(after[w].tobytes())
                back = seen[w].get(key)
                if back is not None and not (paths[w][back] == after[w]).all():
                    back = None     # two markings, one hash: not a cycle (and not kept)
                    if len(paths[w]) <= depth:
                        paths[w].append(after[w].copy())
                        continue
                if back is None and len(paths[w]) <= depth:
                    seen[w][key] = len(paths[w])
                    paths[w].append(after[w].copy())
                    continue
                if back is not None:
                    yield np.asarray(paths[w]), back
            else:
                yield np.asarray(paths[w]), None
            paths[w], seen[w] = [m0], {start: 0}             # this walker starts over
            after[w] = m0
        marking = after
