"""Checking a property of a net's runs on its state space, with a shortest counterexample.

A property (:mod:`mcl2pnml.core.patterns`) is one of Dwyer, Avrunin and
Corbett's specification patterns in one of their scopes ("Patterns in
property specifications for finite-state verification", ICSE 1999), read
over the runs of the net: maximal firing sequences from M0 seen as marking
sequences, a finite run ending in a dead marking and taken as it is.

Method: the product of the reachability graph with a small deterministic
observer of the marking sequence. After each marking the observer is in one
of three conditions:

* ``BAD``: the prefix read already violates the property whatever follows
  (a safety violation, or a scope interval closed with its obligation unmet);
  absorbing;
* *pending*: an obligation is open (existence not yet fulfilled, a response
  owed) in a part of the scope that counts even if never closed; a finite
  run that ends here violates the property, and so does an infinite run
  that stays pending forever;
* otherwise nothing is owed.

So the property fails iff the product reaches a ``BAD`` state, or a pending
state on a dead marking, or a cycle of pending states (a nontrivial strongly
connected component of the pending part). Breadth first search gives the
shortest prefix; a lasso's cycle is the shortest one back within the
pending part, and the counterexample returned is the shortest of all in the
product. A finite one is so among the net's runs too; a lasso may not be: the
observer can need several turns of a loop of the net to see the violation (a
scope opened on the loop), and the product's lasso holds those turns, its loop
moved back as far as the markings allow.

The observer's state is ``(scope, pattern)``:

* scope: ``OUT`` (not in the scope yet, or between intervals), ``IN``
  (inside), ``DONE`` (the scope is over for good: before's R met). Globally
  starts ``IN``; before starts ``IN`` and goes ``DONE`` at the first R (the
  R marking is outside); after goes ``IN`` at the first Q, for good; between
  and after-until go ``IN`` at a marking with Q and not R and back ``OUT``
  at the next R (outside too). Dwyer et al.'s mappings quantify over every
  Q position (``[](Q & !R -> ...)``): a Q inside an open interval opens one
  nested in it, ending at the same R. For absence, universality, bounded
  existence and response the outer interval's obligation implies the inner
  one's; for existence and precedence it does not, so a new Q re-arms them
  (P needed again, S needed again).
* pattern: ``seen`` (absence: P met; universality: not-P met; existence: P
  met; precedence: S met), ``owed`` (response: a P not yet answered by S),
  ``count`` and ``last`` (bounded existence: times P became true, capped at
  bound + 1, and whether P held in the scope's previous marking), ``broken``
  (between: the current interval already violates, which counts once R
  closes it).

The LTL mappings followed (Dwyer et al.'s catalogue), e.g. absence
``[]!P``, ``<>Q -> ...``; existence between ``[](Q & !R -> (!R W (P & !R)))``
read so that only R-closed intervals count; after-until
``[](Q & !R -> (!R U ...))`` with unclosed intervals counting to the run's
end; *before R* ``<>R -> ...``: like an interval of between opened at M0, it
counts only once R closes it, so a run where R never holds satisfies it.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Iterable, Iterator

import networkx as nx
import numpy as np

from mcl2pnml.core.bounds import MAX_CHECK_STATES
from mcl2pnml.core.net import Net
from mcl2pnml.core.patterns import And, Not, Or, Predicate, Property, Tokens, holds, places_of
from mcl2pnml.core.structure import structure

# (the observers and verdicts, imported from here by the callers too)
from mcl2pnml.analysis.checking.observers import BAD, Marked, Shape, Status, Verdict, pending, step  # noqa: F401
from mcl2pnml.analysis.checking.observers import ObserverTable, initial, path_to, truths as _truths
from mcl2pnml.analysis.checking import on_the_fly as onthefly
from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore
from mcl2pnml.analysis.statespace.rows import by_source


def check_property(net: Net, prop: Property, max_states: int = MAX_CHECK_STATES) -> Verdict:
    """Whether ``prop`` holds on every run of ``net``, with a shortest counterexample if not."""
    return check_properties(net, [prop], max_states)[0]


#: How :func:`check_properties` decides: on the fly where it applies, else the reference; the
#: reference alone (every marking first, then each property's product); on the fly alone.
METHODS = ("auto", "full", "on-the-fly")


def check_properties(net: Net, properties: Iterable[Property],
                     max_states: int = MAX_CHECK_STATES, method: str = "auto", stubborn: bool = False,
                     safe: bool = False) -> list[Verdict]:
    """Each property's verdict, in order.

    ``auto``: on the fly (:mod:`mcl2pnml.analysis.checking.on_the_fly`: the product in C, stopping at
    the first violation) where the net is safe and the loops in C are built;
    otherwise, or with ``full``, the reference method: one exploration of the
    state space, then each property's product with its observer.
    ``stubborn``: on the fly with partial-order reduction, on a net proven 1-safe
    (``safe``: by a certificate; else a P-invariant must prove it), which keeps the
    verdict but not always the shortest counterexample.
    """
    properties = list(properties)
    if method not in METHODS:
        raise ValueError(f"method {method!r}: one of {', '.join(METHODS)}")
    if stubborn and method == "full":
        raise ValueError("the reduction is the on-the-fly checker's: not with method 'full'")
    if method != "full":
        verdicts = onthefly.check_properties_on_the_fly(net, properties, max_states,
                                                        stubborn=stubborn, safe=safe)
        if verdicts is not None:
            return verdicts
        if method == "on-the-fly":
            raise ValueError("this net is not for the on-the-fly checker (not 1-safe, "
                             "or its loops in C are not built)")
    return _check_all_full(net, properties, max_states)


def _check_all_full(net: Net, properties: list[Property], max_states: int) -> list[Verdict]:
    """The reference method: every reachable marking, then each property's product."""
    try:
        space = explore(net, max_states=max_states)
    except ExplorationLimit as e:
        return [Verdict(p, Status.UNKNOWN, states=e.explored or max_states,
                        reason=f"more than {max_states:,} reachable markings") for p in properties]
    if space.coverability:
        return [Verdict(p, Status.UNKNOWN, states=space.states,
                        reason="the net is unbounded (its coverability graph is no run graph)")
                for p in properties]
    ids = [pl.id for pl in net.places]
    tids = [t.id for t in net.transitions]
    after = _successors(space.states, space.src, space.dst, space.trans)
    # a property reads a few places of every marking: their columns, not the markings
    index = {pid: k for k, pid in enumerate(ids)}
    read = sorted({p for prop in properties for x in _truths(prop) for p in places_of(x)})
    columns = {p: space.tokens(index[p]) if p in index else np.zeros(space.states)
               for p in read}   # a place the net has not holds no token, as in holds()

    def marked(node: int) -> Marked:
        """A marking of the counterexample, as its marked places (decoded on demand)."""
        return tuple((ids[k], int(n)) for k, n in enumerate(space.markings[node]) if n)

    verdicts = []
    for prop in properties:
        p, s, q, r = (_holds_everywhere(x, columns, space.states) for x in _truths(prop))
        codes = (8 * p + 4 * s + 2 * q + r).astype(np.int64).tolist()
        verdicts.append(_product(prop, marked, tids, after, codes, max_states))
    return verdicts


