"""Absorbing discrete-time Markov chains whose steps take time: where a run ends, how
likely, and when.

A chain here is any finite DTMC with a start state, a duration per state (the
time a step from it takes: a chain of *instants*, the states between which
nothing happens) and labelled absorbing states (a mission's OK, FAIL,
ABORTED, or a state where it waits for ever). The questions are the classic
ones of absorbing chains (Kemeny and Snell, *Finite Markov Chains*, 1960,
ch. 3): with Q the steps among transient states and N = (I - Q)^-1,

* the probability of ending in each label: N b, b the one-step probability
  of entering it;
* the expected time to end, given that the run ends: g / h with (I - Q) g =
  d * h, h the probability of ending and d the durations; its second moment
  likewise, for the spread;
* the distribution of the end time: the probability mass moved forward in
  time, step by step, each step taking its state's duration.

States from which the chain never reaches an absorbing state (a closed class
of transient states: a loop that repeats for ever) are found first (strongly
connected components) and counted as never ending. Sparse LU (SuperLU, through
scipy) solves the systems.
"""
from __future__ import annotations

import heapq
from dataclasses import dataclass, field

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph
from scipy.sparse.linalg import splu

#: The label of the states of closed classes without an absorbing state (they cycle).
CYCLES = "cycles"


@dataclass(frozen=True)
class Chain:
    """A DTMC: ``P`` (CSR, rows add up to 1), start state 0, each state's step
    ``duration``, and each absorbing state's ``label`` ("" for the others)."""

    P: sparse.csr_matrix
    duration: np.ndarray
    label: tuple[str, ...]

    @property
    def size(self) -> int:
        return self.P.shape[0]


@dataclass(frozen=True)
class Absorption:
    """Where a chain ends from its start state, and when."""

    #: the probability of each label's states (CYCLES among them), from the start
    probability: dict[str, float]
    #: the labels counted as an end (the others: a run that never ends)
    ends: tuple[str, ...]
    #: the expected time to end, given that the run ends (None: it never ends)
    mean: float | None
    #: the standard deviation of that time
    spread: float | None
    #: P(the run has ended by time ``times[k]``), for each k (not conditioned)
    times: np.ndarray = field(repr=False)
    cdf: np.ndarray = field(repr=False)
    #: the probability still unresolved at the last time computed (0 when the
    #: distribution is complete within the horizon)
    beyond: float = 0.0

    @property
    def ended(self) -> float:
        return sum(self.probability.get(e, 0.0) for e in self.ends)

    def quantile(self, q: float) -> float | None:
        """The first time by which a fraction ``q`` of the runs that end have ended."""
        if self.ended <= 0:
            return None
        k = int(np.searchsorted(self.cdf, q * self.ended - 1e-12))
        return float(self.times[k]) if k < len(self.times) else None


def closed_classes(chain: Chain) -> np.ndarray:
    """The transient states (no label) from which no labelled state is reachable."""
    labelled = np.array([bool(x) for x in chain.label])
    # reverse reachability from the labelled states
    reverse = chain.P.T.tocsr()
    seen = labelled.copy()
    frontier = np.flatnonzero(labelled)
    while len(frontier):
        reached = np.unique(reverse[frontier].indices)
        new = reached[~seen[reached]]
        seen[new] = True
        frontier = new
    return np.flatnonzero(~seen)


def solve(chain: Chain, ends: tuple[str, ...], horizon: float = 1e7,
          tolerance: float = 1e-12) -> Absorption:
    """Absorption probabilities, expected end time and end-time distribution from state 0.

    ``ends`` are the labels that count as an end of the run. The distribution is
    computed up to ``horizon`` time (or until less than ``tolerance`` remains).
    """
    n = chain.size
    label = list(chain.label)
    for s in closed_classes(chain):
        label[s] = CYCLES
    absorbing = np.array([bool(x) for x in label])
    transient = np.flatnonzero(~absorbing)
    index = -np.ones(n, dtype=np.int64)
    index[transient] = np.arange(len(transient))
    P = chain.P
    names = sorted({x for x in label if x})
    probability = {}
    if absorbing[0]:
        probability = {x: float(label[0] == x) for x in names}
        h0 = g0 = k0 = None
    else:
        Q, lu, column = _absorbed(P, label, transient, names)
        probability = {x: float(column[x][index[0]]) for x in names}
        h = sum((column[x] for x in ends if x in column), np.zeros(len(transient)))
        d = chain.duration[transient].astype(float)
        g = lu.solve(d * h)
        k = lu.solve(d * d * h + 2 * d * (Q @ g))
        h0, g0, k0 = h[index[0]], g[index[0]], k[index[0]]
    mean = spread = None
    if h0 is not None and h0 > tolerance:
        mean = g0 / h0
        spread = float(np.sqrt(max(k0 / h0 - mean * mean, 0.0)))
    elif absorbing[0] and label[0] in ends:
        mean, spread = 0.0, 0.0
    times, cdf, beyond = _distribution(chain, label, ends, horizon, tolerance)
    return Absorption(probability, tuple(ends), mean, spread, times, cdf, beyond)


