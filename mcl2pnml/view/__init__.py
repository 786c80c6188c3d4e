"""The view: what people look at. Layouts, drawings, the token-game page.

Owns node positions (graphviz ``dot`` or breadth-first layers), the
drawings of nets (:mod:`mcl2pnml.view.drawing`: what is drawn and how, as a
graphviz graph, whose DOT text :mod:`mcl2pnml.io.dot` writes or renders),
and the self-contained HTML page of ``mcl2pnml show``.

May import: :mod:`mcl2pnml.core`, :mod:`mcl2pnml.io` (a drawing is a DOT
file rendered) and :mod:`analysis` (the page shows the P-invariants).
"""