def _holds_everywhere(predicate: Predicate, columns, n: int) -> np.ndarray:
    """Whether ``predicate`` holds in each of the ``n`` markings whose places' tokens are
    ``columns`` (place id -> counts in node order): :func:`holds`, a column at a time."""
    if isinstance(predicate, Tokens):
        total = sum((columns[p] for p in predicate.places), np.zeros(n))
        return total >= predicate.at_least
    if isinstance(predicate, Not):
        return ~_holds_everywhere(predicate.arg, columns, n)
    if isinstance(predicate, (And, Or)):
        parts = [_holds_everywhere(a, columns, n) for a in predicate.args]
        combine = np.logical_and if isinstance(predicate, And) else np.logical_or
        return combine.reduce(parts) if parts else np.full(n, isinstance(predicate, And))
    return np.full(n, bool(predicate.value))


def _successors(states: int, src, dst, trans) -> list[list[tuple[int, int]]]:
    """Each marking's (successor, transition) pairs, in the order the explorer gave them:
    the edges sorted by source (stably, so that a marking's own order is kept), then one
    slice of the pairs per marking (slices in C, where an append per edge took a second on a
    million edges)."""
    bounds, order = by_source(src, states)
    pairs = list(zip(np.asarray(dst)[order].tolist(), np.asarray(trans)[order].tolist()))
    bounds = bounds.tolist()
    return [pairs[bounds[m]:bounds[m + 1]] for m in range(states)]


