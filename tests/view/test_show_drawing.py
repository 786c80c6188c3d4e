"""The token-game page draws a net as its static drawing does (Figs. 2-4): no arc through a
node it does not connect.

The check reads the data the page draws (the JSON inside the page ``mcl2pnml
show`` writes) and follows the page's script: each arc a polyline from its
source's border through its bend points to its target's border, to a copy of
its place where the drawing has one; the nodes as the page draws them. The
shapes are tested with :mod:`drawcheck`'s rules (an arc may graze a circle, not
cut through it). The same data drawn the old way, straight lines from centre to
centre and no copies, does cross nodes: the check would see it.
"""
from __future__ import annotations

import json
import re
import shutil
from collections import Counter
from functools import lru_cache
from pathlib import Path

import pytest
from matplotlib.path import Path as Curve
from matplotlib.transforms import Bbox

from drawcheck import _core
from helpers import ROOT
from mcl2pnml import pipeline
from mcl2pnml.view.layout import drawn_layout
from test_show import TWO_TASKS, page_of  # noqa: F401 (fixtures)

pytestmark = pytest.mark.skipif(shutil.which("dot") is None,
                                reason="graphviz's dot is not installed")

@lru_cache(maxsize=None)
def page_data(what: str, directory: str) -> dict:
    """The data of ``mcl2pnml show WHAT``'s page, read back from the page itself."""
    path = Path(directory) / (Path(what).stem + ".html")
    pipeline.save_show_page(path, pipeline.show_nets(what))
    html = path.read_text()
    return json.loads(re.search(r'<script type="application/json" id="data">(.*?)</script>',
                                html, re.S).group(1))


def nodes(view: dict, v: dict) -> list[tuple[str, Bbox, bool]]:
    """Every node the page draws in ``view`` of the net ``v``: its name, its shape's box
    (as dot laid it out: a circle of its radius, a box of its half sizes), whether it is
    round."""
    out = [(f"place {v['places'][i]['id']}", _box(x, y, r, r), True)
           for i, x, y, r, *_ in view["places"]]
    out += [(f"place {v['places'][i]['id']} (copy {k})", _box(x, y, r, r), True)
            for k, (i, x, y, r, *_) in enumerate(view["copies"])]
    out += [(f"transition {v['transitions'][i]['id']}", _box(x, y, w, h), False)
            for i, x, y, w, h, _ in view["transitions"]]
    return out


def _box(x: float, y: float, hw: float, hh: float) -> Bbox:
    return Bbox([[x - hw, y - hh], [x + hw, y + hh]])


def arcs(view: dict, v: dict, straight: bool = False):
    """Each arc as the page draws it: its name, the names of the two nodes it joins, its
    points (``straight``: from centre to centre, as the page drew them before)."""
    at = {i: (x, y) for i, x, y, *_ in view["places"]}
    where = {i: (x, y) for i, x, y, *_ in view["transitions"]}
    for ti, role, k, copy, flat in view["arcs"]:
        t = v["transitions"][ti]
        place = v["places"][t[role][k][0]]
        if straight:
            copy, flat = -1, []
        end = (f"place {place['id']}" if copy < 0 else f"place {place['id']} (copy {copy})")
        spot = at[t[role][k][0]] if copy < 0 else tuple(view["copies"][copy][1:3])
        bends = list(zip(flat[::2], flat[1::2]))
        ends = [spot, where[ti]]
        if role == "post":
            ends.reverse()
        name = (f"{place['id']}->{t['id']}" if role != "post" else f"{t['id']}->{place['id']}")
        yield name, {end, f"transition {t['id']}"}, [ends[0], *bends, ends[1]]


def crossings(view: dict, v: dict, straight: bool = False) -> list[str]:
    """Every arc drawn through a node it does not join."""
    shapes = nodes(view, v)
    found = []
    for name, ends, points in arcs(view, v, straight):
        line = Curve(points)
        for node, box, round_ in shapes:
            if node not in ends and line.intersects_bbox(_core(box, round_), filled=False):
                found.append(f"arc {name} through {node}")
    return found


def test_the_task_and_its_reduced_model_are_drawn_around_their_nodes(tmp_path_factory):
    """Fig. 2's task with its primitive, and Fig. 3's reduced task (the page's model
    switch): drawn straight, t3->MTX and t2->MTX ran through EXE and t1."""
    task, reduced = page_data("task", str(tmp_path_factory.mktemp("task")))["variants"]
    assert crossings(task["whole"], task) == []
    assert crossings(reduced["whole"], reduced) == []
    assert crossings(task["whole"], task, straight=True) != []
    old = crossings(reduced["whole"], reduced, straight=True)
    assert any(c.startswith(("arc t3->MTX", "arc t2->MTX")) for c in old), old
    # the places many transitions read (ON, OFF) or get back (MTX) are drawn beside each
    copies = Counter(task["places"][i]["id"] for i, *_ in task["whole"]["copies"])
    assert copies["ON"] >= 3 and copies["OFF"] >= 3 and copies["MTX"] >= 2
    # the primitive in its box, as Fig. 2 draws it
    (name, _, x0, y0, x1, y1), = task["whole"]["groups"]
    on = next(n for n in task["whole"]["transitions"] if task["transitions"][n[0]]["id"] == "on")
    assert name == "primitive" and x0 < on[1] < x1 and y0 < on[2] < y1


