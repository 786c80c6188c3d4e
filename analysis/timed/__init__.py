"""Time: the zone graph of a time Petri net and the verdicts it proves. May import only
:mod:`mcl2pnml.core`, :mod:`mcl2pnml.analysis.checking` (the same observers as the untimed
checker) and the standard and numeric libraries (networkx)."""
