"""Generated missions, proven by the analysis and run by both engines.

Every mission that ``missions()`` draws (structures three levels deep, the
same task called from several places and from parallel branches, functions
calling tasks and functions, functions as conditions) is compiled, and its
net's state space is explored as the golden files state a verdict: started
from ``mission.B``, and again with an abort already pending
(``mission.A``). Both must be 1-safe, deadlock-free and reusable (mcl.md:
"Every net returns to its initial marking plus exactly one result place";
"The composed net stays 1-safe"). The executor and the reference engine
must also agree on outcome, time and trace, with generated vehicle scripts.

State spaces are bounded by ``MAX_STATES`` per start. A mission past the
limit is still run on both engines, then discarded (``assume``); each test
counts what it drew and what it analysed, and fails if too few were
analysed, so that a generator drifting to huge missions cannot pass by
proving nothing.
"""
from __future__ import annotations

from collections import Counter

import pytest
from hypothesis import HealthCheck, assume, given, seed, settings, strategies as st

from mcl2pnml.analysis.behaviour import behaviour
from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore
from mcl2pnml.pipeline import check_source
from mcl2pnml.core.structure import structure
from mcl2pnml.language import ast
from mcl2pnml.language.compiler import compile_checked

from helpers import both
from missions import missions, scripts

MAX_STATES = 20_000
#: The most parallel and monitor structures in one mission, functions included.
MAX_CONCURRENT = 2
#: Three levels of structures, two statements a block, at most two structures
#: that run things at once: deep, yet small enough that most state spaces fit
#: (each concurrent structure multiplies them, and a pending abort races every
#: branch; with three, about 40% of missions pass 20,000 markings, with two 20%).
GENERATED = missions(depth=3, width=2, function_depth=1).filter(
    lambda s: s.count("parallel(") + s.count("monitor(") <= MAX_CONCURRENT)
#: The share of drawn missions that must be analysed from both starts.
MIN_ANALYSED = 0.7
FAST_EXAMPLES = 40
#: The seed of the draws in `make test` (the slow variant seeds each chunk apart).
FAST_SEED = 0
SLOW_CHUNKS, SLOW_EXAMPLES = 10, 1_000     # 10,000 analysed missions in all
STARTS = (("mission.B", {}), ("mission.B + mission.A", {"mission.A": 1}))


# -- what a mission exercises -------------------------------------------------------


def _children(s) -> list:
    if isinstance(s, ast.Block):
        return list(s.body)
    if isinstance(s, ast.Parallel):
        return list(s.items)
    if isinstance(s, ast.Monitor):
        return [s.watched, s.watcher]
    if isinstance(s, ast.If):
        return [s.condition, s.then] + ([s.otherwise] if s.otherwise else [])
    if isinstance(s, ast.While):
        return [s.condition, s.body]
    return []


def _depth(s) -> int:
    """Structures nested in ``s`` (blocks included), not counting function bodies."""
    kids = _children(s)
    return (1 + max(map(_depth, kids), default=0)) if not isinstance(s, ast.Call) else 0


def _tasks_run(s, functions: dict) -> set[str]:
    """Every task that ``s`` may run, through the functions it calls."""
    if isinstance(s, ast.Call):
        f = functions.get(s.name)
        return _tasks_run(f.body, functions) if f else {s.name}
    return set().union(*(_tasks_run(k, functions) for k in _children(s)))


def _walk(s):
    yield s
    for k in _children(s):
        yield from _walk(k)


def features(checked) -> set[str]:
    """The shapes the generator is meant to reach, found in one checked mission."""
    fs, found = checked.functions, set()
    bodies = [checked.mission.body] + [f.body for f in fs.values()]
    nodes = [n for b in bodies for n in _walk(b)]
    calls = Counter(n.name for n in nodes if isinstance(n, ast.Call))
    if _depth(checked.mission.body) >= 4:          # the body's block + three structures
        found.add("three levels deep")
    if any(calls[t] >= 2 for t in checked.tasks):
        found.add("a task called from several places")
    for n in nodes:
        if isinstance(n, ast.Parallel):
            runs = [_tasks_run(i, fs) for i in n.items]
            if any(a & b for i, a in enumerate(runs) for b in runs[i + 1:]):
                found.add("one task in two parallel branches")
        if isinstance(n, (ast.If, ast.While)) and isinstance(n.condition, ast.Call) \
                and n.condition.name in fs:
            found.add("a function as a condition")
    for f in fs.values():
        inner = {n.name for n in _walk(f.body) if isinstance(n, ast.Call)}
        if inner & set(checked.tasks):
            found.add("a function calling a task")
        if inner & set(fs):
            found.add("a function calling a function")
    return found