def test_the_sequence_is_drawn_around_its_nodes_with_t1_and_t2_boxed(tmp_path_factory):
    """Fig. 4's sequence: T1 and T2 in their boxes, no arc through a node."""
    v, = page_data("sequence", str(tmp_path_factory.mktemp("sequence")))["variants"]
    assert crossings(v["whole"], v) == []
    assert sorted(b[0] for b in v["whole"]["groups"]) == ["T1", "T2"]


def test_a_mission_is_drawn_around_its_nodes(tmp_path_factory):
    """A two-task mission, in full and reduced (its page's model switch)."""
    directory = tmp_path_factory.mktemp("two")
    (directory / "two.mcl").write_text(TWO_TASKS)
    for v in page_data(str(directory / "two.mcl"), str(directory))["variants"]:
        whole = v["whole"]
        assert crossings(whole, v) == [], v["label"]
        # each box of the overview holds its nodes
        where = {name: (x0, y0, x1, y1) for name, _, x0, y0, x1, y1 in whole["groups"]}
        for kind in ("places", "transitions"):
            for i, x, y, *_ in whole[kind]:
                n = v[kind][i]
                if n["group"] is not None:
                    x0, y0, x1, y1 = where[n["group"]]
                    assert x0 <= x <= x1 and y0 <= y <= y1, n["id"]
        # one call at a time: each call's own nodes, no arc through a node
        for name, view in v["calls"]["views"].items():
            assert crossings(view, v) == [], (v["label"], name)
            assert {v["transitions"][i]["id"].rpartition(".")[0]
                    for i, *_ in view["transitions"]} == {name}


def test_the_copies_are_the_pages_alone_pnml_draws_the_nets_own_nodes():
    """The copies of Fig. 2's ON, OFF and MTX are in the drawing, not in its PNML."""
    from lxml import etree

    net = pipeline.template_net("task")
    drawn = drawn_layout(net, "dot", pipeline.template_clusters("task"))
    assert drawn.copies and set(drawn.positions) == {n.id for n in (*net.places,
                                                                     *net.transitions)}
    assert {place for place, _ in drawn.copies.values()} == {"ON", "OFF", "MTX"}
    root = etree.fromstring(pipeline.to_pnml_bytes(net, "dot"))
    ids = {e.get("id") for e in root.iter() if e.tag.endswith(("}place", "}transition"))}
    assert ids == set(drawn.positions)


def test_the_page_draws_arcs_along_their_bends_and_copies_with_their_place(tmp_path, page_of):
    """In the browser: an arc with bend points is a path through them, and a copy of a
    place shows the place's tokens."""
    data = page_data("task", str(tmp_path))["variants"][0]    # (it writes tmp_path/task.html)
    page = page_of(tmp_path / "task.html")
    points = page.locator('#net path.arc[data-from="t05"][data-to="W_OK"], '
                          '#net path.arc[data-from="EXE"][data-to="t03"]').evaluate_all(
        "(ps) => ps.map((p) => p.getAttribute('d').split('L').length)")
    view = data["whole"]
    assert [a for a in view["arcs"] if a[1] == "post" and a[4]], "no arc of the task has bends"
    # every arc drawn with all its points: its two ends and each bend between them
    counts = page.locator("#net path.arc").evaluate_all(
        "(ps) => ps.map((p) => p.getAttribute('d').split('L').length)")
    expected = sorted(2 + len(flat) // 2 for *_, flat in view["arcs"])
    assert sorted(counts) == expected and max(counts) > 2 and points
    # OFF and its copies hold its token; after t01 and on, ON's copies hold one
    off = page.locator('#net g.place[data-id="OFF"], #net g.copy[data-id="OFF"]')
    assert off.count() == 1 + sum(data["places"][i]["id"] == "OFF" for i, *_ in view["copies"])
    assert off.evaluate_all("(gs) => gs.map((g) => g.querySelectorAll('.token').length)") \
        == [1] * off.count()
    page.click('#net g.transition[data-id="t01"]')
    page.click('#net g.transition[data-id="on"]')
    assert off.evaluate_all("(gs) => gs.map((g) => g.querySelectorAll('.token').length)") \
        == [0] * off.count()
    on = page.locator('#net g.place[data-id="ON"], #net g.copy[data-id="ON"]')
    assert on.evaluate_all("(gs) => gs.map((g) => g.querySelectorAll('.token').length)") \
        == [1] * on.count()
    assert page.locator('#net g.copy[data-id="ON"].gained').count() == on.count() - 1