def _moves(obs: ObserverTable) -> list[int]:
    """The observer's every state and move, worked out before the product: ``moves[k * 16 +
    code]`` is the state after state ``k`` reads a marking whose truths are ``code``. The
    observer is finite (its counter stops at the bound plus one), so this ends; the product
    then reads a move from a list, with no call."""
    todo, seen = [obs.start, obs.bad], set()
    while todo:
        k = todo.pop()
        if k not in seen:
            seen.add(k)
            todo.extend(obs.after(k, code) for code in range(16))
    return [obs.after(k, code) for k in range(len(obs.states)) for code in range(16)]


def _product(prop, marked, tids, after, codes, max_states) -> Verdict:
    """The breadth-first product of the state space with the observer of ``prop``: its
    shortest violation (a bad prefix, a dead end with an obligation open, or a lasso whose
    cycle keeps one open). A product state is the integer ``marking * K + observer state``
    (K observer states), so that the maps this loop fills are keyed by integers, not pairs:
    it runs once per product edge, millions of times on an example."""
    obs = ObserverTable(prop)
    moves = _moves(obs)
    k_obs = len(obs.states)
    bad, pend = obs.bad, obs.pending
    open_ = [o != bad and pend[o] for o in range(k_obs)]
    start = moves[obs.start * 16 + codes[0]]        # marking 0
    # (node, transition) that first reached each state, in the order they were reached
    parent: dict = {start: None}
    dist = {start: 0}
    queue = deque([start])
    # a lasso needs the product's edges among states with an obligation open: kept only when
    # the observer has such a state (an absence or universality never has)
    succ: dict | None = {} if any(open_) else None
    best = None   # (length, shape, state) of the shortest violation so far
    while queue:
        node = queue.popleft()
        m, o = divmod(node, k_obs)
        if o == bad:
            if best is None or dist[node] < best[0]:
                best = (dist[node], Shape.PREFIX, node)
            if succ is not None:
                succ[node] = []
            continue
        edges = after[m]
        if not edges and pend[o]:
            if best is None or dist[node] < best[0]:
                best = (dist[node], Shape.FINITE, node)
        d = dist[node] + 1
        row = o * 16
        children = [(b * k_obs + moves[row + codes[b]], t) for b, t in edges]
        for child, t in children:
            if child not in parent:
                if len(parent) >= max_states:
                    return Verdict(prop, Status.UNKNOWN, states=len(parent),
                                   reason=f"more than {max_states:,} product states")
                parent[child] = (node, t)
                dist[child] = d
                queue.append(child)
        if succ is not None:
            succ[node] = children
    lasso = None if succ is None else _shortest_lasso(
        lambda n: open_[n % k_obs], parent, succ, dist, best[0] if best else None)
    if lasso is not None and (best is None or lasso[0] < best[0]):
        length, node, cycle = lasso
        path = path_to(parent, node)
        trans = path[1] + cycle[1]
        ms = [n // k_obs for n in path[0] + cycle[0]]
        loop = len(path[0]) - 1
        # the same infinite run, its loop entered earlier where the markings allow: the
        # observer may need a turn of the cycle to settle that the marking run does not
        while loop > 0 and ms[loop - 1] == ms[-2] and trans[loop - 1] == trans[-1]:
            loop -= 1
            ms.pop()
            trans.pop()
        return Verdict(prop, Status.FAILS, tuple(tids[t] for t in trans),
                       tuple(marked(m) for m in ms), Shape.LASSO, loop=loop, states=len(parent))
    if best is None:
        return Verdict(prop, Status.HOLDS, states=len(parent))
    nodes, trans = path_to(parent, best[2])
    return Verdict(prop, Status.FAILS, tuple(tids[t] for t in trans),
                   tuple(marked(n // k_obs) for n in nodes), best[1], states=len(parent))


def _shortest_lasso(open_, order, succ, dist, bound):
    """(prefix + cycle length, entry state, (cycle states after entry, transitions)) of
    the shortest lasso whose cycle stays in states with an obligation open (``open_`` of
    the product state), or None; ``order``: the states in the order they were reached."""
    g = nx.DiGraph()
    for node in order:
        if open_(node):
            g.add_node(node)
            for child, _ in succ[node]:
                if open_(child):
                    g.add_edge(node, child)
    on_cycle = set()
    for comp in nx.strongly_connected_components(g):
        if len(comp) > 1 or any(g.has_edge(n, n) for n in comp):
            on_cycle |= comp
    best = None
    # the entries nearest M0 first, ties in the order they were reached: breadth first,
    # that is already by distance (so the lasso chosen is one function of the product)
    for node in (n for n in order if n in on_cycle):
        if best is not None and dist[node] + 1 >= best[0]:
            break   # every later entry is at least as far, and a cycle is one step at least
        if bound is not None and dist[node] + 1 >= bound:
            break
        cycle = _shortest_cycle(node, succ, on_cycle)
        if cycle is not None and (best is None or dist[node] + len(cycle[1]) < best[0]):
            best = (dist[node] + len(cycle[1]), node, cycle)
    return best


def _shortest_cycle(start, succ, allowed):
    back = {start: None}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        for child, t in succ[node]:
            if child not in allowed:
                continue
            if child == start:
                trans = [t]
                while back[node] is not None:
                    node, u = back[node]
                    trans.append(u)
                return _cycle_states(start, trans[::-1], succ)
            if child not in back:
                back[child] = (node, t)
                queue.append(child)
    return None


def _cycle_states(start, trans, succ):
    """The product states after each transition of the cycle from ``start``."""
    states, node = [], start
    for t in trans:
        node = next(c for c, u in succ[node] if u == t)
        states.append(node)
    return states, trans


# -- a given run ---------------------------------------------------------------------------------



@dataclass(frozen=True)
class Shown:
    """How one firing sequence shows a property violated (:func:`judge`).

    ``step``: the number of firings after which it shows: the first marking
    the observer reads as ``BAD`` (a prefix), the run's dead end (a finite
    run), or the second visit of the cycle's first state (a lasso, whose
    cycle starts after ``loop`` firings).
    """

    shape: Shape
    step: int
    loop: int | None = None


def judge(net: Net, prop: Property, transitions: Iterable[str],
          silent: Iterable[str] = (), loop: int | None = None) -> Shown | None:
    """Whether the run that fires ``transitions`` from M0 shows ``prop`` violated, and how.

    The same observer as :func:`check_property` reads the run's markings. It shows a
    violation when the observer reaches ``BAD``; when the run ends in a dead
    marking (no transition of the net enabled) with an obligation open; or
    when it comes back to a state of the product (marking, observer) with an
    obligation open at every marking in between: that cycle, repeated for
    ever, is an infinite run that violates the property. A transition that
    is not enabled where the run fires it is an error (ValueError): the
    sequence is no run of the net. ``silent``: transitions that may stay
    unfired for ever (under a timed semantics, a vehicle's reports: a run may
    end where only they are enabled, the vehicle silent). ``loop``: the
    sequence is a lasso verdict's, its firings from ``loop`` on repeated for
    ever; they are fired again until the observer starts a turn in a state it
    started one in before, since a verdict enters its loop where the markings
    allow, and the observer may need more than one turn to come back.
    """
    s = structure(net)
    index = s.transition_index
    m = list(s.initial_vector())
    preds = _truths(prop)

    def read() -> tuple[bool, ...]:
        marking = {s.places[k]: n for k, n in enumerate(m) if n}
        return tuple(holds(x, marking) for x in preds)

    fired = list(transitions)

    def firings() -> Iterator[str]:
        """The sequence, then its cycle again while each turn starts the observer in a
        state no turn started it in before (``obs`` is read as the loop below leaves it)."""
        yield from fired
        starts = set()
        while loop is not None and fired[loop:] and obs is not BAD and obs not in starts:
            starts.add(obs)
            yield from fired[loop:]

    obs = step(prop, initial(prop.scope.kind), *read())
    seen = {(tuple(m), obs): 0}
    open_since = 0 if pending(prop, obs) else None   # obligations open from this step on
    k = 0
    for k, tid in enumerate(firings(), 1):
        if obs is BAD:
            return Shown(Shape.PREFIX, k - 1)
        if tid not in index:
            raise ValueError(f"'{tid}' is no transition of '{net.name}'")
        j = index[tid]
        if not s.enabled(m, j):
            raise ValueError(f"'{tid}' is not enabled after {k - 1} firings")
        s.fire(m, j)
        obs = step(prop, obs, *read())
        if not pending(prop, obs):
            open_since = None
        elif open_since is None:
            open_since = k
        state = (tuple(m), obs)
        if obs is not BAD and state in seen and open_since is not None \
                and seen[state] >= open_since:
            return Shown(Shape.LASSO, k, loop=seen[state])
        seen[state] = k    # the latest visit: the shortest cycle back to it
    if obs is BAD:
        return Shown(Shape.PREFIX, k)
    quiet = {index[t] for t in silent if t in index}
    dead = not any(s.enabled(m, j) for j in range(len(s.transitions)) if j not in quiet)
    if dead and pending(prop, obs):
        return Shown(Shape.FINITE, k)
    return None
