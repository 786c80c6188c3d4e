"""Re-checking a certificate against a compiled PNML, without trusting the compiler.

:mod:`mcl2pnml.certify.certificate` claims that a net is made of proven
parts joined by the rules. This module checks the claim on the net alone,
in one pass over its nodes and arcs:

* every node of the net belongs to one instance of the certificate's tree
  (by its id's prefix: the longest instance name that starts it), and every
  instance is there;
* each instance's own net (its transitions, their arcs, its places, and the
  places it shares, renamed to the slots the tree says they fill: a
  structure's ``T1_B`` is its first child's ``B``, a call site's ``to.B`` its
  callee's, its ``lock.k`` the k-th primitive of its task, a task's ``E``
  its primitive's) has the digest of the part proven in
  ``templates/proofs.json``: a structure's template, a task's pattern with
  or without its time-out, a primitive, a call site with its locks;
* the signatures: what each node can do from B with no abort asked (end
  OK, FAIL, and whether it may run for ever instead), derived bottom-up
  from the proofs' results tables (a task's from its pattern's, a call's
  from its callee's, a structure's from its children's), no node's row a
  breach, a root that may run for ever only with an abort pending, and the
  conclusion's ends the root's;
* the side conditions: functions call only functions before them (no
  recursion, so gates are taken in one order); a call site of a task takes
  exactly its primitives' locks (the renaming allows no other); a place a
  part shares is one the tree gives it; M0 is every part at rest with
  ``mission.B`` marked.

What it trusts: the proofs file (each entry was checked against the contract
by exploring the part, and ``python -m mcl2pnml.certify.templates --update``
does it again) and the argument of the rules. Not the compiler: a net that
differs from its certificate by one arc is refused, naming the instance.
"""
from __future__ import annotations

import re
from typing import Any, NamedTuple

from mcl2pnml.certify.templates import (CALL_SITE, SHARED_CALLEE, current, results_key,
                                        shape_of)
from mcl2pnml.core.net import ArcKind, Net
from mcl2pnml.core.payloads import MISSION

READ = ArcKind.READ

CONTROL = ("B", "A", "MTX", "OK", "FAIL", "ABORTED")
#: A structure's slot place: ``T1_B``.
_SLOT = re.compile(r"T\d+_")
PRIMITIVE_ROLES = ("ON", "OFF", "E", "D", "S1", "S2")


def check(net: Net, cert: dict[str, Any], proofs: dict[str, dict] | None = None) -> list[str]:
    """Every way ``net`` departs from ``cert`` (none: the certificate holds for it).

    ``proofs``: the proven parts to hold the instances to (default: the library in use,
    :func:`mcl2pnml.certify.templates.current`: the stored proofs, and a user's templates
    proven now)."""
    proofs = proofs if proofs is not None else current()
    problems: list[str] = []
    parts: dict[str, dict[str, Any]] = {}     # instance -> what it is
    for p in cert.get("primitives", {}):
        parts[p] = {"rule": "primitive"}
    for t, info in cert.get("tasks", {}).items():
        parts[t] = {"rule": "task", **info}
    for tree, nodes in cert.get("trees", {}).items():
        children: list[list[str]] = [[] for _ in nodes]
        for node in nodes:       # one pass: each node under its parent, in order
            if node.get("parent", -1) >= 0:
                children[node["parent"]].append(node["instance"])
        for k, node in enumerate(nodes):
            parts[node["instance"]] = {**node, "children": children[k], "tree": tree,
                                       "root": k == 0}
    functions = cert.get("functions", [])
    owner = _owners(net, parts)
    for missing in sorted(set(parts) - set(owner.values())):
        problems.append(f"instance '{missing}' of the certificate has no node in the net")
    for node_id, inst in owner.items():
        if inst is None:
            problems.append(f"'{node_id}' belongs to no instance of the certificate")
    problems += _side_conditions(cert, functions)
    derived, faults = results(cert, proofs)
    problems += [message for _, message in faults]
    claimed = (cert.get("conclusion") or {}).get("ends")
    if not faults and MISSION in derived:
        ends = root_ends(derived[MISSION], f"{MISSION}.A" in cert.get("start", ()))
        if ends is None:
            problems.append(f"{MISSION} may run for ever (from '{derived[MISSION].origin}'), "
                            "and no abort is pending at the start")
        elif claimed != ends:
            problems.append(f"the conclusion's ends {claimed} are not the root's: {ends}")
    own_places: dict[str, list[str]] = {}
    for p in net.places:
        if owner.get(p.id):
            own_places.setdefault(owner[p.id], []).append(p.id)
    arcs_of: dict[str, list] = {}
    places = net.place_index
    for a in net.arcs:       # each arc under its transition's instance
        inst = owner.get(a.source if a.source not in places else a.target)
        if inst:
            arcs_of.setdefault(inst, []).append(a)
    transitions_of: dict[str, list[str]] = {}
    for t in net.transitions:
        if owner.get(t.id):
            transitions_of.setdefault(owner[t.id], []).append(t.id)
    for name, part in parts.items():
        if name not in own_places and name not in transitions_of:
            continue
        problems += _part(net, name, part, parts, own_places.get(name, []),
                          transitions_of.get(name, []), arcs_of.get(name, []), proofs,
                          functions, cert.get("start", [f"{MISSION}.B"]))
    return problems


