"""A failing property's counterexample for a mission engineer: its run in the mission's terms,
the vehicle script that replays a violation on both engines, and the page that steps through it.

mcl2pnml/counterexample.py turns the checker's firing sequence into calls, actions, vehicle
events and time-outs on a clock, and writes the vehicle script of cli.md that gives it. The
replay is judged as the checker judges: the Petri-net executor's firings, read by the same
observer (``mcl2pnml.analysis.checking.on_graph.judge``), must show the property violated, and the reference
engine must send the same actions and see the same events. Here the replays are run again
through the command line, each engine in its own process, as a user runs them.
"""
from __future__ import annotations

import functools
import json
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.analysis.checking.on_graph import Shape, Status, check_properties, judge
from mcl2pnml import pipeline
from mcl2pnml.commands import analyze as analyzing, witnesses as explaining
from mcl2pnml.counterexample import (CYCLE_REPEATS, StepKind, engine_run, explain, replay,
                                     schedule, witness)
from mcl2pnml.core.net import NetBuilder, Timing

from helpers import ENGINES, ROOT, run_cli
from sampling import variants
from missions import generated_properties, missions

EXAMPLES = ROOT / "examples"
#: Each example's false property that the engines can be led to, and the run that leads
#: them there: the checker's own ("same") or another the engines take ("own").
REPLAYED = {("docking", "AtMostThreeTries"): "own", ("sampling", "AtMostThreeBottles"): "own",
            ("multi_leg", "FixOnlyAfterNavigationFailure"): "same",
            ("sauce", "AlwaysOK"): "own", ("sauce", "SurveyAlwaysFlown"): "own",
            ("lawnmower", "SurveyAlwaysCompletes"): "own"}
#: The others, with the reason no script gives them: each holds in time (its example's
#: .props says so), the engines' runs being in time.
NOT_REPLAYED = {("sauce", "Ends"): "reports twice in one enabling",
                ("sauce", "SurveyAlwaysStarts"): "a run of the untimed net only",
                ("docking", "LatchOnlyAfterHoming"): "a run of the untimed net only",
                ("lawnmower", "NoReportAfterCompleteSurvey"): "a run of the untimed net only"}

LOOP = """primitive P(v);
primitive Q(v);
task T(x) = AchieveGoal(P(x)) timeout 10;
task U(x) = AchieveGoal(Q(x)) timeout 10;
mission { while (T(1)) { U(2); } }
"""


# computed once per test process: five tests ask for sauce's, each asked the checker again
@functools.cache
def _witnesses(name: str):
    """The untimed verdicts (``--untimed``) of the example's failing properties on the net:
    its false ones and those of its true ones that hold in time only (docs/time.md), with
    their witnesses."""
    mission = EXAMPLES / f"{name}.mcl"
    net, props = pipeline.properties_of(mission, extra=EXAMPLES / f"{name}.false.props")
    _, true = pipeline.properties_of(mission, extra=EXAMPLES / f"{name}.props")
    verdicts = [v for v in pipeline.check_properties(net, props + true)
                if v.status is Status.FAILS]
    return net, tuple(verdicts), tuple(explaining.witnesses(mission, net, verdicts))


def _fired(log: str) -> list[str]:
    return [e["fire"] for e in map(json.loads, log.splitlines()) if "fire" in e]


@pytest.fixture(scope="module")
def analyzed(tmp_path_factory):
    """``analyze --untimed --state-space --counterexamples`` of an example's false
    properties, run once per example and test process: sauce's two replayed properties and
    the page's test read the same files, which each analyzed again (the state space, every
    witness and its replays). Returns the command's result and the folder it wrote."""
    done: dict[str, tuple] = {}

    def analyze(name: str):
        if name not in done:
            folder = tmp_path_factory.mktemp(f"cx-{name}") / "cx"
            out = run_cli("analyze", EXAMPLES / f"{name}.mcl", "--untimed", "--state-space",
                          "--no-progress", "--properties", EXAMPLES / f"{name}.false.props",
                          "--counterexamples", folder)
            done[name] = (out, folder)
        return done[name]
    return analyze


#: The replays of the quick suite: one of each kind (a script of its own, the same one), and
#: sampling's (its drawing is the tall one, laid out left to right); the others reach no
#: line or branch of ours that these do not (``make test-slow`` runs them)
QUICK_REPLAYED = [("docking", "AtMostThreeTries"), ("multi_leg", "FixOnlyAfterNavigationFailure"),
                  ("sampling", "AtMostThreeBottles")]


