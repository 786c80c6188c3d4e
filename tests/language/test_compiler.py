"""Step 2 of the compiler: missions to one composed net, proven by the analysis.

Golden files in the sqlglot style: for each mission, the functional form
(step 1), the size of the net (step 2), and the verdict of the analysis of
the templates issue (state space, 1-safety, deadlocks, reusability, the
results the mission can end with), from ``mission.B`` and again with an
abort already pending (``mission.A``). The small missions under
``data/mcl/golden`` cover one feature each; ``examples/`` are the realistic
ones. ``MCL2PNML_REGOLD=1`` rewrites the golden files (tests/support/helpers.py).
"""
from __future__ import annotations

from pathlib import Path

import pytest

from mcl2pnml.analysis.behaviour import behaviour
from mcl2pnml.analysis.statespace.explore import explore
from mcl2pnml.pipeline import check_file, compile_file
from mcl2pnml.language.compiler import compile_checked
from mcl2pnml.language.functional import format_node, function_expression, mission_expression
from mcl2pnml.core.net import ArcKind, Timing, thaw
from mcl2pnml.core.structure import structure
from mcl2pnml.io.pnml import parse_pnml, write_pnml, to_pnml

from bench.missions import survey

from helpers import DATA, ROOT, assert_golden

GOLDEN = DATA / "mcl" / "golden"
SMALL = sorted(GOLDEN.glob("*.mcl"))
EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))
#: Missions whose state space with a pending abort is too large for every run
#: (millions of markings): their abort case runs under ``-m slow``.
ABORT_IS_SLOW = {"dam_inspection"}


def golden_path(mission: Path) -> Path:
    if mission.parent == GOLDEN:
        return mission.with_suffix(".golden")
    return GOLDEN / "examples" / f"{mission.stem}.golden"


def verdict(net, initial: dict[str, int]) -> tuple[list[str], object, object]:
    """The analysis lines for one start, plus the state space and behaviour."""
    space = explore(structure(net), initial)
    b = behaviour(space)
    mission = {p.id for p in net.places if p.id.startswith("mission.")}
    results = sorted({" + ".join(p for p in marking if p.split("*")[0] in mission)
                      for marking in b.terminal})
    lines = [f"states {space.states:,}; {'1-safe' if space.safe else 'NOT SAFE'}; "
             f"{'deadlock-free' if b.deadlock_free else 'DEADLOCKS'}; "
             f"{'reusable' if b.reusable else 'NOT REUSABLE'}",
             *(f"ends with {r}" for r in results)]
    return lines, space, b


def render(mission: Path, with_abort: bool) -> tuple[str, list]:
    checked = check_file(mission)
    lines = ["# step 1: functional form"]
    for name in checked.function_order:
        f = checked.functions[name]
        lines.append(f"{name}({', '.join(f.params)}) = {format_node(function_expression(f))}")
    lines.append(format_node(mission_expression(checked.mission)))
    net = compile_checked(checked)
    timed = sum(t.timing is not None for t in net.transitions)
    reads = sum(a.kind is ArcKind.READ for a in net.arcs)
    lines += ["# step 2: one composed net",
              f"{len(net.places):,} places, {len(net.transitions):,} transitions ({timed} timed), "
              f"{len(net.arcs):,} arcs ({reads} read), {sum(net.initial.values())} tokens"]
    checks = []
    starts = [("mission.B", {})] + ([("mission.B + mission.A", {"mission.A": 1})]
                                    if with_abort else [])
    for label, extra in starts:
        initial = {**net.initial, **extra}
        found, space, b = verdict(net, initial)
        lines += [f"# analysis from {label}", *found]
        checks.append((label, space, b))
    return "\n".join(lines) + "\n", checks


CASES = [pytest.param(m, id=m.stem) for m in SMALL + EXAMPLES]


