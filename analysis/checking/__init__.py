"""Properties of a net's runs: the observers of the property patterns, checked on a state
space, on the fly, and as a task's interface contract. May import only :mod:`mcl2pnml.core`,
:mod:`mcl2pnml.analysis.statespace` and the standard and numeric libraries (numpy, scipy,
networkx)."""
