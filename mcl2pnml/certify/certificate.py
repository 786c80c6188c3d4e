"""A mission's certificate: the proof, from its parts, that its net behaves (sections 2.3-2.5).

The argument, rule by rule, each resting on a proof of
:mod:`mcl2pnml.certify.templates` (a component checked once against the
interface contract of :mod:`mcl2pnml.analysis.checking.contract`, its children reduced):

* **task**: a task's net is its pattern fused with its primitives (with its
  time-out, or without one); the pattern's proof covers it, used by one call
  at a time (its gate), its primitives by one task at a time (their locks);
* **call**: a call site with its callee behind the callee's gate and its
  primitives' locks keeps the contract if the callee does (the joint's
  proof; the shared-callee proof where several sites call one callee);
* **structure**: a structure whose children keep the contract keeps it: the
  reduced model (Fig. 3) restricted to the results a child can give
  allows every behaviour that child shows at the fusion places, and still
  can give each of them, and the template was proven with reduced children
  giving every choice of results (its results table): the row of the
  children's results says what the structure gives, or that it breaks the
  contract (``while`` on a condition that never fails never ends), and
  then the mission is not certified;
* **function**: a function's body is a structure behind its gate, entered
  by call sites; functions are not recursive (each calls only functions
  declared before it), so gates are taken in one order and cannot deadlock;
* **mission**: the root structure, started by ``mission.B``: by the
  contract, the net is 1-safe, an end is always reachable, every end is the
  rest marking with one of the root's results (no abort is asked; each of
  them is reached by some run), when the result is marked the rest is
  already at rest (every primitive disabled), and from there the mission can
  run again (reusable). A root that may run for ever is certified only with
  an abort pending (``mission.A`` marked at the start: it then always ends,
  ABORTED among its ends); without one, :class:`NotCertified` points at the
  node it comes from.

:func:`certify` writes the tree of the mission (and of each function) with
the rule and the proof used at each node, the side conditions, and the
conclusion. :mod:`mcl2pnml.certify.recheck` re-checks it against the PNML
alone. No state space is explored: the cost is linear in the mission.
"""
from __future__ import annotations

from typing import Any

from mcl2pnml.certify import form
from mcl2pnml.certify.recheck import results, root_ends, said_signature
from mcl2pnml.certify.templates import current, untrusted_reduced
from mcl2pnml.core.errors import Location, Mcl2PnmlError, line_of, source_lines
from mcl2pnml.core.gcpause import without_gc
from mcl2pnml.core.payloads import MISSION
from mcl2pnml.language.compiler import STRUCTURE_TEMPLATE
from mcl2pnml.language.functional import (FCall, function_expression, instances,
                                          mission_expression)
from mcl2pnml.language.library import Library, default_library

@without_gc      # 20,000 instances for a 10,000-call survey: nothing cyclic among them
def certify(checked, lib: Library | None = None, net_name: str | None = None,
            abort_pending: bool = False, proofs: dict[str, dict] | None = None
            ) -> dict[str, Any]:
    """The certificate of a checked mission (:class:`mcl2pnml.language.semantics.Checked`),
    started by ``mission.B`` (and, ``abort_pending``, with ``mission.A`` marked too: the
    abort racing every step, as the analysis proves that an aborted mission ends).
    ``proofs``: the library's (:func:`mcl2pnml.certify.templates.current`), if already
    read."""
    lib = lib or default_library()
    refused = untrusted_reduced(lib)
    if refused is not None:
        raise refused
    proofs = proofs if proofs is not None else current(lib)
    calls: dict[str, int] = {}
    trees = {MISSION: _tree(mission_expression(checked.mission), MISSION, "", lib, proofs,
                            calls)}
    for name in checked.function_order:
        trees[name] = _tree(function_expression(checked.functions[name]), name, name, lib,
                            proofs, calls)
    tasks = {}
    for name, task in checked.tasks.items():
        pattern = checked.patterns[name].name
        subject = pattern if task.timeout is not None else f"{pattern} without a time-out"
        tasks[name] = {"pattern": pattern, "subject": subject,
                       "primitives": [p.name for p in task.primitives],
                       "slots": list(checked.patterns[name].primitives),
                       "timeout": None if task.timeout is None else task.timeout.value,
                       "proof": proofs[subject]["digest"],
                       "local": proofs[subject]["local"]}
    used = sorted({p for t in tasks.values() for p in t["primitives"]})
    cert = {
        "format": form.FORMAT,
        "mission": net_name or checked.program.file,
        "rules": list(form.RULES),
        "proofs": {name: p["digest"] for name, p in sorted(proofs.items()) if "digest" in p},
        "primitives": {p: {"local": proofs["primitive"]["local"]} for p in used},
        "tasks": tasks,
        "functions": list(checked.function_order),
        "trees": trees,
        "calls": calls,
        "side_conditions": dict(form.SIDE_CONDITIONS),
        "start": form.start(abort_pending),
    }
    derived, faults = results(cert, proofs)
    ends = None if faults else root_ends(derived[MISSION], abort_pending)
    if not faults and ends is None:
        origin = derived[MISSION].origin
        how = ("never ends" if not derived[origin].ends else
               f"may end {' or '.join(derived[origin].ends)}, or run on for ever")
        faults = [(origin, f"the mission {how} unless it is aborted" if origin == MISSION else
                   f"'{origin}' {how} unless it is aborted, and the mission with it")]
    if faults:
        name, message = faults[0]
        raise NotCertified(f"{message}: the mission is not certified (`mcl2pnml analyze "
                           "--state-space --explore` shows the run)", _where(checked, name))
    for nodes in trees.values():
        for node in nodes:
            node.update(said_signature(derived[node["instance"]]))
    for name, task in tasks.items():
        task.update(said_signature(derived[name]))
    cert["conclusion"] = form.conclusion(ends, abort_pending)
    return cert


class NotCertified(Mcl2PnmlError):
    """A mission whose parts, joined as written, break the contract (a loop that can never
    end): it has no certificate, and exploring its net shows the fault."""


def _where(checked, name: str) -> Location:
    """Where the instance ``name`` is written."""
    for root, scope, expr in ((MISSION, "", mission_expression(checked.mission)),
                              *((f, f, function_expression(checked.functions[f]))
                                for f in checked.function_order)):
        for inst in instances(expr, root, scope):
            if inst.name == name:
                pos = inst.node.pos
                # the lines as the parser counts them (cut at "\n" only)
                lines = source_lines(checked.program.source)
                return Location(checked.program.file, pos.line, pos.column,
                                line_of(lines, pos.line))
    return Location(checked.program.file)


def _tree(root, root_name: str, scope: str, lib: Library, proofs: dict[str, dict],
          calls: dict[str, int]) -> list:
    """The instances of one tree in pre-order: name, rule, what it uses, its parent."""
    out = []
    for inst in instances(root, root_name, scope):
        if isinstance(inst.node, FCall):
            calls[inst.node.name] = calls.get(inst.node.name, 0) + 1
            out.append({"instance": inst.name, "rule": "call", "callee": inst.node.name,
                        "parent": inst.parent})
        else:
            template = lib.get(STRUCTURE_TEMPLATE[inst.node.kind])
            out.append({"instance": inst.name, "rule": "structure", "template": template.name,
                        "slots": list(template.children[:len(inst.node.children)]),
                        "local": proofs[template.name]["local"], "parent": inst.parent})
    return out
