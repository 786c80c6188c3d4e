"""Composition by place fusion: the one operation that builds missions.

The paper builds every net the same way (sections 2.3 and 2.5, after
Iordache and Antsaklis 2006): small nets are joined by *fusing* places, that
is, by merging places of different nets into one place that keeps all their
arcs. A task is the task net fused with the primitive net on
``{E, D, OFF, S1, S2}``; a sequence is fused with its two structures on
``T1_*`` and ``T2_*`` and with its parent on ``{B, A, MTX, OK, FAIL, ABORTED}``.

Two functions do it, each linear in the size of the nets:

* :func:`union` puts nets side by side, prefixing every node id with the
  component's name (``AchieveDepth.MTX``), so that names stay unique;
* :func:`fuse` merges groups of places of one net.

:func:`compose` is their composition. The laws the tests check: fusion is
associative (fusing ``{a, b}`` then ``{a, c}`` is fusing ``{a, b, c}``),
union is associative up to prefixes, names stay unique, and nothing is lost:
every transition and every arc survives, and the place count drops by exactly
the number of places merged away.
"""
from __future__ import annotations

from functools import partial
from itertools import chain
from typing import Callable, Iterable, Mapping, Sequence

from .errors import NetError
from .net import Arc, Marking, Net, Place, Transition, is_valid_id


def compose(components: Mapping[str, Net] | Iterable[tuple[str, Net]],
            groups: Iterable[Sequence[str]] = (), name: str = "net",
            separator: str = ".") -> Net:
    """Union of the components, then fusion of the groups (qualified ids), in one pass.

    The result is ``fuse(union(components, name), groups)``, built without the
    intermediate net: every node is renamed once and every arc rewritten once
    (in C, through the components' arc columns), which is what lets a mission
    of 10,000 calls, a million arcs, compile in linear time.

    The components are valid nets, so the result is valid by construction
    except in three ways, which are checked here instead of checking the
    whole net again: two qualified ids may clash, a prefix may start with
    white space, and a transition may come to both read and consume a fused
    place. Transitions are never fused, so two arcs can only come to join the
    same ends inside one component, when two of its own places are fused;
    only such components pay for merging arc weights.
    """
    items = list(components.items() if isinstance(components, Mapping) else components)
    tables: list[dict[str, str]] = []   # per component: local id -> qualified id
    order: dict[str, int] = {}          # qualified place id -> position in the union
    doubtful = False                    # whether the result needs a full check
    n_transitions = 0
    for prefix, net in items:
        if prefix:
            stem = prefix + separator
            doubtful = doubtful or not is_valid_id(stem + "x")
            table = {n.id: stem + n.id for n in net.places}
            table.update((t.id, stem + t.id) for t in net.transitions)
        else:
            table = {n.id: n.id for n in net.places}
            table.update((t.id, t.id) for t in net.transitions)
        tables.append(table)
        n_transitions += len(net.transitions)
        for p in net.places:
            q = table[p.id]
            if q in order:
                raise NetError(f"duplicate id '{q}' in the union '{name}'; ids must be "
                               "unique across places and transitions")
            order[q] = len(order)

    def what(p: str) -> str:  # for an error message only: not a place, but a node?
        node = any(p in set(table.values()) for table in tables)
        return "a transition" if node else "no place"

    rep = _representatives(order, groups, name, what)

    places: list[Place] = []
    transitions: list[Transition] = []
    arcs: list[Arc] = []
    tokens: dict[str, int] = {}
    marked_by: dict[str, str] = {}
    for (prefix, net), table in zip(items, tables):
        final = table
        if rep and not rep.keys().isdisjoint(table.values()):
            final = {local: rep.get(q, q) for local, q in table.items()}
            places.extend(p.with_id(table[p.id]) if prefix else p
                          for p in net.places if final[p.id] == table[p.id])
        elif prefix:
            places.extend(p.with_id(table[p.id]) for p in net.places)
        else:
            places.extend(net.places)
        transitions.extend([t.with_id(table[t.id]) for t in net.transitions] if prefix
                           else net.transitions)
        for p, n in net.initial.items():
            r = final[p]
            if r in tokens and tokens[r] != n:
                raise NetError(
                    f"cannot fuse '{marked_by[r]}' ({tokens[r]} tokens) with "
                    f"'{table[p]}' ({n} tokens): fused places must start with the "
                    "same marking")
            tokens[r] = n
            marked_by.setdefault(r, table[p])
        if final is not table and _fuses_within(net, final):
            weights: dict[tuple, int] = {}
            for a in net.arcs:
                key = (final[a.source], final[a.target], a.kind)
                weights[key] = weights.get(key, 0) + a.weight
            merged = [Arc(s, t, w, k) for (s, t, k), w in weights.items()]
            doubtful = doubtful or len({(a.source, a.target) for a in merged}) < len(merged)
            arcs.extend(merged)
        elif prefix or final is not table:
            sources, targets, weights_, kinds = net.columns
            arcs.extend(map(_make_arc, zip(map(final.__getitem__, sources),
                                           map(final.__getitem__, targets), weights_, kinds)))
        else:
            arcs.extend(net.arcs)
    ids = len(order) + n_transitions
    doubtful = doubtful or len(set(chain(order, (t.id for t in transitions)))) < ids
    build = Net if doubtful else Net._trusted
    return build(name, tuple(places), tuple(transitions), tuple(arcs), Marking(tokens))


