"""Re-checking a certificate against a compiled PNML, trusting the net and the proofs,
never the certificate (docs/certificate.md, section 6).

:mod:`mcl2pnml.certify.certificate` claims that a net is made of proven
parts joined by the rules. This module checks the claim on the net alone,
in time linear in the net. The certificate only guides (it names the
instances, and the proof each is held to); every fact the verdict rests on
is computed here:

* the certificate is of its schema (:mod:`mcl2pnml.certify.form`), no
  larger than the net it describes, and read into a :class:`Model` (:func:`read`):
  one tree for the mission and one per function, each rooted at the node
  named as it and every node reached from the root once, names unique, a
  structure's children filling its template's slots in the template's
  order, a call naming a task or a function, the functions ordered callees
  first (a cycle refused: gates are then taken in one order), the start
  ``mission.B`` (and ``mission.A``, an abort pending);
* the net is exactly the union of the model's instances (:class:`_Layout`):
  each instance's own net is the own net of its proven part (a structure's
  template, a task's pattern with or without its time-out, a primitive, a
  call site with its locks; the library's, its digest the one in
  ``templates/proofs.json``), its nodes prefixed with the instance's name,
  and the places it shares being the ones the model says fill them (a
  structure's ``T1_B`` is its first child's ``B``, a call site's ``to.B``
  its callee's, its ``lock.k`` the k-th primitive of its task, a task's
  ``E`` its primitive's); every node of the net is one instance's own, once;
  no arc is missing and none is added; M0 is every part at rest, with the
  start marked and each function's gate free;
* the signatures (:func:`signatures`): what each node can do from B with no
  abort asked (end OK, FAIL, and whether it may run for ever instead),
  derived bottom-up, keyed by node, on the same model, from the proofs'
  results tables; no node's row a breach, a root that may run for ever only
  with an abort pending;
* every claim of the certificate (each node's results, the calls counted,
  the digests, the rules, the conclusion) is what was computed
  (:func:`_claims`): compared, never used.

The comparison with the net is of integers: every node numbered, an arc a
number, each part written for all its instances at once with numpy. Where
the net differs, it says what, instance by instance: the node or the arc
missing or added, the token misplaced.

What it trusts (docs/certificate.md, section 7): the proofs file (each entry
was checked against the contract by exploring the part, and ``python -m
mcl2pnml.certify.templates --update`` does it again), the library's parts
whose digests are in it (the reduced model the package's own), the argument
of the rules, and the net reader. Not the compiler: a net that differs from
its certificate by one arc is refused, naming the instance. Not the
certificate.
"""
from __future__ import annotations

import functools
from graphlib import CycleError, TopologicalSorter
from itertools import compress, count, repeat
from operator import is_not, itemgetter, not_
from typing import Any, NamedTuple

import numpy as np

from mcl2pnml.certify import form
from mcl2pnml.certify.templates import (CALL_SITE, SHARED_CALLEE, Proofs, current,
                                        results_key, shape, untrusted_reduced)
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.gcpause import without_gc
from mcl2pnml.core.net import ArcKind, Net
from mcl2pnml.core.payloads import MISSION
from mcl2pnml.language.library import default_library
from mcl2pnml.language.template_parser import CONTROL, TemplateKind

NORMAL = ArcKind.NORMAL

PRIMITIVE_ROLES = ("ON", "OFF", "E", "D", "S1", "S2")


@without_gc      # a million arcs: nothing cyclic to collect while they are read
def check_certificate(net: Net, cert: Any, proofs: dict[str, dict] | None = None, *,
          shaped: bool = False) -> list[str]:
    """Every way ``net`` departs from ``cert`` (none: the certificate holds for it), at most
    :data:`form.MAX_FAULTS` of each kind.

    Nothing the verdict rests on is taken from ``cert``: it is held to its schema, read
    into a :class:`Model` that must be a tree as the net's own places join it, and every
    fact it states (each node's results, the calls, the digests, the conclusion) is
    computed again and must be what it says (``shaped``: the caller held it to its schema
    already, :func:`mcl2pnml.pipeline.load_certificate`). ``proofs``: the proven parts to
    hold the instances to (default: the library in use,
    :func:`mcl2pnml.certify.templates.current`: the stored proofs, and a user's templates
    proven now)."""
    faults = [] if shaped else form.shape_faults(cert)
    if faults:
        return [f"the certificate is malformed: {f}" for f in faults]
    instances = len(cert["primitives"]) + len(cert["tasks"]) + sum(map(len,
                                                                       cert["trees"].values()))
    size = len(net.place_index) + len(net.transition_index)
    if instances > size:      # each instance has a node of its own: a padded certificate
        return [f"the certificate names {instances:,} instances, and the net has {size:,} "
                "nodes: every instance has nodes of its own"]
    proofs = proofs if proofs is not None else current()
    if not isinstance(proofs, Proofs):     # read from a file: the library in use has them
        proofs = Proofs(proofs, default_library())
    refused = untrusted_reduced(proofs.lib)
    if refused is not None:
        return [refused.message]
    model, problems = read(cert, proofs)
    if model is None:
        return _capped(problems)
    derived, faults = signatures(model, proofs)
    problems += [message for _, message in faults]
    if not faults:
        problems += _claims(cert, model, proofs, derived)
    layout = _Layout(net, _plans(model), set(form.start(model.pending)))
    return _capped(layout.check(proofs, problems))


