"""The contest's generic examinations (its global properties) on any P/T net.

* ReachabilityDeadlock: some reachable marking is dead;
* OneSafe: no place ever holds more than one token;
* StableMarking: some place holds the same number of tokens in every reachable marking;
* QuasiLiveness: every transition fires in some reachable marking;
* Liveness: from every reachable marking, every transition can fire again.

Where the reachability graph is small (up to :data:`~.answers.FIRST_STATES` markings) it
is built and decides each examination at once, as one pass over its markings (a stable
place: a bit the same in the OR and the AND of the packed markings; liveness: every
transition fires in every bottom strongly connected component).

Past it, structure first: on a strongly connected state machine every distribution of
the tokens is reachable, and each examination follows from their number; a place no
transition changes is a stable one; an empty siphon at M0 with a consumer leaves a
transition that never fires. Then an examination is what its *atoms* say, each a question
of the contest's formula language, as the contest's tools split them (Thierry-Mieg's
ITS-Tools, its global-property solver):

* ReachabilityDeadlock: ``E F deadlock``;
* OneSafe: ``A G (p <= 1)`` for each place p, true where every one is;
* StableMarking: ``A G (p = M0(p))`` for each place p, true where one is;
* QuasiLiveness: ``E F fireable(t)`` for each transition, true where every one is;
* Liveness: ``A G E F fireable(t)`` for each transition, true where every one is; refuted
  first by a marking met by random walks with an empty siphon that a transition needs
  (that siphon stays empty), then by a reachable deadlock or a transition that never
  fires (reachability questions, far cheaper), then decided by the whole graph where it
  can be built.

The atoms go to the state equation, random walks, the equation's solutions fired and the
guided search, then to the formula files' portfolio (:func:`~.answers.answers_as_found`).
The answer comes as soon as the atoms settled so far decide it (a false atom decides
"every one", a true atom "one"), with the words of the atoms settled up to then, and is
unanswered, with the reason, where they do not.
"""
from __future__ import annotations

import time
from itertools import chain
from typing import Iterator, Sequence

import numpy as np

from mcl2pnml.core import queries as q
from mcl2pnml.core.bounds import MAX_STATES
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import Net
from mcl2pnml.core.structure import structure

from mcl2pnml.analysis.contest import answers
from mcl2pnml.analysis.contest.answers import FIRST_STATES, Answer, Graph, answers_as_found
from mcl2pnml.analysis.contest.reachability_queries import (WALK_SECONDS,
                                                            settled_by_equation_witness,
                                                            settled_by_guided_search,
                                                            settled_by_state_equation,
                                                            settled_by_walks)
from mcl2pnml.analysis.statespace.packedmarkings import PackedStateSpace
from mcl2pnml.analysis.statespace.walks import random_walks
from mcl2pnml.analysis.structure.siphons import max_siphon_within
from mcl2pnml.analysis.structure.state_machine import free_tokens

#: The contest's generic examinations, by name.
GENERIC = ("ReachabilityDeadlock", "OneSafe", "StableMarking", "QuasiLiveness", "Liveness")


def generic(net: Net, examinations: Sequence[str] = GENERIC, *, max_states: int = MAX_STATES,
            max_memory: int | None = None) -> list[Answer]:
    """Each examination's answer, in the order asked (:func:`generic_as_found`)."""
    return list(generic_as_found(net, examinations, max_states=max_states,
                                 max_memory=max_memory))


def generic_as_found(net: Net, examinations: Sequence[str] = GENERIC, *,
                     max_states: int = MAX_STATES, max_memory: int | None = None
                     ) -> Iterator[Answer]:
    """Each examination's answer, one at a time in the order asked (the module's
    documentation)."""
    for name in examinations:
        if name not in GENERIC:
            raise Mcl2PnmlError(f"unknown examination '{name}'; known: {', '.join(GENERIC)}")
    # the portfolio's exploration and graph loops, one of each (a test swaps them there)
    space, _, _ = answers._space(net, min(max_states, FIRST_STATES), max_memory)
    if space is not None:
        yield from (_on_graph(space, name) for name in examinations)
        return
    del space
    for name in examinations:
        yield _by_atoms(net, name, max_states, max_memory)


def _on_graph(space, name: str) -> Answer:
    """``name`` decided on the whole reachability graph."""
    s = space.structure
    if name == "ReachabilityDeadlock":
        value = bool(space.terminal)
    elif name == "OneSafe":
        value = bool(space.safe)
    elif name == "StableMarking":
        value = _stable_place(space)
    elif name == "QuasiLiveness":
        value = len(np.unique(np.asarray(space.trans))) == len(s.transitions)
    else:
        value = _live(Graph(space), len(s.transitions))   # the one that needs the graph
    return Answer(name, value, "EXPLICIT STATE_SPACE")


