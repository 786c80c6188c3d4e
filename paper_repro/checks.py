"""Equations 1-26 computed from the templates, each compared with the paper.

Every "computed" value comes from the analysis of the nets in ``templates/``
(incidence matrix, invariant basis, minimal siphons, explored state space);
the paper's side comes from :mod:`paper_repro.paper`. A row matches when:

* an invariant: the paper's vector y satisfies y^T C = 0 on the template's
  net (computed from the incidence matrix) and y . M0 is the paper's value;
  together the paper's invariants must span the whole computed basis;
* a siphon: it is one of the computed minimal siphons, marked at M0 and
  controlled by a P-invariant (Iordache and Antsaklis 2006);
* M0: the template's initial marking is the paper's;
* a final marking: it is a dead marking reached from the paper's M0, and
  the computed dead markings from that M0 are exactly the paper's group.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import sympy

from mcl2pnml.analysis.behaviour import final_markings_agree
from mcl2pnml.analysis.structure.invariants import (format_invariant,
                                 minimal_semipositive_p_invariants, p_invariant_basis)
from mcl2pnml.analysis.structure.siphons import minimal_siphons, siphon_control
from mcl2pnml.analysis.statespace.explore import explore
from mcl2pnml.core.structure import Structure, structure
from mcl2pnml.language.library import Library
from mcl2pnml.language.template_parser import CONTROL

from paper_repro import nets, paper
from paper_repro.paper import EQUATIONS, Equation


@dataclass
class Row:
    number: int
    net: str
    paper: str
    computed: str
    match: bool
    reading: str = ""
    data: dict[str, Any] = field(default_factory=dict)


def _fmt(places) -> str:
    return "{" + ", ".join(places) + "}"


class Analysis:
    """The computed facts about one template's net, computed once."""

    def __init__(self, lib: Library, name: str):
        self.net = lib.composed(name)
        self.s: Structure = structure(self.net)
        self.basis = p_invariant_basis(self.s)
        self.semipositive = minimal_semipositive_p_invariants(self.s)
        self.siphons = [frozenset(self.s.names(x)) for x in minimal_siphons(self.s)]
        self.control = {frozenset(r.places): r
                        for r in siphon_control(self.s, minimal_siphons(self.s), self.semipositive)}
        self._finals: dict[tuple, Any] = {}

    def is_invariant(self, y: dict[str, int]) -> tuple[bool, list[str]]:
        """y^T C = 0, from the incidence matrix; and the transitions where it fails."""
        idx = self.s.place_index
        broken = [self.s.transitions[j] for j, col in enumerate(self.s.incidence)
                  if sum(y.get(self.s.places[p], 0) * v for p, v in col.items())]
        unknown = [p for p in y if p not in idx]
        return (not broken and not unknown), broken + unknown

    def value(self, y: dict[str, int]) -> int:
        return sum(c * self.net.initial[p] for p, c in y.items())

    def span_rank(self, vectors: list[dict[str, int]]) -> int:
        rows = [[v.get(p, 0) for p in self.s.places] for v in vectors]
        return sympy.Matrix(rows).rank() if rows else 0

    def finals(self, start: tuple[str, ...]):
        if start not in self._finals:
            space = explore(self.s, {p: 1 for p in start})
            self._finals[start] = space
        return self._finals[start]


def check_equations(lib: Library) -> list[Row]:
    analyses = {name: Analysis(lib, name) for name in {e.net for e in EQUATIONS}}
    rows = []
    for eq in EQUATIONS:
        a = analyses[eq.net]
        rows.append({"invariant": _invariant, "siphon": _siphon, "marking": _marking,
                     "final": _final}[eq.kind](eq, a))
    return rows


def _invariant(eq: Equation, a: Analysis) -> Row:
    ok, broken = a.is_invariant(eq.coefficients)
    value = a.value(eq.coefficients)
    if ok:
        computed = f"{format_invariant(eq.coefficients, value)}: y^T C = 0 on {a.net.name}"
    else:
        computed = f"not a P-invariant of {a.net.name}: y^T C != 0 at {', '.join(broken)}"
    return Row(eq.number, eq.net, eq.text, computed, ok and value == eq.value, eq.reading,
               {"invariant": ok, "value_at_M0": value})


