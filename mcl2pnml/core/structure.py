"""The indexed pre/post view of a net: what analysis and execution start from.

Places and transitions are numbered in the net's order. For transition ``j``:

* ``pre[j]``  = {place index: weight} consumed (normal input arcs),
* ``read[j]`` = {place index: weight} needed but not consumed (read arcs),
* ``post[j]`` = {place index: weight} produced.

The incidence matrix ``C`` (places x transitions, Murata 1989, section VII)
has ``C[p][t] = post - pre``; a read arc adds nothing to it, exactly as the
self-loop it stands for. It is kept sparse (a dict per place) because the
nets of compiled missions have thousands of places and a handful of arcs per
transition.

For siphons and traps a read arc counts as an arc both ways (the transition
is in the pre-set and the post-set of the place), which is the firing rule
of the equivalent self-loop.

It serves the invariants (``C``, Murata section VII), the siphons and traps
(•p, p•, •t, t•), the three state-space explorers (the firing rule, and the
bit masks of the safe-net ones), and the executor of
:mod:`mcl2pnml.runtime.executor` (the paper's section 2.1: what a firing
takes, reads and changes, and each place's consumers).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

from mcl2pnml.core.net import ArcKind, Net


@dataclass(frozen=True, eq=False)
class Structure:
    """Index-based view of a net; built once per net with :func:`structure`."""

    net: Net
    places: tuple[str, ...]
    transitions: tuple[str, ...]
    pre: tuple[dict[int, int], ...]
    read: tuple[dict[int, int], ...]
    post: tuple[dict[int, int], ...]

    @cached_property
    def place_index(self) -> dict[str, int]:
        return {p: i for i, p in enumerate(self.places)}

    @cached_property
    def transition_index(self) -> dict[str, int]:
        return {t: j for j, t in enumerate(self.transitions)}

    @cached_property
    def incidence(self) -> tuple[dict[int, int], ...]:
        """Column ``j`` of C as {place index: post - pre}, zeros left out."""
        cols = []
        for pre, post in zip(self.pre, self.post):
            col = dict(post)
            for p, w in pre.items():
                col[p] = col.get(p, 0) - w
            cols.append({p: v for p, v in col.items() if v})
        return tuple(cols)

    @cached_property
    def incidence_rows(self) -> tuple[dict[int, int], ...]:
        """Row ``i`` of C as {transition index: value}: C transposed, sparse."""
        rows: list[dict[int, int]] = [{} for _ in self.places]
        for j, col in enumerate(self.incidence):
            for p, v in col.items():
                rows[p][j] = v
        return tuple(rows)

    @cached_property
    def place_pre(self) -> tuple[frozenset[int], ...]:
        """•p: the transitions that put tokens in p (read arcs included)."""
        out: list[set[int]] = [set() for _ in self.places]
        for j, post in enumerate(self.post):
            for p in post:
                out[p].add(j)
        for j, read in enumerate(self.read):
            for p in read:
                out[p].add(j)
        return tuple(frozenset(s) for s in out)

    @cached_property
    def place_post(self) -> tuple[frozenset[int], ...]:
        """p•: the transitions that take tokens from p (read arcs included)."""
        out: list[set[int]] = [set() for _ in self.places]
        for j, (pre, read) in enumerate(zip(self.pre, self.read)):
            for p in pre:
                out[p].add(j)
            for p in read:
                out[p].add(j)
        return tuple(frozenset(s) for s in out)

    @cached_property
    def transition_inputs(self) -> tuple[frozenset[int], ...]:
        """•t: places a transition takes from or reads (for siphons)."""
        return tuple(frozenset(pre) | frozenset(read) for pre, read in zip(self.pre, self.read))

    @cached_property
    def transition_outputs(self) -> tuple[frozenset[int], ...]:
        """t•: places a transition puts into or reads (for traps)."""
        return tuple(frozenset(post) | frozenset(read) for post, read in zip(self.post, self.read))

    def initial_vector(self) -> tuple[int, ...]:
        return tuple(self.net.initial[p] for p in self.places)

    def enabled(self, m, j: int) -> bool:
        """Whether transition ``j`` may fire in marking ``m`` (token counts by place index):
        every place it consumes from or reads holds the arc's weight."""
        return all(m[p] >= w for arcs in (self.pre[j], self.read[j]) for p, w in arcs.items())

    def fire(self, m: list[int], j: int) -> None:
        """Fire transition ``j`` in marking ``m``, in place (``m`` a list of counts)."""
        for p, w in self.pre[j].items():
            m[p] -= w
        for p, w in self.post[j].items():
            m[p] += w

    def names(self, indices) -> list[str]:
        return [self.places[i] for i in sorted(indices)]

    def dense_incidence(self) -> list[list[int]]:
        """C as a list of rows (places); for small nets and cross-checks only."""
        rows = [[0] * len(self.transitions) for _ in self.places]
        for j, col in enumerate(self.incidence):
            for p, v in col.items():
                rows[p][j] = v
        return rows


def structure(net: Net) -> Structure:
    """The index-based structure of ``net`` (linear in its size)."""
    places = tuple(p.id for p in net.places)
    transitions = tuple(t.id for t in net.transitions)
    pi = {p: i for i, p in enumerate(places)}
    tj = {t: j for j, t in enumerate(transitions)}
    pre: list[dict[int, int]] = [{} for _ in transitions]
    read: list[dict[int, int]] = [{} for _ in transitions]
    post: list[dict[int, int]] = [{} for _ in transitions]
    for a in net.arcs:
        if a.source in pi:  # place -> transition
            target = read if a.kind is ArcKind.READ else pre
            target[tj[a.target]][pi[a.source]] = a.weight
        else:
            post[tj[a.source]][pi[a.target]] = a.weight
    return Structure(net, places, transitions, tuple(pre), tuple(read), tuple(post))
