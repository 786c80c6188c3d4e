"""One analysis of a net, as the JSON of ``mcl2pnml analyze --json`` and as a readable report.

The JSON object holds what docs/interop.md lists (``places``,
``transitions``, ``p_invariants``, ``siphons``, ``bounded``, ``safe``,
``terminal_markings``, ``reusable``, ``deadlock_free``, ``states``) and more:
``initial_marking``, ``t_invariants``, the minimal semi-positive invariants,
``traps``, each siphon's control (Iordache and Antsaklis 2006), and the
termination facts of :mod:`mcl2pnml.analysis.behaviour`.

Results that could not be computed within their limits (a state space past
``--max-states`` or its memory budget, ``--max-memory``; minimal siphons,
whose number can grow exponentially) are reported as ``null`` with the
reason under ``"limits"``, never silently left out; the structural results
are computed first, so they are there when the state space is too large,
with ``"partial"``: the markings explored and whether a dead one was met.

The memory budget (``--max-memory``) is the whole process's: each stage is
estimated before it runs and left out when it would not fit, and runs under
:func:`mcl2pnml.core.memory.guard`, which stops it at the budget; what the
budget left out is under ``"partial"`` too (``"left_out"``), so that the
answer is partial (exit status 3) rather than the process killed.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Any, Mapping

from mcl2pnml.core.bounds import MAX_STATES
from mcl2pnml.core.memory import (NEGLIGIBLE, SLACK, Budget, BudgetExceeded, floored, guard,
                                  margin, release, resident, size_text)
from mcl2pnml.core.net import Net
from mcl2pnml.core.payloads import RESULT_PLACES
from mcl2pnml.core.structure import structure
from mcl2pnml.core.vocabulary import CAN_END, NO_DEADLOCK, REUSABLE, SAFE, counted

from mcl2pnml.analysis.behaviour import behaviour
from mcl2pnml.analysis.structure.invariants import (AnalysisLimit, format_invariant,
                                                   minimal_semipositive_p_invariants,
                                                   minimal_semipositive_t_invariants,
                                                   p_invariant_basis, t_invariant_basis)
from mcl2pnml.analysis.structure.siphons import minimal_siphons, minimal_traps, siphon_control
from mcl2pnml.analysis.statespace.explore import ExplorationLimit, MemoryLimit, Progress, explore
from mcl2pnml.analysis.statespace.explorers import CHOICES

#: The explorer unless told: ``auto``, the fastest for the net's kind and size (the first
#: of the choices, :func:`~mcl2pnml.analysis.statespace.explore.explore`'s policy).
AUTO = CHOICES[0]

#: Bounds on the exponential parts; past them the result says "limit reached".
FARKAS_LIMIT = 20_000
SIPHON_LIMIT = 20_000
#: The work either enumeration may do, in row (or subproblem) entries: each
#: intermediate row of Farkas' algorithm spans every place and transition,
#: each siphon subproblem every place, so the counts above are lowered on a
#: wide net. 20,000 rows of a 20,000-place net took 50 s; a million places
#: would never end, nor fit in memory.
WORK_LIMIT = 20_000_000
#: The places the siphon (or trap) enumeration may look at in all, some seconds'
#: work: a minimal siphon of k places costs about 2k^2 to shrink and test (a ring
#: of 20,000 places, 8 * 10^8: minutes), a subproblem a copy of its parent's set.
SIPHON_WORK = 50_000_000

# What the stages hold, in bytes, measured on the nets of tests/support/bignets.py at
# 10^5 places and rounded up: the estimates a stage is refused or left out by.
#: the structure (pre, post, incidence both ways, pre- and post-sets) per arc and per node
STRUCTURE_ARC, STRUCTURE_NODE = 900, 700
#: the exact elimination (its sparse rows, the held entries and their index) per nonzero
#: of C, before fill-in
ELIMINATION_ENTRY = 600
#: a Farkas row, per entry of its two parts
FARKAS_ENTRY = 250
#: an answer printed (as JSON with indentation, or as the report's tables), per entry
#: of a vector or set: the objects, the text and the pieces it is joined from
OUTPUT_ENTRY = 160


def _limit(count: int, width: int) -> int:
    """The count limit of an enumeration whose items are ``width`` entries wide."""
    return max(1, min(count, WORK_LIMIT // max(1, width)))


def structure_estimate(net: Net) -> int:
    """Bytes the indexed structure of ``net`` holds (:func:`mcl2pnml.core.structure.structure`)."""
    return (len(net.arcs) * STRUCTURE_ARC
            + (len(net.places) + len(net.transitions)) * STRUCTURE_NODE)


def elimination_estimate(s) -> int:
    """Bytes an invariant basis's elimination holds at least: the nonzeros of C as
    rationals, twice (the integer matrix and its rational copy). Fill-in may add
    more, which no estimate tells: the elimination also runs under the budget's guard."""
    return 2 * ELIMINATION_ENTRY * sum(len(col) for col in s.incidence)


