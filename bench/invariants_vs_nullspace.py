"""The exact P-invariant basis against plain sympy, on mission-shaped nets.

Run:  .venv/bin/python -m bench.invariants_vs_nullspace [SIZES...]

The nets are shaped like compiled missions: chains of task nets (the
AchieveGoal pattern with its primitive, Fig. 2 of the paper, about four arcs
per transition), each task's OK fused with the next one's B, and one mutex
MTX for the whole chain. The default sizes are 100, 300, 1,000 and 5,000
places.

* ours: ``mcl2pnml.analysis.structure.invariants.p_invariant_basis`` (an exact elimination
  on the sparse rows), the median of three runs;
* plain: ``sympy.Matrix(dense C).T.nullspace()``, one run (building the
  dense matrix not counted), in a child process stopped after 60 s; once it
  has not finished in time the larger sizes skip it.

Both must find the same space. Ours is checked on its own at every size:
every vector satisfies y^T C = 0 (exactly, on the sparse columns); the
vectors are independent (their first places differ: each comes from another
free column of the echelon form); and there are |P| - rank(C) of them, rank
certified by the rank of C modulo a prime (python-flint's ``nmod_mat``),
which is at most the rank over QQ: together with the independent
invariants found, equality is exact. Where plain sympy finishes, its
dimension must be ours too.
"""
from __future__ import annotations

import multiprocessing as mp
import statistics
import sys
import time

import flint
import sympy

from mcl2pnml.analysis.structure.invariants import p_invariant_basis
from mcl2pnml.core.compose import fuse, union
from mcl2pnml.core.net import Net
from mcl2pnml.core.structure import Structure, structure
from mcl2pnml.language.library import default_library

PLAIN_LIMIT = 60.0        # seconds for one run of plain sympy
PRIME = 2**61 - 1         # for the rank certificate
RATIO_AT = 300            # the size whose ratio the summary line quotes


def mission_like(places: int) -> Net:
    """A chain of task nets with about ``places`` places."""
    task = default_library().composed("AchieveGoal")
    per_task = len(task.places) - 2  # B and MTX are shared with the others
    k = max(1, round((places - 2) / per_task))
    net = union({f"task{i}": task for i in range(k)}, name=f"chain of {k} tasks")
    # only the first task starts; the others wait for their predecessor's OK
    net = net.with_initial({p: n for p, n in net.initial.items()
                            if not p.endswith(".B") or p == "task0.B"})
    groups = [[f"task{i}.OK", f"task{i + 1}.B"] for i in range(k - 1)]
    groups.append([f"task{i}.MTX" for i in range(k)])
    return fuse(net, groups)


def median_time(fn, runs: int = 3):
    times, result = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def _plain(s: Structure, conn) -> None:
    """In a child: builds the dense matrix, says so, then sends (seconds,
    dimension) of plain sympy's nullspace of C^T."""
    c = sympy.Matrix(s.dense_incidence())
    conn.send("built")
    t0 = time.perf_counter()
    space = c.T.nullspace()
    conn.send((time.perf_counter() - t0, len(space)))


def plain_nullspace(s: Structure) -> tuple[float, int] | None:
    """(seconds, dimension) of plain sympy, or None if it needed more than the limit.

    A child process, so that it can be stopped; the limit counts from when
    the dense matrix is built (that part is not what is compared).
    """
    receive, send = mp.Pipe(duplex=False)
    child = mp.Process(target=_plain, args=(s, send))
    child.start()
    receive.recv()  # the dense matrix is built
    ready = receive.poll(PLAIN_LIMIT)
    result = receive.recv() if ready else None
    if not ready:
        child.terminate()
    child.join()
    return result


def certified(s: Structure, basis: list[dict[str, int]]) -> bool:
    """y^T C = 0 for each vector, independent, and |P| - rank(C) of them."""
    idx = s.place_index
    vectors = [{idx[p]: c for p, c in y.items()} for y in basis]
    for y in vectors:  # y^T C, from the rows of C on the support of y
        total: dict[int, int] = {}
        for p, c in y.items():
            for j, v in s.incidence_rows[p].items():
                total[j] = total.get(j, 0) + c * v
        if any(total.values()):
            return False
    if len({min(y) for y in vectors}) != len(vectors):
        return False
    c = flint.nmod_mat(len(s.transitions), len(s.places), PRIME)
    for j, col in enumerate(s.incidence):
        for p, v in col.items():
            c[j, p] = v % PRIME
    return len(basis) == len(s.places) - c.rank()


def main(argv: list[str]) -> None:
    sizes = [int(a) for a in argv] or [100, 300, 1000, 5000]
    print("| places | transitions | arcs per transition | P-invariants | ours (s) "
          "| plain sympy (s) | plain / ours | checked |")
    print("|---:|---:|---:|---:|---:|---:|---:|:---|")
    plain_ok, ratios, skipped = True, {}, []
    for size in sizes:
        net = mission_like(size)
        s = structure(net)
        ours, basis = median_time(lambda: p_invariant_basis(s))
        check = "y^T C = 0, dimension = places - rank" if certified(s, basis) else "FAILED"
        plain_cell, ratio_cell = "skipped", "-"
        if plain_ok:
            plain = plain_nullspace(s)
            if plain is None:
                plain_ok = False
                plain_cell = f"> {PLAIN_LIMIT:.0f} (stopped)"
            else:
                seconds, dim = plain
                if dim != len(basis):
                    check = f"FAILED: plain sympy finds {dim} dimensions"
                plain_cell = f"{seconds:.2f}"
                ratios[size] = seconds / ours
                ratio_cell = f"{ratios[size]:,.0f}x"
        else:
            skipped.append(size)
        print(f"| {len(s.places):,} | {len(s.transitions):,} | "
              f"{len(net.arcs) / len(s.transitions):.2f} | {len(basis):,} | {ours:.3f} | "
              f"{plain_cell} | {ratio_cell} | {check} |")
    print()
    if RATIO_AT in ratios:
        print(f"At about {RATIO_AT} places the sparse basis is {ratios[RATIO_AT]:,.0f} times "
              "faster than plain sympy.")
    if skipped:
        print(f"Plain sympy skipped at {', '.join(map(str, skipped))} places: it did not "
              f"finish a smaller net within {PLAIN_LIMIT:.0f} s.")


if __name__ == "__main__":
    main(sys.argv[1:])
