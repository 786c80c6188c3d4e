"""A compiled mission one call at a time: the net of one instance, its callees shut.

A compiled mission (section 2.5) is a net of instances, each prefixing its
nodes' ids (:func:`instance_clusters`): the mission's root structure, each
structure of a body, each call site, one shared net per task and per
function, one per primitive. An instance *calls* another when its
transitions mark the other's begin place (``B``; a task marks its
primitive's ``E``): the mission's root calls its structures and call sites,
a call site its task or function, a task its primitive (:func:`calls_of`).

Shown whole, the paper's mission is 421 nodes: a grey tangle on a screen. One
instance at a time (:func:`call_net`), it is a template's net (16 to 40 nodes)
and its callees, each shut in a box named as in MCL, the places it marks in
them framed with the box: what a slide or a projector shows readably. The
token-game page (:mod:`mcl2pnml.view.show`) and ``compile --format svg
--expand NAME`` draw these views; a box opens the view of its callee.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Collection, Mapping

from mcl2pnml.core.net import ArcKind, Marking, Net
from mcl2pnml.core.settings import SettingError
from mcl2pnml.core.errors import did_you_mean

#: The interface places through which an instance calls another: a structure or call site
#: starts its callee through the callee's B, a task its primitive through E.
CALLS = ("B", "E")

#: A box's name is at most this many characters (a call with a long tuple is cut, with …).
LONGEST_LABEL = 48


def instance_clusters(net: Net) -> dict[str, list[str]]:
    """Nodes grouped by instance: the part of their id before the last dot.

    A compiled mission names every node after its component
    (``mission.sequence-1.t2``), so this draws each task, structure and call
    site in its own box. Ids without a dot, and groups of one, stay loose.
    """
    groups: dict[str, list[str]] = {}
    for node in (*net.places, *net.transitions):
        stem, dot, _ = node.id.rpartition(".")
        if dot and stem:
            groups.setdefault(stem, []).append(node.id)
    return {k: v for k, v in groups.items() if len(v) > 1}


def calls_of(net: Net, clusters: Mapping[str, Collection[str]]) -> dict[str, set[str]]:
    """Which boxes each box calls: those whose begin place (:data:`CALLS`) its
    transitions mark and theirs take from."""
    box = {n: name for name, members in clusters.items() for n in members}
    writers: dict[str, set[str]] = {}
    readers: dict[str, set[str]] = {}
    for a in net.arcs:
        place, transition = ((a.source, a.target) if a.source in net.place_index
                             else (a.target, a.source))
        if a.kind is ArcKind.NORMAL and transition in box:
            (writers if a.target == place else readers).setdefault(place, set()).add(
                box[transition])
    calls: dict[str, set[str]] = {name: set() for name in clusters}
    for p in net.places:
        if p.interface in CALLS:
            for caller in writers.get(p.id, ()):
                calls[caller] |= readers.get(p.id, set()) - {caller}
    return calls


@dataclass(frozen=True)
class Calls:
    """The instances of a compiled mission and who calls whom: ``clusters`` each instance's
    nodes, ``callees`` and ``callers`` in the net's order, ``roots`` those no one calls
    (the mission's ``mission``)."""

    clusters: dict[str, list[str]]
    callees: dict[str, tuple[str, ...]]
    callers: dict[str, tuple[str, ...]]
    roots: tuple[str, ...]

    def name(self, asked: str, labels: Mapping[str, str]) -> str:
        """The instance ``asked`` names: its own name, or its label when one instance
        alone has it (``Dive(Depth)``); else a :class:`SettingError` of ``expand``."""
        if asked in self.clusters:
            return asked
        named = [n for n in self.clusters if labels.get(n) == asked]
        if len(named) == 1:
            return named[0]
        if named:
            raise SettingError("expand", f"{len(named)} calls are {asked!r} "
                                         f"({', '.join(named)}): name one")
        raise SettingError("expand", f"no call {asked!r} in this mission"
                           + did_you_mean(asked, self.clusters, "calls"))

    def within(self, name: str) -> tuple[list[str], list[str]]:
        """What runs inside the box of ``name``: the instances only it reaches (itself,
        its structures and call sites, a task only its call site calls) and the shared
        ones it reaches (a task called from elsewhere too, its primitive), which are its
        own while it runs: a shared net's gate lets in one call at a time."""
        below: list[str] = []
        seen = {name}
        stack = [name]
        while stack:
            for c in self.callees[stack.pop()]:
                if c not in seen:
                    seen.add(c)
                    below.append(c)
                    stack.append(c)
        own = {name}
        changed = True
        while changed:      # an instance all of whose callers are its own is its own too
            changed = False
            for c in below:
                if c not in own and all(k in own for k in self.callers[c]):
                    own.add(c)
                    changed = True
        return [name, *(c for c in below if c in own)], [c for c in below if c not in own]


def mission_calls(net: Net) -> Calls:
    """The instances of the compiled mission ``net`` and who calls whom."""
    clusters = instance_clusters(net)
    calls = calls_of(net, clusters)
    order = {name: k for k, name in enumerate(clusters)}
    callees = {name: tuple(sorted(calls[name], key=order.__getitem__)) for name in clusters}
    callers: dict[str, list[str]] = {name: [] for name in clusters}
    for name in clusters:
        for c in callees[name]:
            callers[c].append(name)
    roots = tuple(name for name in clusters if not callers[name])
    return Calls(clusters, callees, {k: tuple(v) for k, v in callers.items()}, roots)


def call_net(net: Net, calls: Calls, opened: Collection[str]) -> tuple[Net, dict[str, list[str]]]:
    """The part of ``net`` that the view of the instances ``opened`` draws, and its boxes:
    each opened instance's nodes, each of its callees' (a box, shut), and the places of
    other instances that the opened ones' transitions touch (a primitive's lock taken by
    a call site); the arcs of the opened instances' transitions, and the arcs of the
    callees' transitions between these nodes. The boxes are the opened instances first,
    then their callees, in the net's order."""
    opened = [n for n in calls.clusters if n in set(opened)]
    shut = [c for c in calls.clusters if c not in opened
            and any(c in calls.callees[o] for o in opened)]
    mine = {n for o in opened for n in calls.clusters[o]}
    inside = mine | {n for c in shut for n in calls.clusters[c]}
    keep = set(inside)
    arcs = []
    for a in net.arcs:
        place, transition = ((a.source, a.target) if a.source in net.place_index
                             else (a.target, a.source))
        if transition in mine:
            keep.add(place)
            arcs.append(a)
        elif transition in inside and place in inside:
            arcs.append(a)
    part = Net(net.name, tuple(p for p in net.places if p.id in keep),
               tuple(t for t in net.transitions if t.id in keep), tuple(arcs),
               Marking({p: k for p, k in net.initial.items() if p in keep}))
    # a callee's place that the opened calls' transitions touch is on its box's border
    # (drawn beside it), even where the callee's own transitions never do (its gate)
    touched = {a.source if a.source in net.place_index else a.target
               for a in arcs if a.source in mine or a.target in mine}
    boxes = {name: list(calls.clusters[name]) for name in opened}
    boxes.update((name, [n for n in calls.clusters[name] if n not in touched]) for name in shut)
    return part, boxes


#: A box's name is broken after a comma into lines of about this many characters: a
#: structure's name is long, and a box as wide as its name widens its whole view.
LINE = 24


def short_label(label: str) -> str:
    """A box's name no longer than :data:`LONGEST_LABEL` characters, broken after its
    commas into lines of about :data:`LINE` characters (``monitor(Survey(),`` then
    ``FindCross())``)."""
    label = label if len(label) <= LONGEST_LABEL else label[:LONGEST_LABEL - 1] + "\u2026"
    pieces, depth, start = [], 0, 0
    for k, c in enumerate(label):      # the commas between a call's arguments, not a tuple's
        depth += (c == "(") - (c == ")")
        if c == "," and depth == 1 and label[k + 1:k + 2] == " ":
            pieces.append(label[start:k + 1])
            start = k + 2
    pieces.append(label[start:])
    lines = [pieces[0]]
    for piece in pieces[1:]:
        if len(lines[-1]) + 1 + len(piece) > LINE:
            lines.append(piece)
        else:
            lines[-1] += " " + piece
    return "\n".join(line.rstrip() for line in lines)
