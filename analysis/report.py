"""One analysis of a net, as the JSON of ``mcl2pnml analyze --json`` and as a readable report.

The JSON object holds what ``shared/spec/cli.md`` lists (``places``,
``transitions``, ``p_invariants``, ``siphons``, ``bounded``, ``safe``,
``terminal_markings``, ``reusable``, ``deadlock_free``, ``states``) and more:
``initial_marking``, ``t_invariants``, the minimal semi-positive invariants,
``traps``, each siphon's control (Iordache and Antsaklis 2006), and the
termination facts of :mod:`analysis.behaviour`.

Results that could not be computed within their limits (a state space past
``--max-states`` or its memory budget, ``--max-memory``; minimal siphons,
whose number can grow exponentially) are reported as ``null`` with the
reason under ``"limits"``, never silently left out; the structural results
are computed first, so they are there when the state space is too large,
with ``"partial"``: the markings explored and whether a dead one was met.
"""
from __future__ import annotations

from typing import Any

from mcl2pnml.core.net import Net
from mcl2pnml.core.payloads import RESULT_PLACES
from mcl2pnml.core.structure import structure

from analysis.behaviour import behaviour
from analysis.invariants import (AnalysisLimit, format_invariant, minimal_semipositive_p_invariants,
                         minimal_semipositive_t_invariants, p_invariant_basis,
                         t_invariant_basis)
from analysis.siphons import minimal_siphons, minimal_traps, siphon_control
from analysis.statespace import ExplorationLimit, MemoryLimit, Progress, explore, resident

#: Bounds on the exponential parts; past them the result says "limit reached".
FARKAS_LIMIT = 20_000
SIPHON_LIMIT = 20_000
#: The work either enumeration may do, in row (or subproblem) entries: each
#: intermediate row of Farkas' algorithm spans every place and transition,
#: each siphon subproblem every place, so the counts above are lowered on a
#: wide net. 20,000 rows of a 20,000-place net took 50 s; a million places
#: would never end, nor fit in memory.
WORK_LIMIT = 20_000_000


