"""State spaces: which explorer builds a net's reachable markings, the explorers, and the packed
markings they share. May import only :mod:`mcl2pnml.core`, :mod:`mcl2pnml.analysis.structure`
(the P-invariants that bound a net) and the standard and numeric libraries (numpy,
networkx)."""