def _capped(problems: list[str]) -> list[str]:
    """At most :data:`form.MAX_FAULTS` problems, and how many more: a hostile file may
    have a million."""
    more = len(problems) - form.MAX_FAULTS
    return problems[:form.MAX_FAULTS] + ([f"and {more} more"] if more > 0 else [])


class Signature(NamedTuple):
    """What a task, node or function can do from B with no abort asked: end in one of
    ``ends`` (OK, FAIL), and, if ``stuck``, run for ever instead until it is aborted;
    ``origin``: the node where running for ever comes from (its children cannot)."""

    ends: tuple[str, ...]
    stuck: bool
    origin: str | None = None


class Node(NamedTuple):
    """One instance of a tree, as the checker reads it: a call site of ``subject`` (a
    task or a function), or a structure of template ``subject`` whose slots its
    ``children`` fill in the template's order (indices into :attr:`Model.nodes`)."""

    name: str
    call: bool
    subject: str
    children: tuple[int, ...]
    tree: str


class Model(NamedTuple):
    """A certificate read and validated: what the checker reasons on. Every name is one
    instance's (unique); each tree is a tree (one root, named as the tree, every node
    reached from it once); each structure has one child per slot of its template; each
    call names a task or a function; the functions are ordered callees first (computed:
    a call cycle is refused); a task's primitives are the certificate's, one per slot of
    its pattern."""

    primitives: tuple[str, ...]
    tasks: dict[str, tuple[str, tuple[str, ...]]]     # name -> (subject, its primitives)
    nodes: tuple[Node, ...]
    roots: dict[str, int]           # MISSION and each function -> its root's index
    order: tuple[str, ...]          # MISSION's and the functions' trees, callees first
    uses: dict[str, int]            # a task's or function's call sites, counted
    pending: bool                   # mission.A marked at the start too
    slots: dict[str, tuple[str, ...]]   # each template used -> its slots, in order


class _Reader:
    """What :func:`read` gathers as it goes through a certificate: every problem, in the
    order met; the names given so far; each template's slots looked up once, as the kind
    it is used for; the tasks, the trees' nodes, their roots, calls and call counts."""

    def __init__(self, cert: dict[str, Any], proofs: dict[str, dict]):
        self.cert, self.proofs = cert, proofs
        self.lib = getattr(proofs, "lib", None) or default_library()
        self.functions = list(cert["functions"])
        self.problems: list[str] = []
        self.owner: dict[str, str] = {}
        self.slots_of: dict[tuple[str, TemplateKind], tuple[str, ...] | None] = {}
        self.tasks: dict[str, tuple[str, tuple[str, ...]]] = {}
        self.nodes: list[Node] = []
        self.roots: dict[str, int] = {}
        self.calls: dict[str, set[str]] = {}
        self.uses: dict[str, int] = {}

    def named(self, name: str, what: str) -> None:
        """``name`` given to ``what``: a problem if it was given before."""
        if name in self.owner:
            self.problems.append(f"the name '{name}' is given to {self.owner[name]} and to "
                                 f"{what}: every instance has its own")
        else:
            self.owner[name] = what

    def header(self) -> None:
        """The trees named as the mission and the functions, the start one of the two."""
        cert, functions = self.cert, self.functions
        if set(cert["trees"]) != {MISSION, *functions} or MISSION in functions:
            self.problems.append(f"the trees are {sorted(cert['trees'])}: they must be "
                                 f"'{MISSION}' and one for each function of 'functions' "
                                 f"{functions}")
        if cert["start"] not in (form.start(False), form.start(True)):
            self.problems.append(f"the start {cert['start']} is not {form.start(False)} or "
                                 f"{form.start(True)}: a mission starts at mission.B, an "
                                 "abort pending or not")

    def read_tasks(self) -> None:
        """Each task a proven pattern whose slots its primitives fill, in order."""
        cert = self.cert
        for name, task in cert["tasks"].items():
            self.named(name, f"task '{name}'")
            subject, pattern = task["subject"], task["pattern"]
            entry = self.proofs.get(subject) or {}
            key = (pattern, TemplateKind.PATTERN)
            if key not in self.slots_of:
                self.slots_of[key] = _slots(self.lib, *key)
            slots = self.slots_of[key]
            if entry.get("kind") != "pattern" or \
                    subject not in (pattern, f"{pattern} without a time-out") or slots is None:
                self.problems.append(f"task '{name}': '{subject}' is no proven pattern")
                continue
            prims = tuple(task["primitives"])
            if len(prims) != len(slots) or list(task["slots"]) != list(slots):
                self.problems.append(f"task '{name}': its pattern {pattern} has the primitive "
                                     f"slots {list(slots)}, filled by {list(prims)} as "
                                     f"{task['slots']}")
            unknown = [p for p in prims if p not in cert["primitives"]]
            if unknown:
                self.problems.append(f"task '{name}' uses {unknown[0]}, no primitive of the "
                                     "certificate")
            self.tasks[name] = (subject, prims)

    def tree_shape(self, tree: str, raw: list) -> tuple[list[list[int]], int] | None:
        """Each node's children and the root of ``tree``, or None (its problems said) if
        the parents do not make one tree rooted at the node named as it."""
        children: list[list[int]] = [[] for _ in raw]
        top = []
        for k, node in enumerate(raw):
            parent = int(node["parent"])    # JSON's 1.0 is the schema's integer 1
            if parent == -1:
                top.append(k)
            elif parent >= len(raw) or parent == k:
                self.problems.append(f"'{node['instance']}' of tree '{tree}': parent {parent} "
                                     "is no other node of the tree")
            else:
                children[parent].append(k)
        if len(top) != 1 or raw[top[0]]["instance"] != tree:
            self.problems.append(f"tree '{tree}' must have one root, named '{tree}': it has "
                                 f"{[raw[k]['instance'] for k in top] or 'none'}")
            return None
        reached, todo = [False] * len(raw), [top[0]]
        while todo:
            k = todo.pop()
            reached[k] = True
            todo.extend(children[k])
        if not all(reached):
            stray = next(raw[k]["instance"] for k in range(len(raw)) if not reached[k])
            self.problems.append(f"'{stray}' of tree '{tree}' is not reached from its root: "
                                 "the parents make a cycle")
            return None
        return children, top[0]

    def read_tree(self, tree: str) -> None:
        """The nodes of ``tree``: each call a task or a function, each structure a proven
        template whose slots its children fill, in order."""
        raw, base = self.cert["trees"][tree], len(self.nodes)
        shaped = self.tree_shape(tree, raw)
        if shaped is None:
            return
        children, root = shaped
        self.roots[tree] = base + root
        self.calls[tree] = set()
        for k, node in enumerate(raw):
            name = node["instance"]
            self.named(name, f"a node of tree '{tree}'")
            if node["rule"] == "call":
                self.call(tree, name, node["callee"], children[k])
                continue
            template = node["template"]
            key = (template, TemplateKind.STRUCTURE)
            if key not in self.slots_of:
                self.slots_of[key] = _slots(self.lib, *key) \
                    if (self.proofs.get(template) or {}).get("kind") == "structure" else None
            slots = self.slots_of[key]
            if slots is None:
                self.problems.append(f"'{name}': '{template}' is no proven structure")
            elif len(children[k]) != len(slots) or list(node["slots"]) != list(slots):
                self.problems.append(
                    f"'{name}' ({template}) has {len(children[k])} children and the slots "
                    f"{node['slots']}; the template has the slots {list(slots)}, each filled "
                    "by one child, in order")
            self.nodes.append(Node(name, False, template,
                                   tuple(base + c for c in children[k]), tree))

    def call(self, tree: str, name: str, callee: str, children: list[int]) -> None:
        """Call site ``name`` of ``tree``: a leaf naming a task or a function, counted."""
        if children:
            self.problems.append(f"call '{name}' has children: a call site has none")
        if callee not in self.tasks and callee not in self.functions:
            self.problems.append(f"'{name}' calls '{callee}', no task or function of the "
                                 "certificate")
        elif callee in self.functions:
            self.calls[tree].add(callee)
        self.uses[callee] = self.uses.get(callee, 0) + 1
        self.nodes.append(Node(name, True, callee, (), tree))

    def call_order(self) -> tuple[str, ...]:
        """The trees callees first; a cycle of calls a problem (and no order)."""
        try:
            return tuple(TopologicalSorter(self.calls).static_order())
        except CycleError as e:
            cycle = " -> ".join(e.args[1])
            self.problems.append(f"the functions call each other in a cycle ({cycle}): gates "
                                 "could be taken out of order, and the argument needs none")
            return ()


