"""What the paper asks of every net: it ends, it ends well, and it can run again.

The paper (sections 2.2 and 2.3) calls a net *reusable* when its final marking
"coincides with the initial marking", and checks that no reachable marking is
a deadlock. For nets that are started from outside, such as a task (B, A) or
a primitive (E, D), and that report to the outside (OK, FAIL, ABORTED), this
module makes those notions precise for any P/T net:

* **input places**: places no transition writes to (B, A; E, D): the outside
  marks them;
* **result places**: places no transition takes from or reads (OK, FAIL,
  ABORTED): the outside reads them;
* the **rest marking**: M0 on every other place;
* a terminal (dead) marking is **proper** when it equals the rest marking on
  every other place and holds exactly one token in result places (none if
  the net has none). Tokens left in input places are allowed: that is the
  paper's "abort problem" (equations 17, 18), which the structure above
  drains.

Then: ``deadlock_free`` = every terminal marking is proper; ``reusable`` =
deadlock-free, and from every reachable marking a proper terminal marking
can still be reached (or, for a net with no terminal marking at all, M0 can
always be reached again: a home marking).

:func:`final_markings_agree` is the reduced-model check of section 2.3: two
nets (the full task and its reduced model) reach the same final markings
seen on a set of interface places.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import Net
from mcl2pnml.core.structure import Structure

from mcl2pnml.analysis.statespace.explore import StateSpace, explore


def input_places(s: Structure) -> frozenset[int]:
    return frozenset(i for i in range(len(s.places)) if not s.place_pre[i])


def result_places(s: Structure) -> frozenset[int]:
    return frozenset(i for i in range(len(s.places)) if not s.place_post[i] and s.place_pre[i])


@dataclass(frozen=True)
class Behaviour:
    """Termination and reusability of one explored state space."""

    terminal: tuple[tuple[str, ...], ...]
    improper: tuple[tuple[str, ...], ...]      # terminal markings that are deadlocks
    deadlock_free: bool
    final_always_reachable: bool
    home_marking: bool
    reusable: bool


def behaviour(space: StateSpace) -> Behaviour:
    s = space.structure
    inputs, results = input_places(s), result_places(s)
    m0 = space.markings[0]
    inner = [i for i in range(len(s.places)) if i not in inputs and i not in results]
    wanted = 1 if results else 0

    def proper(node: int) -> bool:
        m = space.markings[node]
        return (all(m[i] == m0[i] for i in inner)
                and sum(m[i] for i in results) == wanted)

    terminal = space.terminal
    good = [n for n in terminal if proper(n)]
    bad = [n for n in terminal if not proper(n)]
    reach_good = space.always_can_reach(good) if good else False
    # One backward pass, not two: a dead marking reaches nothing but itself, so
    # with one M0 is a home marking only when it is the only reachable marking
    # (then it is that dead marking); the search from M0 is needed only when no
    # marking is dead.
    if not space.bounded:
        home = False
    elif terminal:
        home = space.states == 1
    else:
        home = space.home_initial
    reusable = space.bounded and not bad and (reach_good if terminal else home)
    return Behaviour(
        terminal=tuple(tuple(space.format(n)) for n in terminal),
        improper=tuple(tuple(space.format(n)) for n in bad),
        deadlock_free=not bad,
        final_always_reachable=reach_good if terminal else home,
        home_marking=home,
        reusable=reusable,
    )


@dataclass(frozen=True)
class Agreement:
    """The final markings of two nets, projected on the interface."""

    interface: tuple[str, ...]
    finals_a: frozenset[tuple[str, ...]]
    finals_b: frozenset[tuple[str, ...]]

    @property
    def equal(self) -> bool:
        return self.finals_a == self.finals_b

    @property
    def only_a(self) -> frozenset[tuple[str, ...]]:
        return self.finals_a - self.finals_b

    @property
    def only_b(self) -> frozenset[tuple[str, ...]]:
        return self.finals_b - self.finals_a


def projected_finals(space: StateSpace, interface: Iterable[str]) -> frozenset[tuple[str, ...]]:
    keep = set(interface)
    out = set()
    for n in space.terminal:
        out.add(tuple(p for p in space.format(n) if p.split("*", 1)[0] in keep))
    return frozenset(out)


def final_markings_agree(a: Net, b: Net, interface: Iterable[str],
                         initial_a: dict[str, int] | None = None,
                         initial_b: dict[str, int] | None = None) -> Agreement:
    """Section 2.3's reduced-model check, for any two nets and interface places.

    Both nets are explored from their initial markings (or the given ones);
    the final (dead) markings of each, restricted to ``interface``, must be
    the same sets.
    """
    interface = tuple(interface)
    for net in (a, b):
        missing = [p for p in interface if p not in net.place_index]
        if missing:
            raise Mcl2PnmlError(f"net '{net.name}' has no interface place "
                                f"{', '.join(missing)}")
    fa = projected_finals(explore(a, initial_a), interface)
    fb = projected_finals(explore(b, initial_b), interface)
    return Agreement(interface, fa, fb)
