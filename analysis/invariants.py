"""Place and transition invariants, exactly (Murata 1989, section VII).

A P-invariant is an integer vector y with y^T C = 0: the weighted token
count y . M is the same in every reachable marking (the paper's equations 1-3
and 8-13). A T-invariant is x with C x = 0: firing each transition x_t times
returns to the same marking.

* :func:`p_invariant_basis`, :func:`t_invariant_basis`: an exact basis of the
  invariant space, from the nullspace of C^T (or C) computed over the
  rationals with sympy's *sparse* domain matrices (``DomainMatrix`` in SDM
  form), never a dense ``Matrix``: compiled missions have thousands of
  places and four or five arcs per transition. Each vector is scaled to
  coprime integers with its first nonzero coefficient positive.
* :func:`minimal_semipositive_p_invariants` and the T version: the
  invariants with nonnegative coefficients and minimal support, by the
  Farkas algorithm with the minimal-support pruning of Martinez and Silva
  (1982). These are the ones that prove boundedness and control siphons.
"""
from __future__ import annotations

from fractions import Fraction
from math import gcd
from typing import Mapping, Sequence

from sympy import QQ, ZZ
from sympy.polys.matrices import DomainMatrix

from mcl2pnml.errors import Mcl2PnmlError

from .matrix import Structure


class AnalysisLimit(Mcl2PnmlError):
    """An exponential analysis reached its bound before it finished."""