def read(cert: dict[str, Any], proofs: dict[str, dict]) -> tuple[Model | None, list[str]]:
    """``cert`` (of the schema's shape) as a :class:`Model`, or None and every reason it
    is not one."""
    r = _Reader(cert, proofs)
    r.header()
    primitives = tuple(cert["primitives"])
    for p in primitives:
        r.named(p, f"primitive '{p}'")
    r.read_tasks()
    # a primitive is proven idle at rest only inside the proof of a task that uses it
    used = {p for _, prims in r.tasks.values() for p in prims}
    r.problems += [f"primitive '{p}' is used by no task: no proof covers it alone"
                   for p in primitives if p not in used]
    for tree in (t for t in cert["trees"] if t == MISSION or t in r.functions):
        r.read_tree(tree)
    order = r.call_order()
    if r.problems:
        return None, r.problems
    return Model(primitives, r.tasks, tuple(r.nodes), r.roots, order, r.uses,
                 cert["start"] == form.start(True),
                 {t: slots for (t, _), slots in r.slots_of.items() if slots is not None}), []


def _slots(lib, name: str, kind: TemplateKind) -> tuple[str, ...] | None:
    """The slots of template ``name`` in the library, if it is of ``kind``: a pattern's
    primitive slots, a structure's children's (None: no such template)."""
    try:
        t = lib.get(name)
    except Mcl2PnmlError:
        return None
    if t.kind is not kind:
        return None
    return tuple(t.primitives if kind is TemplateKind.PATTERN else t.children)


def results(cert: dict[str, Any], proofs: dict[str, dict]
            ) -> tuple[dict[str, Signature], list[tuple[str, str]]]:
    """The signature of each task, node and function of ``cert`` by name, and the faults
    (:func:`signatures`); a certificate that is no :class:`Model` is all faults."""
    model, problems = read(cert, proofs)
    if model is None:
        return {}, [(MISSION, p) for p in problems]
    return signatures(model, proofs)