@pytest.mark.parametrize("mission", CASES)
def test_golden_and_proven(mission: Path):
    text, checks = render(mission, with_abort=mission.stem not in ABORT_IS_SLOW)
    assert_golden(golden_path(mission), text)
    for label, space, b in checks:
        # the properties themselves, so that a regression names what broke
        assert space.safe, f"{mission.name} from {label}: not 1-safe"
        assert b.deadlock_free, f"{mission.name} from {label}: deadlocks {b.improper[:3]}"
        assert b.reusable, f"{mission.name} from {label}: not reusable"


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(ABORT_IS_SLOW))
def test_large_missions_with_a_pending_abort(name: str):
    net = compile_file(ROOT / "examples" / f"{name}.mcl")
    _, space, b = verdict(net, {**net.initial, "mission.A": 1})
    assert space.safe and b.deadlock_free and b.reusable


def compiled(path: Path):
    return compile_file(path)


def inside(space, marker: str) -> list[int]:
    """Per reachable marking, how many call sites of ``marker`` are inside their callee."""
    return [sum(1 for p in space.marking(n) if marker in p and p.endswith(".IN"))
            for n in range(space.states)]


@pytest.mark.parametrize("mission, callers", [
    ("concurrent_calls", ["Goto-"]),           # one task, two calls at once: its gate
    ("shared_primitive", ["Dive-", "Hold-"]),  # two tasks, one primitive: its lock
])
def test_concurrent_calls_are_serialized(mission, callers):
    net = compiled(GOLDEN / f"{mission}.mcl")
    space = explore(structure(net))
    counts = [sum(c) for c in zip(*(inside(space, m) for m in callers))]
    assert max(counts) == 1, "two calls inside at once"
    # ... and both calls do run, in either order
    sites = {p.id for p in net.places if p.id.endswith(".IN")
             and any(m in p.id for m in callers)}
    assert len(sites) == 2
    for site in sites:
        assert any(space.markings[n][space.structure.place_index[site]]
                   for n in range(space.states)), f"{site} never runs"


def test_a_pending_call_aborted_ends_aborted_without_starting(tmp_path):
    path = tmp_path / "one.mcl"
    path.write_text("primitive P(x);\ntask T(x) = AchieveGoal(P(x)) timeout 5;\n"
                    "mission { T(1.0); }\n")
    net = compiled(path)
    start = {**net.initial, "mission.A": 1}
    space = explore(structure(net), start)
    s = space.structure
    abort = s.transition_index["mission.pending_abort"]
    [after] = [d for k, d in enumerate(space.dst) if space.src[k] == 0 and space.trans[k] == abort]
    expected = {p: n for p, n in start.items() if p not in ("mission.B", "mission.A")}
    assert space.marking(after) == {**expected, "mission.ABORTED": 1}
    assert after in space.terminal   # nothing was started: the task and P are at rest


def test_payloads_carry_what_the_vehicle_needs():
    """Actions, bindings with their scope, time-outs and events: the PNML alone runs."""
    net = compiled(GOLDEN / "functions.mcl")
    t = net.transition_index
    payload = lambda tid: thaw(t[tid].payload)
    enables = [a for tr in net.transitions for a in (thaw(tr.payload) or {}).get("actions", [])
               if a["action"] == "enable"]
    assert {"action": "enable", "primitive": "KeepDepth", "scope": "Depth",
            "args": [{"param": "d"}]} in enables
    assert {"action": "enable", "primitive": "GoToWayPoint", "scope": "Goto",
            "args": [{"param": "wp"}]} in enables
    enters = {tid: payload(tid) for tid in t if tid.endswith(".enter")}
    # inside a function, arguments are the function's parameters
    assert enters["Leg.Depth-1.enter"]["bind"] == {"d": {"param": "d"}}
    assert enters["Leg.Depth-1.enter"]["scope"] == "Leg"
    # from the mission, constants are resolved to values
    leg = next(p for tid, p in enters.items()
               if p["call"] == "Leg" and p["scope"] == "mission")
    assert leg["bind"] == {"wp": {"value": [0.0, 0.0, 2.0]}, "d": {"value": 0.0}}
    box = next(p for p in enters.values() if p["call"] == "Leg" and p["scope"] == "Box"
               and p["bind"]["wp"] == {"value": [10.0, 0.0, 2.0]})
    assert box["bind"]["d"] == {"param": "d"}
    # time-outs are timed transitions, with the delay of the task's declaration
    assert t["Goto.t03"].timing == Timing.delay(100) and payload("Goto.t03")["timeout"] == 100
    assert t["Depth.t03"].timing == Timing.delay(60)
    # every primitive transition says which event of which primitive it is
    events = {payload(tid)["event"] for tid in t if tid.startswith("KeepDepth.")}
    assert events == {"on", "achieved", "failed", "off"}


