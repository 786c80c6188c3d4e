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

from typing import Iterable, Mapping, Sequence

from .errors import NetError
from .net import Arc, Marking, Net, Place, Transition


def union(components: Mapping[str, Net] | Iterable[tuple[str, Net]], name: str = "net",
          separator: str = ".") -> Net:
    """Disjoint union of nets, each node id prefixed by ``prefix + separator``.

    An empty prefix keeps the component's ids as they are (for a net that is
    already qualified); clashes are then reported as duplicate ids.
    """
    items = components.items() if isinstance(components, Mapping) else components
    places: list[Place] = []
    transitions: list[Transition] = []
    arcs: list[Arc] = []
    marking: dict[str, int] = {}
    for prefix, net in items:
        q = (lambda i: f"{prefix}{separator}{i}") if prefix else (lambda i: i)
        places.extend(Place(q(p.id), p.name, p.interface, p.payload, p.position)
                      for p in net.places)
        transitions.extend(Transition(q(t.id), t.name, t.timing, t.payload, t.position)
                           for t in net.transitions)
        arcs.extend(Arc(q(a.source), q(a.target), a.weight, a.kind) for a in net.arcs)
        for p, n in net.initial.items():
            marking[q(p)] = n
    return Net(name, tuple(places), tuple(transitions), tuple(arcs), Marking(marking))


def fuse(net: Net, groups: Iterable[Sequence[str]], name: str | None = None) -> Net:
    """Merge each group of places into one place.

    The merged place keeps the id and attributes of the member that comes
    first in the net (its representative; put the component whose names
    should survive first in the :func:`union`). Groups that share a place are
    merged together, so the result depends only on which places end up
    together, not on how the groups were written: that makes fusion
    associative and the order of groups irrelevant. Arcs that come to join the same place and
    transition add their weights. A fused place is one place, so its tokens
    are counted once: the members that are marked must be marked alike (the
    unmarked ones take their marking), and two members marked differently are
    a modelling error, reported as such.
    """
    parent: dict[str, str] = {}

    def find(p: str) -> str:
        root = p
        while parent[root] != root:
            root = parent[root]
        while parent[p] != root:  # path compression keeps this near-linear
            parent[p], p = root, parent[p]
        return root

    index = net.place_index
    order = {p.id: i for i, p in enumerate(net.places)}
    for group in groups:
        group = list(group)
        for p in group:
            if p not in index:
                kind = "a transition" if p in net.transition_index else "no place"
                raise NetError(f"cannot fuse '{p}': {kind} of that name in net '{net.name}'")
            parent.setdefault(p, p)
        for p in group[1:]:
            a, b = find(group[0]), find(p)
            if a != b:
                # the member that comes first in the net survives: a choice that
                # does not depend on how the groups were written or split
                if order[b] < order[a]:
                    a, b = b, a
                parent[b] = a

    rep = {p: find(p) for p in parent}
    tokens: dict[str, int] = {}
    marked_by: dict[str, str] = {}
    for p, r in rep.items():
        n = net.initial[p]
        if n:
            if r in tokens and tokens[r] != n:
                raise NetError(
                    f"cannot fuse '{marked_by[r]}' ({tokens[r]} tokens) with '{p}' ({n} tokens): "
                    "fused places must start with the same marking")
            tokens[r] = n
            marked_by.setdefault(r, p)

    places = tuple(p for p in net.places if rep.get(p.id, p.id) == p.id)
    weights: dict[tuple, int] = {}
    for a in net.arcs:
        key = (rep.get(a.source, a.source), rep.get(a.target, a.target), a.kind)
        weights[key] = weights.get(key, 0) + a.weight
    arcs = tuple(Arc(s, t, w, k) for (s, t, k), w in weights.items())
    marking = {p: n for p, n in net.initial.items() if p not in rep}
    marking.update(tokens)
    return Net(name or net.name, places, net.transitions, arcs, Marking(marking))


def compose(components: Mapping[str, Net] | Iterable[tuple[str, Net]],
            groups: Iterable[Sequence[str]], name: str = "net") -> Net:
    """Union of the components, then fusion of the groups (qualified ids)."""
    return fuse(union(components, name), groups)


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