_make_arc = partial(tuple.__new__, Arc)   # Arc from a 4-tuple, called from C


def _fuses_within(net: Net, table: Mapping[str, str]) -> bool:
    """Whether two places of ``net`` end up as one (so its arcs may collide)."""
    return len({table[p.id] for p in net.places}) < len(net.places)


def _representatives(order: Mapping[str, int], groups: Iterable[Sequence[str]],
                     name: str, what: Callable[[str], str]) -> dict[str, str]:
    """Place -> the place it is fused into: the member of its class first in ``order``.

    Groups that share a place are merged together, so the result depends only
    on which places end up together, not on how the groups were written: that
    makes fusion associative and the order of groups irrelevant.
    """
    parent: dict[str, str] = {}

    def find(p: str) -> str:
        root = p
        while parent[root] != root:
            root = parent[root]
        while parent[p] != root:  # path compression keeps this near-linear
            parent[p], p = root, parent[p]
        return root

    for group in groups:
        group = list(group)
        for p in group:
            if p not in order:
                raise NetError(f"cannot fuse '{p}': {what(p)} of that name in net '{name}'")
            parent.setdefault(p, p)
        for p in group[1:]:
            a, b = find(group[0]), find(p)
            if a != b:
                if order[b] < order[a]:
                    a, b = b, a
                parent[b] = a
    return {p: find(p) for p in parent}


def union(components: Mapping[str, Net] | Iterable[tuple[str, Net]], name: str = "net",
          separator: str = ".") -> Net:
    """Disjoint union of nets, each node id prefixed by ``prefix + separator``.

    An empty prefix keeps the component's ids as they are (for a net that is
    already qualified); clashes are then reported as duplicate ids.
    """
    return compose(components, (), name, separator)


def fuse(net: Net, groups: Iterable[Sequence[str]], name: str | None = None) -> Net:
    """Merge each group of places into one place.

    The merged place keeps the id and attributes of the member that comes
    first in the net (its representative; put the component whose names
    should survive first in the :func:`union`). Groups that share a place are
    merged together, so the result depends only on which places end up
    together, not on how the groups were written. Arcs that come to join the
    same place and transition add their weights. A fused place is one place,
    so its tokens are counted once: the members that are marked must be
    marked alike (the unmarked ones take their marking), and two members
    marked differently are a modelling error, reported as such.
    """
    return compose([("", net)], groups, name or net.name)


def glue(nets: Sequence[Net], name: str | None = None) -> Net:
    """Join nets on their shared interface places: same id, both interface.

    This is fusion by name, the way the paper's figures are joined: the task
    net's ``E`` *is* the primitive's ``E``. Any other clash of ids (a place
    that is interface on one side only, two transitions of the same name) is
    an error, so that nothing is fused by accident. The first net's places
    survive the fusion.
    """
    seen: dict[str, Place] = {}
    transitions: set[str] = set()
    parts: list[tuple[str, Net]] = []
    groups: list[list[str]] = []
    for k, net in enumerate(nets):
        renames: dict[str, str] = {}
        for p in net.places:
            first = seen.get(p.id)
            if first is None:
                seen[p.id] = p
            elif first.interface is not None and p.interface is not None:
                renames[p.id] = f"{p.id}#{k}"  # a placeholder id, fused away below
                groups.append([p.id, renames[p.id]])
            else:
                raise NetError(f"cannot join nets on place '{p.id}': it is not an interface "
                               "place of both")
        for t in net.transitions:
            if t.id in transitions:
                raise NetError(f"cannot join nets: both have a transition '{t.id}'")
            transitions.add(t.id)
        if renames:
            r = lambda i: renames.get(i, i)
            net = Net(net.name,
                      tuple(Place(r(p.id), p.name, p.interface, p.payload, p.position)
                            for p in net.places),
                      net.transitions,
                      tuple(Arc(r(a.source), r(a.target), a.weight, a.kind) for a in net.arcs),
                      Marking({r(p): n for p, n in net.initial.items()}))
        parts.append(("", net))
    joined = union(parts, name or (nets[0].name if nets else "net"))
    return fuse(joined, groups)


def prefixed(net: Net, prefix: str, separator: str = "_") -> Net:
    """The same net with every id prefixed (``B`` -> ``T1_B``); labels kept."""
    return union([(prefix, net)], net.name, separator) if prefix else net