def test_a_task_without_timeout_has_no_timeout_transition():
    net = compiled(GOLDEN / "monitor_abort.mcl")
    assert "Goto.t03" not in net.transition_index
    assert "Obstacle.t03" in net.transition_index


@pytest.mark.parametrize("mission", EXAMPLES + SMALL, ids=lambda p: p.stem)
def test_compiled_pnml_is_valid_and_keeps_everything(mission, assert_valid):
    net = compiled(mission)
    data = to_pnml(net)
    assert_valid(data, mission.name)
    assert parse_pnml(data) == net   # payloads and timings included: the executor's input


def _grows_exactly_linearly(tmp_path, most: int) -> None:
    """The size of the net is affine in the number of calls, up to ``most`` calls (the time
    is in bench/)."""
    sizes = {}
    for calls in (100, 200, most):
        path = tmp_path / f"survey{calls}.mcl"
        path.write_text(survey(calls))
        net = compiled(path)
        sizes[calls] = (len(net.places), len(net.transitions), len(net.arcs))
        if calls == most:
            out = write_pnml(net, tmp_path / "survey.pnml")
            assert out.stat().st_size > 0
            assert sum(1 for tr in net.transitions if tr.id.endswith(".enter")) == calls
    per_call = [(b - a) / 100 for a, b in zip(sizes[100], sizes[200])]
    predicted = tuple(round(a + (most - 100) * d) for a, d in zip(sizes[100], per_call))
    assert sizes[most] == predicted


def test_two_thousand_calls_compile_and_grow_exactly_linearly(tmp_path):
    _grows_exactly_linearly(tmp_path, 2_000)


@pytest.mark.slow
def test_ten_thousand_calls_compile_and_grow_exactly_linearly(tmp_path):
    _grows_exactly_linearly(tmp_path, 10_000)


@pytest.mark.parametrize("mission", [
    pytest.param(m, marks=pytest.mark.slow) if m.stem == "dam_inspection" else m
    for m in EXAMPLES], ids=lambda p: p.stem)
def test_every_task_reduced_ends_the_mission_alike(mission: Path):
    """Section 2.3's reduced-model argument, on whole missions: with each task replaced
    by its reduced model (Fig. 3), the mission's own places end the same ways, from
    mission.B and with an abort pending (dam inspection, whose full state space takes
    minutes with an abort pending, under the slow marker)."""
    from mcl2pnml.analysis.behaviour import final_markings_agree
    from mcl2pnml.language.compiler import compile_checked as compile_

    checked = check_file(mission)
    full, reduced = compile_(checked), compile_(checked, reduced=True)
    assert not any(p.id.endswith(".LOCK") or ".S1" in p.id for p in reduced.places)
    assert len(reduced.places) < len(full.places)
    ends = ["mission.OK", "mission.FAIL", "mission.ABORTED", "mission.MTX", "mission.A"]
    for extra in ({}, {"mission.A": 1}):
        agree = final_markings_agree(full, reduced, ends, {**full.initial, **extra},
                                     {**reduced.initial, **extra})
        assert agree.equal, (extra, agree.finals_a, agree.finals_b)