def signatures(model: Model, proofs: dict[str, dict]
               ) -> tuple[dict[str, Signature], list[tuple[str, str]]]:
    """The signature of each task, node and function of ``model`` (by name: names are
    unique), derived bottom-up from the proofs' results tables; and the faults, each
    (instance, what is wrong): a node whose row is a breach (with its children doing what
    they do, the structure breaks the contract in a way no reduced model stands for), or
    that no row covers. Tasks first, then each tree after the functions it calls, each
    node after its children: an order computed from the model, not read."""
    by_node: list[Signature | None] = [None] * len(model.nodes)
    tasks: dict[str, Signature] = {}
    faults: list[tuple[str, str]] = []
    # a long mission asks the same few rows again and again: each read once
    rows: dict[tuple, tuple[str, dict | None]] = {}

    def row(subject: str, below: list[Signature], what: str, name: str,
            slots=("the callee",)) -> Signature | None:
        shape = (subject, *((b.ends, b.stuck) for b in below))
        if shape not in rows:
            key = results_key([(frozenset(b.ends), b.stuck) for b in below])
            rows[shape] = key, (proofs.get(subject) or {}).get("results", {}).get(key)
        key, entry = rows[shape]
        if entry is None:
            faults.append((name, f"{what}: no proof of {subject} covers its children's "
                                 f"signatures {key or '(none)'}"))
            return None
        if "ends" not in entry:
            faults.append((name, f"{what}: with {_said(below, slots)}, the {subject} breaks "
                                 f"the contract ({entry.get('breach')})"))
            return None
        stuck = bool(entry.get("stuck"))
        return Signature(tuple(entry["ends"]), stuck,
                         next((b.origin for b in below if b.stuck), name) if stuck else None)

    for name, (subject, _) in model.tasks.items():
        got = row(subject, [], f"task '{name}'", name)
        if got is not None:
            tasks[name] = got
    nodes = model.nodes
    for tree in (*(t for t in model.order if t != MISSION), MISSION):
        post: list[int] = []
        todo = [model.roots[tree]]
        while todo:          # pre-order, reversed: every node after its children
            k = todo.pop()
            post.append(k)
            todo.extend(nodes[k].children)
        for k in reversed(post):
            node = nodes[k]
            if node.call:
                callee = (tasks.get(node.subject) if node.subject in model.tasks
                          else by_node[model.roots[node.subject]])
                if callee is None:
                    continue
                got = row(CALL_SITE, [callee], f"call '{node.name}'", node.name)
                if model.uses[node.subject] > 1:
                    row(SHARED_CALLEE, [callee], f"call '{node.name}'", node.name)
            else:
                below = [by_node[c] for c in node.children]
                if any(b is None for b in below):
                    continue
                got = row(node.subject, below, f"'{node.name}' ({node.subject})", node.name,
                          model.slots[node.subject])
            by_node[k] = got
    out = dict(tasks)
    out.update((node.name, sig) for node, sig in zip(nodes, by_node) if sig is not None)
    return out, faults


def root_ends(root: Signature, pending: bool) -> list[str] | None:
    """The ends a certificate concludes for a root of signature ``root``, started with an
    abort ``pending`` or not; None when it may run for ever and no abort is pending."""
    if root.stuck and not pending:
        return None
    return [f"{MISSION}.{r}" for r in root.ends] + ([f"{MISSION}.ABORTED"] if pending else [])


def _said(below: list[Signature], slots) -> str:
    """The children's signatures in words, slot by slot: "T1 ending only OK, T2 ending
    OK or FAIL or running for ever"."""
    def one(sig: Signature) -> str:
        said = ("only " if len(sig.ends) == 1 and not sig.stuck else "") + " or ".join(sig.ends)
        if sig.stuck:
            said = f"{said} or running for ever" if sig.ends else "running for ever"
        return f"ending {said}" if sig.ends else said
    return ", ".join(f"{slot} {one(sig)}" for slot, sig in zip(slots, below))


def said_signature(sig: Signature) -> dict[str, Any]:
    """What a certificate says a node can do."""
    return {"results": list(sig.ends), **({"may run for ever": True} if sig.stuck else {})}