def _atoms(net: Net, name: str) -> tuple[list[q.Query], bool, int]:
    """The atoms of ``name``; whether it holds where every one of them does (else: where
    one does); and how many atoms, first in the list, only refute it (a value against
    "every" decides it; the rest decide it whole)."""
    s = structure(net)
    places = [q.TokensCount((p,)) for p in s.places]
    fireable = [q.Fireable((t,)) for t in s.transitions]

    def queries(formulas, tag: str = "") -> list[q.Query]:
        return [q.Query(f"{name}{tag}-{k}", f) for k, f in enumerate(formulas)]
    if name == "ReachabilityDeadlock":
        return queries([q.ExistsPath(q.Finally(q.Deadlock()))]), False, 0
    if name == "OneSafe":
        return queries(q.AllPaths(q.Globally(q.IntLe(p, q.IntConst(1))))
                       for p in places), True, 0
    if name == "StableMarking":
        return queries(q.AllPaths(q.Globally(q.Conj((q.IntLe(p, q.IntConst(int(m))),
                                                     q.IntLe(q.IntConst(int(m)), p)))))
                       for p, m in zip(places, s.initial_vector())), False, 0
    reached = queries((q.ExistsPath(q.Finally(f)) for f in fireable), "-fires")
    if name == "QuasiLiveness":
        return reached, True, 0
    # Liveness: a reachable dead marking, or a transition that never fires, refutes it
    refuting = queries([q.AllPaths(q.Globally(q.Neg(q.Deadlock())))], "-deadlock") + reached
    return refuting + queries(q.AllPaths(q.Globally(q.ExistsPath(q.Finally(f))))
                              for f in fireable), True, len(refuting)


def _by_atoms(net: Net, name: str, max_states: int, max_memory: int | None) -> Answer:
    """``name`` decided past the first exploration (the module's documentation), or
    unanswered with the reason of the first deciding atom left open."""
    s = structure(net)
    if not s.transitions and name in ("QuasiLiveness", "Liveness"):
        return Answer(name, True, "STRUCTURAL")       # every transition: none to ask
    tokens = free_tokens(s)
    if tokens is not None:
        return Answer(name, _on_state_machine(name, tokens, len(s.places)),
                      "STRUCTURAL STATE_MACHINE")
    if name == "StableMarking" and any(not row for row in s.incidence_rows):
        return Answer(name, True, "STRUCTURAL")      # no transition changes that place
    if name == "QuasiLiveness" and _never_again(s, 0.0):
        return Answer(name, False, "STRUCTURAL SIPHON_TEST")   # M0 alone: dead already
    if name != "Liveness":
        return _settled_by(net, name, _atoms(net, name), max_states, max_memory)
    if _never_again(s, WALK_SECONDS):
        return Answer(name, False, "RANDOM_WALK STRUCTURAL SIPHON_TEST")
    atoms, every, refuting = _atoms(net, name)
    # the refutations first, by the cheap techniques and the first exploration alone;
    # then the whole graph, where it can be built, decides at once
    first = _settled_by(net, name, (atoms[:refuting], every, refuting), FIRST_STATES,
                        max_memory)
    if first.value is False:
        return first
    space, why, _ = answers._space(net, max_states, max_memory)
    if space is not None:
        return _on_graph(space, name)
    del space
    # past it, each transition's A G E F by the techniques that need no graph
    last = _settled_by(net, name, (atoms[refuting:], every, 0), FIRST_STATES, max_memory)
    return last if last.value is not None else Answer(name, None, "", why)


def _on_state_machine(name: str, tokens: int, places: int) -> bool:
    """``name`` on a strongly connected state machine holding ``tokens`` in all: every
    distribution of them is reachable (:func:`free_tokens`), so a token can always move
    on, reach any transition's input place, and gather with the others in one place."""
    if name == "ReachabilityDeadlock":
        return tokens == 0
    if name == "OneSafe":
        return tokens <= 1
    if name == "StableMarking":
        return tokens == 0 or places == 1
    return tokens > 0                                 # QuasiLiveness, Liveness


