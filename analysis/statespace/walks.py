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


def random_walks(s: Structure, seconds: float, walkers: int = WALKERS, seed: int = 0
                 ) -> Iterator[np.ndarray]:
    """Batches of reached markings (rows of counts, a column per place), each the markings
    of up to :data:`STEPS` steps of every walker (:data:`BATCH_BYTES` at most), until
    ``seconds`` have passed (checked between batches) or no walker can move."""
    from scipy.sparse import csr_matrix   # scipy: only for a walk
    places, transitions = len(s.places), len(s.transitions)
    m0 = np.asarray(s.initial_vector(), dtype=np.int64)
    if transitions == 0 or places == 0:
        return
    arc_place, arc_weight, arc_transition = [], [], []
    for j in range(transitions):
        need: dict[int, int] = dict(s.pre[j])
        for p, w in s.read[j].items():
            need[p] = need.get(p, 0) + w
        for p, w in need.items():
            arc_place.append(p)
            arc_weight.append(w)
            arc_transition.append(j)
    at = np.asarray(arc_place, dtype=np.int64)
    aw = np.asarray(arc_weight, dtype=np.int64)
    # transitions x arcs: a transition's count of missing inputs is its row's sum
    inputs = csr_matrix((np.ones(len(at), dtype=np.float32),
                         (np.asarray(arc_transition, dtype=np.int64), np.arange(len(at)))),
                        shape=(transitions, len(at)))
    change = incidence_matrix(s)[0].T.tocsr().astype(np.int64)   # a row per transition
    rng = np.random.default_rng(seed)
    steps = max(1, min(STEPS, BATCH_BYTES // (8 * walkers * places)))
    marking = np.tile(m0, (walkers, 1))
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        batch = np.empty((steps * walkers, places), dtype=np.int64)
        for k in range(steps):
            missing = inputs @ (marking[:, at] < aw).T.astype(np.float32)   # T x walkers
            enabled = missing == 0
            if not enabled.any():
                return                                  # every walker dead at M0 too
            score = rng.random(enabled.shape) * enabled
            chosen = score.argmax(axis=0)
            moving = enabled[chosen, np.arange(walkers)]
            marking = np.where(moving[:, None], marking + change[chosen].toarray(),
                               m0[None, :])             # a dead walker starts over
            batch[k * walkers:(k + 1) * walkers] = marking
        yield batch