def _claims(cert: dict[str, Any], model: Model, proofs: dict[str, dict],
            derived: dict[str, Signature]) -> list[str]:
    """Every fact ``cert`` states that is not what the checker computes: the proofs'
    digests, each part's own digest, each node's results, the calls counted, the
    conclusion. None of them is used: a certificate that says them wrong is refused,
    never half believed."""
    problems = []
    digests = {name: p["digest"] for name, p in sorted(proofs.items()) if "digest" in p}
    if cert["proofs"] != digests:
        other = sorted(k for k in digests.keys() | cert["proofs"].keys()
                       if digests.get(k) != cert["proofs"].get(k))
        problems.append(f"the certificate's proofs are not the library's in use (they differ "
                        f"for {', '.join(other[:5])}): it was made with other templates")
    if cert["rules"] != form.RULES or cert["side_conditions"] != form.SIDE_CONDITIONS:
        problems.append("the rules or the side conditions are not this checker's")
    local = {name: p.get("local") for name, p in proofs.items()}
    for p in model.primitives:
        if cert["primitives"][p]["local"] != local.get("primitive"):
            problems.append(f"primitive '{p}': its own digest is not the proven primitive's")
    for name, (subject, _) in model.tasks.items():
        task = cert["tasks"][name]
        if task["proof"] != digests.get(subject) or task["local"] != local.get(subject):
            problems.append(f"task '{name}': its digests are not those of {subject}'s proof")
        if name in derived and said_signature(derived[name]) != _said_of(task):
            problems.append(f"task '{name}' is said to end {_said_of(task)}; its proof says "
                            f"{said_signature(derived[name])}")
    for tree, raw in cert["trees"].items():
        for node in raw:
            name = node["instance"]
            if node["rule"] == "structure" and node["local"] != local.get(node["template"]):
                problems.append(f"'{name}': its own digest is not {node['template']}'s")
            if name in derived and said_signature(derived[name]) != _said_of(node):
                problems.append(f"'{name}' is said to end {_said_of(node)}; derived from its "
                                f"parts it ends {said_signature(derived[name])}")
    if cert["calls"] != model.uses:
        problems.append(f"the calls counted are {model.uses}, not {cert['calls']}")
    if MISSION not in derived:      # never a certificate that holds with nothing said
        problems.append(f"the root '{MISSION}' has no signature derived from its parts")
    else:
        ends = root_ends(derived[MISSION], model.pending)
        if ends is None:
            problems.append(f"{MISSION} may run for ever (from '{derived[MISSION].origin}'), "
                            "and no abort is pending at the start")
        elif cert["conclusion"] != form.conclusion(ends, model.pending):
            problems.append(f"the conclusion is not the one derived from the parts: ends "
                            f"{cert['conclusion']['ends']}, derived {ends}")
    return problems


def _said_of(node: dict[str, Any]) -> dict[str, Any]:
    return {"results": list(node["results"]),
            **({"may run for ever": True} if node.get("may run for ever") else {})}


def _owners(ids: list[str], names: set[str] | dict) -> list[str | None]:
    """Each node's instance: the longest instance name followed by a dot that starts its
    id (None: no instance's)."""
    # the longest candidate is nearly always the one: found for every node by loops in C
    out: list[str | None] = list(map(itemgetter(0), map(str.rpartition, ids, repeat("."))))
    for k in compress(count(), map(not_, map(names.__contains__, out))):
        node_id, i, out[k] = ids[k], len(out[k]), None
        while i > 0:
            i = node_id.rfind(".", 0, i)
            if i > 0 and node_id[:i] in names:
                out[k] = node_id[:i]
                break
    return out


class _Plan(NamedTuple):
    """Where one instance of the certificate sits in the net: the proven part it must be
    (``subject``), and the places it shares: each slot place of the template with the
    net's place that fills it (a structure's ``T1_B``: its first child's ``B``; ...)."""

    name: str
    subject: str
    fills: dict[str, str]
    gate: str | None          # a function's gate: a place of its root, the call sites' arcs


def _plans(model: Model) -> dict[str, _Plan]:
    """Every instance of ``model``, primitives, tasks and tree nodes, placed: the slots
    each fills are the model's, the same the signatures were derived on."""
    plans = {p: _Plan(p, "primitive", {}, None) for p in model.primitives}
    for name, (subject, prims) in model.tasks.items():
        fills = {}
        for slot, prim in zip(model.slots[subject.removesuffix(" without a time-out")],
                              prims):
            fills.update({(f"{slot}_{r}" if slot else r): f"{prim}.{r}"
                          for r in PRIMITIVE_ROLES})
        plans[name] = _Plan(name, subject, fills, None)
    site = tuple(p for p in ("GATE", *CONTROL) if p != "MTX")
    site_slots, site_ends = tuple(f"to.{p}" for p in site), tuple(f".{p}" for p in site)
    ends = tuple(f".{p}" for p in CONTROL)
    slot_places: dict[str, tuple[str, ...]] = {}      # T1 -> T1_B, T1_A, ...
    gates = {model.roots[t] for t in model.roots if t != MISSION}
    sites: dict[str, tuple[str, dict[str, str]]] = {}
    nodes = model.nodes
    for k, node in enumerate(nodes):
        name = node.name
        if node.call:
            callee = node.subject
            if callee not in sites:      # every site of one callee shares the same places
                prims = sorted(set(model.tasks[callee][1])) if callee in model.tasks else []
                fills = dict(zip(site_slots, map(callee.__add__, site_ends)))
                fills.update({f"lock.{k}": f"{p}.LOCK" for k, p in enumerate(prims, 1)})
                sites[callee] = f"{CALL_SITE}/{len(prims)}", fills
            subject, fills = sites[callee]
        else:
            subject, fills = node.subject, {}
            for slot, child in zip(model.slots[subject], node.children):
                if slot not in slot_places:
                    slot_places[slot] = tuple(f"{slot}_{p}" for p in CONTROL)
                fills.update(zip(slot_places[slot], map(nodes[child].name.__add__, ends)))
        plans[name] = _Plan(name, subject, fills, f"{name}.GATE" if k in gates else None)
    return plans