class Signature(NamedTuple):
    """What a task, node or function can do from B with no abort asked: end in one of
    ``ends`` (OK, FAIL), and, if ``stuck``, run for ever instead until it is aborted;
    ``origin``: the node where running for ever comes from (its children cannot)."""

    ends: tuple[str, ...]
    stuck: bool
    origin: str | None = None


def results(cert: dict[str, Any], proofs: dict[str, dict]
            ) -> tuple[dict[str, Signature], list[tuple[str, str]]]:
    """The signature of each task, node and function of ``cert``, derived bottom-up from
    the proofs' results tables; and the faults, each (instance, what is wrong): a node
    whose row is a breach (with its children doing what they do, the structure breaks the
    contract in a way no reduced model stands for), or that no row covers. One pass over
    the trees, functions before their callers."""
    out: dict[str, Signature] = {}
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

    for name, task in cert.get("tasks", {}).items():
        got = row(task.get("subject"), [], f"task '{name}'", name)
        if got is not None:
            out[name] = got
    calls = cert.get("calls", {})
    trees = cert.get("trees", {})
    for tree in (*cert.get("functions", []), MISSION):
        nodes = trees.get(tree, [])
        children: list[list[int]] = [[] for _ in nodes]
        for k, node in enumerate(nodes):
            if node.get("parent", -1) >= 0:
                children[node["parent"]].append(k)
        for k in range(len(nodes) - 1, -1, -1):     # children before their parent
            node, name = nodes[k], nodes[k]["instance"]
            if node.get("rule") == "call":
                callee = out.get(node.get("callee"))
                if callee is None:
                    continue
                got = row(CALL_SITE, [callee], f"call '{name}'", name)
                if calls.get(node.get("callee"), 0) > 1:
                    row(SHARED_CALLEE, [callee], f"call '{name}'", name)
            else:
                below = [out.get(nodes[c]["instance"]) for c in children[k]]
                if any(b is None for b in below):
                    continue
                got = row(node.get("template"), below, f"'{name}' ({node.get('template')})",
                          name, node.get("slots", ()))
            if got is not None:
                out[name] = got
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


def _owners(net: Net, parts: dict[str, Any]) -> dict[str, str | None]:
    """Each node id's instance: the longest instance name followed by a dot that starts it."""
    out: dict[str, str | None] = {}
    for node in (*net.places, *net.transitions):
        i, found = node.id.rfind("."), None
        while i > 0:
            if node.id[:i] in parts:
                found = node.id[:i]
                break
            i = node.id.rfind(".", 0, i)
        out[node.id] = found
    return out