def farkas_rows(s, free: int, transposed: bool = False) -> int:
    """How many Farkas rows fit in ``free`` bytes: each starts as a row of C (its
    nonzeros) and one entry of y, and a new row is about as long as two of them."""
    rows = s.incidence if transposed else s.incidence_rows
    nonzeros = sum(len(r) for r in rows)
    entry = FARKAS_ENTRY * (2 * max(1, nonzeros // max(1, len(rows))) + 2)
    return max(1, free // entry)


def output_estimate(vectors) -> int:
    """Bytes printing a list of vectors or sets takes: its entries, with their names."""
    return sum(len(v) * OUTPUT_ENTRY + sum(map(len, v)) * 2 for v in vectors)


@dataclass(frozen=True)
class StateSpaceFacts:
    """What the state space says of a net (all of ``--state-space``): None where it was not
    explored; the termination facts are :mod:`mcl2pnml.analysis.behaviour`'s."""

    net: str
    places: int
    transitions: int
    arcs: int
    #: the initial marking as the answer writes markings: ``P``, ``P*2``
    initial_marking: list[str]
    states: int | None
    bounded: bool | None
    safe: bool | None
    terminal_markings: list[list[str]] | None
    #: "mission": the paper's interface (fusion places or result places); "none": any other
    interface: str
    deadlock_free: bool | None
    deadlock_free_textbook: bool | None
    deadlocks: list[list[str]] | None
    ends_properly: bool | None
    final_always_reachable: bool | None
    home_marking: bool | None
    reusable: bool | None


@dataclass(frozen=True)
class Structural:
    """Invariants, siphons and traps (:class:`_Stages`); each None past its limit or left
    out by the budget, the reason in :attr:`Analysis.limits`."""

    p_invariants: list[dict[str, int]] | None
    t_invariants: list[dict[str, int]] | None
    semipositive_p_invariants: list[dict[str, int]] | None
    semipositive_t_invariants: list[dict[str, int]] | None
    siphons: list[list[str]] | None
    #: each siphon's control (Iordache and Antsaklis 2006): siphon, marked, source,
    #: controlled, controlled_by
    siphon_control: list[dict[str, Any]] | None
    siphons_controlled: bool | None
    traps: list[list[str]] | None


@dataclass(frozen=True)
class Partial:
    """Why the answer is partial: the exploration stopped (``stopped``: the markings it
    explored, None when they are lost, and whether a dead one was met), or the budget
    left stages out (``left_out``: each stage and why)."""

    stopped: bool = False
    markings_explored: int | None = None
    deadlock_found: bool | None = None
    left_out: Mapping[str, str] = field(default_factory=dict)

    def as_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        if self.stopped:
            out.update(markings_explored=self.markings_explored,
                       deadlock_found=self.deadlock_found)
        if self.left_out:
            out["left_out"] = dict(self.left_out)
        return out


@dataclass(frozen=True)
class CertifiedFacts:
    """A certificate beside the net that holds for it (:mod:`mcl2pnml.certify`): the
    behaviour it proves, without exploring; ``ends`` those the checker derived."""

    file: str
    ends: list[str]

    def as_json(self) -> dict[str, Any]:
        return {"file": self.file, "holds": True, "ends": self.ends}


@dataclass(frozen=True)
class Analysis:
    """One analysis of a net: what :func:`analyze` found, as ``analyze --json`` prints it
    (:meth:`as_json`) and as the report for people (:meth:`text`).

    ``structural``: None under ``--state-space`` (the answer then has no such keys);
    ``limits``: each result not computed, and why; ``certificate``: the certificate whose
    facts replace the exploration's; ``stubborn``: verdicts found under partial-order
    reduction.
    """

    facts: StateSpaceFacts
    structural: Structural | None = None
    partial: Partial | None = None
    limits: Mapping[str, str] = field(default_factory=dict)
    certificate: CertifiedFacts | None = None
    stubborn: bool = False

    def certified(self, certificate: CertifiedFacts) -> "Analysis":
        """This analysis with the facts a holding certificate proves (sections 2.3-2.5):
        bounded, 1-safe, free of deadlocks, ends properly, a proper end always reachable,
        reusable (:mod:`mcl2pnml.core.vocabulary`)."""
        proven = replace(self.facts, bounded=True, safe=True, deadlock_free=True,
                         ends_properly=True, final_always_reachable=True, reusable=True)
        return replace(self, facts=proven, certificate=certificate)

    def as_json(self) -> dict[str, Any]:
        """The object ``analyze --json`` prints, its keys in the order it prints them."""
        out = {f.name: getattr(self.facts, f.name) for f in fields(StateSpaceFacts)}
        if self.structural is not None:
            out.update((f.name, getattr(self.structural, f.name))
                       for f in fields(Structural))
        if self.partial is not None:
            out["partial"] = self.partial.as_json()
        if self.limits:
            out["limits"] = dict(self.limits)
        if self.certificate is not None:
            out["certificate"] = self.certificate.as_json()
        if self.stubborn:
            out["stubborn"] = True
        return out

    def text(self) -> str:
        """The report of short tables, for people (:func:`render_text`)."""
        return render_text(self.as_json())


def analyze(net: Net, initial: dict[str, int] | None = None, *, state_space_only: bool = False,
            max_states: int = MAX_STATES, progress: Progress | None = None,
            explorer: str = AUTO, max_memory: int | None = None,
            explore_states: bool = True, enumerate_all: bool = False) -> Analysis:
    """Everything we know how to prove about ``net``, as typed data (:class:`Analysis`).

    ``explorer`` is one of :data:`mcl2pnml.analysis.statespace.explore.BACKENDS`; ``max_memory``
    is the exploration's budget in bytes (default: half the memory available).
    The invariant bases come first, then the exploration, then the enumerations
    (minimal semi-positive invariants, siphons, traps: exponential in the worst case,
    and past their bounds on every compiled mission) where the reachability graph was
    not built whole, on a net of at most :data:`QUICK_PLACES` places, or with
    ``enumerate_all``; elsewhere the graph decides every property they bear on, and they
    are not run (:data:`DECIDED`). An exploration stopped by its budget still ends in a partial
    answer: ``"partial"`` says how many markings were explored and whether a dead
    marking was met among them.
    ``explore_states=False``: no exploration (a certificate decides the behaviour), the
    state space's facts left None.
    """
    # the budget is the whole process's: what the net and the structural results
    # hold counts against it (the default, half of what is free now, comes on top
    # of what the process holds already)
    budget = Budget(max_memory)
    if initial is not None:
        net = net.with_initial(initial)
    budget.check(structure_estimate(net), f"net '{net.name}': {len(net.places):,} places, "
                 f"{len(net.transitions):,} transitions and {len(net.arcs):,} arcs to analyse")
    s = structure(net)
    limits: dict[str, str] = {}
    left_out: dict[str, str] = {}
    partial = None
    stages = _Stages(s, limits, left_out, budget)
    bases = {} if state_space_only else stages.bases()
    release()

    def structural(decided: bool) -> dict[str, Any]:
        if state_space_only:
            return {}
        if enumerate_all or not decided or len(s.places) <= QUICK_PLACES:
            return {**bases, **stages.enumerations()}
        return {**bases, **stages.decided()}

    if not explore_states:     # the caller knows the behaviour otherwise (a certificate)
        result = _state_space_facts(net, s, None)
        result.update(structural(True))
        _fit_output(result, limits, left_out, budget)
        return _typed(result, state_space_only, None, limits)
    try:
        with guard(floored(budget), "the exploration"):
            space = explore(s, max_states=max_states, progress=progress, backend=explorer,
                            max_memory=budget.limit,
                            held=resident() + 2 * margin(budget.limit))
            facts = _state_space_facts(net, s, space)
            whole = not getattr(space, "coverability", False)
            del space   # the markings are not the structural stages' to pay for
        release()
    except BudgetExceeded as e:
        # an explorer's estimate of its markings fell short (or what follows the
        # exploration did not fit): the markings found are lost with it
        limits["states"] = e.message
        partial = Partial(stopped=True)
        facts = _state_space_facts(net, s, None)
    except ExplorationLimit as e:
        if state_space_only and not isinstance(e, MemoryLimit):
            raise
        limits["states"] = e.message
        partial = Partial(True, e.explored, None if e.deadlocks is None else e.deadlocks > 0)
        facts = _state_space_facts(net, s, None)
    result = facts
    result.update(structural(partial is None and whole))
    _fit_output(result, limits, left_out, budget)
    if left_out:
        partial = replace(partial or Partial(), left_out=left_out)
    return _typed(result, state_space_only, partial, limits)


def _typed(result: dict[str, Any], state_space_only: bool, partial: Partial | None,
           limits: dict[str, str]) -> Analysis:
    """The answer built as a dictionary (the budget leaves its lists out by key) as an
    :class:`Analysis`."""
    facts = StateSpaceFacts(**{f.name: result[f.name] for f in fields(StateSpaceFacts)})
    structural = None if state_space_only else Structural(
        **{f.name: result[f.name] for f in fields(Structural)})
    return Analysis(facts, structural, partial, limits)


#: The lists of the answer that can be left out when printing them would not fit,
#: largest first among them.
_PRINTED = ("siphon_control", "traps", "siphons", "semipositive_t_invariants",
            "semipositive_p_invariants", "t_invariants", "p_invariants")


def _fit_output(result: dict[str, Any], limits: dict[str, str], left_out: dict[str, str],
                budget: Budget) -> None:
    """Leave out, largest first, the lists that printing would not fit in the budget.

    Printing (``--json`` or the report) builds the text whole before writing it:
    about :data:`OUTPUT_ENTRY` bytes an entry. The number of vectors left out is
    said, so that a reader still knows the dimension of an invariant space.
    """
    sizes = {}
    for key in _PRINTED:
        value = result.get(key)
        if value:
            entries = [c["siphon"] for c in value] if key == "siphon_control" else value
            sizes[key] = output_estimate(entries)
    free = budget.free()
    total = sum(sizes.values())
    for key in sorted(sizes, key=sizes.get, reverse=True):
        if total <= max(free, NEGLIGIBLE):
            break
        n = len(result[key])
        why = (f"{n:,} {'vectors' if 'invariants' in key else 'sets'}, not printed: printing "
               f"them would need about {size_text(sizes[key])}; {budget.says()}")
        result[key] = None
        limits[key] = left_out[key] = why
        total -= sizes[key]
        if key == "siphons":
            result["siphon_control"] = result["siphons_controlled"] = None


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
        # the textbook's deadlock-freedom, whatever the interface: no dead marking at all
        # (a mission's proper ends are dead, so it is false for every mission that ends)
        "deadlock_free_textbook": not b.terminal if b else None,
        "deadlocks": sorted(list(m) for m in (b.improper if ours else b.terminal))
        if b else None,
        "ends_properly": b.deadlock_free if b else None,
        "final_always_reachable": b.final_always_reachable if b else None,
        "home_marking": b.home_marking if b else None,
        "reusable": b.reusable if b else None,
    }


#: What each structural stage computes, as its messages name it.
STAGES = {
    "p_invariants": "the P-invariant basis (exact elimination)",
    "t_invariants": "the T-invariant basis (exact elimination)",
    "semipositive_p_invariants": "the minimal semi-positive P-invariants (Farkas)",
    "semipositive_t_invariants": "the minimal semi-positive T-invariants (Farkas)",
    "siphons": "the minimal siphons",
    "traps": "the minimal traps",
    "siphon_control": "the control of the siphons",
}


#: A net this small is enumerated within the full bounds whatever decides its properties:
#: the paper's templates take a second at most, and their siphons are its equations'.
#: A larger one, whose reachability graph was built whole, is not enumerated at all:
#: the graph decides every property they bear on, and a compiled mission's minimal
#: siphons and semi-positive P-invariants are past even the full bounds, reached in
#: seconds. ``--structure`` asks for them.
QUICK_PLACES = 100
#: What the report says of each enumeration the graph made moot.
DECIDED = ("the reachability graph, built whole, decides every property they bear on; "
           "--structure computes them")


class _Stages:
    """The structural stages of one analysis, each within its limit (past it: None and the
    reason in ``limits``).

    Each stage is estimated first and left out when its estimate does not fit
    in what is left of ``budget``; it then runs under the budget's guard. What
    the budget left out is also in ``left_out``: the answer is partial.
    """

    def __init__(self, s, limits: dict[str, str], left_out: dict[str, str], budget: Budget):
        self.s, self.limits, self.left_out, self.budget = s, limits, left_out, budget

    def run(self, key: str, fn, *args, need: int = 0):
        what = STAGES[key]
        try:
            self.budget.check(need, what)
            with guard(floored(self.budget), what):
                return fn(*args)
        except BudgetExceeded as e:
            self.limits[key] = self.left_out[key] = e.message
        except AnalysisLimit as e:
            self.limits[key] = e.message
        finally:
            release()   # what a stage built and dropped is not the next stage's to pay
        return None

    def bases(self) -> dict[str, Any]:
        """The invariant bases (linear algebra): before the exploration, whose budget then
        counts what they hold."""
        s = self.s
        elimination = elimination_estimate(s)
        return {"p_invariants": self.run("p_invariants", p_invariant_basis, s, need=elimination),
                "t_invariants": self.run("t_invariants", t_invariant_basis, s, need=elimination)}

    def decided(self) -> dict[str, Any]:
        """The enumerations a reachability graph built whole made moot (:data:`DECIDED`)."""
        for key in ("semipositive_p_invariants", "semipositive_t_invariants", "siphons",
                    "traps"):
            self.limits[key] = DECIDED
        return self._enumerated(None, None, None, None)

    def enumerations(self) -> dict[str, Any]:
        """The minimal semi-positive invariants, siphons and traps, and the siphons'
        control, within their bounds."""
        s = self.s
        free = max(self.budget.free(), NEGLIGIBLE)
        rows = _limit(FARKAS_LIMIT, len(s.places) + len(s.transitions))
        semi_p = self.run("semipositive_p_invariants", minimal_semipositive_p_invariants,
                          s, min(rows, farkas_rows(s, free)))
        semi_t = self.run("semipositive_t_invariants", minimal_semipositive_t_invariants,
                          s, min(rows, farkas_rows(s, free, True)))
        sets = _limit(SIPHON_LIMIT, len(s.places))
        siphons = self.run("siphons", minimal_siphons, s, sets, SIPHON_WORK)
        traps = self.run("traps", minimal_traps, s, sets, SIPHON_WORK)
        return self._enumerated(semi_p, semi_t, siphons, traps)

    def _enumerated(self, semi_p, semi_t, siphons, traps) -> dict[str, Any]:
        s = self.s
        control = None
        if siphons is not None:
            _with_sympy()
            control = self.run("siphon_control", siphon_control, s, siphons, semi_p or [])
        return {
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


def _with_sympy() -> None:
    # the siphons' control uses sympy's linear programs: loaded before its guard (the
    # module is not the stage's); a net whose siphons are past their bound does without
    # it (most of a second to import)
    import sympy  # noqa: F401


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


def _textbook(r: dict[str, Any]) -> tuple[bool | None, str]:
    """The textbook's deadlock-freedom (no dead marking reachable), with how many are."""
    free = r.get("deadlock_free_textbook")
    if free is None and r.get("terminal_markings") is not None:   # an answer of before
        free = not r["terminal_markings"]
    if free is not False or r.get("terminal_markings") is None:
        return free, _yes(free)
    n = len(r["terminal_markings"])
    return free, f"no ({n:,} dead marking{'s' if n != 1 else ''})"


def verdict_rows(r: dict[str, Any]) -> list[tuple[str, bool | None, str]]:
    """The analysis's verdicts (``r`` as :meth:`Analysis.as_json` gives it), each as the
    property, whether it holds (None: not computed, a count, or the textbook's deadlocks of
    a mission, whose dead markings are its ends) and the words the report says it in: the
    report's first table, and a notebook's (:mod:`mcl2pnml.notebook`)."""
    def row(what: str, key: str) -> tuple[str, bool | None, str]:
        return what, r.get(key), _yes(r.get(key))
    free, said = _textbook(r)
    textbook = ("deadlock-free (textbook: no dead marking reachable)",
                free if r.get("interface") == "none" else None, said)
    states = r["states"]
    return [
        row("bounded", "bounded"),
        row("every siphon marked and controlled (inputs aside)", "siphons_controlled"),
        row(SAFE, "safe"),
        *([textbook,
           row(NO_DEADLOCK, "deadlock_free"),
           row(CAN_END, "final_always_reachable"),
           row(REUSABLE, "reusable")] if r.get("interface") != "none" else
          [textbook, row("M0 reachable again from every marking", "home_marking")]),
        ("reachable markings" + (" (coverability nodes)" if r["bounded"] is False else ""),
         None, "not computed" if states is None else f"{states:,}"),
    ]


def render_text(r: dict[str, Any]) -> str:
    """The analysis as a report of short tables, for people."""
    size = ", ".join(counted(r[key], noun) if isinstance(r.get(key), int) else f"? {key}"
                     for key, noun in (("places", "place"), ("transitions", "transition")))
    out = [f"Net {r['net']}: {size}; M0 = {{{', '.join(r.get('initial_marking', []))}}}", ""]
    out.append(_table(["property", "holds"], [[what, said] for what, _, said in verdict_rows(r)]))
    m0 = _tokens(r)
    if r["terminal_markings"] is not None:
        out += ["", f"Terminal markings ({len(r['terminal_markings'])}), the dead ones, as "
                "changes from M0 (--json: in full):"]
        out += [f"  {_change(m0, m)}" for m in r["terminal_markings"]] or ["  none"]
    if "p_invariants" in r:
        if r["p_invariants"] is None:
            out += ["", "P-invariants: not computed (see below)"]
        else:
            out += ["", f"P-invariants (a basis of {len(r['p_invariants'])}):"]
            m0 = _tokens(r)
            rows = [[str(sum(c * m0.get(p, 0) for p, c in y.items())), format_invariant(y)]
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
            out += ["", f"T-invariants (a basis of {len(r['t_invariants'])}; its entries may "
                    "be negative):"]
            out += [f"  {format_invariant(x)}" for x in r["t_invariants"]] or ["  none"]
        semi = r.get("semipositive_t_invariants")
        if semi is not None:
            out += ["", f"Minimal semi-positive T-invariants ({len(semi)}; no negative entry: "
                    "firing each, where it can fire, returns to the marking it left):"]
            out += [f"  {format_invariant(x)}" for x in semi] or ["  none"]
    partial = r.get("partial") or {}
    if "markings_explored" in partial:
        found, explored = partial["deadlock_found"], partial["markings_explored"]
        out += ["", "Partial answer: " + ("the markings explored are lost; " if explored is None
                                          else f"{explored:,} markings explored; ")
                + {True: "a dead marking was already found among them.",
                   False: "no dead marking among those expanded.",
                   None: "dead markings not checked."}[found]]
    if partial.get("left_out"):
        out += ["", "Partial answer: left out to stay within the memory budget: "
                + ", ".join(k.replace("_", " ") for k in partial["left_out"]) + "."]
    if r.get("deadlocks") and r.get("interface") != "none":
        out += ["", "Dead markings that are not a proper end, as changes from M0:"]
        out += [f"  {_change(m0, m)}" for m in r["deadlocks"]]
    for key, why in r.get("limits", {}).items():
        out += ["", f"{key}: not computed ({why})"]
    out += ["", "The terms (proper end, reusable, siphon, controlled, inputs aside, "
            "invariants): see docs/glossary.md"]
    return "\n".join(out)


def _change(m0: dict[str, int], marking: list[str]) -> str:
    """A marking as its difference from M0: ``-B +FAIL`` (``p*2``: two tokens; ``w``: any
    number, on a coverability node), or ``M0`` when it is M0."""
    tokens = {}
    for entry in marking:
        name, _, n = entry.partition("*")
        tokens[name] = n or "1"
    words = []
    for name in sorted(set(m0) | set(tokens), key=lambda p: (p not in m0, p)):
        have, had = tokens.get(name, "0"), m0.get(name, 0)
        if not have.isdigit():          # unbounded: omega
            words.append(f"+{name}*{have}")
            continue
        delta = int(have) - had
        if delta:
            words.append(("+" if delta > 0 else "-") + name
                         + (f"*{abs(delta)}" if abs(delta) != 1 else ""))
    return " ".join(words) or "M0 (no change)"


def _tokens(r: dict[str, Any]) -> dict[str, int]:
    """The initial marking of the answer, place -> tokens (read once: a scan per
    place would be quadratic on a net marked everywhere)."""
    tokens = {}
    for entry in r.get("initial_marking", []):
        name, _, n = entry.partition("*")
        tokens[name] = int(n) if n else 1
    return tokens
