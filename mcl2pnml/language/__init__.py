"""The language: MCL from text to one composed Petri net (the paper's section 2.4).

Owns the AST, the parser (lark), the checker, step 1 (the functional form,
the paper's Algorithm 2), step 2 (the compiler, which fuses template nets),
and the template language with its library of the paper's nets (Figs. 1-4).

May import: :mod:`mcl2pnml.core` only.
"""