# -- one mission ----------------------------------------------------------------------


def prove(source: str, run_scripts: list[dict], tally: Counter) -> None:
    """Compile, run on both engines, analyse from both starts; count what was done."""
    checked = check_source(source, "generated.mcl")
    net = compile_checked(checked)
    tally["drawn"] += 1
    for script in run_scripts:
        petri, reference = both(checked, script, net)
        assert petri == reference, f"the engines disagree with {script} on\n{source}"
    tally["runs"] += len(run_scripts)
    s = structure(net)
    spaces = []
    for label, extra in STARTS:
        try:
            space = explore(s, {**net.initial, **extra}, max_states=MAX_STATES)
        except ExplorationLimit:
            tally["over the limit"] += 1
            assume(False)
        b = behaviour(space)
        assert space.safe, f"from {label}: not 1-safe\n{source}"
        assert b.deadlock_free, f"from {label}: deadlocks {b.improper[:3]}\n{source}"
        assert b.reusable, f"from {label}: not reusable\n{source}"
        spaces.append(space.states)
    tally["analysed"] += 1
    tally["largest"] = max(tally["largest"], *spaces)
    tally["states"] += sum(spaces)
    tally.update(features(checked))


def proven(examples: int):
    """A test proving ``examples`` generated missions, and the tally it fills as it runs."""
    tally: Counter = Counter()

    @settings(max_examples=examples, deadline=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
    @given(GENERATED, st.lists(scripts, min_size=1, max_size=2))
    def one(source, run_scripts):
        prove(source, run_scripts, tally)

    return tally, one


def check_tally(tally: Counter, examples: int) -> None:
    """Enough missions analysed, not just drawn: the limit must not swallow the test."""
    assert tally["analysed"] >= examples, f"only {tally['analysed']} of {examples} analysed: {tally}"
    share = tally["analysed"] / tally["drawn"]
    assert share >= MIN_ANALYSED, (
        f"only {share:.0%} of the drawn missions fit in {MAX_STATES:,} states: {tally}")


def test_generated_missions_are_safe_deadlock_free_reusable_and_run_the_same():
    tally, one = proven(FAST_EXAMPLES)
    # a fixed seed: the share that fits under the state limit is a property of
    # the draws, and a share drawn afresh at each run made the test flaky
    seed(FAST_SEED)(one)()
    check_tally(tally, FAST_EXAMPLES)


def test_the_generator_reaches_the_shapes_it_is_meant_to():
    """Deep nesting, shared tasks across parallel branches, functions as conditions...

    Counted over generated missions, checked without exploring them: each
    shape must turn up, or the proofs above say nothing about it.
    """
    seen: Counter = Counter()

    # 200 draws: a function calling a function comes about once in twenty, and
    # with 100 draws fewer than three of them happened about once in six runs
    @settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(GENERATED)
    def one(source):
        seen.update(features(check_source(source, "generated.mcl")))

    seed(FAST_SEED)(one)()
    wanted = ["three levels deep", "a task called from several places",
              "one task in two parallel branches", "a function as a condition",
              "a function calling a task", "a function calling a function"]
    missing = [w for w in wanted if seen[w] < 3]
    assert not missing, f"the generator rarely or never gives {missing}: {dict(seen)}"


@pytest.mark.slow
@pytest.mark.parametrize("chunk", range(SLOW_CHUNKS))
def test_ten_thousand_generated_missions(chunk: int):
    """10,000 missions in chunks of 1,000, each from its own seed (run chunks apart with -k)."""
    tally, one = proven(SLOW_EXAMPLES)
    seed(chunk)(one)()
    check_tally(tally, SLOW_EXAMPLES)
    print(f"\nchunk {chunk}: {dict(tally)}")
