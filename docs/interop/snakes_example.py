"""A compiled mission read by SNAKES: the net and its state graph.

    python docs/interop/snakes_example.py NET.pnml

docs/interop.md runs it on the paper's mission. SNAKES reads a P/T net as a
net of black tokens, names nodes by their XML id, skips our toolspecific
data, and sees a read arc as the self-loop our PNML writes.
"""
import sys

import snakes.pnml
from snakes.nets import StateGraph

with open(sys.argv[1]) as f:
    net = snakes.pnml.loads(f.read())
marked = sorted(place for place, tokens in net.get_marking().items() if tokens)
print(f"{len(net.place())} places, {len(net.transition())} transitions; "
      f"initial marking: {len(marked)} places marked")

graph = StateGraph(net)
graph.build()
dead = sum(1 for state in graph if not list(graph.successors(state)))
print(f"state graph: {len(graph)} markings, {dead} of them dead")
