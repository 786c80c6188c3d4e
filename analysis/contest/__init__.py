"""The Model Checking Contest's questions, answered on a net's reachability graph or without it.
May import only :mod:`mcl2pnml.core`, the analysis subpackages under it (structure, statespace,
checking) and the standard and numeric libraries (numpy)."""
