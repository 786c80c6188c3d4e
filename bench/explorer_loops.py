"""The exploration loops' two backends on the same nets: C and the plain-Python reference.

Run:  .venv/bin/python -m bench.explorer_loops

Each backend of :class:`~mcl2pnml.analysis.statespace.loops.interface.Loops`
explores the same zoo nets with the explorers built on the loops: the
native one (a safe net's packed markings) and the counter one (a bounded
net's counters), in one process, the two backends in turn, and then answers
what ``analyze --state-space`` asks (terminal markings, whether the initial
marking stays reachable). The Python reference serves where C was not
built; this says what that costs. Each figure is the median of :data:`RUNS`
runs.
"""
from __future__ import annotations

import json
import statistics
import time

from mcl2pnml.core.structure import structure

from mcl2pnml.analysis import zoo
from mcl2pnml.analysis.statespace.explorers import EXPLORERS
from mcl2pnml.analysis.statespace.loops import backends

RUNS = 5

#: (family, size, explorer): nets small enough for the Python loops.
CASES = (("cycles", 5, "native"), ("philosophers", 8, "native"),
         ("shared memory", 6, "native"), ("kanban", 1, "counters"))

_NETS = {"cycles": zoo.cycles, "philosophers": zoo.philosophers_left_first,
         "shared memory": zoo.shared_memory, "kanban": zoo.kanban}


def _once(explorer: str, s, loops) -> tuple[int, float, float]:
    """Markings, seconds exploring, seconds answering (terminal markings, reachability)."""
    t0 = time.perf_counter()
    space = EXPLORERS[explorer].explore(s, s.initial_vector(), 10_000_000, RuntimeError("limit"),
                                        loops=loops)
    t1 = time.perf_counter()
    space.terminal
    space.can_reach([0])
    return space.states, t1 - t0, time.perf_counter() - t1


def run(cases=CASES, log=print) -> list[dict]:
    """Every case on every backend that runs here."""
    rows = []
    names = [n for n in ("c", "python") if backends.named(n) is not None]
    for family, size, explorer in cases:
        s = structure(_NETS[family](size))
        times: dict[str, list[tuple[float, float]]] = {n: [] for n in names}
        for _ in range(RUNS):
            for name in names:   # in turn, so that the machine's drift falls on both
                states, explored, answered = _once(explorer, s, backends.named(name))
                times[name].append((explored, answered))
        row = {"net": f"{family} {size}", "explorer": explorer, "states": states}
        for name, t in times.items():
            row[name] = {"explore": statistics.median(e for e, _ in t),
                         "answer": statistics.median(a for _, a in t)}
        log(json.dumps(row))
        rows.append(row)
    return rows


def section(rows: list[dict]) -> list[str]:
    """The Markdown section of bench/RESULTS.md."""
    lines = ["## The exploration loops: C and the plain-Python reference", "",
             "The loops' two backends (`analysis/statespace/loops/`) on the same nets, in one "
             "process, in turn: seconds to explore with the explorer built on them, and to "
             "answer what `analyze --state-space` adds (terminal markings, reachability of "
             "the initial marking); medians of "
             f"{RUNS} runs. The Python reference serves where C was not built.", "",
             "| net | explorer | states | C explore (s) | C answer (s) | Python explore (s) "
             "| Python answer (s) | Python / C |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        c, py = r.get("c"), r.get("python")
        cells = [r["net"], r["explorer"], f"{r['states']:,}"]
        cells += [f"{c['explore']:.4f}", f"{c['answer']:.4f}"] if c else ["-", "-"]
        cells += [f"{py['explore']:.3f}", f"{py['answer']:.3f}"]
        cells.append(f"{(py['explore'] + py['answer']) / (c['explore'] + c['answer']):,.0f}x"
                     if c else "-")
        lines.append("| " + " | ".join(cells) + " |")
    return lines


if __name__ == "__main__":
    print("\n".join(section(run())))
