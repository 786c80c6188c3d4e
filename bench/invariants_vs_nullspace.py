"""The exact P-invariant basis against plain sympy, on mission-shaped nets.

Run:  .venv/bin/python -m bench.invariants_vs_nullspace [SIZES...]

The nets are chains of sequence structures with reduced tasks (the shape of
a compiled mission: a few arcs per transition). Ours is
``analysis.invariants.p_invariant_basis`` (sparse domain matrices over QQ);
the peer is ``sympy.Matrix(C).T.nullspace()`` on the dense incidence matrix,
run only where it finishes within the time limit. Both must find a space of
the same dimension.
"""
from __future__ import annotations

import statistics
import sys
import time

import sympy

from analysis.invariants import p_invariant_basis
from analysis.matrix import structure
from mcl2pnml.compose import fuse, union
from mcl2pnml.template_library import default_library

PLAIN_LIMIT = 60.0  # seconds: plain sympy is skipped on larger nets after one this slow


def mission_like(places: int):
    seq = default_library().composed("sequence")
    k = max(1, round(places / len(seq.places)))
    net = union({f"s{i}": seq for i in range(k)})
    return fuse(net, [[f"s{i}.T2_OK", f"s{i + 1}.B"] for i in range(k - 1)])


def timed(fn, runs: int = 3):
    times, result = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def main(argv: list[str]) -> None:
    sizes = [int(a) for a in argv] or [100, 300, 1000, 5000]
    print("| places | ours (s) | plain Matrix.nullspace (s) | ratio | dimension |")
    print("|---:|---:|---:|---:|---:|")
    plain_ok = True
    for size in sizes:
        s = structure(mission_like(size))
        ours, basis = timed(lambda: p_invariant_basis(s))
        plain, ratio, dim = None, None, len(basis)
        if plain_ok:
            dense = sympy.Matrix(s.dense_incidence())
            plain, space = timed(lambda: dense.T.nullspace(), runs=1)
            assert len(space) == dim, "the two disagree on the dimension"
            ratio = plain / ours
            plain_ok = plain < PLAIN_LIMIT / 10
        print(f"| {len(s.places):,} | {ours:.3f} | "
              + (f"{plain:.2f} | {ratio:,.0f}x" if plain is not None else "skipped | -")
              + f" | {dim} |")


if __name__ == "__main__":
    main(sys.argv[1:])
