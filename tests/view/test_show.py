"""`mcl2pnml show`: the token game page, played in a real browser (headless Chromium).

Chromium comes from Debian (`make setup` installs it where missing) and is
driven by Playwright, pointed at /usr/bin/chromium; nothing is downloaded.
Screenshots go to out/screenshots/, for people to look at (the tutorial's
pictures of the page, docs/tutorial/show_*.png, are copies of them).
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from helpers import ROOT, run_cli as run
from shown import shown

SHOTS = ROOT / "out" / "screenshots"
TWO_TASKS = """\
primitive GoToWayPoint(wp);
primitive KeepDepth(d);
task Goto(wp) = AchieveGoal(GoToWayPoint(wp)) timeout 100;
task Depth(d) = AchieveGoal(KeepDepth(d)) timeout 60;
mission {
    Depth(2.0);
    Goto((10.0, 5.0, 5.0));
}
"""


VIEWPORT = {"width": 1600, "height": 900}


@pytest.fixture
def page_of(browser, tab):
    """Opens a page file; afterwards, no request but the file itself, and no script error.

    The first page of a test is the shared tab navigated to the file (a new document; a
    new page would cost Chromium a window), any other a page of its own."""
    pages = []

    def open_(path: Path):
        page = tab.page(VIEWPORT) if not pages else browser.new_page(viewport=VIEWPORT)
        requests, errors = [], []
        watch = {"request": lambda r: requests.append(r.url),
                 "pageerror": lambda e: errors.append(str(e)),
                 "console": lambda m: errors.append(m.text) if m.type == "error" else None}
        for event, handler in watch.items():
            page.on(event, handler)
        page.goto(path.resolve().as_uri())
        pages.append((page, watch, requests, errors, path))
        return page

    yield open_
    for k, (page, watch, requests, errors, path) in enumerate(pages):
        if not page.is_closed():
            for event, handler in watch.items():
                page.remove_listener(event, handler)
        if k == 0:
            tab.leave()
        else:
            page.close()
    for page, watch, requests, errors, path in pages:
        assert requests == [path.resolve().as_uri()], f"the page fetched {requests[1:]}"
        assert not errors, errors


def marking(page) -> list[str]:
    return page.text_content("#marking").split(", ")


def test_the_task_played_by_clicking(tmp_path, page_of):
    out = run("show", "task", "-o", tmp_path / "task.html")
    assert out.returncode == 0, out.stderr
    page = page_of(tmp_path / "task.html")
    assert page.title().startswith("task")
    assert marking(page) == ["A", "B", "C", "MTX", "OFF"]
    assert page.text_content("#invariants-status") == "6 invariants, all hold"
    # only t01 and t11 can start (B with MTX, or B with A): click t01's bar in the drawing
    assert sorted(page.locator("#enabled button").all_text_contents()) == ["t01", "t11"]
    page.click('#net g.transition[data-id="t01"]')
    assert marking(page) == ["A", "C", "E", "EXE", "OFF"]
    assert page.text_content("#invariants-status") == "6 invariants, all hold"
    page.click('#net g.transition[data-id="on"]')           # the vehicle: enabled
    page.click('#net g.transition[data-id="t07"]')          # the abort: disable it
    assert marking(page) == ["C", "D", "ON", "W_A"]
    page.click('#net g.transition[data-id="t02"]')          # not enabled: nothing happens
    assert marking(page) == ["C", "D", "ON", "W_A"]
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / "show_task.png"))
    page.click("#back")
    assert marking(page) == ["A", "C", "EXE", "ON"]          # t07 undone
    page.click("#reset")
    assert marking(page) == ["A", "B", "C", "MTX", "OFF"]
    assert page.text_content("#history") == ""
    # the reduced model of Fig. 3: B, A and MTX, and t5 aborts before the start
    page.select_option("#variant", "1")
    assert marking(page) == ["A", "B", "MTX"]
    page.click('#net g.transition[data-id="t5"]')
    assert marking(page) == ["ABORTED", "MTX"]
    assert page.text_content("#enabled") == "none: a dead marking"


def two_tasks_run(directory: Path) -> tuple[Path, Path, list[str]]:
    """The two-task mission in ``directory``, run on a scripted vehicle: the mission,
    its log, and the transitions the run fired."""
    mission = directory / "two.mcl"
    mission.write_text(TWO_TASKS)
    script = directory / "vehicle.json"
    script.write_text(json.dumps({"KeepDepth": ["ok@5"], "GoToWayPoint": ["ok@20"]}))
    log = directory / "run.jsonl"
    done = run("run", mission, "--vehicle", script, "--log", log)
    assert done.returncode == 0, done.stderr
    fired = [json.loads(line)["fire"] for line in log.read_text().splitlines()
             if '"fire"' in line]
    return mission, log, fired


def test_a_recorded_run_followed_step_by_step(tmp_path, page_of):
    mission, log, fired = two_tasks_run(tmp_path)
    out = run("show", mission, "--run", log, "-o", tmp_path / "two.html")
    assert out.returncode == 0, out.stderr
    page = page_of(tmp_path / "two.html")
    assert "mission.B" in marking(page)
    page.click("#run-next")                                 # up to the first firing
    assert page.text_content("#history") == fired[0]
    for _ in fired[1:]:
        page.click("#run-next")
    assert page.locator("#history li").all_text_contents() == fired
    assert "mission.OK" in marking(page) and "mission.B" not in marking(page)
    page.click("#run-next")                                 # the outcome: nothing fires
    assert page.locator("#history li").count() == len(fired)
    assert re.fullmatch(r"step (\d+) of \1", page.text_content("#run-position"))
    status = page.text_content("#invariants-status")
    n = int(status.split()[0])
    assert status == f"{n} invariants, all hold" and n > 10
    page.click("#run-back")
    assert page.locator("#history li").all_text_contents() == fired[:-1]
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / "show_run.png"))


def test_the_page_is_one_file_that_fetches_nothing(tmp_path_factory):
    # the sequence's page as the graph's tests open it, made once per run (shown.py)
    html = shown(tmp_path_factory, "sequence.html", "sequence").read_text()
    assert "default-src 'none'" in html                    # the browser enforces it
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", html)


def test_bad_arguments_are_one_message(tmp_path):
    out = run("show", "sequense")
    assert out.returncode == 2 and "did you mean 'sequence'" in out.stderr
    other = tmp_path / "other.jsonl"
    other.write_text('{"t": 0, "fire": "nowhere.t1"}\n')
    mission = tmp_path / "two.mcl"
    mission.write_text(TWO_TASKS)
    out = run("show", mission, "--run", other, "-o", tmp_path / "x.html")
    assert out.returncode == 2 and "'nowhere.t1', which is no transition" in out.stderr
    assert not (tmp_path / "x.html").exists()
    broken = tmp_path / "broken.jsonl"
    broken.write_text('{"t": 0, "fire": "mission.t1"}\n{"t": 1,\n')
    out = run("show", mission, "--run", broken, "-o", tmp_path / "x.html")
    assert out.returncode == 2 and f"{broken}:2:" in out.stderr and "Traceback" not in out.stderr


def test_the_paper_mission_followed_to_its_end(tmp_path, page_of):
    """The SAUC-E mission on the simulated AUV, replayed on its net: the tutorial's
    pictures (out/screenshots/show_sauce*.png)."""
    log = tmp_path / "sauce.jsonl"
    done = run("run", ROOT / "examples" / "sauce.mcl", "--log", log)
    assert done.returncode == 0, done.stderr
    out = run("show", ROOT / "examples" / "sauce.mcl", "--run", log, "-o",
              tmp_path / "sauce.html")
    assert out.returncode == 0, out.stderr
    page = page_of(tmp_path / "sauce.html")
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / "show_sauce.png"))     # fitted: the whole mission
    for _ in range(12):                                      # the view follows the run
        page.click("#run-next")
    page.screenshot(path=str(SHOTS / "show_sauce_follow.png"))
    page.click("#run-end")
    assert "mission.OK" in marking(page)
    assert page.text_content("#run-message") == ""
    fired = sum('"fire"' in line for line in log.read_text().splitlines())
    assert page.locator("#history li").count() == fired
    page.screenshot(path=str(SHOTS / "show_sauce_run.png"))
    # the monitor's part of the net; the cross was found, so the survey was aborted
    page.click('#tree div.node[data-name="monitor-1"]')
    states = page.locator("#tree div.node").evaluate_all(
        "(d) => Object.fromEntries(d.map((e) => [e.dataset.name, e.dataset.state]))")
    assert states["monitor-1"] == "OK" and states["Survey-1"] == "ABORTED"
    assert states["NULL-1"] == "idle" and states["mission"] == "OK"
    page.screenshot(path=str(SHOTS / "show_sauce_tree.png"))
    page.select_option("#view-kind", "graph")                # the end: a dead marking
    assert page.locator("#graph g.marking.current.dead").count() == 1
    page.screenshot(path=str(SHOTS / "show_sauce_graph.png"))
    page.select_option("#view-kind", "net")
    # the reduced mission: every task is Fig. 3's, and the run does not apply
    page.select_option("#variant", "1")
    assert "mission.B" in marking(page)
    assert "full model" in page.text_content("#run-position")


def test_a_run_needs_a_mission(tmp_path):
    log = tmp_path / "run.jsonl"
    log.write_text('{"t": 0, "fire": "t01"}\n')
    out = run("show", "task", "--run", log, "-o", tmp_path / "x.html")
    assert out.returncode == 2 and "a run is of a mission" in out.stderr
    out = run("show", tmp_path / "missing.mcl")
    assert out.returncode == 2 and "no file" in out.stderr and "Traceback" not in out.stderr
