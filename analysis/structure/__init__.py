"""Structural analysis: place and transition invariants, siphons and traps, from the incidence
matrix without a state space. May import only :mod:`mcl2pnml.core` and the standard and numeric
libraries (sympy for exact arithmetic)."""