class _Template(NamedTuple):
    """A proven part's own net in its template's ids: its nodes in one order (own places,
    shared places, transitions), its arcs as pairs of positions in that order, so that
    every instance's arcs are written at once, in numbers."""

    own: tuple[str, ...]                    # places of the part itself
    slots: tuple[str, ...]                  # places it shares: a child's, a callee's, a lock
    transitions: tuple[str, ...]
    sources: tuple[int, ...]                # arc k joins sources[k] to targets[k]
    targets: tuple[int, ...]
    unusual: dict[tuple[int, int], tuple[int, ArcKind]]    # arcs of a weight > 1, or read
    marked: tuple[tuple[int, int], ...]     # (own place, tokens) at rest

    @property
    def nodes(self) -> tuple[str, ...]:
        return self.own + self.slots + self.transitions

    @classmethod
    def of(cls, net: Net, slots: frozenset[str]) -> "_Template":
        """The template of a part from its own net and the places it shares."""
        own = tuple(p.id for p in net.places if p.id not in slots)
        shared = tuple(p.id for p in net.places if p.id in slots)
        transitions = tuple(t.id for t in net.transitions)
        at = {x: k for k, x in enumerate(own + shared + transitions)}
        return cls(own, shared, transitions, tuple(at[a.source] for a in net.arcs),
                   tuple(at[a.target] for a in net.arcs),
                   {(at[a.source], at[a.target]): (a.weight, a.kind) for a in net.arcs
                    if a.weight != 1 or a.kind is not NORMAL},
                   tuple((at[p], net.initial[p]) for p in own if net.initial[p]))


