"""A compiled mission read by pm4py: the net, its reachable markings, and a drawing.

    python docs/interop/pm4py_example.py NET.pnml [DRAWING.svg]

docs/interop.md runs it on the paper's mission. pm4py names nodes by their
XML id, keeps a transition's name as its label, and sees a read arc as the
self-loop our PNML writes. A PNML file declares no final marking (ours do
not), so pm4py returns None for it and warns; the warning is printed here,
on standard output, with the rest. The drawing is written to a file:
``pm4py.view_petri_net`` opens a viewer, and waits for one on a machine with
no display.
"""
import sys
import warnings

import pm4py
from pm4py.objects.petri_net.obj import Marking
from pm4py.objects.petri_net.utils.reachability_graph import construct_reachability_graph

path = sys.argv[1]
with warnings.catch_warnings(record=True) as said:
    warnings.simplefilter("always")
    net, initial, final = pm4py.read_pnml(path)
for warning in said:
    print("pm4py warns:", warning.message)
# a read arc reaches pm4py as two arcs, from a place and back to it
loops = sum(1 for t in net.transitions
            if {a.source for a in t.in_arcs} & {a.target for a in t.out_arcs})
print(f"{len(net.places)} places, {len(net.transitions)} transitions, {len(net.arcs)} arcs; "
      f"{loops} transitions with a self-loop")
print(f"initial marking: {len(initial)} places marked; final marking: {final}")

graph = construct_reachability_graph(net, initial)
dead = sum(1 for state in graph.states if not state.outgoing)
print(f"reachability graph: {len(graph.states)} markings, {dead} of them dead")

if len(sys.argv) > 2:
    pm4py.save_vis_petri_net(net, initial, final or Marking(), sys.argv[2])
    print("drew", sys.argv[2])
