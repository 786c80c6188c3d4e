"""Figs. 1 to 4 of the paper, redrawn from the templates (graphviz, SVG and PNG)."""
from __future__ import annotations

from pathlib import Path

from mcl2pnml.draw import render, to_dot
from mcl2pnml.template_library import Library

FIGURES = {
    1: ("primitive", "Fig. 1. Vehicle primitive Petri net model (M0 = {OFF, C})"),
    2: ("task", "Fig. 2. Basic control task (AchieveGoal) fused with the primitive"),
    3: ("task-reduced", "Fig. 3. Reduced Petri net model for a task"),
    4: ("sequence", "Fig. 4. Sequence control structure with two reduced tasks"),
}


def clusters(lib: Library, name: str) -> dict[str, list[str]]:
    """The nodes each slot brought in: the primitive of a task, T1 and T2 of a structure."""
    t = lib.get(name)
    own = {n.id for n in (*t.net.places, *t.net.transitions)}
    net = lib.composed(name)
    nodes = [n.id for n in (*net.places, *net.transitions) if n.id not in own]
    if t.primitives:
        return {("primitive " + p if p else "primitive"): [
            n for n in nodes if (n.startswith(p + "_") if p else True)] for p in t.primitives}
    return {slot: [n for n in nodes if n.startswith(slot + "_")] for slot in t.children}


def draw_all(lib: Library, out: Path) -> list[Path]:
    written = []
    for number, (name, title) in FIGURES.items():
        graph = to_dot(lib.composed(name), clusters=clusters(lib, name), title=title)
        for fmt in ("svg", "png"):
            path = out / f"fig{number}.{fmt}"
            render(graph, str(path), fmt)
            written.append(path)
    return written
