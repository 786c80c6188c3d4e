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
from itertools import chain, compress, islice
from operator import attrgetter
from typing import Callable, Iterable, Mapping, Sequence

from mcl2pnml.core.errors import NetError
from mcl2pnml.core.net import Arc, ArcKind, Marking, Net, Place, Transition, is_valid_id


def compose(components: Mapping[str, Net] | Iterable[tuple[str, Net]],
            groups: Iterable[Sequence[str]] = (), name: str = "net",
            separator: str = ".") -> Net:
    """Union of the components, then fusion of the groups (qualified ids), in one pass.

    The result is ``fuse(union(components, name), groups)``, built without the
    intermediate net: every node is renamed once and every arc rewritten once,
    which is what lets a mission of 10,000 calls, a million arcs, compile in
    linear time. Components made from one prototype (a compiled mission has
    thousands of call sites of one task, and of sequences) share a
    :class:`_Shape`, their ids and arcs by position, worked out once; places
    are then numbered in union order and fused by number, so that renaming
    a component is a few passes in C over its columns.

    The components are valid nets, so the result is valid by construction
    except in three ways, which are checked here instead of checking the
    whole net again: two qualified ids may clash, a prefix may start with
    white space, and a transition may come to both read and consume a fused
    place. Ids of one component cannot clash, and those of two components
    can only when one's prefix and separator start the other's, which is
    checked on the prefixes. Transitions are never fused, so two arcs can
    only come to join the same ends inside one component, when two of its
    own places are fused; only such components pay for merging arc weights.
    """
    items = list(components.items() if isinstance(components, Mapping) else components)
    # doubtful: whether the result needs a full check
    parts, order, doubtful = _qualified(items, separator, name)

    def what(p: str) -> str:  # for an error message only: not a place, but a node?
        node = any(p in qualified for _, _, _, qualified, _ in parts)
        return "a transition" if node else "no place"

    root = _roots(order, groups, name, what)
    place_ids = list(order)
    fused = list(map(place_ids.__getitem__, root))   # place number -> id it is fused into

    places: list[Place] = []
    transitions: list[Transition] = []
    sources: list[str] = []
    targets: list[str] = []
    weights: list[int] = []
    kinds: list[ArcKind] = []
    tokens: dict[str, int] = {}
    marked_by: dict[str, str] = {}
    for prefix, net, shape, qualified, first in parts:
        n = shape.n_places
        numbers = range(first, first + n)
        roots = root[first:first + n]
        final = fused[first:first + n] + qualified[n:]
        within = False   # whether two of the component's own places are now one
        if roots == list(numbers):   # no place of the component is fused away
            places.extend(map(Place.with_id, net.places, qualified) if prefix else net.places)
        else:
            within = len(set(roots)) < n
            kept = list(map(int.__eq__, roots, numbers))
            places.extend(map(Place.with_id, compress(net.places, kept), compress(qualified, kept))
                          if prefix else compress(net.places, kept))
        transitions.extend(map(Transition.with_id, net.transitions, qualified[n:]) if prefix
                           else net.transitions)
        _mark(net, shape, final, qualified, tokens, marked_by)
        ends = (list(map(final.__getitem__, shape.sources)),
                list(map(final.__getitem__, shape.targets)))
        if within:
            ends, own_weights, own_kinds, clash = _merged(ends, shape)
            doubtful = doubtful or clash
        else:
            own_weights, own_kinds = shape.weights, shape.kinds
        sources.extend(ends[0])
        targets.extend(ends[1])
        weights.extend(own_weights)
        kinds.extend(own_kinds)
    columns = (tuple(sources), tuple(targets), tuple(weights), tuple(kinds))
    arcs = tuple(map(_make_arc, zip(*columns)))
    if doubtful:
        return Net(name, tuple(places), tuple(transitions), arcs, Marking(tokens))
    return Net._trusted(name, tuple(places), tuple(transitions), arcs, Marking(tokens), columns)


def _qualified(items: list[tuple[str, Net]], separator: str, name: str
               ) -> tuple[list[tuple[str, Net, "_Shape", list[str], int]], dict[str, int], bool]:
    """Each component with its shape, its qualified ids and the number of its first place
    in the union; each qualified place id's number; and whether the result needs a full
    check (a prefix that is no id's start, none, or one that starts another's)."""
    shapes: dict[tuple, _Shape] = {}
    parts: list[tuple[str, Net, _Shape, list[str], int]] = []
    order: dict[str, int] = {}          # qualified place id -> position in the union
    doubtful = False
    for prefix, net in items:
        shape = _Shape.of(net, shapes)
        if prefix:
            stem = prefix + separator
            doubtful = doubtful or not is_valid_id(stem + "x")
            qualified = list(map(stem.__add__, shape.ids))
        else:
            qualified = shape.ids
        first = len(order)
        parts.append((prefix, net, shape, qualified, first))
        order.update(zip(qualified[:shape.n_places], range(first, first + shape.n_places)))
        if len(order) < first + shape.n_places:
            _duplicate(chain.from_iterable(q[:s.n_places] for _, _, s, q, _ in parts), name)
    # sorted, a stem that starts others comes right before the first of them
    stems = sorted(prefix + separator for prefix, *_ in parts)
    doubtful = (doubtful or not all(prefix for prefix, *_ in parts)
                or any(b.startswith(a) for a, b in zip(stems, stems[1:])))
    return parts, order, doubtful


