"""Scalable compiled missions for the state-space benchmarks, beside the textbook
nets of :mod:`analysis.zoo` (which builds nets from the core alone, not from MCL).

* ``mission(width)``: a compiled MCL mission, ``width`` tasks in parallel,
  each on its own primitive (``examples``-style, from the compiler).
"""
from __future__ import annotations

from mcl2pnml.core.net import Net


def mission(width: int) -> Net:
    from mcl2pnml.pipeline import compile_source

    lines = [f"primitive P{i}(x);" for i in range(width)]
    lines += [f"task T{i}(x) = AchieveGoal(P{i}(x)) timeout 10;" for i in range(width)]
    calls = ", ".join(f"T{i}({i})" for i in range(width))
    body = f"parallel({calls});" if width > 1 else "T0(0);"
    lines.append(f"mission {{ {body} }}")
    return compile_source("\n".join(lines), f"parallel-{width}.mcl")
