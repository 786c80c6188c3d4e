"""Hostile certificates for the soundness campaign of tests/certify/test_certificate_soundness.py.

Small generated missions are certified (:func:`bases`); their certificates, and with them
their nets, are then changed in every way the certificate's JSON allows (:data:`MUTATIONS`,
each a function of a certificate, a net and a random source); and :func:`judged` explores a
net to say whether what an accepted certificate claims of it is true. The checker is only
reached through :mod:`mcl2pnml.pipeline`, so that this module holds whatever the checker
becomes inside.
"""
from __future__ import annotations

import json
import random
import tempfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from mcl2pnml import pipeline
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import Arc, ArcKind, Net, NetError, Transition

#: A net with more markings than this is not explored here: its mission is drawn again.
MAX_MARKINGS = 20_000

RESULTS = ("mission.OK", "mission.FAIL", "mission.ABORTED")
STRUCTURES = {"sequence": ["T1", "T2"], "parallel": ["T1", "T2"], "monitor": ["T1", "T2"],
              "while": ["T1", "T2"], "if-then-else": ["T1", "T2", "T3"], "null": []}

# -- generated missions ------------------------------------------------------------------------

#: Callees of every signature a certificate tells apart: A ends OK or FAIL, F only fails or
#: keeps its goal for ever, E only ends OK (a loop on it never ends).
HEADER = """primitive Pa(v);
primitive Pb(v);
task A(x) = AchieveGoal(Pa(x)) timeout 3;
task F(x) = KeepGoal(Pb(x));
function E() { { } }
"""


def _call(rng: random.Random, callees: list[str]) -> str:
    name = rng.choice(callees)
    return f"{name}()" if name in ("E", "G") else f"{name}({rng.randint(1, 3)})"


def _statement(rng: random.Random, depth: int, callees: list[str]) -> str:
    if depth == 0 or rng.random() < 0.35:
        return _call(rng, callees) + ";"
    kind = rng.choice(["block", "parallel", "monitor", "if", "while", "while"])
    inner = [_statement(rng, depth - 1, callees) for _ in range(rng.randint(1, 2))]

    def part() -> str:      # what a structure takes: a call, or a block
        if rng.random() < 0.6:
            return _call(rng, callees)
        return "{ " + " ".join(_statement(rng, depth - 1, callees)
                               for _ in range(rng.randint(1, 2))) + " }"
    if kind == "block":
        return "{ " + " ".join(inner) + " }"
    if kind in ("parallel", "monitor"):
        return f"{kind}({part()}, {part()});"
    body = "{ " + " ".join(inner) + " }" if rng.random() < 0.8 else "{ }"
    if kind == "if":
        other = " else { " + _statement(rng, depth - 1, callees) + " }" \
            if rng.random() < 0.5 else ""
        return f"if ({part()}) then {body}{other}"
    # E as a condition half the time: a loop on it never ends, which makes forged bases
    condition = "E()" if rng.random() < 0.4 else part()
    return f"while ({condition}) {body}"


def mission_text(rng: random.Random, depth: int = 2) -> str:
    """A small mission on A, F and E, perhaps with a function G calling them."""
    text = HEADER
    callees = ["A", "F", "E"]
    if rng.random() < 0.4:
        text += f"function G() {{ {_statement(rng, 1, callees)} }}\n"
        callees.append("G")
    body = " ".join(_statement(rng, depth, callees) for _ in range(rng.randint(1, 2)))
    return text + f"mission {{ {body} }}\n"


@dataclass(frozen=True)
class Base:
    """A mission, one start of it, its net and the certificate it is given (as JSON text,
    so that every mutation starts from a fresh copy). ``kind``: ``from B`` and ``abort
    pending`` are the certificates ``certify`` writes; ``forged`` is, for a mission that is
    not certified from B, its certificate with an abort pending stripped to look like one
    from B (the checker must refuse it: the mission may never end)."""

    text: str
    kind: str
    net: Net
    cert_json: str
    #: what the checker found wrong with the unmutated pair (nothing, unless forged)
    problems: tuple[str, ...] = ()

    def cert(self) -> dict[str, Any]:
        return json.loads(self.cert_json)


