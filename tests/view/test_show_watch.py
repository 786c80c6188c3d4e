"""`mcl2pnml show` for watching a mission: fit and follow, the marking's change, filters,
the mission's tree, the clock and the reachability graph, in headless Chromium.

One browser for the module (the fixture of test_show.py) and one small
mission, two tasks in sequence, compiled and run once: its page is opened
afresh by each test. Screenshots go to out/screenshots/show_*.png, the
tutorial's pictures.
"""
from __future__ import annotations

import json
import re

import pytest

from helpers import ROOT, run_cli as run
from test_show import SHOTS, marking, page_of, two_tasks_run  # noqa: F401 (fixtures)

from mcl2pnml.analysis.statespace.explore import explore
from mcl2pnml import pipeline
from mcl2pnml.view.reachability import reachability_graph


@pytest.fixture(scope="module")
def mission(tmp_path_factory):
    """The two-task mission, a run of it on a scripted vehicle, and its page."""
    d = tmp_path_factory.mktemp("watch")
    source, log, fired = two_tasks_run(d)
    out = run("show", source, "--run", log, "-o", d / "two.html", "--graph-json",
              d / "graph.json")
    assert out.returncode == 0, out.stderr
    return {"source": source, "log": log, "page": d / "two.html", "graph": d / "graph.json",
            "fired": fired}


def shot(page, name: str) -> None:
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / f"show_{name}.png"))


def view_box(page) -> str:
    return page.get_attribute("#net", "viewBox")


def inside(page, selector: str) -> bool:
    """Every element ``selector`` finds lies inside the drawing's window."""
    return page.evaluate("""(selector) => {
        const r = document.getElementById("net").getBoundingClientRect();
        return [...document.querySelectorAll(selector)].every((e) => {
            const b = e.getBoundingClientRect();
            return b.left >= r.left - 0.5 && b.right <= r.right + 0.5 &&
                   b.top >= r.top - 0.5 && b.bottom <= r.bottom + 0.5;
        });
    }""", selector)


def whole(page) -> None:
    """The mission's whole net drawn, not one call at a time (every node in the window)."""
    page.select_option("#view-kind", "whole")


def tree_state(page, name: str) -> str:
    return page.get_attribute(f'#tree div.node[data-name="{name}"]', "data-state")


def test_fit_shows_the_whole_mission(page_of, mission):
    page = page_of(mission["page"])
    whole(page)
    nodes = "#net g.place circle, #net g.transition rect"
    assert page.locator(nodes).count() > 100 and inside(page, nodes)   # the first view
    page.mouse.move(700, 450)
    for _ in range(8):
        page.mouse.wheel(0, -100)                                       # zoom in
    assert not inside(page, nodes)
    page.click("#fit")
    assert inside(page, nodes)
    shot(page, "fit")


def test_follow_pans_to_each_firing(page_of, mission):
    page = page_of(mission["page"])
    whole(page)
    assert page.is_checked("#follow")                 # on by default with a run
    seen = set()
    for _ in range(4):
        page.click("#run-next")
        last = page.locator("#history li").last.text_content()
        assert inside(page, f'#net g.transition[data-id="{last}"] rect')
        seen.add(view_box(page))
    assert len(seen) == 4                             # each step moved the window
    shot(page, "follow")
    page.uncheck("#follow")
    before = view_box(page)
    page.click("#run-next")
    assert view_box(page) == before


def test_the_marking_shows_what_the_last_firing_changed(page_of, mission):
    page = page_of(mission["page"])
    page.click('#enabled button[data-id="mission.t1"]')
    net = pipeline.compile_file(mission["source"])
    pre = {a.source for a in net.pre["mission.t1"]}
    post = {a.target for a in net.post["mission.t1"]}
    gained = sorted(post - pre)
    lost = sorted(pre - post)
    assert sorted(page.locator("#net g.place.gained").evaluate_all(
        "(g) => g.map((e) => e.dataset.id)")) == gained
    assert sorted(page.locator("#net g.place.lost").evaluate_all(
        "(g) => g.map((e) => e.dataset.id)")) == lost
    assert sorted(page.locator("#marking span.gained").all_text_contents()) == gained
    # places left empty are listed apart: the list holds only marked places
    assert page.text_content("#marking-lost") == "\u2212 " + ", ".join(lost)
    assert not set(lost) & set(marking(page))
    shot(page, "diff")
    page.click("#back")
    assert page.locator("#net g.place.gained, #net g.place.lost").count() == 0