def _siphon(eq: Equation, a: Analysis) -> Row:
    target = frozenset(eq.places)
    found = target in a.siphons
    report = a.control.get(target)
    if not found:
        computed = f"not a minimal siphon; minimal siphons: {', '.join(map(_fmt, map(sorted, a.siphons)))}"
        match = False
    else:
        by = report.controlled_by
        computed = (f"minimal siphon, marked at M0: {'yes' if report.marked else 'no'}, "
                    f"controlled by {format_invariant(by, a.value(by)) if by else 'no invariant'}")
        match = report.marked and report.controlled
    return Row(eq.number, eq.net, eq.text, computed, match,
               data={"minimal_siphon": found,
                     "controlled_by": report.controlled_by if report else None})


def _marking(eq: Equation, a: Analysis) -> Row:
    m0 = sorted(a.net.initial)
    return Row(eq.number, eq.net, eq.text, f"M0 = {_fmt(m0)}", set(m0) == set(eq.places))


def _final(eq: Equation, a: Analysis) -> Row:
    space = a.finals(eq.start)
    finals = {frozenset(space.format(n)) for n in space.terminal}
    group = {frozenset(e.places) for e in EQUATIONS if e.number in eq.group}
    computed = (f"from {_fmt(eq.start)}: {len(finals)} dead marking(s) "
                + ", ".join(_fmt(sorted(f)) for f in sorted(finals, key=sorted))
                + f"; {space.states} reachable markings, "
                + ("every place 1-bounded" if space.safe else "NOT 1-bounded"))
    match = frozenset(eq.places) in finals and finals == group and space.safe
    return Row(eq.number, eq.net, eq.text, computed, match,
               data={"finals": sorted(sorted(f) for f in finals), "safe": space.safe})


# ---------------------------------------------------------------------------
# what the numbered equations rest on, and what the paper leaves open


def invariant_space(lib: Library) -> list[Row]:
    """Section 2.2 finds three invariants and section 2.3 six: the paper's sets
    must be a basis of the computed invariant space."""
    rows = []
    for net, count in paper.INVARIANT_COUNT.items():
        a = Analysis(lib, net)
        vectors = [e.coefficients for e in EQUATIONS if e.net == net and e.kind == "invariant"]
        rank = a.span_rank(vectors)
        rows.append(Row(0, net, f"{count} place invariants",
                        f"basis of {len(a.basis)} computed; the paper's {len(vectors)} have "
                        f"rank {rank}", len(a.basis) == count == rank,
                        data={"basis": a.basis}))
    return rows


def siphon_16_control(lib: Library) -> Row:
    a = Analysis(lib, "task")
    y: dict[str, int] = {}
    for n in paper.SIPHON_16_CONTROL:
        for p, c in EQUATIONS[n - 1].coefficients.items():
            y[p] = y.get(p, 0) + c
    y = {p: c for p, c in y.items() if c}
    ok, _ = a.is_invariant(y)
    siphon = frozenset(EQUATIONS[15].places)
    positive = {p for p, c in y.items() if c > 0}
    match = ok and positive == set(siphon) and all(c > 0 for c in y.values()) and a.value(y) > 0
    return Row(16, "task", "siphon 16 controlled by 10 + 12 + 13",
               f"10 + 12 + 13 = {format_invariant(y, a.value(y))}, support = siphon 16",
               match)


def other_siphons(lib: Library) -> list[Row]:
    """The minimal siphons the paper does not list, and why they are harmless."""
    rows = []
    for net in ("primitive", "task"):
        a = Analysis(lib, net)
        listed = {frozenset(e.places) for e in EQUATIONS if e.net == net and e.kind == "siphon"}
        for siphon in a.siphons:
            if siphon in listed:
                continue
            r = a.control[siphon]
            if r.source:
                why = ("source places: nothing in this net writes to them, the structure "
                       "above marks them (they need no control)")
            elif r.controlled:
                why = f"controlled by {format_invariant(r.controlled_by, a.value(r.controlled_by))}"
            else:
                why = "NOT controlled"
            rows.append(Row(0, net, "(not listed)", f"{_fmt(sorted(siphon))}: {why}",
                            r.source or (r.controlled and r.marked)))
    return rows