def _side_conditions(cert: dict[str, Any], functions: list[str]) -> list[str]:
    problems = []
    order = {f: k for k, f in enumerate(functions)}
    for tree, nodes in cert.get("trees", {}).items():
        for node in nodes:
            callee = node.get("callee")
            if callee in order and tree in order and order[callee] >= order[tree]:
                problems.append(f"function '{tree}' calls '{callee}', which is not before it: "
                                "a call cycle could take gates out of order")
            if node.get("rule") == "call" and callee not in order and \
                    callee not in cert.get("tasks", {}):
                problems.append(f"'{node['instance']}' calls '{callee}', no task or function "
                                "of the certificate")
    return problems


def _part(net, name, part, parts, places, transitions, arcs, proofs, functions,
          cert_start) -> list[str]:
    """One instance's own net, renamed to its template's ids, against the proven digest."""
    rule = part["rule"]
    rename: dict[str, str] = {}
    if rule == "structure":
        subject = part["template"]
        for slot, child in zip(part["slots"], part["children"]):
            rename.update({f"{child}.{p}": f"{slot}_{p}" for p in CONTROL})
    elif rule == "call":
        callee = part["callee"]
        prims = sorted(set(parts.get(callee, {}).get("primitives", [])))
        subject = f"{CALL_SITE}/{len(prims)}"
        rename.update({f"{callee}.{p}": f"to.{p}" for p in ("GATE", *CONTROL) if p != "MTX"})
        rename.update({f"{p}.LOCK": f"lock.{k}" for k, p in enumerate(prims, 1)})
    elif rule == "task":
        subject = part["subject"]
        for slot, prim in zip(part["slots"], part["primitives"]):
            rename.update({f"{prim}.{r}": (f"{slot}_{r}" if slot else r)
                           for r in PRIMITIVE_ROLES})
    else:
        subject = "primitive"
    entry = proofs.get(subject)
    if entry is None or "local" not in entry:
        return [f"'{name}' is a {subject}, which no stored proof covers"]
    problems = []
    prefix = name + "."
    gate = f"{name}.GATE" if part.get("root") and part.get("tree") in functions else None
    local_places = {}
    for p in places:
        if p == gate:
            continue
        local_places[p] = p[len(prefix):]
    shared = set()
    index = net.place_index
    for end, slot in rename.items():   # every place the template shares, used or not
        if end in index:
            local_places[end] = slot
            shared.add(slot)
    cut = len(prefix)
    local_arcs = []
    for a in arcs:           # one pass: each arc renamed, a place it may not touch said
        source, target = a.source, a.target
        if source in index:
            place, transition = source, target
        else:
            place, transition = target, source
        got = local_places.get(place)
        if got is None:
            problems.append(f"'{name}' ({rule}) has an arc with '{place}', which the "
                            "certificate does not give it")
            continue
        t = transition[cut:]
        local_arcs.append((got, t, a.weight, "read" if a.kind is READ else "normal")
                          if place is source else (t, got, a.weight, "normal"))
    if problems:
        return problems
    initial = {}
    start = set(cert_start)
    for p, local in local_places.items():
        n = net.initial[p]
        if part.get("root") and part.get("tree") == MISSION and local in ("B", "A"):
            if n != (f"{MISSION}.{local}" in start):
                problems.append(f"M0 {'marks' if n else 'does not mark'} {MISSION}.{local}; "
                                f"the certificate starts from {', '.join(sorted(start))}")
            n = 0
        initial[local] = n
    if rule == "structure":     # a slot the tree leaves empty is still a slot
        shared |= {x for x in local_places.values() if _SLOT.match(x)}
    digest = shape_of(((x, None if x in shared else n) for x, n in initial.items()),
                      (t[cut:] for t in transitions), local_arcs)
    if digest != entry["local"]:
        problems.append(f"'{name}' is not the proven {subject}: its places, transitions or "
                        "arcs differ")
    if gate is not None and net.initial[gate] != 1:
        problems.append(f"the gate '{gate}' is not free in M0")
    return problems
