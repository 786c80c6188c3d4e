"""Strongly connected state machines: nets whose reachable markings are every distribution
of their tokens.

A *state machine* is a net whose every transition takes one token from one place and puts
one token in one place (Murata 1989, section II-B: no synchronisation). Its tokens move
independently, each along the arcs of the place graph (a place to the next, through a
transition). Where that graph is strongly connected, any token can reach any place, so
from M0 every marking with M0's total is reachable, one token moved at a time, and no
other marking is (the total is a P-invariant). Then the bound of a place sum is that total
times the largest number of times the sum names one place, reached.
"""
from __future__ import annotations

from mcl2pnml.core.structure import Structure


def free_tokens(s: Structure) -> int | None:
    """M0's total where every distribution of it is reachable (``s`` is a strongly
    connected state machine without read arcs), else None."""
    places = len(s.places)
    if not places or not s.transitions:
        return None
    after: list[list[int]] = [[] for _ in range(places)]
    before: list[list[int]] = [[] for _ in range(places)]
    for pre, post, read in zip(s.pre, s.post, s.read):
        if read or len(pre) != 1 or len(post) != 1:
            return None
        (p, w), (r, v) = next(iter(pre.items())), next(iter(post.items()))
        if w != 1 or v != 1:
            return None
        after[p].append(r)
        before[r].append(p)
    for edges in (after, before):           # every place reached from place 0, both ways
        seen, todo = {0}, [0]
        while todo:
            for r in edges[todo.pop()]:
                if r not in seen:
                    seen.add(r)
                    todo.append(r)
        if len(seen) < places:
            return None
    return sum(s.initial_vector())