def reduced_model(lib: Library) -> list[Row]:
    """Section 2.3: the task and its reduced model end alike, seen from above."""
    rows = []
    full, reduced = lib.composed("task"), lib.composed("task-reduced")
    for start_full, start_red in ((paper.TASK_M0, paper.REDUCED_M0),
                                  (paper.TASK_M0_NO_ABORT, paper.REDUCED_M0_NO_ABORT)):
        agree = final_markings_agree(full, reduced, CONTROL, {p: 1 for p in start_full},
                                     {p: 1 for p in start_red})
        rows.append(Row(0, "task / task-reduced", f"same finals on {_fmt(CONTROL)} from "
                        f"{_fmt(start_red)}",
                        "; ".join(_fmt(f) for f in sorted(agree.finals_a))
                        + (" (both)" if agree.equal else
                           f" vs {'; '.join(_fmt(f) for f in sorted(agree.finals_b))}"),
                        agree.equal))
    return rows


def structures(lib: Library) -> list[Row]:
    """Fig. 4 and the structures described in words, and the patterns: each
    ends as a reduced task does (22-26), with its slots back at rest. A
    structure may never reach some end (NULL never fails): its finals must be
    among the reduced task's, and an end must always be reachable."""
    rows = []
    reduced = lib.composed("task-reduced")
    for t in lib.unique():
        if t.kind.value not in ("structure", "pattern"):
            continue
        net = lib.composed(t.name)
        rest = {p for p in net.initial if p not in ("B", "A")}
        for inputs in (("B", "A"), ("B",)):
            start = {p: 1 for p in (*inputs, *rest)}
            space = explore(net, start)
            finals = {frozenset(space.format(n)) for n in space.terminal}
            red = explore(reduced, {p: 1 for p in (*inputs, "MTX")})
            expected = {frozenset((set(red.format(n)) - {"MTX"}) | rest) for n in red.terminal}
            reach = space.always_can_reach(space.terminal)
            missing = sorted(set().union(*(e - frozenset(rest) for e in expected - finals)))
            rows.append(Row(0, t.name, f"from {_fmt(sorted(start))}: the finals of "
                            + ("22-24" if "A" in inputs else "25-26"),
                            "; ".join(_fmt(sorted(f)) for f in sorted(finals, key=sorted))
                            + f" ({space.states} markings, "
                            + ("1-safe" if space.safe else "NOT 1-safe")
                            + (", an end always reachable" if reach else ", CAN GET STUCK")
                            + (f"; never ends {_fmt(missing)}" if missing else "") + ")",
                            bool(finals) and finals <= expected and space.safe and reach))
    return rows


def sequence_fusion(lib: Library) -> Row:
    """Equations 27-29: the sequence's three groups of fusion places."""
    net = lib.composed("sequence")
    missing = [p for group in paper.SEQUENCE_FUSION.values() for p in group
               if p not in net.place_index]
    return Row(27, "sequence", "fusion groups 27, 28, 29",
               "all present as fused places" if not missing
               else f"missing: {', '.join(missing)}", not missing)


def recall(lib: Library) -> list[Row]:
    """The abort problem and the mutex: a task called again as soon as it ends."""
    rows = []
    for net in (lib.composed("task"), nets.literal_task(lib)):
        space = explore(nets.called_again(net))
        pending = nets.mutex_free_while_pending(space)
        over = [n for n, m in enumerate(space.markings) if max(m) > 1]
        computed = (f"{space.states} markings; "
                    + ("1-safe" if space.safe else
                       f"NOT 1-safe: after {' '.join(space.path_to(over[0]))} the marking is "
                       f"{_fmt(space.format(over[0]))}")
                    + "; MTX free while E or D pending: "
                    + ("never" if not pending else
                       f"after {' '.join(space.path_to(pending[0]))}"))
        ours = net.name == "task"
        # the claim is what is checked: ours holds it, the literal task is expected to fail it
        claim = ("called again at once: 1-safe, MTX never free with a request pending" if ours
                 else "the literal task, called again at once, is not 1-safe (the paper's flaw)")
        rows.append(Row(0, net.name, claim, computed,
                        (space.safe and not pending) if ours else not space.safe,
                        data={"expected": "holds" if ours else "fails (the paper's flaw)"}))
    return rows