@pytest.mark.parametrize("name,prop", variants(sorted(REPLAYED), QUICK_REPLAYED,
                                               ids=[f"{n}.{p}" for n, p in sorted(REPLAYED)]))
def test_the_script_leads_both_engines_to_the_violation(name, prop, tmp_path, analyzed):
    """analyze --counterexamples writes the script; `run --vehicle` on each engine, in its own
    process, then reaches the violation: the executor's firings show it, and the reference
    engine's trace is the executor's."""
    mission = EXAMPLES / f"{name}.mcl"
    out, cx = analyzed(name)
    assert out.returncode == 1, out.stderr
    script = cx / f"{prop}.vehicle.json"
    assert script.is_file() and f"wrote {script}" in out.stderr
    traces = {}
    for engine in ENGINES:
        log = tmp_path / f"{engine}.log"
        ran = run_cli("run", mission, "--engine", engine, "--vehicle", script, "--json",
                      "--log", log)
        assert ran.returncode in (0, 1, 4, 5), ran.stderr
        traces[engine] = json.loads(ran.stdout)["trace"]
        if engine == "petri":
            net, props = pipeline.properties_of(mission,
                                                extra=EXAMPLES / f"{name}.false.props")
            [p] = [p for p in props if p.name == prop]
            shown = judge(net, p, _fired(log.read_text()))
            assert shown is not None, (prop, shown)
    assert traces["petri"] == traces["reference"]
    text = (cx / f"{prop}.txt").read_text()
    assert ("a run the engines take that violates it too" in text) == (REPLAYED[name, prop] == "own")


@pytest.mark.parametrize("name,prop", sorted(NOT_REPLAYED), ids="{0[0]}.{0[1]}".format)
def test_a_run_no_script_gives_says_why(name, prop):
    _, verdicts, witnesses = _witnesses(name)
    [w] = [w for v, w in zip(verdicts, witnesses) if v.property.name == prop]
    assert w.replayed is None and NOT_REPLAYED[name, prop] in w.why_not
    assert w.run.lines(), "the run is still told in the mission's terms"


def test_every_false_example_property_is_classified():
    """Every example's false property (dam_inspection's aside: slow) is one of the above."""
    for mission in sorted(EXAMPLES.glob("*.mcl")):
        if mission.stem == "dam_inspection":
            continue
        _, verdicts, witnesses = _witnesses(mission.stem)
        for v, w in zip(verdicts, witnesses):
            key = (mission.stem, v.property.name)
            assert (w.replayed is not None) == (key in REPLAYED), (key, w.why_not)
            assert key in REPLAYED or key in NOT_REPLAYED, key


def test_the_mission_terms_name_calls_actions_events_and_time_outs():
    _, verdicts, witnesses = _witnesses("multi_leg")
    lines = "\n".join(witnesses[0].run.lines())
    assert "call Goto((500, 0, 15))" in lines
    assert "enable GoToWayPoint((500, 0, 15))" in lines
    assert "KeepDepth reports achieved" in lines
    assert "t=901  the time-out of Goto (900 s) expires" in lines
    assert "+ended(Goto, FAIL)" in lines
    # each line ends with the step of the firing sequence it comes from
    steps = [s for s in witnesses[0].run.steps if s.kind is StepKind.TIMEOUT]
    assert [s.transition for s in steps] == ["Goto.t03"]
    assert f"[{steps[0].number}]" in lines


def test_the_page_steps_through_the_replayed_run(tmp_path, analyzed):
    """NAME.log is a run log that `show --run` follows (every firing enabled in turn, notes in
    the mission's terms) and NAME.html is that page, the log inside it as data."""
    mission = EXAMPLES / "multi_leg.mcl"
    out, cx = analyzed("multi_leg")
    assert out.returncode == 1, out.stderr
    log = (cx / "FixOnlyAfterNavigationFailure.log").read_text()
    entries = [json.loads(line) for line in log.splitlines()]
    assert any(e.get("note", "").startswith("call Goto") for e in entries)
    assert entries[-1]["note"] == "the property is violated (prefix)"
    net, props = pipeline.properties_of(mission, extra=EXAMPLES / "multi_leg.false.props")
    assert judge(net, props[0], _fired(log)).shape is Shape.PREFIX
    page = (cx / "FixOnlyAfterNavigationFailure.html").read_text()
    assert "the property is violated (prefix)" in page and "<script>" in page
    # the same page as `show --run` writes from the log
    again = run_cli("show", mission, "--run", cx / "FixOnlyAfterNavigationFailure.log",
                    "-o", tmp_path / "again.html")
    assert again.returncode == 0, again.stderr
    assert (tmp_path / "again.html").read_text() == page


