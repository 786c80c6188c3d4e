"""A mission's page one call at a time, in headless Chromium: the mission's own net first,
each call it makes a box named as MCL writes it, opened by a click and left by the
breadcrumb; a box shows whether its inside runs and how many of its transitions may
fire; *follow* goes to the call where a firing happened; the mission's result in its
own colour.
"""
from __future__ import annotations

import pytest

from helpers import run_cli as run
from test_show import TWO_TASKS, marking, page_of  # noqa: F401 (fixtures)


@pytest.fixture(scope="module")
def two(tmp_path_factory):
    """The two-task mission's page (Depth(2.0), then Goto((10.0, 5.0, 5.0)))."""
    folder = tmp_path_factory.mktemp("calls")
    (folder / "two.mcl").write_text(TWO_TASKS)
    out = run("show", folder / "two.mcl", "-o", folder / "two.html")
    assert out.returncode == 0, out.stderr
    return folder / "two.html"


def crumbs(page) -> list[str]:
    return page.locator("#crumbs button").all_text_contents()


def boxes(page) -> dict[str, str]:
    """Each box drawn: its name, and the state it shows."""
    return dict(page.locator("#net g.box").evaluate_all(
        "(gs) => gs.map((g) => [g.dataset.name, g.querySelector('text.state').textContent])"))


def drawn(page) -> set[str]:
    return {i.rpartition(".")[0] for i in page.locator("#net g.transition").evaluate_all(
        "(gs) => gs.map((g) => g.dataset.id)")}


def test_a_box_opens_its_call_and_the_breadcrumb_goes_back(two, page_of):
    page = page_of(two)
    assert page.input_value("#view-kind") == "net" and page.is_checked("#follow")
    assert crumbs(page) == ["mission"] and drawn(page) == {"mission"}
    assert boxes(page) == {"Depth-1": "idle", "Goto-1": "idle"}
    names = page.locator("#net g.box text:not(.state)").all_text_contents()
    assert names == ["Depth(2.0)", "Goto((10.0, 5.0, 5.0))"]
    # the supervisor's steps: the first call runs, its task's primitive waits for the vehicle
    page.click("#settle")
    assert crumbs(page) == ["mission"]              # the steps were inside a box drawn here
    # (said short where the box is narrow)
    assert boxes(page)["Depth-1"] in ("running \u00b7 1 enabled", "running \u00b7 1")
    assert boxes(page)["Goto-1"] == "idle"
    page.click('#net g.box[data-name="Depth-1"]')
    assert crumbs(page) == ["mission", "Depth(2.0)"] and drawn(page) == {"Depth-1"}
    page.click('#net g.box[data-name="Depth"]')
    assert crumbs(page) == ["mission", "Depth(2.0)", "task Depth(d)"]
    page.click('#net g.box[data-name="KeepDepth"]')
    assert drawn(page) == {"KeepDepth"} and boxes(page) == {}
    # the token game goes on in the call: the vehicle's ack, clicked in the drawing
    page.click('#net g.transition[data-id="KeepDepth.on"]')
    assert "KeepDepth.ON" in marking(page)
    page.click("#crumbs button >> nth=0")
    assert crumbs(page) == ["mission"] and boxes(page)["Depth-1"].startswith("running")
    page.focus('#net g.box[data-name="Goto-1"]')        # a box is a button of the keyboard too
    page.keyboard.press("Enter")
    assert crumbs(page) == ["mission", "Goto((10.0, 5.0, 5.0))"]


def test_follow_goes_to_the_call_of_a_firing(two, page_of):
    page = page_of(two)
    page.click("#settle")
    page.click('#net g.box[data-name="Goto-1"]')       # a call that does not run yet
    assert crumbs(page) == ["mission", "Goto((10.0, 5.0, 5.0))"]
    page.click('#enabled button[data-id="KeepDepth.on"]')
    assert crumbs(page) == ["mission", "Depth(2.0)", "task Depth(d)", "primitive KeepDepth(d)"]
    page.uncheck("#follow")
    page.click("#crumbs button >> nth=0")
    page.click('#enabled button[data-id="KeepDepth.achieved"]')
    assert crumbs(page) == ["mission"]


@pytest.mark.parametrize("result, colour", [("OK", "rgb(26, 127, 55)"),
                                            ("FAIL", "rgb(198, 40, 40)"),
                                            ("ABORTED", "rgb(138, 90, 0)")])
def test_the_missions_result_in_its_own_colour(two, page_of, result, colour):
    page = page_of(two)
    said = page.evaluate("""(result) => {
      setTokens(V.places.findIndex((p) => p.id === "mission." + result), 1);
      playStep();
      const status = document.getElementById("play-status");
      return [status.textContent, getComputedStyle(status).color];
    }""", result)
    assert said == [f"The mission ended: mission.{result} (t = 0 s, 0 firings).", colour]