def _normalise(vec: Mapping[int, Fraction | int]) -> dict[int, int]:
    """Coprime integers, first nonzero (lowest index) positive, zeros left out."""
    items = sorted((k, Fraction(v)) for k, v in vec.items() if v)
    if not items:
        return {}
    lcm = 1
    for _, v in items:
        lcm = lcm * v.denominator // gcd(lcm, v.denominator)
    ints = [(k, int(v * lcm)) for k, v in items]
    g = 0
    for _, v in ints:
        g = gcd(g, v)
    sign = -1 if ints[0][1] < 0 else 1
    return {k: sign * v // g for k, v in ints}


def nullspace(rows: Sequence[Mapping[int, int]], ncols: int) -> list[dict[int, int]]:
    """An integer basis of {x : A x = 0} for a sparse A (a dict per row)."""
    data = {i: {j: ZZ(v) for j, v in row.items() if v} for i, row in enumerate(rows)}
    data = {i: r for i, r in data.items() if r}
    if not data:  # every vector is a solution
        return [{j: 1} for j in range(ncols)]
    a = DomainMatrix(data, (len(rows), ncols), ZZ).to_sparse().convert_to(QQ)
    basis = a.nullspace()
    out = []
    for i, row in basis.to_sdm().items():
        out.append(_normalise({j: Fraction(int(v.numerator), int(v.denominator))
                               for j, v in row.items()}))
    return sorted(out, key=lambda v: sorted(v))


def p_invariant_basis(s: Structure) -> list[dict[str, int]]:
    """A basis of the P-invariants, each as {place: coefficient}."""
    basis = nullspace(s.incidence, len(s.places))  # y^T C = 0  <=>  C^T y = 0
    return [{s.places[i]: c for i, c in v.items()} for v in basis]


def t_invariant_basis(s: Structure) -> list[dict[str, int]]:
    """A basis of the T-invariants, each as {transition: coefficient}."""
    basis = nullspace(s.incidence_rows, len(s.transitions))
    return [{s.transitions[j]: c for j, c in v.items()} for v in basis]


def format_invariant(y: Mapping[str, int], value: int | None = None) -> str:
    """``ON + OFF = 1``: an invariant as the paper writes it."""
    text = ""
    for p, c in y.items():
        mag = "" if abs(c) == 1 else f"{abs(c)} "
        text += (" - " if c < 0 else " + ") + mag + p
    text = text[3:] if text.startswith(" + ") else "-" + text[3:]
    return text if value is None else f"{text} = {value}"


def is_p_invariant(s: Structure, y: Mapping[str, int]) -> bool:
    idx = s.place_index
    if any(p not in idx for p in y):
        return False
    return all(sum(y.get(s.places[p], 0) * v for p, v in col.items()) == 0
               for col in s.incidence)


def invariant_value(y: Mapping[str, int], marking: Mapping[str, int]) -> int:
    """y . M: the constant the invariant keeps."""
    return sum(c * marking.get(p, 0) for p, c in y.items())


# ---------------------------------------------------------------------------
# Farkas / Martinez-Silva


def _farkas(columns_of: Sequence[Mapping[int, int]], n: int, ncols: int,
            limit: int | None) -> list[dict[int, int]]:
    """Minimal-support semi-positive solutions y >= 0 of y^T A = 0.

    ``columns_of[i]`` is row i of A as {column: value}; each working row is
    (the remaining combination of A's row, the identity part y). Columns are
    eliminated one at a time, cheapest first (fewest positive x negative
    pairs); a new row is kept only if its support (the places of y) contains
    no other row's support: Martinez and Silva's rule, which keeps exactly
    the minimal supports and stops the rows from multiplying needlessly.
    """
    rows: list[tuple[dict[int, int], dict[int, int]]] = [
        (dict(columns_of[i]), {i: 1}) for i in range(n)]
    remaining = set(range(ncols))
    while remaining:
        def cost(j):
            pos = sum(1 for a, _ in rows if a.get(j, 0) > 0)
            neg = sum(1 for a, _ in rows if a.get(j, 0) < 0)
            return pos * neg, j
        j = min(remaining, key=cost)
        remaining.discard(j)
        keep = [r for r in rows if not r[0].get(j)]
        pos = [r for r in rows if r[0].get(j, 0) > 0]
        neg = [r for r in rows if r[0].get(j, 0) < 0]
        supports = [frozenset(y) for _, y in keep]
        new: list[tuple[dict[int, int], dict[int, int]]] = []
        for a1, y1 in pos:
            for a2, y2 in neg:
                support = frozenset(y1) | frozenset(y2)
                if any(s <= support for s in supports):
                    continue
                f1, f2 = -a2[j], a1[j]
                a = {k: f1 * a1.get(k, 0) + f2 * a2.get(k, 0) for k in set(a1) | set(a2)}
                y = {k: f1 * y1.get(k, 0) + f2 * y2.get(k, 0) for k in support}
                a = {k: v for k, v in a.items() if v}
                g = 0
                for v in (*a.values(), *y.values()):
                    g = gcd(g, v)
                new.append(({k: v // g for k, v in a.items()}, {k: v // g for k, v in y.items()}))
        # among the new rows, drop those whose support contains another's
        new.sort(key=lambda r: len(r[1]))
        for a, y in new:
            support = frozenset(y)
            if not any(s <= support for s in supports):
                keep.append((a, y))
                supports.append(support)
        rows = keep
        if limit is not None and len(rows) > limit:
            raise AnalysisLimit(f"more than {limit:,} intermediate rows in the Farkas algorithm")
    results = {frozenset(y): y for a, y in rows if not a and y}
    minimal = [y for sup, y in results.items()
               if not any(other < sup for other in results)]
    return sorted(minimal, key=lambda y: (len(y), sorted(y)))


def minimal_semipositive_p_invariants(s: Structure, limit: int | None = None
                                      ) -> list[dict[str, int]]:
    """Minimal-support P-invariants with nonnegative coefficients."""
    found = _farkas(s.incidence_rows, len(s.places), len(s.transitions), limit)
    return [{s.places[i]: c for i, c in sorted(y.items())} for y in found]


def minimal_semipositive_t_invariants(s: Structure, limit: int | None = None
                                      ) -> list[dict[str, int]]:
    """Minimal-support T-invariants with nonnegative coefficients."""
    found = _farkas(s.incidence, len(s.transitions), len(s.places), limit)
    return [{s.transitions[j]: c for j, c in sorted(y.items())} for y in found]
