"""Figs. 1 to 4 of the paper, redrawn from the templates (graphviz, SVG and PNG).

The same drawing as ``mcl2pnml template NAME --format svg``: each slot's net
(the primitive of Fig. 2, T1 and T2 of Fig. 4) in its own box, the fusion
places between the boxes, tokens flowing from B at the top to the results.
"""
from __future__ import annotations

from pathlib import Path

from mcl2pnml.io.dot import write_image
from mcl2pnml.language.library import Library
from mcl2pnml.view.drawing import drawing

FIGURES = {
    1: ("primitive", "Fig. 1. Vehicle primitive Petri net model (M0 = {OFF, C})"),
    2: ("task", "Fig. 2. Basic control task (AchieveGoal) fused with the primitive"),
    3: ("task-reduced", "Fig. 3. Reduced Petri net model for a task"),
    4: ("sequence", "Fig. 4. Sequence control structure with two reduced tasks"),
}


def figure(lib: Library, number: int):
    """Fig. ``number`` (1-4) as a graphviz graph: the template composed as the paper
    analyses it, every slot's box open."""
    name, title = FIGURES[number]
    return drawing(lib.composed(name), title, clusters=lib.slots(name), expand=None)


def draw_all(lib: Library, out: Path) -> list[Path]:
    written = []
    for number in FIGURES:
        graph = figure(lib, number)
        for fmt in ("svg", "png"):
            path = out / f"fig{number}.{fmt}"
            write_image(graph.source, path, fmt)
            written.append(path)
    return written