def _limit(count: int, width: int) -> int:
    """The count limit of an enumeration whose items are ``width`` entries wide."""
    return max(1, min(count, WORK_LIMIT // max(1, width)))


def analyze(net: Net, initial: dict[str, int] | None = None, *, state_space_only: bool = False,
            max_states: int = 5_000_000, progress: Progress | None = None,
            explorer: str = "auto", max_memory: int | None = None) -> dict[str, Any]:
    """Everything we know how to prove about ``net``, as JSON-ready data.

    ``explorer`` is one of :data:`analysis.statespace.BACKENDS`; ``max_memory``
    is the exploration's budget in bytes (default: half the memory available).
    The structural results come first, so that an exploration stopped by its
    budget still ends in a partial answer: ``"partial"`` says how many
    markings were explored and whether a dead marking was met among them.
    """
    if initial is not None:
        net = net.with_initial(initial)
    s = structure(net)
    limits: dict[str, str] = {}
    structural = {} if state_space_only else _structural(s, limits)
    partial = None
    try:
        # a budget given is the whole process's: what the net and the structural
        # results hold counts against it (the default, half of what is free now,
        # leaves it out already)
        space = explore(s, max_states=max_states, progress=progress, backend=explorer,
                        max_memory=max_memory, held=0 if max_memory is None else resident())
    except ExplorationLimit as e:
        if state_space_only and not isinstance(e, MemoryLimit):
            raise
        space = None
        limits["states"] = e.message
        partial = {"markings_explored": e.explored,
                   "deadlock_found": None if e.deadlocks is None else e.deadlocks > 0}
    result = _state_space_facts(net, s, space)
    result.update(structural)
    if partial is not None:
        result["partial"] = partial
    if limits:
        result["limits"] = limits
    return result


def _state_space_facts(net: Net, s, space) -> dict[str, Any]:
    """What the state space says: also all of ``--state-space``."""
    b = behaviour(space) if space is not None else None
    ours = has_mission_interface(net)
    return {
        "net": net.name,
        "places": len(s.places),
        "transitions": len(s.transitions),
        "arcs": len(net.arcs),
        "initial_marking": net.initial.format(),
        "states": space.states if space else None,
        "bounded": space.bounded if space else None,
        "safe": space.safe if space else None,
        "terminal_markings": sorted(list(m) for m in b.terminal) if b else None,
        # a net with the paper's interface ends properly in a dead marking (one
        # result marked, the rest at rest): a deadlock is a dead marking that
        # is not such an end. Another net's every dead marking is a deadlock,
        # as every other tool counts them.
        "interface": "mission" if ours else "none",
        "deadlock_free": (b.deadlock_free if ours else not b.terminal) if b else None,
        "deadlocks": sorted(list(m) for m in (b.improper if ours else b.terminal))
        if b else None,
        "ends_properly": b.deadlock_free if b else None,
        "final_always_reachable": b.final_always_reachable if b else None,
        "home_marking": b.home_marking if b else None,
        "reusable": b.reusable if b else None,
    }


def _structural(s, limits: dict[str, str]) -> dict[str, Any]:
    """Invariants, siphons and traps, each within its limit (past it: None and the reason)."""
    width = len(s.places) + len(s.transitions)

    def bounded_run(key: str, fn, *args):
        try:
            return fn(*args)
        except AnalysisLimit as e:
            limits[key] = e.message
            return None

    semi_p = bounded_run("semipositive_p_invariants", minimal_semipositive_p_invariants,
                         s, _limit(FARKAS_LIMIT, width))
    semi_t = bounded_run("semipositive_t_invariants", minimal_semipositive_t_invariants,
                         s, _limit(FARKAS_LIMIT, width))
    siphons = bounded_run("siphons", minimal_siphons, s, _limit(SIPHON_LIMIT, len(s.places)))
    traps = bounded_run("traps", minimal_traps, s, _limit(SIPHON_LIMIT, len(s.places)))
    control = (siphon_control(s, siphons, semi_p or [])
               if siphons is not None else None)
    return {
        "p_invariants": p_invariant_basis(s),
        "t_invariants": t_invariant_basis(s),
        "semipositive_p_invariants": semi_p,
        "semipositive_t_invariants": semi_t,
        "siphons": None if siphons is None else [s.names(x) for x in siphons],
        "siphon_control": None if control is None else [
            {"siphon": list(r.places), "marked": r.marked, "source": r.source,
             "controlled": r.controlled, "controlled_by": r.controlled_by}
            for r in control],
        # Iordache and Antsaklis: every siphon marked and controlled (inputs
        # from outside, which nothing inside writes to, need no control)
        "siphons_controlled": None if control is None else all(
            r.source or (r.marked and r.controlled) for r in control),
        "traps": None if traps is None else [s.names(x) for x in traps],
    }


def has_mission_interface(net: Net) -> bool:
    """Whether ``net`` has the paper's interface: fusion places (a template or a task, as
    our files label them), or a compiled mission's result places (which TINA and LoLA
    files keep by name)."""
    return (any(p.interface is not None for p in net.places)
            or any(r.id in net.place_index for r in RESULT_PLACES))


# ---------------------------------------------------------------------------
# the readable report


#: A column grows to fit its cells up to this width; longer cells (the
#: invariants of a compiled mission) overflow their row instead of widening
#: every row of the table.
COLUMN = 60


def _table(headers: list[str], rows: list[list[str]]) -> str:
    widths = [min(COLUMN, max(len(h), *(len(r[i]) for r in rows))) if rows else len(h)
              for i, h in enumerate(headers)]
    line = lambda cells: "  ".join(c.ljust(w) for c, w in zip(cells, widths)).rstrip()
    out = [line(headers), line(["-" * w for w in widths])]
    out.extend(line(r) for r in rows)
    return "\n".join(out)


def _yes(flag) -> str:
    return {True: "yes", False: "NO", None: "not computed"}[flag]


def render_text(r: dict[str, Any]) -> str:
    """The analysis as a report of short tables, for people."""
    out = [f"Net {r['net']}: {r.get('places', '?')} places, {r.get('transitions', '?')} "
           f"transitions; M0 = {{{', '.join(r.get('initial_marking', []))}}}", ""]
    out.append(_table(["property", "holds"], [
        ["bounded", _yes(r["bounded"])],
        ["every siphon marked and controlled (inputs aside)", _yes(r.get("siphons_controlled"))],
        ["safe (1-bounded)", _yes(r["safe"])],
        *([["deadlock-free (every dead marking is a proper end)", _yes(r.get("deadlock_free"))],
           ["a proper end is always reachable", _yes(r.get("final_always_reachable"))],
           ["reusable", _yes(r.get("reusable"))]] if r.get("interface") != "none" else
          [["deadlock-free (no dead marking)", _yes(r.get("deadlock_free"))],
           ["M0 reachable again from every marking", _yes(r.get("home_marking"))]]),
        ["reachable markings" + (" (coverability nodes)" if r["bounded"] is False else ""),
         "not computed" if r["states"] is None else f"{r['states']:,}"],
    ]))
    if r["terminal_markings"] is not None:
        out += ["", f"Terminal markings ({len(r['terminal_markings'])}):"]
        out += [f"  {{{', '.join(m)}}}" for m in r["terminal_markings"]] or ["  none"]
    if "p_invariants" in r:
        out += ["", f"P-invariants (a basis of {len(r['p_invariants'])}):"]
        rows = [[str(sum(c * _count(r, p) for p, c in y.items())), format_invariant(y)]
                for y in r["p_invariants"]]
        out.append(_table(["value at M0", "invariant"], rows) if rows else "  none")
        if r.get("siphon_control") is not None:
            out += ["", f"Minimal siphons ({len(r['siphon_control'])}):"]
            rows = [["{" + ", ".join(c["siphon"]) + "}", _yes(c["marked"]),
                     ("by " + format_invariant(c["controlled_by"])) if c["controlled_by"]
                     else ("source places (marked from outside)" if c["source"] else "NO")]
                    for c in r["siphon_control"]]
            out.append(_table(["siphon", "marked at M0", "controlled"], rows))
        if r.get("t_invariants") is not None:
            out += ["", f"T-invariants (a basis of {len(r['t_invariants'])}):"]
            out += [f"  {format_invariant(x)}" for x in r["t_invariants"]] or ["  none"]
    if r.get("partial"):
        found = r["partial"]["deadlock_found"]
        out += ["", f"Partial answer: {r['partial']['markings_explored']:,} markings explored; "
                + {True: "a dead marking was already found among them.",
                   False: "no dead marking among those expanded.",
                   None: "dead markings not checked."}[found]]
    if r.get("deadlocks") and r.get("interface") != "none":
        out += ["", "Dead markings that are not a proper end:"]
        out += [f"  {{{', '.join(m)}}}" for m in r["deadlocks"]]
    for key, why in r.get("limits", {}).items():
        out += ["", f"{key}: not computed ({why})"]
    return "\n".join(out)


def _count(r: dict[str, Any], place: str) -> int:
    for entry in r.get("initial_marking", []):
        name, _, n = entry.partition("*")
        if name == place:
            return int(n) if n else 1
    return 0
