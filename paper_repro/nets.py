"""Nets the paper's argument needs beyond the templates themselves.

* :func:`literal_task`: the task exactly as the paper's text describes it,
  where the time-out and the abort do not wait for the primitive to be on
  (our template's t03 and t07 without their read arc on ON);
* :func:`called_again`: a task whose caller starts it again as soon as it
  ends, and aborts it once at any moment: the composition that shows
  whether the mutex MTX can be freed while the primitive still has an enable
  (E) or disable (D) request pending, which would put a second token in E.
"""
from __future__ import annotations

from mcl2pnml.core.compose import glue
from mcl2pnml.core.net import ArcKind, Net, NetBuilder
from mcl2pnml.language.library import Library

#: The transitions of the task template that read ON; the paper's text has none.
WAIT_FOR_ON = ("t03", "t07")


def literal_task(lib: Library) -> Net:
    net = lib.composed("task")
    arcs = tuple(a for a in net.arcs
                 if not (a.kind is ArcKind.READ and a.source == "ON" and a.target in WAIT_FOR_ON))
    return Net("task-as-in-the-paper", net.places, net.transitions, arcs, net.initial)


def caller() -> Net:
    """Starts the task again whenever it ends, and aborts it once, at any time."""
    b = NetBuilder("caller")
    for p in ("B", "A", "OK", "FAIL", "ABORTED"):
        b.place(p, interface=p)
    b.place("ABORT_ONCE", 1)
    for result in ("OK", "FAIL", "ABORTED"):
        t = b.transition(f"again_after_{result}")
        b.arc(result, t)
        b.arc(t, "B")
    b.transition("abort")
    b.arc("ABORT_ONCE", "abort")
    b.arc("abort", "A")
    return b.build()


def called_again(task: Net) -> Net:
    """``task`` (from its M0 without A) glued with :func:`caller`."""
    start = task.with_initial({p: n for p, n in task.initial.items() if p != "A"})
    return glue([start, caller()], name=f"{task.name}-called-again")


def mutex_free_while_pending(space) -> list[int]:
    """Nodes where MTX is marked while E or D still holds a request."""
    idx = space.structure.place_index
    mtx, e, d = idx["MTX"], idx["E"], idx["D"]
    return [n for n, m in enumerate(space.markings) if m[mtx] and (m[e] or m[d])]
