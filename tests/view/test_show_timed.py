"""`mcl2pnml show`: the page's clock follows the engines' timed semantics, in headless Chromium.

The supervisor's steps (neither a time-out nor fired by a vehicle event)
come first: *Advance time* is refused while one is enabled, and *Settle*
takes them in the executor's order. Played against the executor itself
(:class:`~mcl2pnml.runtime.executor.PetriEngine`) with the same stimuli, a
vehicle event fired by its transition at its time and a time-out by
*Advance time*, then *Settle*, the page fires the same transitions in the
same order, at the same times, and reaches the same markings. A replayed
log (a run's, a counterexample's) shows when each of its steps happened.
"""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from helpers import ROOT, run_cli as run
from shown import shown
from test_show import TWO_TASKS, marking, page_of  # noqa: F401 (fixtures)

from mcl2pnml import pipeline
from mcl2pnml.core.net import NetBuilder, Timing
from mcl2pnml.core.payloads import read_transition
from mcl2pnml.runtime.aal import Event, EventKind
from mcl2pnml.runtime.executor import PetriEngine
from mcl2pnml.view.show import page as show_page, role, variant


def fired(page) -> list[str]:
    return page.evaluate("() => history.map((i) => V.transitions[i].id)")


def page_marking(page) -> dict[str, int]:
    return page.evaluate("() => Object.fromEntries(V.places.map((p, i) => [p.id, marking[i]])"
                         ".filter(([, n]) => n))")


def engine_marking(engine: PetriEngine) -> dict[str, int]:
    return {p: n for p, n in zip(engine.places, engine.marking) if n}


def clock(page) -> str:
    return page.text_content("#clock")


def seconds(t: float) -> str:
    return f"t = {round(t * 1000) / 1000:g} s"


def lockstep(page, net, log: Path) -> int:
    """Plays the stimuli of ``log`` (a run of ``net``) on the page and on the executor alike:
    the page must fire what the engine fires, in its order and at its time, and reach its
    marking, after each. Returns the number of time-outs played."""
    engine = PetriEngine(net)
    done: list[str] = []
    engine.on_fire = lambda t, name: done.append(name)
    engine.start(0.0)
    page.click("#settle")
    assert fired(page) == done and page_marking(page) == engine_marking(engine)
    assert page.is_disabled("#settle")                  # settled: nothing more to take
    timeouts = 0
    timed = {t.id for t in net.transitions if t.timing is not None}   # fired by timers only
    entries = [json.loads(line) for line in log.read_text().splitlines() if line.strip()]
    for k, entry in enumerate(entries):
        if engine.outcome is not None:
            break
        if "event" in entry:
            before = len(done)
            engine.on_event(Event(entry["t"], EventKind(entry["event"]), entry["primitive"]))
            if len(done) == before:
                continue                                 # ignored by the mission
            # the vehicle: the transition its event fired, at its time
            page.evaluate("([id, t]) => fire(byId.get(id), false, t)", [done[before], entry["t"]])
        elif "fire" in entry and entry["fire"] in timed:
            # a time-out: time passes to its due time, as the run loop lets it
            due, task = engine.next_timer()
            assert page.is_enabled("#advance")
            page.click("#advance")
            assert clock(page) == seconds(due) and due == entry["t"]
            engine.fire_timer(due, task)
            timeouts += 1
        else:
            continue
        if page.is_enabled("#settle"):
            page.click("#settle")
        assert fired(page) == done, f"line {k + 1} of {log}"
        assert page_marking(page) == engine_marking(engine), f"line {k + 1} of {log}"
    assert engine.outcome is not None and fired(page) == done
    return timeouts


@pytest.fixture(scope="module")
def two(tmp_path_factory):
    d = tmp_path_factory.mktemp("timed")
    mission = d / "two.mcl"
    mission.write_text(TWO_TASKS)
    return shown(tmp_path_factory, "two.html", mission)


def test_advance_time_is_refused_while_the_supervisor_has_steps(page_of, two):
    page = page_of(two)
    # at M0 the mission's first step is enabled: time cannot pass before it
    assert page.is_disabled("#advance") and page.is_enabled("#settle")
    assert "the supervisor has steps to take first" in page.get_attribute("#advance", "title")
    assert "steps to take first (mission.t1)" in page.text_content("#supervisor")
    assert page.evaluate("() => advance()") is False        # refused by the script too
    assert clock(page) == "t = 0 s" and fired(page) == []
    page.click("#settle")
    assert fired(page) == ["mission.t1", "Depth-1.enter", "Depth.t01"]
    assert "settled" in page.text_content("#supervisor") and page.is_disabled("#settle")
    # the vehicle: KeepDepth is on; the time-out is the only thing left, time may pass
    page.click('#enabled button[data-id="KeepDepth.on"]')
    assert page.is_enabled("#advance") and page.is_disabled("#settle")
    page.click("#advance")
    assert clock(page) == "t = 60 s" and fired(page)[-1] == "Depth.t03"
    # the time-out gave the supervisor steps again: time waits for them
    assert page.is_disabled("#advance") and page.is_enabled("#settle")
    assert page.get_attribute("#history li:last-child", "data-t") == "60"
    page.click("#settle")
    assert page.is_disabled("#settle")
    page.click("#back")                                       # undone one firing at a time
    assert page.is_enabled("#settle") and page.is_disabled("#advance")


