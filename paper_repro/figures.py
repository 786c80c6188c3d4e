"""Figs. 1 to 4 of the paper, redrawn from the templates (graphviz, SVG and PNG)."""
from __future__ import annotations

from pathlib import Path

from mcl2pnml.io.dot import render, to_dot
from mcl2pnml.language.library import Library

FIGURES = {
    1: ("primitive", "Fig. 1. Vehicle primitive Petri net model (M0 = {OFF, C})"),
    2: ("task", "Fig. 2. Basic control task (AchieveGoal) fused with the primitive"),
    3: ("task-reduced", "Fig. 3. Reduced Petri net model for a task"),
    4: ("sequence", "Fig. 4. Sequence control structure with two reduced tasks"),
}


def clusters(lib: Library, name: str) -> dict[str, list[str]]:
    """What each slot brings in, its fusion places included: the primitive of
    a task, T1 and T2 of a structure."""
    t = lib.get(name)
    if t.primitives:
        prim = lib.primitive.net
        return {("primitive " + slot if slot else "primitive"):
                [f"{slot}_{n.id}" if slot else n.id for n in (*prim.places, *prim.transitions)]
                for slot in t.primitives}
    child = lib.reduced.net
    return {slot: [f"{slot}_{n.id}" for n in (*child.places, *child.transitions)]
            for slot in t.children}


def draw_all(lib: Library, out: Path) -> list[Path]:
    written = []
    for number, (name, title) in FIGURES.items():
        graph = to_dot(lib.composed(name), clusters=clusters(lib, name), title=title)
        for fmt in ("svg", "png"):
            path = out / f"fig{number}.{fmt}"
            render(graph, str(path), fmt)
            written.append(path)
    return written
