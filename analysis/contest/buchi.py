"""LTL formulas to generalised Büchi automata, for the products that decide them.

A formula (of :mod:`mcl2pnml.core.queries`) is put in negation normal form with its
maximal state subformulas as atoms (:func:`negation_normal_form`), then turned into a
generalised Büchi automaton by Gerth, Peled, Vardi and Wolper's tableau (:func:`tableau`,
1995). The products read the automaton: on an explored graph
(:func:`mcl2pnml.analysis.contest.answers.ltl_holds`) or on the fly from the net
(:mod:`mcl2pnml.analysis.contest.ltl_on_the_fly`).

Formulas in negation normal form are tuples: ``("lit", k)`` an atom (the caller's k-th,
negations included), ``("and", a, b)``, ``("or", a, b)``, ``("X", a)``, ``("U", a, b)``,
``("R", a, b)``; ``("true",)`` and ``("false",)``.
"""
from __future__ import annotations

from typing import Callable

from mcl2pnml.core import queries as q


class NotLTL(ValueError):
    """A path quantifier inside the formula: not the contest's LTL."""


def negation_normal_form(f, negate: bool, atom: Callable[[object, bool], int]):
    """``f`` (negated if ``negate``) in negation normal form; each maximal state
    subformula ``g`` becomes ``("lit", atom(g, negated))``."""
    def nnf(f, negate):
        if q.is_state(f):
            return ("lit", atom(f, negate))
        if isinstance(f, q.Neg):
            return nnf(f.arg, not negate)
        if isinstance(f, (q.Conj, q.Disj)):
            parts = [nnf(a, negate) for a in f.args]
            op = "and" if isinstance(f, q.Conj) != negate else "or"
            out = parts[0]
            for p in parts[1:]:
                out = (op, out, p)
            return out
        if isinstance(f, q.Next):
            return ("X", nnf(f.arg, negate))
        if isinstance(f, q.Finally):        # F a = true U a;  not F a = false R not a
            a = nnf(f.arg, negate)
            return ("R", ("false",), a) if negate else ("U", ("true",), a)
        if isinstance(f, q.Globally):       # G a = false R a;  not G a = true U not a
            a = nnf(f.arg, negate)
            return ("U", ("true",), a) if negate else ("R", ("false",), a)
        if isinstance(f, q.Until):          # not (a U b) = not a R not b
            a, b = nnf(f.before, negate), nnf(f.reach, negate)
            return ("R", a, b) if negate else ("U", a, b)
        raise NotLTL("a path quantifier inside an LTL formula")
    return nnf(f, negate)


def tableau(phi) -> tuple[list[frozenset], list[set[int]], set[int], list[tuple]]:
    """The generalised Büchi automaton of ``phi`` by Gerth, Peled, Vardi and Wolper's
    tableau (1995): each node's literals (its ``old`` set's), its predecessors, the
    initial nodes, and the ``U`` subformulas (one acceptance set each)."""
    nodes: list[dict] = []
    INIT = -1
    stack = [{"incoming": {INIT}, "new": [phi], "old": set(), "next": set()}]
    while stack:
        node = stack.pop()
        if not node["new"]:
            same = next((n for n in nodes if n["old"] == node["old"]
                         and n["next"] == node["next"]), None)
            if same is not None:
                same["incoming"] |= node["incoming"]
                continue
            node["id"] = len(nodes)
            nodes.append(node)
            stack.append({"incoming": {node["id"]}, "new": list(node["next"]), "old": set(),
                          "next": set()})
            continue
        f = node["new"].pop()
        if f in node["old"]:
            stack.append(node)
            continue
        kind = f[0]
        if kind == "false":
            continue
        if kind in ("true", "lit"):
            node["old"].add(f)
            stack.append(node)
        elif kind == "and":
            node["old"].add(f)
            node["new"] += [g for g in f[1:] if g not in node["old"]]
            stack.append(node)
        elif kind == "X":
            node["old"].add(f)
            node["next"].add(f[1])
            stack.append(node)
        else:
            a, b = f[1], f[2]
            if kind == "or":
                one, two = ([a], set()), ([b], set())
            elif kind == "U":                   # a U b = b or (a and X(a U b))
                one, two = ([a], {f}), ([b], set())
            else:                               # a R b = b and (a or X(a R b))
                one, two = ([b], {f}), ([a, b], set())
            for new, nxt in (one, two):
                stack.append({"incoming": set(node["incoming"]),
                              "new": node["new"] + [g for g in new if g not in node["old"]],
                              "old": node["old"] | {f}, "next": node["next"] | nxt})
    untils = sorted({g for n in nodes for g in n["old"] if g[0] == "U"}, key=repr)
    literals = [frozenset(g[1] for g in n["old"] if g[0] == "lit") for n in nodes]
    accepting = [{k for k, n in enumerate(nodes) if u not in n["old"] or u[2] in n["old"]}
                 for u in untils]
    initial = {k for k, n in enumerate(nodes) if INIT in n["incoming"]}
    edges = [(j, k) for k, n in enumerate(nodes) for j in n["incoming"] if j != INIT]
    return literals, accepting, initial, edges