def test_a_hand_played_time_out_keeps_its_timer_while_enabled(page_of, two):
    page = page_of(two)
    page.click("#settle")
    page.click('#enabled button[data-id="KeepDepth.on"]')    # Depth.t03 enabled at t = 0
    assert page.text_content("#clock-next") == "next time-out: Depth.t03 at t = 60"
    # the vehicle reports at t = 5: the time-out stays enabled and keeps its timer, and
    # the supervisor's step that answers the report comes before time may pass
    page.evaluate("() => fire(byId.get('KeepDepth.achieved'), false, 5)")
    assert clock(page) == "t = 5 s"
    assert page.text_content("#clock-next") == "next time-out: Depth.t03 at t = 60"
    assert page.is_disabled("#advance")
    page.click("#settle")                                    # the task ends: no time-out
    assert page.text_content("#clock-next") == "no time-out is waiting"


def test_a_time_out_keeps_its_timer_when_its_input_is_taken_and_given_back(tmp_path, page_of):
    """The executor's rule: a transition enabled before and after a firing keeps its
    timer, even if the firing took its input and gave it back."""
    b = NetBuilder("keep")
    b.place("p", tokens=1)
    b.place("done")
    b.transition("timeout", timing=Timing(10, 10))
    b.transition("touch")
    b.arc("p", "timeout")
    b.arc("timeout", "done")
    b.arc("p", "touch")
    b.arc("touch", "p")
    net = b.build()
    (tmp_path / "keep.html").write_text(show_page("keep", [variant(net, "keep")]))
    page = page_of(tmp_path / "keep.html")
    assert page.text_content("#clock-next") == "next time-out: timeout at t = 10"
    page.evaluate("() => fire(byId.get('touch'), false, 4)")
    assert clock(page) == "t = 4 s"
    assert page.text_content("#clock-next") == "next time-out: timeout at t = 10"


def test_settle_takes_the_executors_steps_on_the_sauce_mission(tmp_path, page_of,
                                                               tmp_path_factory):
    """From M0, *Settle* fires what the executor's start fires, in its order; then, event
    after event of a run on the simulated AUV, what the executor fires for it."""
    source = ROOT / "examples" / "sauce.mcl"
    log = tmp_path / "sauce.jsonl"
    done = run("run", source, "--log", log)
    assert done.returncode == 0, done.stderr
    page = page_of(shown(tmp_path_factory, "sauce.html", source))
    lockstep(page, pipeline.compile_file(source), log)
    assert "mission.OK" in marking(page)
    assert "has its result" in page.text_content("#supervisor")


def test_time_outs_fire_at_their_time_as_the_engines_fire_them(tmp_path, page_of,
                                                               tmp_path_factory):
    """A run of the multi-leg mission whose legs time out (the vehicle of a counterexample):
    each time-out fires at the time the run loop fires it, after the supervisor settled."""
    source = ROOT / "examples" / "multi_leg.mcl"
    script = tmp_path / "vehicle.json"
    script.write_text(json.dumps({"KeepDepth": ["ok@1", "ok@1"]}))
    log = tmp_path / "run.jsonl"
    done = run("run", source, "--vehicle", script, "--log", log)
    assert done.returncode in (0, 1), done.stderr
    page = page_of(shown(tmp_path_factory, "ml.html", source))
    assert lockstep(page, pipeline.compile_file(source), log) >= 2


def test_settle_takes_the_step_enabled_longest_first(tmp_path, page_of):
    """Two steps enabled at once: the one enabled first fires first, whatever the net's
    order (here it decides the outcome, as in the executor)."""
    b = NetBuilder("order")
    for place in ("mission.B", "p", "q", "r", "mission.OK", "mission.FAIL",
                  "mission.ABORTED"):
        b.place(place, tokens=1 if place == "mission.B" else 0)
    for t, pre, post in (("tA", "r", "mission.OK"), ("tB", "p", "r"),
                         ("start", "mission.B", "p"), ("tC", "q", "mission.FAIL")):
        b.transition(t)
        b.arc(pre, t)
        b.arc(t, post)
    b.arc("start", "q")
    net = b.build()
    engine = PetriEngine(net)
    done: list[str] = []
    engine.on_fire = lambda t, name: done.append(name)
    engine.start(0.0)
    assert done == ["start", "tB", "tC"]     # tC, enabled at the first firing, before tA
    (tmp_path / "order.html").write_text(show_page("order", [variant(net, "order")]))
    page = page_of(tmp_path / "order.html")
    page.click("#settle")
    assert fired(page) == done and page_marking(page) == engine_marking(engine)
    assert "has its result" in page.text_content("#supervisor")