def test_places_and_invariants_filtered(page_of, mission):
    page = page_of(mission["page"])
    whole(page)
    page.fill("#place-filter", "keepdepth")
    assert marking(page) == ["KeepDepth.C", "KeepDepth.LOCK", "KeepDepth.OFF"]
    assert page.locator("#net g.place.match").count() == 8        # marked or not
    page.fill("#place-filter", "")
    page.check("#away")                                # the tokens at rest left out
    assert page.text_content("#marking") == ""
    page.click('#enabled button[data-id="mission.t1"]')
    assert "mission.B*0" in marking(page) and "KeepDepth.OFF" not in marking(page)
    page.uncheck("#away")
    # folded to one line, so that the recorded run stays in sight
    status = page.text_content("#invariants-status")
    n = int(status.split()[0])
    assert status == f"{n} invariants, all hold"
    assert page.is_hidden("#invariants") and page.is_visible("#run-entries")
    page.click("#invariants-toggle")
    assert page.locator("#invariants tr").count() == n
    page.fill("#invariant-filter", "Goto-1.IN")
    rows = page.locator("#invariants td.formula").all_text_contents()
    assert 0 < len(rows) < n and all("Goto-1.IN" in r for r in rows)


def test_the_tree_follows_a_replayed_run(page_of, mission):
    page = page_of(mission["page"])
    labels = page.locator("#tree div.node > span:first-child").all_text_contents()
    assert labels == ["mission = sequence", "Depth(2.0)", "Goto((10.0, 5.0, 5.0))"]
    states = {"Depth-1": [], "Goto-1": [], "mission": []}
    for _ in mission["fired"]:
        for name, seen in states.items():
            now = tree_state(page, name)
            if not seen or seen[-1] != now:
                seen.append(now)
        page.click("#run-next")
        if page.locator("#history li").last.text_content() == "Goto.t01":
            shot(page, "tree")
    for name, seen in states.items():
        seen.append(tree_state(page, name))
    assert states["Depth-1"][:3] == ["idle", "running", "OK"]
    assert states["Goto-1"][:3] == ["idle", "running", "OK"]
    assert states["mission"][-1] == "OK"
    while page.locator("#history li").last.text_content() != "Goto-1.return_OK":
        page.click("#run-back")
    page.click("#run-back")                            # stepping back: running again
    assert tree_state(page, "Goto-1") == "running" and tree_state(page, "mission") == "running"
    # a node's part of the net: its instance's nodes, highlighted and in the window
    whole(page)
    page.click("#fit")
    before = view_box(page)
    page.click('#tree div.node[data-name="Depth-1"]')
    assert view_box(page) != before
    focus = page.locator("#net .focus").evaluate_all("(g) => g.map((e) => e.dataset.id)")
    assert focus and all(i.startswith("Depth-1.") for i in focus)
    assert inside(page, "#net .focus")


def test_the_tree_of_the_reduced_model(page_of, mission):
    """The states come from the instances' places, which the reduced model (Fig. 3) keeps."""
    page = page_of(mission["page"])
    page.select_option("#variant", "1")
    for _ in range(40):                               # every task ends OK (t3 would FAIL)
        ok = [b for b in page.locator("#enabled button:enabled").all_text_contents()
              if not b.endswith(".t3")]
        if not ok:
            break
        page.click(f'#enabled button[data-id="{ok[0]}"]')
    assert "mission.OK" in marking(page)
    assert [tree_state(page, n) for n in ("mission", "Depth-1", "Goto-1")] == ["OK"] * 3


def test_a_time_out_waits_for_its_time(page_of, mission):
    page = page_of(mission["page"])
    whole(page)
    assert page.text_content("#clock") == "t = 0 s"
    for t in ("mission.t1", "Depth-1.enter", "Depth.t01", "KeepDepth.on"):
        page.click(f'#enabled button[data-id="{t}"]')
    # the task's time-out (60 s) is enabled, and must wait for its time
    assert page.is_disabled('#enabled button[data-id="Depth.t03"]')
    page.locator('#net g.transition[data-id="Depth.t03"]').dispatch_event("click")
    assert page.locator("#history li").last.text_content() == "KeepDepth.on"
    assert page.text_content("#clock-next") == "next time-out: Depth.t03 at t = 60"
    shot(page, "clock")
    page.click("#advance")
    assert page.text_content("#clock") == "t = 60 s"
    assert page.locator("#history li").last.text_content() == "Depth.t03"
    page.click("#back")                               # time goes back with the firing
    assert page.text_content("#clock") == "t = 0 s"
    # a recorded run sets the clock: the vehicle reached the depth at t=5
    page.click("#reset")
    while page.locator("#history li").count() < mission["fired"].index("KeepDepth.achieved") + 1:
        page.click("#run-next")
    assert page.text_content("#clock") == "t = 5 s"


