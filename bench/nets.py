"""Scalable compiled missions for the state-space benchmarks, beside the textbook
nets of :mod:`mcl2pnml.analysis.zoo` (which builds nets from the core alone, not from MCL).

* ``mission(width)``: a compiled MCL mission, ``width`` tasks in parallel,
  each on its own primitive (``examples``-style, from the compiler);
* ``dam(aborted)``: ``examples/dam_inspection.mcl`` compiled, from
  ``mission.B`` (``aborted=0``) or with an abort already pending as well
  (``aborted=1``: ``mission.A`` marked too, the abort racing every step).
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

from mcl2pnml.core.net import Marking, Net

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def mission(width: int) -> Net:
    from mcl2pnml.pipeline import compile_source

    lines = [f"primitive P{i}(x);" for i in range(width)]
    lines += [f"task T{i}(x) = AchieveGoal(P{i}(x)) timeout 10;" for i in range(width)]
    calls = ", ".join(f"T{i}({i})" for i in range(width))
    body = f"parallel({calls});" if width > 1 else "T0(0);"
    lines.append(f"mission {{ {body} }}")
    return compile_source("\n".join(lines), f"parallel-{width}.mcl")


def dam(aborted: int) -> Net:
    from mcl2pnml.pipeline import compile_file

    net = compile_file(EXAMPLES / "dam_inspection.mcl")
    if not aborted:
        return net
    return dataclasses.replace(net, initial=Marking({**net.initial, "mission.A": 1}))
