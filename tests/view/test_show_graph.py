"""`mcl2pnml show`: the reachability graph's drawing, in headless Chromium.

Each edge is labelled with its transitions' names; a marking clicked is
reached from M0 by a path that stays drawn (and grows as play goes on), a
real firing sequence of the net; edges are routed between the layers, not
through other markings; past a few hundred markings (the paper's mission has
1,509) the strongly connected components are drawn as nodes, the current
marking's expanded.
"""
from __future__ import annotations

from pathlib import Path

import pytest

from helpers import ROOT
from shown import shown
from test_show import SHOTS, page_of  # noqa: F401 (fixtures)

from mcl2pnml.core.structure import structure
from mcl2pnml.view.reachability import CONDENSE_ABOVE, reachability_graph

SAUCE = ROOT / "examples" / "sauce.mcl"


@pytest.fixture(scope="module")
def pages(tmp_path_factory) -> dict[str, Path]:
    """The paper's mission and the sequence structure (22 markings) as pages."""
    return {name: shown(tmp_path_factory, f"{name}.html", what)
            for name, what in (("sauce", SAUCE), ("sequence", "sequence"))}


@pytest.fixture(scope="module")
def sauce_graph(examples):
    net = examples.net("sauce")
    return net, reachability_graph(net)


def open_graph(page_of, path: Path):
    page = page_of(path)
    page.select_option("#view-kind", "graph")
    return page


def test_every_edge_is_labelled_with_its_transitions(pages, page_of):
    page = open_graph(page_of, pages["sequence"])
    pairs = page.evaluate("""() => {
      const labels = [...document.querySelectorAll('#graph text.edge-label')];
      const edges = [...document.querySelectorAll('#graph .edge')];
      return [edges.length, labels.map((t) => [t.textContent, t.dataset.edge]),
              edges.map((e) => e.querySelector('title').textContent)];
    }""")
    count, labels, titles = pairs
    assert count == 36 == len(labels) == len(titles)      # the sequence's 36 firings
    for (text, _), title in zip(labels, titles):
        assert text and text == title                      # one transition each, named
    # readable: a label is over the edges (a white halo) and not hidden under a marking
    halo = page.evaluate("""() => { const s = getComputedStyle(
      document.querySelector('#graph text.edge-label'));
      return [s.paintOrder, s.stroke, parseFloat(s.fontSize)]; }""")
    assert halo[0].startswith("stroke") and halo[1] == "rgb(255, 255, 255)" and halo[2] >= 8
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / "show_graph.png"))


#: Points along each edge that fall inside another node's shape (its circle, its square).
THROUGH = """() => {
  const rows = new Map();                  // the nodes by their row (a layer's y)
  for (const g of document.querySelectorAll('#graph :is(g.marking, g.component)')) {
    const m = g.transform.baseVal[0].matrix, y = Math.round(m.f);
    if (!rows.has(y)) rows.set(y, []);
    rows.get(y).push([m.e, m.f, g.classList.contains('marking') ? 'M' + g.dataset.index
                                                               : 'C' + g.dataset.component]);
  }
  const ys = [...rows.keys()];
  const hits = [];
  for (const e of document.querySelectorAll('#graph .edge')) {
    const n = e.getTotalLength();
    for (let s = 0; s <= n; s += 5) {
      const p = e.getPointAtLength(s);
      for (const y of ys) {
        if (Math.abs(p.y - y) >= 8) continue;
        for (const [x, , name] of rows.get(y)) {
          if (name === e.dataset.from || name === e.dataset.to) continue;
          if (Math.abs(p.x - x) < 9) hits.push([e.dataset.from, e.dataset.to, name]);
        }
      }
    }
  }
  return hits;
}"""


def test_edges_go_between_the_markings_not_through_them(pages, page_of):
    page = open_graph(page_of, pages["sequence"])
    assert page.evaluate(THROUGH) == []
    # the edges that span layers or go back are curves through the gaps between them
    assert page.locator("#graph path.edge").count() > 0


