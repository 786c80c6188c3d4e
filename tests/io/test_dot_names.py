"""Names DOT would misread: every node drawn once, where its id says, its label as text.

Ids and names come from files other tools wrote (a TINA place ``a:b``, a
PNML id that looks like markup). In DOT, ``a:b`` in an edge is node ``a``,
port ``b``; ``<...>`` is an HTML string, which graphviz renders (and whose
``<IMG>`` it reads from disk); ``\\N`` in a label is the node's name. The
drawing must show each of them as the text it is, and the layout read back
from dot must place every node under its own id.
"""
from __future__ import annotations

import json
import shutil
import subprocess

import pytest

from mcl2pnml.core.net import NetBuilder
from mcl2pnml.io.dot import node_id, node_name
from mcl2pnml.view.drawing import dot_graph

HOSTILE = ["a:b", "<img src=/etc/passwd>", "x\\N", 'q"uote', "p%41", "node", "edge:1", "<b>"]


def hostile_net():
    b = NetBuilder("hostile")
    for k, name in enumerate(HOSTILE):
        b.place(name, 1 if k == 0 else 0, name=name + "\\l")
        b.transition(f"t{k}", name=f"<i>{k}</i>")
    for k, name in enumerate(HOSTILE):
        b.arc(name, f"t{k}")
        b.arc(f"t{k}", HOSTILE[(k + 1) % len(HOSTILE)])
    return b.build()


def test_names_round_trip_and_never_carry_what_dot_reads_specially():
    for name in HOSTILE + ["plain", "mission.sequence-1.t2", "é"]:
        drawn = node_name(name)
        assert node_id(drawn) == name
        assert ":" not in drawn and "\\" not in drawn and '"' not in drawn
        assert not (drawn.startswith("<") and drawn.endswith(">"))
    assert node_name("mission.B") == "mission.B"      # ordinary ids are kept as they are


def test_dot_draws_every_node_once_with_its_label_as_text():
    if shutil.which("dot") is None:
        pytest.skip("graphviz's dot is not installed (make setup installs it with apt-get)")
    net = hostile_net()
    source = dot_graph(net, legend=False).source
    out = subprocess.run(["dot", "-Tjson0"], input=source.encode(), capture_output=True,
                         timeout=60, check=True)
    graph = json.loads(out.stdout)
    objects = [o for o in graph["objects"] if "nodes" not in o]     # nodes, not clusters
    ids = sorted(node_id(o["name"]) for o in objects)
    assert ids == sorted([p.id for p in net.places] + [t.id for t in net.transitions])
    # what a reader of the picture sees: each name as written (backslash
    # included), never rendered as markup
    from lxml import etree
    svg = subprocess.run(["dot", "-Tsvg"], input=source.encode(), capture_output=True,
                         timeout=60, check=True).stdout
    texts = [t.text for t in etree.fromstring(svg).iter("{http://www.w3.org/2000/svg}text")]
    for node in (*net.places, *net.transitions):
        assert node.label in texts, (node.label, texts)
    # every arc joins the nodes it joins in the net (no port, no stray node)
    names = [o["name"] for o in graph["objects"]]
    drawn = {(node_id(names[e["tail"]]), node_id(names[e["head"]])) for e in graph["edges"]}
    assert drawn == {(a.source, a.target) for a in net.arcs}


def test_the_dot_layout_places_every_node_under_its_id():
    if shutil.which("dot") is None:
        pytest.skip("graphviz's dot is not installed (make setup installs it with apt-get)")
    from mcl2pnml.view.layout import _dot_layout
    net = hostile_net()
    pos = _dot_layout(net)      # None would be dot failing (the layers would stand in)
    assert pos is not None
    assert set(pos) == {p.id for p in net.places} | {t.id for t in net.transitions}
    assert len(set(pos.values())) == len(pos)       # one place each, not piled up
