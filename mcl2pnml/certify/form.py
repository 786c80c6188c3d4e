"""The certificate's JSON form: its schema, the parts every certificate says alike, and its
conclusion, written once for :mod:`mcl2pnml.certify.certificate`, which writes them, and
:mod:`mcl2pnml.certify.recheck`, which holds a file to them.

The shape is ``certificate.schema.json`` (JSON Schema, draft 7) beside this module: a
valid certificate passes it in one compiled function (``fastjsonschema``, a fifth of a
second for a 10,000-call survey); an invalid one is validated again by ``jsonschema``,
whose errors name the JSON path of each fault. The shape is only the first gate: what the
fields mean, and which of them the checker recomputes rather than believe, is
docs/certificate.md.
"""
from __future__ import annotations

import functools
import json
from itertools import islice
from importlib import resources
from typing import Any

import fastjsonschema

from mcl2pnml.core.payloads import MISSION

#: The version of the certificate's JSON form (2: contract 2, and every fact recomputed).
FORMAT = 2

#: The rules of the argument, in the order the certificate lists them.
RULES = ["task", "call", "structure", "function", "mission"]

SIDE_CONDITIONS = {
    "functions not recursive": "each function calls only functions that do not call it back "
                               "(the checker orders them itself)",
    "locks": "every call site of a task takes the locks of exactly the task's primitives, "
             "and gives them back with its result",
    "gates": "every call site of a task or function takes its gate on entry and gives it "
             "back with its result",
}

#: The most faults said of one certificate: a hostile file may have a million.
MAX_FAULTS = 20


def start(pending: bool) -> list[str]:
    """The places marked at the start: ``mission.B``, and ``mission.A`` with an abort
    pending."""
    return [f"{MISSION}.B", *([f"{MISSION}.A"] if pending else [])]


def conclusion(ends: list[str], pending: bool) -> dict[str, Any]:
    """What a certificate concludes of a mission whose root ends in ``ends``: the one
    conclusion the checker accepts, computed, never read."""
    return {"ends": ends, "safe": True, "an end always reachable": True, "reusable": True,
            "at rest when it ends": True,
            **({"abort": f"{MISSION}.A is consumed exactly when the end is {MISSION}.ABORTED, "
                         "and left marked otherwise"} if pending else {}),
            "why": "the root keeps the interface contract (rules above), started by "
                   "mission.B" + (" with mission.A pending (A consumed exactly when the end "
                                  "is ABORTED)" if pending else " with no abort asked")}


@functools.cache
def schema() -> dict[str, Any]:
    text = resources.files("mcl2pnml.certify").joinpath("certificate.schema.json").read_text(
        encoding="utf-8")
    return json.loads(text)


@functools.cache
def _fast():
    """The schema compiled to one function, its references written in place: a call less
    per name and per node, a third of the time on a 20,000-node certificate."""
    definitions = schema()["definitions"]

    def inline(part):
        if isinstance(part, dict):
            if set(part) == {"$ref"}:
                return inline(definitions[part["$ref"].rsplit("/", 1)[1]])
            return {k: inline(v) for k, v in part.items() if k != "definitions"}
        return [inline(x) for x in part] if isinstance(part, list) else part
    return fastjsonschema.compile(inline(schema()))


def shape_faults(cert: Any) -> list[str]:
    """Where ``cert`` is not of the certificate's shape, each fault at its JSON path
    (``$.trees.mission[3].parent: 'x' is not of type 'integer'``); at most
    :data:`MAX_FAULTS`.

    The compiled validator finds the first fault in one pass; ``jsonschema`` then says it,
    validating only the part of the file that holds it (a node, a task; the whole file
    only if no part alone shows it): a file of 100,000 nodes with a fault in the last one
    is said at once, not after validating every node again."""
    try:
        _fast()(cert)
        return []
    except fastjsonschema.JsonSchemaValueException as e:
        path = [int(k) if k.isdigit() and _is_array(cert, e.path[1:], i) else k
                for i, k in enumerate(e.path[1:])]
    except (fastjsonschema.JsonSchemaException, RecursionError):
        path = []
    import jsonschema   # 0.2 s to import: only to say where a malformed certificate is wrong
    for depth in range(len(path), -1, -1):     # the deepest part that shows the fault
        found = _part(cert, path[:depth])
        if found is None:
            continue
        part, sub = found
        validator = jsonschema.Draft7Validator({**sub, "definitions": schema()["definitions"]})
        try:
            errors = list(islice(validator.iter_errors(part), MAX_FAULTS))
        except RecursionError:
            return ["$: nested too deeply for a certificate"]
        if errors:
            where = "$" + "".join(f"[{k}]" if isinstance(k, int) else f".{k}"
                                  for k in path[:depth])
            return [f"{where}{e.json_path[1:]}: {_short(e.message)}" for e in errors]
    return ["$: not of the certificate's shape"]


def _is_array(cert: Any, path: list[str], i: int) -> bool:
    """Whether the ``i``-th step of ``path`` indexes an array."""
    node = cert
    for k in path[:i]:
        try:
            node = node[int(k)] if isinstance(node, list) else node[k]
        except (KeyError, IndexError, TypeError, ValueError):
            return False
    return isinstance(node, list)


def _part(cert: Any, path: list) -> tuple[Any, dict] | None:
    """The part of ``cert`` at ``path`` and the schema it must keep (None: the schema
    does not say one alone, e.g. under a condition)."""
    node, sub = cert, schema()
    definitions = sub["definitions"]
    for k in path:
        while "$ref" in sub:
            sub = definitions[sub["$ref"].rsplit("/", 1)[1]]
        if isinstance(k, int):
            if not isinstance(node, list) or not isinstance(sub.get("items"), dict):
                return None
            node, sub = node[k], sub["items"]
        else:
            if not isinstance(node, dict) or k not in node:
                return None
            nxt = sub.get("properties", {}).get(k, sub.get("additionalProperties"))
            if not isinstance(nxt, dict) or "if" in sub:
                return None
            node, sub = node[k], nxt
    top = {k: v for k, v in sub.items() if k != "definitions"}
    return node, top


def _short(message: str, limit: int = 200) -> str:
    """A validator's message, cut in the middle: it quotes the value (which may be a whole
    tree) first and says what is wrong with it last."""
    if len(message) <= limit:
        return message
    return message[:limit // 2] + " ... " + message[-limit // 2:]