def test_a_clicked_marking_keeps_its_path_from_m0(pages, page_of, sauce_graph):
    net, graph = sauce_graph
    s = structure(net)
    page = open_graph(page_of, pages["sauce"])
    target = max(range(len(graph.markings)), key=lambda k: (graph.layers[k], -k))  # the deepest
    comp = graph.components[target]
    # a component of the condensed view clicked: play goes on from its marking nearest M0
    page.click(f'#graph g.component[data-component="{comp}"] rect')
    current = page.get_attribute("#graph g.marking.current", "data-index")
    assert graph.components[int(current)] == comp
    path = page.evaluate("() => currentPath()")
    assert len(path) == graph.layers[int(current)] > 20     # a shortest path from M0

    def check(path, end):
        m = list(s.initial_vector())
        at = 0
        for a, b, t in path:                                  # a real firing sequence
            assert a == at and s.enabled(m, t), (a, net.transitions[t].id)
            s.fire(m, t)
            assert {p: n for p, n in enumerate(m) if n} == dict(graph.markings[b])
            at = b
        assert at == end
    check(path, int(current))
    # shown: the path's edges and markings lit, listed by name
    text = page.text_content("#graph-path")
    assert text.startswith(f"Path from M0 ({len(path)} firings): ")
    assert text.split(": ", 1)[1].split(" \u2192 ") == [net.transitions[t].id for *_, t in path]
    lit = page.locator("#graph .edge.path").evaluate_all(
        "(es) => es.map((e) => [e.dataset.from, e.dataset.to])")
    ends = {(a, b) for a, b in lit}
    node = (lambda k: f"M{k}" if graph.components[k] == comp else f"C{graph.components[k]}")
    assert ends == {(node(a), node(b)) for a, b, _ in path if node(a) != node(b)}
    # play goes on: the path grows with each firing, a step back takes one off, nothing lost
    page.click("#enabled button >> nth=0")
    longer = page.evaluate("() => currentPath()")
    assert longer[:-1] == path and len(longer) == len(path) + 1
    check(longer, longer[-1][1])
    page.click("#back")
    assert page.evaluate("() => currentPath()") == path
    assert page.locator("#graph .edge.path").count() == len(lit)
    # a marking of the expanded component clicked: its own path
    page.click('#graph g.marking[data-index="0"], #graph g.component[data-component="0"]')
    assert page.evaluate("() => currentPath()") == []
    assert page.text_content("#graph-path").endswith("the current marking is M0.")
    page.click("#reset")


def test_the_condensed_view_expands_the_current_component(pages, page_of, sauce_graph):
    net, graph = sauce_graph
    n = len(graph.markings)
    assert n == 1509 > CONDENSE_ABOVE
    page = open_graph(page_of, pages["sauce"])
    components = max(graph.components) + 1

    def drawn():
        return (page.locator("#graph g.marking").evaluate_all("(g) => g.map((e) => +e.dataset.index)"),
                page.locator("#graph g.component").evaluate_all(
                    "(g) => g.map((e) => +e.dataset.component)"))

    markings, comps = drawn()
    assert len(markings) + len(comps) < n                    # fewer nodes than markings
    assert markings == [0] and 0 not in comps and len(comps) == components - 1
    # into a component of four markings: those four drawn, the rest as components
    big = next(c for c in range(components) if graph.components.count(c) == 4)
    page.click(f'#graph g.component[data-component="{big}"] rect')
    markings, comps = drawn()
    members = [k for k in range(n) if graph.components[k] == big]
    assert sorted(markings) == members and big not in comps and len(comps) == components - 1
    assert int(page.get_attribute("#graph g.marking.current", "data-index")) in members
    # inside it, every firing between its markings is drawn and labelled
    inner = {(f"M{a}", f"M{b}") for a, b, _ in graph.edges
             if graph.components[a] == big and graph.components[b] == big}
    shown = page.locator("#graph .edge").evaluate_all(
        "(es) => es.map((e) => [e.dataset.from, e.dataset.to])")
    assert inner and inner <= {tuple(e) for e in shown}
    labels = page.locator("#graph text.edge-label").count()
    assert labels == len(shown)
    assert page.evaluate(THROUGH) == []
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / "show_graph_condensed.png"))
    # Reset: back to M0, M0's component expanded again
    page.click("#reset")
    markings, _ = drawn()
    assert markings == [0]
