"""Analysis of Petri nets: of any P/T net, not only those the compiler writes, read through
:mod:`mcl2pnml.core` alone (docs/ARCHITECTURE.md, the layer under the CLI beside the language
and the file formats).

May import :mod:`mcl2pnml.core` and the standard and numeric libraries (numpy, scipy, sympy,
networkx), nothing else of ours. Installed as ``mcl2pnml.analysis``; its subpackages,
each over those listed before it:

- :mod:`~mcl2pnml.analysis.structure` the structure alone: P- and T-invariants, siphons and traps.
- :mod:`~mcl2pnml.analysis.statespace` the reachable markings: which explorer, the explorers,
  and their inner loops (in C, and their plain-Python reference).
- :mod:`~mcl2pnml.analysis.checking` properties of runs: the pattern observers, checked on a
  state space or on the fly, and a task's interface contract.
- :mod:`~mcl2pnml.analysis.timed` the zone graph of a time Petri net and the verdicts it proves.
- :mod:`~mcl2pnml.analysis.contest` the Model Checking Contest's questions.

and beside them :mod:`~mcl2pnml.analysis.behaviour` (ends, ends well, can run again),
:mod:`~mcl2pnml.analysis.markov` (absorbing Markov chains whose steps take time),
:mod:`~mcl2pnml.analysis.report` (one analysis as JSON and as a report) and
:mod:`~mcl2pnml.analysis.zoo` (textbook nets whose answers are known by hand).
"""