def _never_again(s, seconds: float) -> bool:
    """Whether M0, or a marking that random walks meet within ``seconds``, has an empty
    siphon with a transition that needs it: that siphon stays empty, so the transition
    never fires again, and the net is not live (Murata 1989: a siphon emptied stays
    empty); at M0, the transition never fires at all. Each pattern of empty places is
    asked once (:func:`max_siphon_within`)."""
    places = len(s.places)
    m0 = np.asarray(s.initial_vector(), dtype=np.int64)[None, :]
    asked: set[bytes] = set()
    end = time.monotonic() + seconds
    walks = random_walks(s, seconds) if seconds > 0 else iter(())
    for batch in chain([m0], walks):
        for row in np.unique(np.packbits(batch == 0, axis=1), axis=0):
            if asked and time.monotonic() > end:      # M0's, at least
                return False
            if row.tobytes() in asked:
                continue
            asked.add(row.tobytes())
            empty = np.flatnonzero(np.unpackbits(row)[:places])
            if any(s.place_post[p] for p in max_siphon_within(s, empty.tolist())):
                return True
    return False


def _settled_by(net: Net, name: str, atoms: tuple[list[q.Query], bool, int], max_states: int,
                max_memory: int | None) -> Answer:
    """``name`` decided by ``atoms`` (:func:`_atoms`'s triple): as soon as an atom settles
    against "every" (or for "one"), or every deciding one has; else unanswered with the
    reason of the first deciding one open. The state equation's proofs, random walks'
    witnesses, the equation's solutions fired and the guided search come first: an
    examination's atoms are many (hundreds, a place or a transition each) and mostly
    settled so, where the formula files' portfolio would give each its own search first;
    what they leave goes through the portfolio (:func:`~.answers.answers_as_found`)."""
    queries, every, refuting = atoms
    deciding = {x.id for x in queries[refuting:]}
    techniques: list[str] = []
    settled, open_ = 0, None

    def found(given: Iterator[Answer]) -> bool | None:
        """The examination's value where ``given`` decide it."""
        nonlocal settled, open_
        for a in given:
            if a.value is None:
                if a.id in deciding and open_ is None:
                    open_ = a
                continue
            techniques.extend(w for w in a.technique.split() if w not in techniques)
            if a.value is not every:           # a false atom of "every", a true one of "one"
                return a.value
            settled += a.id in deciding
        return None
    done: set[str] = set()
    value = None
    # the witnesses first where the atoms are mostly settled by one (a place that moves, a
    # transition that fires), the proofs first where they are mostly proven
    witnesses = (settled_by_walks, settled_by_equation_witness)
    proofs = (settled_by_state_equation,)
    first = witnesses + proofs if name in ("StableMarking", "QuasiLiveness") \
        else proofs + witnesses
    for technique in (*first, settled_by_guided_search):
        if value is None:
            got = technique(net, [x for x in queries if x.id not in done])
            done.update(got)
            value = found(Answer(k, v, t) for k, (v, t) in got.items())
    if value is None:
        stream = answers_as_found(net, [x for x in queries if x.id not in done],
                                  max_states=max_states, max_memory=max_memory)
        try:
            value = found(stream)
        finally:
            stream.close()                      # its explorations' memory, at once
    if value is not None:
        return Answer(name, value, " ".join(techniques))
    if open_ is not None:
        return Answer(name, None, "", f"{open_.reason} ({settled} of {len(deciding)} of "
                                      f"its atoms settled)")
    return Answer(name, every, " ".join(techniques))


def _stable_place(space) -> bool:
    """Whether some place holds the same number of tokens in every reachable marking: on
    markings packed one bit per place, a bit the same in the OR and the AND of them all;
    else a place at a time (its column not kept: a large net has many)."""
    places = len(space.structure.places)
    if isinstance(space, PackedStateSpace) and space.states:
        ones = np.bitwise_or.reduce(space.packed, axis=0)
        both = np.bitwise_and.reduce(space.packed, axis=0)
        same = ~(ones ^ both)
        return any(int(same[i // 64]) >> (i % 64) & 1 for i in range(places))
    for i in range(places):
        column = space.tokens(i)
        if column.min() == column.max():
            return True
    return False


def _live(g: Graph, transitions: int) -> bool:
    """Every transition fires in every bottom strongly connected component: from every
    reachable marking, every transition can fire again."""
    label = np.empty(g.n, dtype=np.int64)
    count = answers._loops.scc(*g.real, np.ones(g.n, dtype=np.uint8), label)
    leaving = label[g.src] != label[g.dst]
    bottom = np.ones(count, dtype=bool)
    bottom[label[g.src[leaving]]] = False
    inside = ~leaving
    for c in np.flatnonzero(bottom):
        fired = np.unique(g.trans[inside & (label[g.src] == c)])
        if len(fired) < transitions:
            return False
    return True