class _Layout:
    """The net, and the net the certificate describes, in the net's node numbers (places
    first, then transitions); an arc is the number ``source * size + target``.

    Renaming every instance back to its template would cost several Python steps per
    arc, a million arcs for 10,000 calls. So the other way round: each proven part's own
    net, whose digest is the proof's, is written for all the part's instances at once in
    numbers (a matrix, instance by node: :meth:`_write`), and the net must be exactly
    their union (:meth:`_holds`): each node some instance's own, once; each arc one some
    instance has; each marking its part's at rest. The comparisons are of integers, in
    numpy; only on a net that does not hold is it walked again, to say where
    (:meth:`_differences`)."""

    def __init__(self, net: Net, plans: dict[str, _Plan], start: set[str]) -> None:
        self.net, self.plans, self.start = net, plans, start
        self.ids = [*net.place_index, *net.transition_index]
        self.places, self.size = len(net.place_index), len(self.ids)
        self.number = dict(zip(self.ids, count()))
        self.batches: list[tuple[_Template, list[_Plan], np.ndarray]] = []

    @functools.cached_property
    def owner(self) -> list[str | None]:
        """Each node's instance, by its id (:func:`_owners`)."""
        return _owners(self.ids, self.plans)

    def check(self, proofs: Proofs, problems: list[str]) -> list[str]:
        """The ``problems`` found already, and where the net is not its instances, each
        the own net of its proven part."""
        problems = list(problems)
        by_subject: dict[str, list[_Plan]] = {}
        for plan in self.plans.values():
            by_subject.setdefault(plan.subject, []).append(plan)
        uncovered: set[str] = set()
        for subject, group in by_subject.items():
            template = self._template(proofs, subject)
            if template is None:
                problems += [f"'{plan.name}' is a {subject}, which no stored proof covers"
                             for plan in group]
                uncovered.update(plan.name for plan in group)
            else:
                problems += self._write(template, group)
        if not self._holds():
            found = self.nodes_of_no_instance() + self._differences(uncovered)
            # never a net that does not hold with nothing said
            problems = found + problems if found or problems else [
                "the net is not its instances' proven parts joined as the certificate says"]
        return problems

    @staticmethod
    def _template(proofs: Proofs, subject: str) -> _Template | None:
        """The template of ``subject``: its own net, if its digest is the proven one."""
        entry = proofs.get(subject)
        if entry is None or "local" not in entry:
            return None
        try:
            own, slots = proofs.own(subject)
        except (Mcl2PnmlError, ValueError):      # a part the library does not have
            return None
        return _Template.of(own, slots) if shape(own, slots) == entry["local"] else None

    def nodes_of_no_instance(self) -> list[str]:
        """The instances with no node in the net; the nodes of no instance."""
        out = [f"instance '{name}' of the certificate has no node in the net"
               for name in sorted(self.plans.keys() - set(self.owner))]
        if None in self.owner:
            out += [f"'{node}' belongs to no instance of the certificate"
                    for node, inst in zip(self.ids, self.owner) if inst is None]
        return out

    def _write(self, template: _Template, group: list[_Plan]) -> list[str]:
        """The instances of one part, written from its ``template``: a row of node numbers
        each (-1: no such node in the net)."""
        if not group:
            return []
        problems = []
        own, slots, transitions = template.own, template.slots, template.transitions
        wanted = set(slots)
        for plan in group:     # (a structure with fewer children has no proof either)
            if not wanted <= plan.fills.keys():
                problems.append(f"'{plan.name}' leaves its slot "
                                f"'{min(wanted - plan.fills.keys())}' unfilled")
        prefixes = [plan.name + "." for plan in group]
        rows = np.empty((len(group), len(template.nodes)), dtype=np.int64)
        rows[:, :len(own)] = self._numbers([p + x for p in prefixes for x in own], len(group))
        rows[:, len(own):len(own) + len(slots)] = self._numbers(
            [plan.fills.get(s, "") for plan in group for s in slots],
            len(group))
        rows[:, len(own) + len(slots):] = self._numbers(
            [p + t for p in prefixes for t in transitions], len(group))
        self.batches.append((template, group, rows))
        return problems

    def _numbers(self, nodes: list[str], instances: int) -> np.ndarray:
        """The numbers of ``nodes`` (-1: not in the net), as ``instances`` rows."""
        if not nodes:
            return np.empty((instances, 0), dtype=np.int64)
        try:     # one C call for all of them; a node missing is rare, and said later
            found = itemgetter(*nodes)(self.number)
        except KeyError:
            found = [self.number.get(node, -1) for node in nodes]
        return np.array(found, dtype=np.int64).reshape(instances, -1)

    def _holds(self) -> bool:
        """Whether the net is exactly the instances :meth:`_write` wrote."""
        owned = []
        size = self.size
        for template, group, rows in self.batches:
            if (rows < 0).any():
                return False
            ordered = np.sort(rows, axis=1)     # one instance's nodes: all distinct
            if (ordered[:, 1:] == ordered[:, :-1]).any():
                return False
            own, shared = len(template.own), len(template.own) + len(template.slots)
            # places where the part has places, transitions where it has transitions
            if (rows[:, :shared] >= self.places).any() or (rows[:, shared:] < self.places).any():
                return False
            owned += [rows[:, :own].ravel(), rows[:, shared:].ravel()]
            gates = [self.number.get(plan.gate, -1) for plan in group if plan.gate]
            if any(not 0 <= gate < self.places for gate in gates):
                return False
            owned.append(np.array(gates, dtype=np.int64))
        owned_all = np.concatenate(owned) if owned else np.empty(0, dtype=np.int64)
        if owned_all.size != size or (size and np.bincount(owned_all, minlength=size).max() > 1):
            return False
        net_arcs, net_unusual = self._net_arcs
        expected, unusual, marked = self._expected()
        if expected.size != net_arcs.size or \
                not np.array_equal(np.sort(expected), np.sort(net_arcs)):
            return False
        return net_unusual == unusual and self._marking() == self._marked(marked)

    def _expected(self) -> tuple[np.ndarray, dict[int, tuple[int, ArcKind]], dict[int, int]]:
        """The arcs the instances :meth:`_write` wrote have, those of a weight > 1 or not
        normal, and the tokens of their parts at rest and of the gates (an instance with a
        node not in the net aside: it has no arcs to write)."""
        arcs, unusual, marked = [], {}, {}
        size = self.size
        for template, group, rows in self.batches:
            whole = (rows >= 0).all(axis=1)
            rows = rows[whole]
            arcs.append((rows[:, template.sources] * size + rows[:, template.targets]).ravel())
            for (s, t), how in template.unusual.items():
                unusual.update(dict.fromkeys((rows[:, s] * size + rows[:, t]).tolist(), how))
            for x, tokens in template.marked:
                marked.update(dict.fromkeys(rows[:, x].tolist(), tokens))
            gates = (self.number.get(plan.gate, -1) for plan in group if plan.gate)
            marked.update(dict.fromkeys((g for g in gates if 0 <= g < self.places), 1))
        return (np.concatenate(arcs) if arcs else np.empty(0, dtype=np.int64)), unusual, marked

    @functools.cached_property
    def _net_arcs(self) -> tuple[np.ndarray, dict[int, tuple[int, ArcKind]]]:
        """The net's arcs in numbers, and those of a weight > 1 or not normal (loops in C)."""
        if not self.net.arcs:
            return np.empty(0, dtype=np.int64), {}
        sources, targets, weights, kinds = self.net.columns
        # two million look-ups: itemgetter makes them in one C call each
        number = self.number
        arcs = (np.array(itemgetter(*sources)(number), dtype=np.int64).reshape(-1) * self.size
                + np.array(itemgetter(*targets)(number), dtype=np.int64).reshape(-1))
        odd = set(compress(count(), map(is_not, kinds, repeat(NORMAL))))
        if max(weights) > 1:
            odd.update(compress(count(), map(int(1).__lt__, weights)))
        return arcs, {int(arcs[k]): (weights[k], kinds[k]) for k in odd}

    def _marking(self) -> dict[int, int]:
        """M0 in numbers."""
        initial = self.net.initial
        return {self.number[p]: initial[p] for p in initial}

    def _marked(self, marked: dict[int, int]) -> dict[int, int]:
        """The marking the certificate says, ``marked`` (every part at rest), and its
        start."""
        out = dict(marked)
        for which in ("B", "A"):
            k = self.number.get(f"{MISSION}.{which}")
            if k is not None:
                out.pop(k, None)
                if f"{MISSION}.{which}" in self.start:
                    out[k] = 1
        return out

    def _differences(self, uncovered: set[str]) -> list[str]:
        """Where the net is not the instances, said instance by instance (nodes of no
        instance, an instance with no node or whose part no proof covers, said already,
        aside). Only on a net that does not hold: its cost does not matter."""
        found = _Differences(self, uncovered | (self.plans.keys() - set(self.owner)))
        found.nodes()
        written, unusual, marked = self._expected()
        found.arcs(self._net_arcs, written, unusual)
        found.marking(self._marking(), self._marked(marked))
        return found.said_all()