def _absorbed(P: sparse.csr_matrix, label: list[str], transient: np.ndarray,
              names: list[str]) -> tuple:
    """Q, the LU factors of I - Q and, for each label, the probability of ending in its
    states from each transient state: (I - Q) x = P[transient] 1_label."""
    into = P[transient]
    Q = into[:, transient]
    lu = splu(sparse.identity(len(transient), format="csc") - Q.tocsc())
    return Q, lu, {x: lu.solve(into @ np.array([lab == x for lab in label], dtype=float))
                   for x in names}


def bottom_components(chain: Chain) -> list[np.ndarray]:
    """The bottom strongly connected components of the chain (no step leaves them; an
    absorbing state, with its self-loop, is one): where every run ends up, and then
    visits every state of its component infinitely often with probability 1."""
    count, component = csgraph.connected_components(chain.P, directed=True,
                                                    connection="strong")
    coo = chain.P.tocoo()
    leaves = component[coo.row] != component[coo.col]
    bottom = np.ones(count, dtype=bool)
    bottom[component[coo.row[leaves]]] = False
    order = np.argsort(component, kind="stable")
    groups = np.split(order, np.cumsum(np.bincount(component, minlength=count))[:-1])
    return [g for c, g in enumerate(groups) if bottom[c]]


def reaching(chain: Chain, label: list[str]) -> dict[str, float]:
    """The probability, from state 0, of reaching each label's states first, when every
    run reaches a labelled state (as when each bottom component is labelled)."""
    names = sorted({x for x in label if x})
    if label[0]:
        return {x: float(label[0] == x) for x in names}
    transient = np.flatnonzero(np.array([not x for x in label]))
    _, _, column = _absorbed(chain.P, label, transient, names)
    start = int(np.searchsorted(transient, 0))
    return {x: float(column[x][start]) for x in names}


def _distribution(chain: Chain, label: list[str], ends: tuple[str, ...], horizon: float,
                  tolerance: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The probability mass moved forward in time: P(ended by t) at each time an end
    can happen (up to ``horizon``), and the mass still moving at the end."""
    end = np.array([x in ends for x in label])
    stop = np.array([bool(x) for x in label])
    P, duration = chain.P, chain.duration
    due: dict[float, dict[int, float]] = {0.0: {0: 1.0}}
    queue = [0.0]
    times, cdf, total, moving = [], [], 0.0, 1.0
    while queue:
        t = heapq.heappop(queue)
        mass = due.pop(t)
        if t > horizon or moving < tolerance:
            return (np.array(times), np.array(cdf),
                    moving if moving >= tolerance else 0.0)
        states = np.fromiter(mass, dtype=np.int64, count=len(mass))
        weights = np.fromiter(mass.values(), dtype=float, count=len(mass))
        finished = end[states]
        if finished.any():
            total += float(weights[finished].sum())
            times.append(t)
            cdf.append(total)
        moving -= float(weights[stop[states]].sum())
        go = ~stop[states]
        for s, w in zip(states[go], weights[go]):
            at = t + float(duration[s])
            row = slice(P.indptr[s], P.indptr[s + 1])
            bucket = due.get(at)
            if bucket is None:
                bucket = due[at] = {}
                heapq.heappush(queue, at)
            for j, p in zip(P.indices[row], P.data[row]):
                bucket[int(j)] = bucket.get(int(j), 0.0) + w * p
    return np.array(times), np.array(cdf), 0.0