def _mark(net: Net, shape: "_Shape", final: list[str], qualified: list[str],
          tokens: dict[str, int], marked_by: dict[str, str]) -> None:
    """The component's initial marking added to ``tokens``, on the places it is fused
    into (``final``); fused places must start alike (section 2.3: fusion merges places
    of one marking)."""
    for p, count in net.initial.items():
        i = shape.index[p]
        r = final[i]
        if r in tokens and tokens[r] != count:
            raise NetError(
                f"cannot fuse '{marked_by[r]}' ({tokens[r]} tokens) with "
                f"'{qualified[i]}' ({count} tokens): fused places must start with the "
                "same marking")
        tokens[r] = count
        marked_by.setdefault(r, qualified[i])


def _merged(ends: tuple[list[str], list[str]], shape: "_Shape"
            ) -> tuple[tuple[list[str], list[str]], list[int], list[ArcKind], bool]:
    """A component's arcs once two of its own places are fused: arcs that come to join
    the same ends, of one kind, are one, their weights added; and whether two arcs of
    different kinds now join the same ends (a transition that reads and consumes a place:
    the result needs a full check)."""
    merged: dict[tuple, int] = {}
    for s, t, w, k in zip(*ends, shape.weights, shape.kinds):
        merged[s, t, k] = merged.get((s, t, k), 0) + w
    clash = len({(s, t) for s, t, _ in merged}) < len(merged)
    return (([s for s, _, _ in merged], [t for _, t, _ in merged]), list(merged.values()),
            [k for _, _, k in merged], clash)


_make_arc = partial(tuple.__new__, Arc)   # Arc from a 4-tuple, called from C
_ID = attrgetter("id")


class _Shape:
    """A component's ids and arcs by position, shared by the components of one prototype.

    ``ids`` are the local ids, places first; ``index`` maps them back to
    positions; ``sources`` and ``targets`` are the arcs' ends as positions
    in ``ids``, next to their ``weights`` and ``kinds``.
    """

    __slots__ = ("ids", "n_places", "index", "sources", "targets", "weights", "kinds")

    @classmethod
    def of(cls, net: Net, shapes: dict[tuple, "_Shape"]) -> "_Shape":
        """The shape of ``net``, from ``shapes`` when a net of the same shape was seen.

        Keyed by the identity of the places and arcs (nets derived from
        one prototype share those tuples, and every component is alive
        while composing, so identities are not reused) and by the
        transitions' ids, which are all that a call site's payload
        stamping leaves alike.
        """
        tids = tuple(map(_ID, net.transitions))
        key = (id(net.places), id(net.arcs), tids)
        shape = shapes.get(key)
        if shape is None:
            shape = shapes[key] = cls()
            shape.ids = [p.id for p in net.places] + list(tids)
            shape.n_places = len(net.places)
            shape.index = {i: k for k, i in enumerate(shape.ids)}
            sources, targets, weights, kinds = net.columns
            shape.sources = list(map(shape.index.__getitem__, sources))
            shape.targets = list(map(shape.index.__getitem__, targets))
            shape.weights, shape.kinds = weights, kinds
        return shape


def _duplicate(ids: Iterable[str], name: str) -> None:
    """Raise on the first place id that an earlier one has."""
    seen: set[str] = set()
    for q in ids:
        if q in seen:
            raise NetError(f"duplicate id '{q}' in the union '{name}'; ids must be "
                           "unique across places and transitions")
        seen.add(q)


def _roots(order: Mapping[str, int], groups: Iterable[Sequence[str]],
           name: str, what: Callable[[str], str]) -> list[int]:
    """Place number (its position in ``order``) -> the number of the place it is fused into.

    That is the member of its class first in ``order``. Groups that share a
    place are merged together, so the result depends only on which places
    end up together, not on how the groups were written: that makes fusion
    associative and the order of groups irrelevant. Union-find on numbers,
    where a class's root is its smallest member, so that every place's
    number is at least its parent's: one pass in increasing order then
    takes every place to its root.
    """
    groups = list(groups)
    numbers = list(map(order.get, chain.from_iterable(groups)))
    if None in numbers:
        p = next(p for p in chain.from_iterable(groups) if p not in order)
        raise NetError(f"cannot fuse '{p}': {what(p)} of that name in net '{name}'")
    parent = list(range(len(order)))
    it = iter(numbers)
    for size in map(len, groups):
        if not size:
            continue
        a = next(it)
        while parent[a] != a:
            a = parent[a]
        for b in islice(it, size - 1):
            x = b
            while parent[b] != b:
                b = parent[b]
            while parent[x] != b:   # path compression keeps this near-linear
                parent[x], x = b, parent[x]
            if a < b:
                parent[b] = a
            elif b < a:
                parent[a] = b
                a = b
    for k, p in enumerate(parent):
        parent[k] = parent[p]
    return parent


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