def test_an_infinite_run_is_replayed_round_its_cycle(tmp_path):
    """A loop that never ends violates "the mission ends": the checker's shortest lasso has
    a primitive lose and regain its goal (no script gives that), the executor's own lasso
    goes round the loop, and its script gives the cycle's replies three times over."""
    mission = tmp_path / "loop.mcl"
    mission.write_text(LOOP)
    side = tmp_path / "loop.props"
    side.write_text("property Ends: eventually (outcome(OK) or outcome(FAIL));\n")
    net, [prop] = pipeline.properties_of(mission, extra=side)
    [v] = pipeline.check_properties(net, [prop])
    assert v.shape is Shape.LASSO
    [w] = explaining.witnesses(mission, net, [v])
    assert "reports twice in one enabling" in w.why_not
    assert w.replayed.shape == "lasso" and w.replay.reached and w.replay.same_on_reference
    assert w.replayed.script == {"P": ["ok@1"] * CYCLE_REPEATS, "Q": ["ok@1"] * CYCLE_REPEATS}
    assert judge(net, prop, w.replay.fired).shape is Shape.LASSO


def test_a_failure_the_engines_never_take_is_said_so(tmp_path):
    """sauce: "the survey always starts before the mission ends OK" fails on the net (the
    detector may fail before the survey's call has entered), but the engines enter every
    call before time passes: no vehicle leads them there, and their runs hold it."""
    net, verdicts, witnesses = _witnesses("sauce")
    [(v, w)] = [(v, w) for v, w in zip(verdicts, witnesses)
                if v.property.name == "SurveyAlwaysStarts"]
    assert "Survey-1.enter" in w.why_not
    assert engine_run(net, v.property) is None


def _timed_net():
    """t (a report's transition) and a 10 s time-out x, both enabled from M0."""
    b = NetBuilder("n")
    b.place("a", 1)
    b.place("b", 1)
    b.place("c")
    b.transition("t", payload={"event": "achieved", "primitive": "P"})
    b.transition("x", timing=Timing.delay(10))
    b.arc("a", "t")
    b.arc("t", "c")
    b.arc("b", "x")
    return b.build()


def test_a_schedule_puts_reports_before_running_time_outs_and_time_outs_on_time():
    net = _timed_net()
    times, departs, why = schedule(net, ["t", "x"], [StepKind.REPORT, StepKind.TIMEOUT])
    assert (times, departs, why) == ([1, 10], None, None)
    # a report after the time-out, which the engines would take first: it comes after it
    times, _, why = schedule(net, ["x", "t"], [StepKind.TIMEOUT, StepKind.REPORT])
    assert times == [10, 11] and why is None


def test_a_lasso_whose_cycle_outlives_a_time_out_has_no_schedule():
    b = NetBuilder("n")
    b.place("a", 1)
    b.place("b", 1)
    b.transition("t", payload={"event": "achieved", "primitive": "P"})
    b.transition("x", timing=Timing.delay(10))
    b.arc("a", "t")
    b.arc("t", "a")
    b.arc("b", "x")
    times, _, why = schedule(b.build(), ["t", "t"], [StepKind.REPORT] * 2, loop=1)
    assert times is None and "x runs all along the cycle" in why


# -- generated missions, generated properties ------------------------------------------------

GENERATED = st.tuples(missions(depth=2, width=2, function_depth=1), st.integers(0, 2**32 - 1))


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(GENERATED)
def test_generated_witnesses_replay_and_the_engines_runs_are_the_nets(case):
    """On generated missions and properties: a property that holds has no violating run of
    the engines (each of their runs is one of the net's); a failing one's witness either
    replays (its script, run again from scratch, leads the executor to the violation and
    the reference engine along the same trace) or says why not."""
    _witnesses_replay(case)


