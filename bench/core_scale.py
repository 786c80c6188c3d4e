"""How the net core scales: build, fuse, write and read PNML of ring nets (:func:`mcl2pnml.analysis.zoo.cycle`).

Run:  .venv/bin/python -m bench.core_scale [SIZES...]

Each size is the total number of places plus transitions. Prints the median
of three runs per step and the exponent of a least-squares fit of
log(time) against log(size): about 1 means linear, 2 quadratic.
"""
from __future__ import annotations

import math
import statistics
import sys
import time

from mcl2pnml.analysis.zoo import cycle
from mcl2pnml import compose, parse_pnml, to_pnml_bytes


def measure(size: int) -> dict[str, float]:
    n = size // 4  # two rings of n places and n transitions
    out: dict[str, list[float]] = {"build": [], "fuse": [], "write": [], "read": []}
    for _ in range(3):
        t0 = time.perf_counter()
        a, b = cycle(n, "a"), cycle(n, "b")
        t1 = time.perf_counter()
        net = compose({"a": a, "b": b}, [["a.p0", "b.p0"]])
        t2 = time.perf_counter()
        data = to_pnml_bytes(net)
        t3 = time.perf_counter()
        parse_pnml(data)
        t4 = time.perf_counter()
        for k, v in zip(out, (t1 - t0, t2 - t1, t3 - t2, t4 - t3)):
            out[k].append(v)
    return {k: statistics.median(v) for k, v in out.items()}


def slope(xs, ys) -> float:
    lx, ly = [math.log(x) for x in xs], [math.log(y) for y in ys]
    mx, my = statistics.mean(lx), statistics.mean(ly)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)


def main(argv: list[str]) -> None:
    sizes = [int(a) for a in argv] or [10_000, 30_000, 100_000]
    rows = {s: measure(s) for s in sizes}
    steps = list(next(iter(rows.values())))
    print("| nodes | " + " | ".join(f"{s} (s)" for s in steps) + " |")
    print("|---:|" + "---:|" * len(steps))
    for s, r in rows.items():
        print(f"| {s:,} | " + " | ".join(f"{r[k]:.2f}" for k in steps) + " |")
    if len(sizes) > 1:
        print("| exponent | " + " | ".join(f"{slope(sizes, [rows[s][k] for s in sizes]):.2f}"
                                         for k in steps) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