def test_the_reachability_graph(page_of, mission):
    page = page_of(mission["page"])
    net = pipeline.compile_file(mission["source"])
    space = explore(net)
    page.select_option("#view-kind", "graph")
    assert page.locator("#graph g.marking").count() == space.states
    dead = page.locator("#graph g.marking.dead").evaluate_all(
        "(g) => g.map((e) => +e.dataset.index)")
    graph = json.loads(mission["graph"].read_text())
    assert len(dead) == len(space.terminal) and sorted(dead) == sorted(graph["dead"])
    assert len(graph["markings"]) == space.states
    assert page.get_attribute("#graph g.marking.current", "data-index") == "0"
    # a dead marking clicked: the token game is there, nothing is enabled
    page.click(f'#graph g.marking[data-index="{dead[0]}"] circle')
    expected = sorted(graph["places"][p] + ("" if n == 1 else f"*{n}")
                      for p, n in graph["markings"][dead[0]])
    assert marking(page) == expected
    assert page.text_content("#enabled") == "none: a dead marking"
    assert page.get_attribute("#graph g.marking.current", "data-index") == str(dead[0])
    assert re.match(rf"{space.states} reachable markings", page.text_content("#graph-message"))
    shot(page, "graph")


def test_no_graph_of_a_large_or_unbounded_net():
    from mcl2pnml.analysis.zoo import kanban
    from mcl2pnml.core.net import NetBuilder
    graph = reachability_graph(kanban(2))                        # 4,600 markings
    assert graph.reason is not None and "more than 2,000" in graph.reason
    assert graph.to_json() == {"reason": graph.reason, "limit": 2000}
    b = NetBuilder("grows")
    b.place("p", 0)
    b.transition("t")
    b.arc("t", "p")
    assert "unbounded" in reachability_graph(b.build()).reason


def test_the_graph_is_the_general_explorers(mission):
    """Whichever explorer made it, the graph has the general explorer's markings, firings
    and dead markings (compared as markings: the explorers number them differently)."""
    net = pipeline.compile_file(mission["source"])
    graph = reachability_graph(net)
    general = explore(net, backend="general")

    def sparse(k):
        return tuple((p, int(n)) for p, n in enumerate(general.markings[k]) if n)

    assert graph.markings[0] == sparse(0)                        # M0 first
    assert set(graph.markings) == {sparse(k) for k in range(general.states)}
    assert {(graph.markings[a], t, graph.markings[b]) for a, b, t in graph.edges} == \
        {(sparse(a), t, sparse(b)) for a, t, b in zip(general.src, general.trans, general.dst)}
    assert {graph.markings[k] for k in graph.dead} == {sparse(k) for k in general.terminal}
    assert graph.layers[0] == 0 and all(
        graph.layers[b] <= graph.layers[a] + 1 for a, b, _ in graph.edges)


@pytest.mark.parametrize("example", ["sauce", "multi_leg", "dam_inspection"])
def test_every_tree_node_is_an_instance_of_both_models(example):
    """The tree's names are the compiler's (one rule, language.functional.instances): each
    node has its instance's places in the mission and in its reduced model, with the
    control interface the page reads its state from (B, OK, FAIL, ABORTED)."""
    from mcl2pnml.view.show import tree_data, tree_parts
    shown = pipeline.show_nets(str(ROOT / "examples" / f"{example}.mcl"))
    tree = tree_data(shown.trees)
    assert tree[0]["name"] == "mission" and len(tree) > 3
    for net, _ in shown.nets:
        for node, part in zip(tree, tree_parts(net, tree)):
            assert part["places"] and all(part[r] is not None
                                          for r in ("B", "OK", "FAIL", "ABORTED")), node


def test_a_block_is_a_column_in_the_tree(tmp_path, page_of):
    """Algorithm 2 nests a block's sequences to the right: drawn as a column, not a
    staircase (the nested sequences keep their place and their state)."""
    calls = "".join(f"    Goto(({k}.0, 0.0, 0.0));\n" for k in range(1, 7))
    mission = tmp_path / "block.mcl"
    mission.write_text("primitive GoToWayPoint(wp);\ntask Goto(wp) = AchieveGoal(GoToWayPoint(wp));"
                       f"\nmission {{\n{calls}}}\n")
    out = run("show", mission, "-o", tmp_path / "block.html")
    assert out.returncode == 0, out.stderr
    page = page_of(tmp_path / "block.html")
    left = page.locator("#tree div.node").evaluate_all(
        "(d) => d.map((e) => [e.firstChild.textContent, e.getBoundingClientRect().left])")
    assert [label for label, _ in left].count("sequence") == 4      # and the root
    assert len({x for _, x in left[1:]}) == 1                    # one column under the root