@pytest.mark.slow
@settings(max_examples=1_000, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(GENERATED)
def test_a_thousand_generated_witnesses_replay(case):
    _witnesses_replay(case)


def _witnesses_replay(case) -> None:
    from mcl2pnml.analysis.statespace.explore import ExplorationLimit, explore
    text, seed = case
    with tempfile.TemporaryDirectory() as folder:
        mission = Path(folder) / "m.mcl"
        mission.write_text(text)
        net = pipeline.compile_file(mission)
        try:
            explore(net, max_states=3_000)
        except ExplorationLimit:
            return
        side = mission.with_suffix(".props")
        side.write_text(generated_properties(net, seed))
        net, props = pipeline.properties_of(mission, extra=side)
        checked = pipeline.check_file(mission)
        for v in check_properties(net, props):
            if v.status is Status.HOLDS:
                assert engine_run(net, v.property) is None, v.property.text
                continue
            w = witness(net, checked, v.property, v.transitions, shape=v.shape.value,
                        loop=v.loop)
            if w.replayed is None:
                assert w.why_not, v.property.text
                continue
            again = replay(w.replayed, net, checked)
            assert again.reached and again.same_on_reference, (v.property.text, again.detail)
            # the script is the replayed run's own, computed again from its firings
            assert explain(net, v.property, [s.transition for s in w.replayed.steps],
                           shape=w.replayed.shape, loop=w.replayed.loop,
                           primitives=list(checked.primitives),
                           callables=[*checked.tasks, *checked.functions]).script \
                == w.replayed.script


# -- the command line ----------------------------------------------------------------------

@pytest.fixture(scope="module")
def explained_json():
    """``analyze --json --explain`` of multi_leg's false property, which two tests read
    (each ran it again: the state space, the witness and its replays)."""
    return run_cli("analyze", EXAMPLES / "multi_leg.mcl", "--untimed", "--state-space",
                   "--json", "--properties", EXAMPLES / "multi_leg.false.props", "--explain")


def test_analyze_json_gives_the_run_in_the_mission_terms_and_its_script(explained_json):
    out = explained_json
    assert out.returncode == 1, out.stderr
    [prop] = json.loads(out.stdout)["properties"]
    cex = prop["counterexample"]
    assert cex["explained"] is True
    assert cex["vehicle_script"] == {"KeepDepth": ["ok@1", "ok@1"]}
    assert cex["why_not"] is None and cex["replayed"]["same_run"]
    assert any("the time-out of Goto (900 s) expires" in line for line in cex["mission"])


def _analyze_spied(monkeypatch, *args):
    """``analyze`` on multi_leg's false property, in this process, with each explanation
    (:func:`mcl2pnml.counterexample.witness`: the mission's terms and the replay on both
    engines) and each replay counted as the facade calls them."""
    from click.testing import CliRunner

    import mcl2pnml.counterexample as counterexample
    from mcl2pnml.cli import main
    calls = {"witness": 0, "replay": 0}

    def spy(name):
        real = getattr(counterexample, name)

        def counted(*a, **k):
            calls[name] += 1
            return real(*a, **k)
        monkeypatch.setattr(counterexample, name, counted)
    spy("witness")
    spy("replay")
    out = CliRunner().invoke(main, ["analyze", str(EXAMPLES / "multi_leg.mcl"), "--untimed",
                                    "--state-space", "--no-progress", "--properties",
                                    str(EXAMPLES / "multi_leg.false.props"), *map(str, args)])
    assert out.exit_code == 1 and "Traceback" not in out.output, out.output
    return out, calls


@pytest.mark.parametrize("as_json", [False, True], ids=["text", "json"])
def test_a_counterexample_is_not_explained_unless_asked(monkeypatch, as_json):
    """Without --explain (or --counterexamples) no counterexample is told in the mission's
    terms nor replayed: the firing sequence is given, and how to ask for the rest."""
    out, calls = _analyze_spied(monkeypatch, *(["--json"] if as_json else []))
    assert calls == {"witness": 0, "replay": 0}
    if as_json:
        [prop] = json.loads(out.stdout)["properties"]
        cex = prop["counterexample"]
        assert cex["explained"] is False and cex["shape"] == "prefix"
        assert cex["transitions"][-1] == "GpsFix.on" and len(cex["markings"]) > 1
        assert not {"mission", "vehicle_script", "replayed", "why_not"} & set(cex)
    else:
        assert "  counterexample (prefix):" in out.stdout
        assert "in the mission's terms (step numbers" not in out.stdout
        assert out.stdout.splitlines()[-1] == explaining.EXPLAIN_HINT
    assert "left out" not in out.stderr


@pytest.mark.parametrize("as_json", [False, True], ids=["text", "json"])
def test_explain_tells_the_run_and_replays_it(monkeypatch, as_json):
    out, calls = _analyze_spied(monkeypatch, "--explain", *(["--json"] if as_json else []))
    assert calls["witness"] == 1 and calls["replay"] >= 1
    if as_json:
        [prop] = json.loads(out.stdout)["properties"]
        cex = prop["counterexample"]
        assert cex["explained"] is True and cex["replayed"]["same_run"]
        assert cex["vehicle_script"] == {"KeepDepth": ["ok@1", "ok@1"]}
    else:
        assert "  in the mission's terms (step numbers in brackets):" in out.stdout
        assert "both engines reach the violation" in out.stdout
        assert explaining.EXPLAIN_HINT not in out.stdout


def test_explain_with_no_counterexample_to_explain_limited(monkeypatch):
    """--max-counterexamples 0 explains none: the number left out is said, no hint given."""
    out, calls = _analyze_spied(monkeypatch, "--explain", "--max-counterexamples", "0")
    assert calls == {"witness": 0, "replay": 0}
    assert "counterexamples of 1 of the 1 failing properties left out" in out.stderr
    assert explaining.EXPLAIN_HINT not in out.stdout


def test_counterexamples_are_explained_for_their_files_without_explain(monkeypatch, tmp_path):
    out, calls = _analyze_spied(monkeypatch, "--counterexamples", tmp_path / "cx")
    assert calls["witness"] == 1 and calls["replay"] >= 1
    assert sorted(p.name for p in (tmp_path / "cx").iterdir()) == [
        f"FixOnlyAfterNavigationFailure.{s}" for s in ("html", "log", "txt", "vehicle.json")]
    assert "in the mission's terms" in (tmp_path / "cx" /
                                        "FixOnlyAfterNavigationFailure.txt").read_text()


def test_the_facade_gives_the_outcome_the_cli_prints(tmp_path, explained_json):
    """commands.analyze decides what `analyze` does; the CLI prints its outcome."""
    outcome = analyzing.analyze(EXAMPLES / "multi_leg.mcl", analyzing.AnalyzeOptions(
        timed=False, state_space=True, properties=str(EXAMPLES / "multi_leg.false.props"),
        counterexamples=tmp_path / "cx"))
    assert outcome.status == 1 and outcome.timed is None and not outcome.hint
    [v], [w] = outcome.verdicts, outcome.witnesses
    assert v.status is Status.FAILS and w.replayed is w.run
    assert outcome.messages == tuple(f"wrote {p}" for p in outcome.written)
    assert len(outcome.written) == 4 and all(p.is_file() for p in outcome.written)
    cli = explained_json
    assert json.loads(cli.stdout) == json.loads(json.dumps(outcome.as_json()))
    quiet = analyzing.analyze(EXAMPLES / "multi_leg.mcl", analyzing.AnalyzeOptions(
        properties=str(EXAMPLES / "multi_leg.false.props")))
    assert quiet.witnesses is None and quiet.hint and quiet.timed is not None
    assert quiet.lines()[-1] == explaining.EXPLAIN_HINT and quiet.written == ()


@pytest.mark.parametrize("args,message", [
    (["--counterexamples", "{tmp}/cx"], "counterexamples are of properties: add --properties"),
    (["--explain"], "Invalid value for --explain: counterexamples are of properties: add "
                    "--properties"),
    (["--properties", "{props}", "--initial", "mission.B", "--explain"],
     "Invalid value for --explain: a replay starts the mission from its start"),
    (["--properties", "{props}", "--initial", "mission.B", "--counterexamples", "{tmp}/cx"],
     "leave out --initial"),
    (["--properties", "{props}", "--counterexamples", "{tmp}/file/cx"],
     "cannot make the folder: Not a directory"),
    (["--properties", "{props}", "--counterexamples", "{tmp}/file"], "is a file"),
])
def test_counterexamples_option_errors(args, message, tmp_path):
    """One message, exit status 2, nothing written."""
    (tmp_path / "file").write_text("")
    args = [a.format(tmp=tmp_path, props=EXAMPLES / "multi_leg.false.props") for a in args]
    out = run_cli("analyze", EXAMPLES / "multi_leg.mcl", "--untimed", "--state-space", *args)
    assert out.returncode == 2 and message in out.stderr, out.stderr
    assert "Traceback" not in out.stderr and out.stderr.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]
