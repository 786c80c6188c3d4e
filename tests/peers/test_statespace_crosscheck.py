"""Our reachability graphs against two independent engines reading our PNML.

pm4py builds the reachability graph of the P/T net it reads; SNAKES builds
its state graph. Both see a read arc as the self-loop our PNML writes, which
has the same firing rule, so the three must find the same markings.
"""
import warnings

import pytest

from mcl2pnml.analysis.statespace.explore import explore
from mcl2pnml.analysis.zoo import cycles
from mcl2pnml.io import ids
from mcl2pnml.io.pnml import write_pnml
from mcl2pnml.language.library import default_library


LIB = default_library()
NETS = [LIB.composed(n) for n in ("task", "task-reduced", "sequence", "parallel", "while",
                                  "monitor", "KeepTwoGoals")] + [cycles(3)]


def _ours(net):
    space = explore(net)
    states = {frozenset((ids.encode(p), n) for p, n in space.marking(k).items())
              for k in range(space.states)}
    return space, states


@pytest.mark.parametrize("net", NETS, ids=lambda n: n.name)
def test_pm4py_finds_the_same_markings(net, tmp_path):
    import pm4py
    from pm4py.objects.petri_net.utils.reachability_graph import (
        construct_reachability_graph, marking_flow_petri)
    path = write_pnml(net, tmp_path / "net.pnml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pn, im, _ = pm4py.read_pnml(str(path))
    space, ours = _ours(net)
    ts = construct_reachability_graph(pn, im)
    assert len(ts.states) == space.states
    assert sum(1 for s in ts.states if not s.outgoing) == len(space.terminal)
    # the markings themselves, from the flow pm4py builds the graph from
    _incoming, outgoing, _ = marking_flow_petri(pn, im)
    theirs = {frozenset((p.name, n) for p, n in m.items()) for m in outgoing}
    assert theirs == ours


@pytest.mark.parametrize("net", NETS, ids=lambda n: n.name)
def test_snakes_finds_the_same_markings(net, tmp_path):
    import snakes.pnml
    from snakes.nets import StateGraph
    path = write_pnml(net, tmp_path / "net.pnml")
    graph = StateGraph(snakes.pnml.loads(path.read_text()))
    graph.build()
    space, ours = _ours(net)
    theirs = set()
    for state in graph:
        graph.goto(state)
        theirs.add(frozenset((p, len(list(ms))) for p, ms in graph.net.get_marking().items()))
    assert len(graph) == space.states and theirs == ours
    assert sum(1 for s in graph if not list(graph.successors(s))) == len(space.terminal)