def test_settle_is_bounded(tmp_path, tab):
    """A loop of supervisor steps that never settles is stopped, with a message."""
    b = NetBuilder("loop")
    b.place("p", tokens=1)
    b.place("q")
    b.transition("t1")
    b.transition("t2")
    b.arc("p", "t1")
    b.arc("t1", "q")
    b.arc("q", "t2")
    b.arc("t2", "p")
    net = b.build()
    (tmp_path / "loop.html").write_text(show_page("loop", [variant(net, "loop")]))
    page = tab.page({"width": 1280, "height": 720})    # a new page's size
    page.goto((tmp_path / "loop.html").resolve().as_uri())
    page.click("#side > .fold")                         # folded on a screen this narrow
    page.click("#settle")
    assert "Settle stopped after 10,000 firings" in page.text_content("#supervisor-note")
    assert page.evaluate("() => history.length") == 10_000
    assert page.is_disabled("#advance")
    tab.leave()


def test_replayed_logs_show_each_steps_time(tmp_path, page_of):
    mission = tmp_path / "two.mcl"
    mission.write_text(TWO_TASKS)
    script = tmp_path / "vehicle.json"
    script.write_text(json.dumps({"KeepDepth": ["ok@5"], "GoToWayPoint": []}))
    log = tmp_path / "run.jsonl"
    done = run("run", mission, "--vehicle", script, "--log", log)
    assert done.returncode == 1, done.stderr                 # Goto timed out: FAIL
    entries = [json.loads(line) for line in log.read_text().splitlines()]
    out = run("show", mission, "--run", log, "-o", tmp_path / "two.html")
    assert out.returncode == 0, out.stderr
    page = page_of(tmp_path / "two.html")
    shown = page.locator("#run-entries li").all_text_contents()
    steps = [e for e in entries if "journal" not in e]
    assert len(shown) == len(steps)
    for text, e in zip(shown, steps):
        assert text.startswith(f"t={e['t']:g}  "), text
    timeout = next(k for k, e in enumerate(steps) if e.get("fire") == "Goto.t03")
    assert shown[timeout] == f"t={steps[timeout]['t']:g}  fire Goto.t03 (time-out)"
    assert steps[timeout]["t"] == 105                       # 5 s, then the 100 s time-out
    page.click("#run-end")
    times = page.locator("#history li").evaluate_all("(l) => l.map((e) => e.dataset.t)")
    assert times == [f"{e['t']:g}" for e in steps if "fire" in e]
    # an entry without a time is shown at the clock's (a hand-made log)
    page.evaluate("""() => loadRun('{"t": 3, "note": "a"}\\n{"note": "b"}\\n')""")
    assert page.locator("#run-entries li").all_text_contents() == ["t=3  \u2014 a",
                                                                   "t=3  \u2014 b"]


def test_a_counterexample_shows_when_each_step_happened(tmp_path, page_of):
    source = ROOT / "examples" / "multi_leg.mcl"
    out = run("analyze", source, "--state-space", "--properties",
              ROOT / "examples" / "multi_leg.false.props", "--counterexamples", tmp_path / "cx")
    assert out.returncode == 1, out.stderr
    page_file = tmp_path / "cx" / "FixOnlyAfterNavigationFailure.html"
    log = [json.loads(line) for line in
           (tmp_path / "cx" / "FixOnlyAfterNavigationFailure.log").read_text().splitlines()]
    page = page_of(page_file)
    shown = page.locator("#run-entries li").all_text_contents()
    assert [s.split("  ", 1)[0] for s in shown] == [f"t={e['t']:g}" for e in log]
    assert any(s.startswith("t=901  fire Goto.t03 (time-out)") for s in shown)


def test_the_pages_roles_are_the_executors(examples):
    net = examples.net("sauce")
    engine = PetriEngine(net)
    roles = {t.id: role(read_transition(t), t.timing is not None) for t in net.transitions}
    for i, t in enumerate(engine.transitions):
        expected = ("event" if i in engine.event_driven else "entry" if engine.entry[i]
                    else "step" if engine.delay[i] is None else "timeout")
        assert roles[t] == expected, t
    assert set(roles.values()) == {"event", "entry", "step", "timeout"}