class _Differences:
    """What :meth:`_Layout._differences` finds, as it goes: problems said on their own, in
    the order met; per instance, what differs in it; each node's claimant (the instance
    it is written for) and each instance's nodes given by the certificate."""

    def __init__(self, layout: _Layout, left_out: set[str]):
        self.layout, self.left_out = layout, left_out
        self.problems: list[str] = []
        self.differ: dict[str, list[str]] = {}
        self.claimed: dict[int, str] = {}      # node -> the instance it is written for
        self.given: dict[str, set[str]] = {}

    def said(self, inst: str | None, what: str) -> None:
        if inst is not None and inst not in self.left_out:
            self.differ.setdefault(inst, []).append(what)

    def kind(self, k: int) -> str:
        return "place" if k < self.layout.places else "transition"

    def claim(self, at: int, node: str, name: str) -> bool:
        """``node``, number ``at``, written for ``name``: unless another has it."""
        if at in self.claimed:
            self.problems.append(f"'{node}' is a {self.kind(at)} of both '{self.claimed[at]}' "
                                 f"and '{name}'")
            return False
        self.claimed[at] = name
        return True

    def nodes(self) -> None:
        """Each instance's nodes where its part has them, of the part's kinds, each the
        instance's alone; then the nodes no instance's part has."""
        layout = self.layout
        places = layout.places
        for template, group, rows in layout.batches:
            for plan, row in zip(group, rows.tolist()):
                name, fills = plan.name, plan.fills
                self.given[name] = {f"{name}.{x}" for x in template.own} | set(fills.values())
                for k, (x, at) in enumerate(zip(template.nodes, row)):
                    shared = x in template.slots
                    node = fills.get(x, "(none)") if shared else f"{name}.{x}"
                    is_place = k < len(template.own) + len(template.slots)
                    if at < 0:
                        self.said(name, f"it has no {'place' if is_place else 'transition'} "
                                        f"'{node}'")
                    elif shared:
                        if at >= places:
                            self.said(name, f"it shares '{node}', which is not a place")
                    elif self.claim(at, node, name) and (at < places) != is_place:
                        self.said(name, f"its {self.kind(at)} '{node}' is a "
                                        f"{'transition' if is_place else 'place'} of the part")
                if plan.gate is not None:
                    gate = layout.number.get(plan.gate, -1)
                    if gate < 0 or gate >= places:
                        self.said(name, f"it has no gate '{plan.gate}'")
                    else:
                        self.claim(gate, plan.gate, name)
                    self.given[name].add(plan.gate)
        for k in sorted(set(range(layout.size)) - self.claimed.keys()):
            self.said(layout.owner[k], f"it has a {self.kind(k)} '{layout.ids[k]}' the proven "
                                       "part has not")

    def arcs(self, in_the_net: tuple[np.ndarray, dict[int, tuple[int, ArcKind]]],
             written: np.ndarray, unusual: dict[int, tuple[int, ArcKind]]) -> None:
        """The arcs the net has (``in_the_net``: all, and those of a weight > 1 or not
        normal) and the parts have not (``written``, ``unusual``), and the other way round;
        those of both whose weight or kind differ."""
        layout = self.layout
        ids, owner, size, places = layout.ids, layout.owner, layout.size, layout.places
        net_arcs, net_unusual = in_the_net
        in_net = set(net_arcs.tolist())
        arcs = set(written.tolist())

        def ends(key: int) -> tuple[str, str, int]:
            s, t = divmod(key, size)
            return ids[s], ids[t], t if t >= places else s

        for key in sorted(in_net - arcs):
            s, t, transition = ends(key)
            inst = owner[transition]
            place = t if ids[transition] == s else s
            if inst in self.given and place not in self.given[inst]:
                self.said(inst, f"it has an arc with '{place}', which the certificate does "
                                "not give it")
            else:
                self.said(inst, f"it has an arc {s} -> {t} the proven part has not")
        for key in sorted(arcs - in_net):
            s, t, transition = ends(key)
            self.said(owner[transition], f"it has no arc {s} -> {t}")
        for key in sorted((net_unusual.keys() | unusual.keys()) & in_net & arcs):
            if net_unusual.get(key, (1, NORMAL)) != unusual.get(key, (1, NORMAL)):
                s, t, transition = ends(key)
                self.said(owner[transition], f"its arc {s} -> {t} is not of the part's weight "
                                             "and kind")

    def marking(self, marking: dict[int, int], expected: dict[int, int]) -> None:
        """M0 (``marking``) against every part at rest, the start marked and each gate free
        (``expected``)."""
        layout = self.layout
        for k in sorted(marking.keys() | expected.keys()):
            n, m = marking.get(k, 0), expected.get(k, 0)
            if n == m or k not in self.claimed:
                continue
            place = layout.ids[k]
            if layout.plans[self.claimed[k]].gate == place:
                self.problems.append(f"the gate '{place}' is not free in M0")
            elif place in (f"{MISSION}.B", f"{MISSION}.A"):
                self.problems.append(
                    f"M0 {'marks' if n else 'does not mark'} {place}; the certificate starts "
                    f"from {', '.join(sorted(layout.start))}")
            else:
                self.said(self.claimed[k], f"M0 puts {n} on '{place}', where the proven part "
                                           f"at rest has {m}")

    def said_all(self) -> list[str]:
        """The problems, then one line per instance that differs (its first three ways)."""
        problems = list(self.problems)
        for inst, whats in self.differ.items():
            more = f"; and {len(whats) - 3} more" if len(whats) > 3 else ""
            problems.append(f"'{inst}' is not the proven {self.layout.plans[inst].subject}: "
                            + "; ".join(whats[:3]) + more)
        return problems