def certified(text: str, abort_pending: bool = False):
    """``certify_file`` on ``text`` (written to a file for it): (cert as JSON data, net,
    problems); :class:`Mcl2PnmlError` when the mission is not certified."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "m.mcl"
        path.write_text(text)
        cert, net, problems = pipeline.certify_file(path, abort_pending=abort_pending)
    return json.loads(json.dumps(cert)), net, problems


def forged(cert: dict[str, Any], net: Net) -> tuple[dict[str, Any], Net]:
    """A certificate with an abort pending made to look like one from mission.B alone, and
    its net without mission.A: what a hostile hand does to a mission that never ends."""
    cert = json.loads(json.dumps(cert))
    cert["start"] = ["mission.B"]
    cert["conclusion"].pop("abort", None)
    cert["conclusion"]["ends"] = [e for e in cert["conclusion"]["ends"]
                                  if e != "mission.ABORTED"]
    cert["conclusion"]["why"] = "the root keeps the interface contract, started by mission.B"
    return cert, net.with_initial({p: n for p, n in net.initial.items() if p != "mission.A"})


def bases(seed: int, missions: int, never_ending: int) -> tuple[list[Base], int]:
    """The bases of ``missions`` generated missions certified from B and ``never_ending``
    ones that are not (forged), all small enough to explore, each also with an abort
    pending; and how many missions were drawn in all."""
    rng = random.Random(seed)
    out: list[Base] = []
    drawn = 0
    wanted = {"from B": missions, "forged": never_ending}
    while any(wanted.values()):
        drawn += 1
        text = mission_text(rng)
        try:
            pending_cert, pending_net, pending_problems = certified(text, True)
        except Mcl2PnmlError:
            continue
        try:
            cert, net, problems = certified(text)
            first = Base(text, "from B", net, json.dumps(cert), tuple(problems))
        except Mcl2PnmlError:
            cert, net = forged(pending_cert, pending_net)
            first = Base(text, "forged", net, json.dumps(cert))
        if not wanted[first.kind] or explored(first.net) is None \
                or explored(pending_net) is None:
            continue
        wanted[first.kind] -= 1
        out += [first, Base(text, "abort pending", pending_net, json.dumps(pending_cert),
                            tuple(pending_problems))]
    return out, drawn


# -- the oracle: exploring ---------------------------------------------------------------------

@dataclass(frozen=True)
class Explored:
    """What exploring a net finds: ``fault`` (not 1-safe; a dead marking that is no proper
    end; a marking from which no end can be reached), None if none; ``ends`` the results
    of its dead markings."""

    fault: str | None
    ends: frozenset[str]
    m0: frozenset[str] = field(default=frozenset())


_EXPLORED: dict[Net, Explored | None] = {}


def explored(net: Net) -> Explored | None:
    """:class:`Explored` for ``net`` from its M0 (None: more than :data:`MAX_MARKINGS`);
    remembered, since most mutations leave the net as it was."""
    if net not in _EXPLORED:
        if len(_EXPLORED) > 5_000:      # the slow campaign draws many nets: keep memory flat
            _EXPLORED.clear()
        _EXPLORED[net] = _explore(net)
    return _EXPLORED[net]


def remember(found: list[tuple[Net, Explored | None]]) -> None:
    """What exploring found of nets, explored by another process (a pool drawn once for
    every worker of a test session)."""
    for net, explored_ in found:
        _EXPLORED.setdefault(net, explored_)


def _explore(net: Net) -> Explored | None:
    from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore
    m0 = frozenset(p for p, n in net.initial.items() if n)
    try:        # the explorer the analysis chooses: a net that is not safe is handed over
        space = explore(net, max_states=MAX_MARKINGS)
    except ExplorationLimit:
        return None
    if not space.safe:      # a fault of the claims already, whatever else it does
        return Explored("not 1-safe: a place holds two tokens", frozenset(), m0)
    s = space.structure
    rest = {p: net.initial.get(p, 0) for p in s.places}
    ends, proper, fault = set(), [], None
    for node in space.terminal:
        marking = dict(zip(s.places, space.markings[node]))
        marked = [r for r in RESULTS if marking.get(r)]
        what = _improper(marking, marked, rest)
        if what is not None:
            fault = fault or f"a dead marking is no proper end ({what}): " \
                             f"{', '.join(space.format(node))}"
            continue
        ends.add(marked[0])
        proper.append(node)
    if fault is None and not space.always_can_reach(proper):
        fault = "from some reachable marking no end can be reached"
    return Explored(fault, frozenset(ends), m0)


def _improper(marking: dict[str, int], marked: list[str], rest: dict[str, int]) -> str | None:
    """Why a dead marking is not a proper end (None: it is): one result, mission.B taken,
    mission.A consumed exactly when the end is ABORTED, every other place as in M0."""
    if len(marked) != 1:
        return f"{len(marked)} results marked"
    if marking.get("mission.B"):
        return "mission.B still marked"
    if "mission.A" in marking:
        kept = marking["mission.A"]
        if marked[0] == "mission.ABORTED" and kept:
            return "ABORTED with mission.A still marked"
        if marked[0] != "mission.ABORTED" and kept != rest["mission.A"]:
            return "mission.A consumed without ending ABORTED"
    for place, tokens in marking.items():
        if place not in _OWN_ENDS and tokens != rest[place]:
            return f"'{place}' not at rest"
    return None


#: The places a proper end may leave otherwise than M0 had them.
_OWN_ENDS = frozenset(("mission.B", "mission.A", *RESULTS))


def judged(net: Net, cert: Any) -> str | None:
    """What exploring ``net`` finds false in what ``cert`` claims, an accepted certificate:
    None when it confirms every claim (1-safe, an end always reachable, every dead marking
    a proper end, the ends exactly the conclusion's, M0 the start said). Raises
    :class:`TooLarge` on a net too large to explore here."""
    found = explored(net)
    if found is None:
        raise TooLarge(net.name)
    if found.fault is not None:
        return found.fault
    try:
        claimed = cert["conclusion"]["ends"]
        start = set(cert["start"])
        if not isinstance(claimed, list) or not all(isinstance(e, str) for e in claimed):
            raise TypeError
    except (KeyError, TypeError, IndexError):
        return "accepted, but its conclusion's ends or its start cannot be read"
    said = {p for p in ("mission.B", "mission.A") if p in start}
    if {p for p in ("mission.B", "mission.A") if p in found.m0} != said:
        return f"M0 marks {sorted(p for p in found.m0 if p.startswith('mission.'))}, the " \
               f"certificate starts from {sorted(start)}"
    if set(claimed) != found.ends:
        return f"the ends are {sorted(found.ends)}, the certificate says {claimed}"
    return None


class TooLarge(Exception):
    """A net with more markings than :data:`MAX_MARKINGS`: not judged here."""


# -- nets changed ------------------------------------------------------------------------------

def _same(node: str) -> str:
    return node


def rebuilt(net: Net, rename: Callable[[str], str] = _same, arcs=None,
            initial=None, transitions=()) -> Net | None:
    """``net`` with every node id passed through ``rename`` (nodes given one id become one
    node, their arcs and tokens joined), ``arcs`` instead of its own, ``initial`` instead of
    its M0, ``transitions`` added; None when that is no net (an arc both read and consumed)."""
    # no renaming (an arc or a transition added, most mutations): the nodes and arcs kept
    # as they are, not copied one by one (a third of the campaign's time)
    same = rename is _same

    def kept(node):
        return node if same and node.name != node.id else node.with_id(rename(node.id))
    places = {}
    for p in net.places:
        places.setdefault(rename(p.id), kept(p))
    trans = {}
    for t in (*net.transitions, *transitions):
        trans.setdefault(rename(t.id), kept(t))
    joined: dict[tuple[str, str], Arc] = {}
    for a in (net.arcs if arcs is None else arcs):
        b = a if same else a._replace(source=rename(a.source), target=rename(a.target))
        if joined.setdefault((b.source, b.target), b) != b:
            return None
    marking: dict[str, int] = {}
    for p, n in (net.initial if initial is None else initial).items():
        marking[rename(p)] = max(marking.get(rename(p), 0), n)
    try:
        return Net(net.name, tuple(places.values()), tuple(trans.values()),
                   tuple(joined.values()), {p: n for p, n in marking.items() if n})
    except NetError:
        return None


def prefix_renamed(net: Net, old: str, new: str) -> Net | None:
    """Every node of instance ``old`` (its id starts ``old.``) moved to ``new``."""
    def rename(node: str) -> str:
        return new + node[len(old):] if node.startswith(old + ".") else node
    return rebuilt(net, rename)


def _owner(node: str) -> str:
    return node.rpartition(".")[0]


# -- mutations ---------------------------------------------------------------------------------

Mutation = Callable[[dict, Net, random.Random], "tuple[dict, Net] | None"]
MUTATIONS: dict[str, Mutation] = {}
#: The mutations that change the net as well as the certificate (or the net alone).
NET_MUTATIONS: set[str] = set()


def mutation(name: str, net: bool = False):
    def register(f: Mutation) -> Mutation:
        MUTATIONS[name] = f
        if net:
            NET_MUTATIONS.add(name)
        return f
    return register


def _tree(cert: dict, rng: random.Random, mission_first: float = 0.7) -> list | None:
    trees = cert.get("trees")
    if not isinstance(trees, dict) or not trees:
        return None
    if "mission" in trees and rng.random() < mission_first:
        nodes = trees["mission"]
    else:
        nodes = trees[rng.choice(sorted(trees))]
    return nodes if isinstance(nodes, list) and nodes else None


def _children(nodes: list, k: int) -> list[int]:
    return [c for c, node in enumerate(nodes) if node.get("parent") == k]


def _reordered(nodes: list, order: list[int], remap: bool = True) -> list:
    """``nodes`` in ``order`` (old indices), the parents following them when ``remap``."""
    at = {old: new for new, old in enumerate(order)}
    out = [dict(nodes[k]) for k in order]
    if remap:
        for node in out:
            p = node.get("parent")
            if isinstance(p, int) and p in at:
                node["parent"] = at[p]
    return out


def _replace_tree(cert: dict, old: list, new: list) -> None:
    for key, nodes in cert["trees"].items():
        if nodes is old:
            cert["trees"][key] = new
            return


def _post_order(nodes: list) -> list[int]:
    order: list[int] = []

    def visit(k: int) -> None:
        for c in _children(nodes, k):
            visit(c)
        order.append(k)
    roots = [k for k, n in enumerate(nodes) if n.get("parent", -1) == -1]
    for r in roots:
        visit(r)
    return order + [k for k in range(len(nodes)) if k not in order]


@mutation("numbers written otherwise")
def _numbers(cert, net, rng):
    """Parents and counts as JSON writes them too (1.0), or as no integer (true, 1.5,
    10**30): the same certificate, or one refused, never a crash."""
    nodes = _tree(cert, rng)
    if not nodes:
        return None
    node = rng.choice(nodes)
    node["parent"] = rng.choice([float(node["parent"]), True, node["parent"] + 0.5,
                                 10**30, -1.0])
    calls = cert.get("calls")
    if isinstance(calls, dict) and calls and rng.random() < 0.5:
        callee = rng.choice(sorted(calls))
        calls[callee] = rng.choice([float(calls[callee]), 0, -3])
    return cert, net


@mutation("root after its children")
def _root_last(cert, net, rng):
    nodes = _tree(cert, rng, 1.0)
    if nodes is None or len(nodes) < 2:
        return None
    _replace_tree(cert, nodes, _reordered(nodes, [*range(1, len(nodes)), 0]))
    return cert, net


@mutation("post-order, parents remapped")
def _post(cert, net, rng):
    nodes = _tree(cert, rng, 1.0)
    if nodes is None or len(nodes) < 2:
        return None
    _replace_tree(cert, nodes, _reordered(nodes, _post_order(nodes)))
    return cert, net


def _shuffle(siblings_kept: bool, remap: bool) -> Mutation:
    """A mutation listing one tree's nodes in a random order: each parent's children
    still in their order among themselves (``siblings_kept``) or not, the parent indices
    following the nodes (``remap``) or left as they were."""
    def shuffled(cert, net, rng):
        nodes = _tree(cert, rng)
        if nodes is None or len(nodes) < 2:
            return None
        order = list(range(len(nodes)))
        rng.shuffle(order)
        position = {old: new for new, old in enumerate(order)}
        for k in [-1, *range(len(nodes))] if siblings_kept else ():
            kids = _children(nodes, k)      # dealt the positions their siblings got
            for c, at in zip(kids, sorted(position[c] for c in kids)):
                order[at] = c
        _replace_tree(cert, nodes, _reordered(nodes, order, remap))
        return cert, net
    return shuffled


mutation("shuffled, siblings in order, parents remapped")(_shuffle(True, True))
mutation("shuffled, parents remapped")(_shuffle(False, True))
mutation("shuffled, parents not remapped")(_shuffle(False, False))


@mutation("mission's tree under another key")
def _mission_key(cert, net, rng):
    trees = cert.get("trees")
    if not isinstance(trees, dict) or "mission" not in trees:
        return None
    key = rng.choice(["main", "Mission", "mission ", "mission.B", "m", "", "mission-1",
                      *[f for f in cert.get("functions", []) if isinstance(f, str)]])
    trees[key] = trees.pop("mission")
    return cert, net


@mutation("function's tree renamed")
def _tree_renamed(cert, net, rng):
    trees = cert.get("trees")
    names = [k for k in trees or {} if k != "mission"]
    if not names:
        return None
    old = rng.choice(names)
    new = rng.choice([old + "x", "mission", old.lower() + "_", "A"])
    trees[new] = trees.pop(old)
    if rng.random() < 0.5:      # and the list of functions told too
        cert["functions"] = [new if f == old else f for f in cert.get("functions", [])]
    return cert, net


@mutation("tree dropped")
def _tree_dropped(cert, net, rng):
    trees = cert.get("trees")
    if not trees:
        return None
    del trees[rng.choice(sorted(trees))]
    return cert, net


@mutation("tree duplicated")
def _tree_duplicated(cert, net, rng):
    trees = cert.get("trees")
    if not trees:
        return None
    key = rng.choice(sorted(trees))
    copy = json.loads(json.dumps(trees[key]))
    trees[rng.choice([key + "2", "other", "mission" if key != "mission" else "main"])] = copy
    return cert, net


@mutation("functions list changed")
def _functions(cert, net, rng):
    functions = cert.get("functions")
    if not isinstance(functions, list):
        return None
    how = rng.randrange(5)
    if how == 0 and functions:
        functions.pop(rng.randrange(len(functions)))
    elif how == 1 and functions:
        functions.insert(rng.randrange(len(functions) + 1), rng.choice(functions))
    elif how == 2 and len(functions) > 1:
        functions.reverse()
    elif how == 3:
        functions.append(rng.choice(["A", "F", "mission", "Nope"]))
    else:
        cert["functions"] = []
    return cert, net


def _random_node(cert: dict, rng: random.Random, name: str, parent: int) -> dict:
    if rng.random() < 0.5:
        callees = [*cert.get("tasks", {}), *cert.get("functions", [])] or ["A"]
        return {"instance": name, "rule": "call", "callee": rng.choice(callees),
                "parent": parent, "results": ["OK", "FAIL"]}
    template = rng.choice(sorted(STRUCTURES))
    return {"instance": name, "rule": "structure", "template": template,
            "slots": STRUCTURES[template], "local": "0" * 64, "parent": parent,
            "results": ["OK"]}


def _inserted(nodes: list, at: int, node: dict) -> list:
    """``nodes`` with ``node`` at index ``at``, the parents after it moved along."""
    out = []
    for old in nodes:
        old = dict(old)
        p = old.get("parent")
        if isinstance(p, int) and p >= at:
            old["parent"] = p + 1
        out.append(old)
    out.insert(at, node)
    return out


@mutation("decoy repeating an instance's name")
def _decoy(cert, net, rng):
    nodes = _tree(cert, rng)
    if nodes is None:
        return None
    k = rng.randrange(len(nodes))
    name = nodes[k].get("instance")
    parent = rng.choice([-1, -1, *range(len(nodes))])
    decoy = _random_node(cert, rng, name, parent)
    # just before the real one and after its parent (read first bottom-up), or anywhere
    at = k if rng.random() < 0.6 else rng.randrange(len(nodes) + 1)
    if isinstance(parent, int) and parent >= at:
        decoy["parent"] = parent + 1
    _replace_tree(cert, nodes, _inserted(nodes, at, decoy))
    return cert, net


@mutation("instance renamed to another's")
def _renamed_to_other(cert, net, rng):
    nodes = _tree(cert, rng)
    if nodes is None:
        return None
    names = [n.get("instance") for ns in cert["trees"].values() if isinstance(ns, list)
             for n in ns] + list(cert.get("tasks", {})) + list(cert.get("primitives", {}))
    node = rng.choice(nodes)
    others = [n for n in names if n != node.get("instance")]
    if not others:
        return None
    node["instance"] = rng.choice(others)
    return cert, net


@mutation("node duplicated")
def _node_duplicated(cert, net, rng):
    nodes = _tree(cert, rng)
    if nodes is None:
        return None
    node = dict(rng.choice(nodes))
    at = rng.randrange(len(nodes) + 1)
    p = node.get("parent")
    if isinstance(p, int) and p >= at:
        node["parent"] = p + 1
    _replace_tree(cert, nodes, _inserted(nodes, at, node))
    return cert, net


@mutation("node dropped")
def _node_dropped(cert, net, rng):
    nodes = _tree(cert, rng)
    if nodes is None:
        return None
    k = rng.randrange(len(nodes))
    up = nodes[k].get("parent", -1)
    out = []
    for j, node in enumerate(nodes):
        if j == k:
            continue
        node = dict(node)
        p = node.get("parent")
        if p == k:
            node["parent"] = up if isinstance(up, int) and up < k else (up - 1 if
                                                                           isinstance(up, int) else up)
        elif isinstance(p, int) and p > k:
            node["parent"] = p - 1
        out.append(node)
    _replace_tree(cert, nodes, out)
    return cert, net


@mutation("node added")
def _node_added(cert, net, rng):
    nodes = _tree(cert, rng)
    if nodes is None:
        return None
    parent = rng.randrange(len(nodes))
    node = _random_node(cert, rng, rng.choice(["extra-1", "while-9", "A-9"]), parent)
    at = rng.randrange(parent + 1, len(nodes) + 1)
    _replace_tree(cert, nodes, _inserted(nodes, at, node))
    return cert, net


def _structure_nodes(cert: dict, rng: random.Random, least_slots: int = 1) -> list[tuple]:
    """(tree, index) of the structure nodes with at least ``least_slots`` slots."""
    out = []
    for key, nodes in (cert.get("trees") or {}).items():
        for k, node in enumerate(nodes if isinstance(nodes, list) else []):
            if isinstance(node, dict) and isinstance(node.get("slots"), list) and \
                    len(node["slots"]) >= least_slots:
                out.append((key, k))
    return out


@mutation("slots reordered")
def _slots(cert, net, rng):
    found = _structure_nodes(cert, rng, 2)
    if not found:
        return None
    key, k = rng.choice(found)
    slots = cert["trees"][key][k]["slots"]
    while True:
        rng.shuffle(slots)
        if slots != sorted(slots):
            break
    return cert, net


@mutation("template changed")
def _template(cert, net, rng):
    found = _structure_nodes(cert, rng, 0)
    if not found:
        return None
    key, k = rng.choice(found)
    node = cert["trees"][key][k]
    node["template"] = rng.choice([t for t in STRUCTURES if t != node.get("template")])
    if rng.random() < 0.5:
        node["slots"] = STRUCTURES[node["template"]]
    return cert, net


@mutation("callee changed")
def _callee(cert, net, rng):
    calls = [n for ns in (cert.get("trees") or {}).values() for n in ns
             if isinstance(n, dict) and n.get("rule") == "call"]
    if not calls:
        return None
    node = rng.choice(calls)
    node["callee"] = rng.choice([c for c in [*cert.get("tasks", {}), *cert.get("functions", []),
                                             "mission", "Pa"] if c != node.get("callee")])
    return cert, net


@mutation("rule changed")
def _rule(cert, net, rng):
    nodes = _tree(cert, rng)
    if nodes is None:
        return None
    node = rng.choice(nodes)
    node["rule"] = rng.choice([r for r in ("call", "structure", "task", "function", "mission",
                                           "") if r != node.get("rule")])
    return cert, net


@mutation("parent changed")
def _parent(cert, net, rng):
    nodes = _tree(cert, rng)
    if nodes is None:
        return None
    node = rng.choice(nodes)
    node["parent"] = rng.choice([-1, -2, len(nodes), *range(len(nodes))])
    return cert, net


@mutation("start changed")
def _start(cert, net, rng):
    cert["start"] = rng.choice([[], ["mission.A"], ["mission.B", "mission.A"], ["mission.B"],
                                ["mission.A", "mission.B"], ["mission.B", "mission.B"],
                                ["mission.B", "A.B"], ["mission.B", "mission.MTX"],
                                ["mission.OK"]])
    return cert, net


@mutation("conclusion's ends changed")
def _ends(cert, net, rng):
    conclusion = cert.get("conclusion")
    if not isinstance(conclusion, dict) or not isinstance(conclusion.get("ends"), list):
        return None
    ends = conclusion["ends"]
    how = rng.randrange(5)
    missing = [r for r in RESULTS if r not in ends]
    if how == 0 and missing:
        ends.insert(rng.randrange(len(ends) + 1), rng.choice(missing))
    elif how == 1 and ends:
        ends.pop(rng.randrange(len(ends)))
    elif how == 2 and len(ends) > 1:
        ends.reverse()
    elif how == 3 and ends:
        ends.append(ends[0])
    else:
        conclusion["ends"] = [] if ends else list(RESULTS[:2])
    return cert, net


@mutation("conclusion's claims changed")
def _claims(cert, net, rng):
    conclusion = cert.get("conclusion")
    if not isinstance(conclusion, dict):
        return None
    how = rng.randrange(4)
    if how == 0:
        del cert["conclusion"]
    elif how == 1:
        conclusion.pop("ends", None)
    else:
        conclusion[rng.choice(["safe", "an end always reachable", "reusable",
                               "at rest when it ends"])] = False
    return cert, net


@mutation("digest changed")
def _digest(cert, net, rng):
    spots = []
    for name in cert.get("proofs", {}):
        spots.append((cert["proofs"], name))
    for task in cert.get("tasks", {}).values():
        spots += [(task, "proof"), (task, "local")]
    for prim in cert.get("primitives", {}).values():
        spots.append((prim, "local"))
    for nodes in (cert.get("trees") or {}).values():
        spots += [(n, "local") for n in nodes if isinstance(n, dict) and "local" in n]
    if not spots:
        return None
    where, key = rng.choice(spots)
    others = [v for v in cert.get("proofs", {}).values() if v != where.get(key)]
    where[key] = rng.choice([*others[:3], "0" * 64, (where.get(key) or "x")[::-1]])
    return cert, net


@mutation("task changed")
def _task(cert, net, rng):
    tasks = cert.get("tasks")
    if not tasks:
        return None
    task = tasks[rng.choice(sorted(tasks))]
    key = rng.choice(["subject", "pattern", "primitives", "slots", "timeout"])
    if key in ("subject", "pattern"):
        choices = ["AchieveGoal", "AchieveGoal without a time-out", "KeepGoal",
                   "KeepGoal without a time-out", "KeepTwoGoals", "task-reduced", "while"]
        task[key] = rng.choice([c for c in choices if c != task.get(key)])
    elif key == "primitives":
        task[key] = rng.choice([[], ["Pa", "Pb"], ["Pb"], ["Pa"], list(cert.get("primitives",
                                                                              {}))[::-1]])
    elif key == "slots":
        task[key] = rng.choice([[], ["", ""], ["P1"], ["x"]])
    else:
        task[key] = rng.choice([None, 0, 99])
    return cert, net


@mutation("calls changed")
def _calls(cert, net, rng):
    calls = cert.get("calls")
    if not isinstance(calls, dict):
        return None
    how = rng.randrange(4)
    if how == 0 and calls:
        calls[rng.choice(sorted(calls))] += rng.choice([-1, 1, 5])
    elif how == 1 and calls:
        del calls[rng.choice(sorted(calls))]
    elif how == 2:
        calls[rng.choice(["A", "F", "E", "G"])] = 2
    else:
        cert["calls"] = {}
    return cert, net


@mutation("signature claims changed")
def _signature(cert, net, rng):
    nodes = [n for ns in (cert.get("trees") or {}).values() for n in ns if isinstance(n, dict)]
    nodes += list(cert.get("tasks", {}).values())
    if not nodes:
        return None
    node = rng.choice(nodes)
    if rng.random() < 0.5:
        node["results"] = rng.choice([[], ["OK"], ["FAIL"], ["OK", "FAIL"], ["ABORTED"]])
    elif node.get("may run for ever"):
        del node["may run for ever"]
    else:
        node["may run for ever"] = True
    return cert, net


def _spots(data: Any, path: tuple = ()) -> list[tuple]:
    """Every (container, key) of a JSON value, at any depth."""
    out = []
    if isinstance(data, dict):
        for key, value in data.items():
            out.append((data, key))
            out += _spots(value)
    elif isinstance(data, list):
        for k, value in enumerate(data):
            out.append((data, k))
            out += _spots(value)
    return out


@mutation("key deleted")
def _key_deleted(cert, net, rng):
    spots = [(c, k) for c, k in _spots(cert) if isinstance(c, dict)]
    container, key = rng.choice(spots)
    del container[key]
    return cert, net


#: Values of every JSON type, and numbers a parent index could trip on.
WRONG = [None, True, False, 0, -1, 1, 10**12, -10**12, 1.5, float("1e300"), "", "x",
         "mission", [], [None], ["mission.B"], {}, {"instance": "mission"}, [[]]]


@mutation("wrong JSON type")
def _wrong_type(cert, net, rng):
    container, key = rng.choice(_spots(cert))
    value = container[key]
    container[key] = rng.choice([w for w in WRONG if type(w) is not type(value) or w != value])
    return cert, net


@mutation("wrong JSON type at the top")
def _wrong_top(cert, net, rng):
    if rng.random() < 0.2:
        return rng.choice(WRONG), net
    cert[rng.choice(["trees", "tasks", "functions", "calls", "start", "conclusion", "proofs",
                     "primitives"])] = rng.choice(WRONG)
    return cert, net


# -- with the net changed to match -------------------------------------------------------------

def _calls_of(cert: dict) -> list[tuple[str, int]]:
    return [(key, k) for key, nodes in (cert.get("trees") or {}).items()
            for k, n in enumerate(nodes if isinstance(nodes, list) else [])
            if isinstance(n, dict) and n.get("rule") == "call"]


@mutation("two call sites made one, net too", net=True)
def _merged_calls(cert, net, rng):
    sites = _calls_of(cert)
    if len(sites) < 2:
        return None
    (k1, i1), (k2, i2) = rng.sample(sites, 2)
    keep, gone = cert["trees"][k1][i1], cert["trees"][k2][i2]
    old, new = gone["instance"], keep["instance"]
    changed = prefix_renamed(net, old, new)
    if changed is None:
        return None
    gone["instance"] = new
    if rng.random() < 0.3 and k1 == k2:        # and the node said once
        nodes = cert["trees"][k2]
        if not _children(nodes, i2):
            _replace_tree(cert, nodes, [dict(n, parent=n["parent"] - (n["parent"] > i2))
                                        for j, n in enumerate(nodes) if j != i2])
    return cert, changed


@mutation("instance renamed, net too", net=True)
def _renamed_both(cert, net, rng):
    nodes = _tree(cert, rng)
    if nodes is None:
        return None
    node = rng.choice(nodes)
    old = node["instance"]
    names = [n.get("instance") for ns in cert["trees"].values() for n in ns] + \
        list(cert.get("tasks", {})) + list(cert.get("primitives", {}))
    new = rng.choice([f"{old}x", f"z{old}", *[n for n in names if n != old]])
    changed = prefix_renamed(net, old, new)
    if changed is None:
        return None
    node["instance"] = new
    return cert, changed


def _arcs_moved(net: Net, name: str, moved: dict[str, str]) -> Net | None:
    """``net`` with the arcs of structure ``name``'s transitions to a child's places moved
    to the places of the child ``moved`` names instead (the children's own arcs stay)."""
    def place(p: str) -> str:
        child = _owner(p)
        return moved[child] + p[len(child):] if child in moved else p
    arcs = []
    for a in net.arcs:
        if _owner(a.target) == name and a.target in net.transition_index:
            a = a._replace(source=place(a.source))
        elif _owner(a.source) == name and a.source in net.transition_index:
            a = a._replace(target=place(a.target))
        arcs.append(a)
    return rebuilt(net, arcs=arcs)


@mutation("slots reordered, net too", net=True)
def _slots_both(cert, net, rng):
    found = [(key, k) for key, k in _structure_nodes(cert, rng, 2)
             if len(_children(cert["trees"][key], k)) >= 2]
    if not found:
        return None
    key, k = rng.choice(found)
    nodes = cert["trees"][key]
    node, kids = nodes[k], [nodes[c]["instance"] for c in _children(nodes, k)]
    slots = list(node["slots"])
    new = list(slots)
    while new == slots:
        rng.shuffle(new)
    # the child that filled slot s is now where s is listed: the structure's arcs move
    # from each child's places to those of the child the new order gives that slot
    filled = dict(zip(slots, kids))
    moved = {filled[s]: kid for s, kid in zip(new, kids) if s in filled}
    changed = _arcs_moved(net, node["instance"], moved)
    if changed is None:
        return None
    node["slots"] = new
    return cert, changed


@mutation("children reordered, net too", net=True)
def _children_both(cert, net, rng):
    """The children listed in another order (parents remapped) and the structure's arcs
    moved to match: the same net read with the slots filled otherwise."""
    found = [(key, k) for key, k in _structure_nodes(cert, rng, 2)
             if len(_children(cert["trees"][key], k)) >= 2]
    if not found:
        return None
    key, k = rng.choice(found)
    nodes = cert["trees"][key]
    kids = _children(nodes, k)
    a, b = rng.sample(range(len(kids)), 2)
    # swap the two whole subtrees' places in the list: swap the nodes' positions by
    # re-listing in pre-order with the two children exchanged
    swap = {kids[a]: kids[b], kids[b]: kids[a]}
    order: list[int] = []

    def visit(j: int) -> None:
        order.append(j)
        for c in _children(nodes, j):
            visit(swap.get(c, c) if j == k else c)
    for r in [j for j, n in enumerate(nodes) if n.get("parent", -1) == -1]:
        visit(r)
    order += [j for j in range(len(nodes)) if j not in order]
    names = {nodes[kids[a]]["instance"]: nodes[kids[b]]["instance"],
             nodes[kids[b]]["instance"]: nodes[kids[a]]["instance"]}
    changed = _arcs_moved(net, nodes[k]["instance"], names)
    if changed is None:
        return None
    _replace_tree(cert, nodes, _reordered(nodes, order))
    return cert, changed


@mutation("start emptied, mission.B's token taken", net=True)
def _start_emptied(cert, net, rng):
    how = rng.randrange(3)
    initial = {p: n for p, n in net.initial.items() if p != "mission.B"}
    if how == 0:
        cert["start"] = []
        initial.pop("mission.A", None)
    elif how == 1:              # the abort alone
        cert["start"] = ["mission.A"]
        initial["mission.A"] = 1
    else:
        cert["start"] = [s for s in cert.get("start", []) if s != "mission.B"]
        if rng.random() < 0.5 and isinstance(cert.get("conclusion"), dict):
            cert["conclusion"]["ends"] = []
    return cert, net.with_initial(initial)


@mutation("abort pending added, net too", net=True)
def _abort_added(cert, net, rng):
    if "mission.A" in net.initial:
        return None
    cert["start"] = ["mission.B", "mission.A"]
    if isinstance(cert.get("conclusion"), dict) and rng.random() < 0.5:
        cert["conclusion"]["ends"] = [*cert["conclusion"].get("ends", []), "mission.ABORTED"]
    return cert, net.with_initial({**net.initial, "mission.A": 1})


@mutation("arc added", net=True)
def _arc_added(cert, net, rng):
    p, t = rng.choice(net.places).id, rng.choice(net.transitions).id
    arc = Arc(p, t) if rng.random() < 0.5 else Arc(t, p)
    if any({a.source, a.target} == {p, t} for a in net.arcs):
        return None
    return cert, rebuilt(net, arcs=(*net.arcs, arc))


@mutation("arc removed", net=True)
def _arc_removed(cert, net, rng):
    gone = rng.randrange(len(net.arcs))
    return cert, rebuilt(net, arcs=[a for k, a in enumerate(net.arcs) if k != gone])


@mutation("arc turned round", net=True)
def _arc_turned(cert, net, rng):
    a = rng.choice(net.arcs)
    if a.kind is ArcKind.READ or any((b.source, b.target) == (a.target, a.source)
                                     for b in net.arcs):
        return None
    return cert, rebuilt(net, arcs=[Arc(a.target, a.source, a.weight) if b == a else b
                                    for b in net.arcs])


@mutation("token added", net=True)
def _token_added(cert, net, rng):
    p = rng.choice(net.places).id
    return cert, net.with_initial({**net.initial, p: net.initial.get(p, 0) + 1})


@mutation("token taken", net=True)
def _token_taken(cert, net, rng):
    p = rng.choice(sorted(net.initial))
    return cert, net.with_initial({q: n for q, n in net.initial.items() if q != p})


@mutation("transition added", net=True)
def _transition_added(cert, net, rng):
    owner = _owner(rng.choice(net.transitions).id)
    extra = Transition(f"{owner}.extra")
    if extra.id in net.transition_index:
        return None
    arcs = list(net.arcs)
    if rng.random() < 0.7:      # fed by one of its instance's places, or by none
        own = [p.id for p in net.places if _owner(p.id) == owner] or [net.places[0].id]
        arcs.append(Arc(rng.choice(own), extra.id))
        arcs.append(Arc(extra.id, rng.choice(own)))
    return cert, rebuilt(net, arcs=arcs, transitions=(extra,))


def mutated(base: Base, names: list[str], rng: random.Random) -> tuple[Any, Net] | None:
    """``base`` changed by each mutation of ``names`` in turn (None: one did not apply),
    the certificate read back as JSON."""
    cert, net = base.cert(), base.net
    for name in names:
        if not isinstance(cert, dict):
            return None
        try:
            got = MUTATIONS[name](cert, net, rng)
        except (KeyError, TypeError, AttributeError, IndexError, ValueError, NetError):
            # an earlier mutation left nothing this one can hold (the mission's places
            # renamed away, say, before an abort is added to them)
            return None
        if got is None or got[1] is None:
            return None
        cert, net = got
    return json.loads(json.dumps(cert)), net


def seed_of(*parts: Any) -> int:
    """A seed that names its parts, the same in every run (``hash`` of a str is not)."""
    return zlib.crc32(repr(parts).encode())


# -- the campaign ------------------------------------------------------------------------------

@dataclass
class Tally:
    """What a campaign found: pairs tried, accepted, refused, accepted but wrong (with a
    reproducer each), too large to judge, and crashes of the checker."""

    pairs: int = 0
    accepted: int = 0
    refused: int = 0
    too_large: int = 0
    broken: list[str] = field(default_factory=list)
    crashes: list[str] = field(default_factory=list)
    accepted_pairs: list[tuple[Net, Any]] = field(default_factory=list)

    def summary(self) -> str:
        return (f"{self.pairs} mutated pairs: {self.accepted} accepted, {self.refused} "
                f"refused, {self.too_large} accepted but too large to explore, "
                f"{len(self.broken)} accepted though exploring disagrees, "
                f"{len(self.crashes)} crashes")

    def report(self, most: int = 3) -> str:
        shown = sorted(self.broken, key=len)[:most] + self.crashes[:most]
        return self.summary() + "".join("\n---\n" + s for s in shown)


def judge(tally: Tally, base: Base, names: list[str], cert: Any, net: Net) -> None:
    """One mutated pair checked and, if accepted, explored; the tally told."""
    tally.pairs += 1
    what = f"{' + '.join(names)} on a certificate {base.kind} of:\n{base.text}"
    try:
        problems = pipeline.check_certificate(net, cert)
    except Mcl2PnmlError:
        tally.refused += 1
        return
    except Exception as e:      # noqa: BLE001 - any other exception is what is looked for
        tally.crashes.append(f"crash {type(e).__name__}: {e}: {what}")
        return
    if not isinstance(problems, list) or not all(isinstance(p, str) for p in problems):
        tally.crashes.append(f"the checker said {problems!r}: {what}")
        return
    if problems:
        tally.refused += 1
        return
    tally.accepted += 1
    try:
        wrong = judged(net, cert)
    except TooLarge:
        tally.too_large += 1
        return
    if wrong is None:
        tally.accepted_pairs.append((net, cert))
    else:
        tally.broken.append(f"accepted, but exploring finds: {wrong}\nafter {what}")


def campaign(pool: list[Base], names: list[str] | None, pairs: int, seed: int,
             depth: int = 3) -> Tally:
    """``pairs`` mutated pairs from the bases of ``pool``: each mutation of ``names`` in
    turn (None: a chain of one to ``depth`` mutations drawn at random from all)."""
    rng = random.Random(seed)
    tally = Tally()
    every = sorted(MUTATIONS)
    attempts = 0
    # half the pairs from forged certificates: a mission that may never end is where a
    # certificate the checker reads otherwise than the net shows most
    forged_ones = [b for b in pool if b.kind == "forged"] or pool
    while tally.pairs < pairs and attempts < 20 * pairs:
        attempts += 1
        base = rng.choice(forged_ones) if rng.random() < 0.5 else rng.choice(pool)
        chain = names or [rng.choice(every) for _ in range(rng.randint(1, depth))]
        got = mutated(base, chain, random.Random(rng.random()))
        if got is not None:
            judge(tally, base, chain, *got)
    return tally
