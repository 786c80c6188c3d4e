"""Place and transition invariants, exactly (Murata 1989).

A *P-invariant* is an integer vector y with y^T C = 0, C the incidence matrix:
the weighted token count y . M is then the same in every reachable marking
(the paper's equations 1-3 and 8-13). A *T-invariant* is an x with C x = 0:
firing each transition x_t times leads back to the marking it started from.
Read arcs add nothing to C (they are self-loops), so they change no
invariant.

* :func:`p_invariant_basis`, :func:`t_invariant_basis`: an exact basis of the
  invariant space, the nullspace of C^T (or C) over the rationals, by an
  exact elimination on the sparse rows, integers kept whole: compiled
  missions have thousands of places and about four arcs per transition, and
  the elimination stays sparse on them (``python -m
  bench.invariants_vs_nullspace`` measures it). A matrix that fills in goes
  to FLINT's dense elimination, in C. sympy's sparse one would do the same,
  but takes a third of a second to import, a hundred times an example's two bases.
* :func:`minimal_semipositive_p_invariants` and the T version: the
  invariants with nonnegative coefficients and minimal support, by the
  Farkas algorithm with the minimal-support pruning of Martinez and Silva
  (1982). These are the ones that prove boundedness and control siphons;
  their number can grow exponentially, hence ``limit`` and
  :class:`AnalysisLimit`.
"""
from __future__ import annotations

import heapq
import time
from fractions import Fraction
from math import gcd, lcm
from typing import Mapping, Sequence

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.structure import Structure


class AnalysisLimit(Mcl2PnmlError):
    """An exponential analysis reached its bound before it finished."""


#: The largest net (in places) whose semi-positive P-invariants a search looks for to
#: bound it (the explorers' widths and walks, the contest's questions); past it, it does
#: without: Farkas can need exponentially many rows.
INVARIANT_PLACES = 2_000
#: The intermediate rows Farkas may hold when a search looks for those bounds (its
#: ``limit``); past it, the search does without them.
INVARIANT_ROWS = 20_000


def integer_multiple(vec: Mapping[int, object]) -> dict[int, int]:
    """The positive multiple of a rational vector with coprime integer entries.

    ``vec`` maps indices to rationals (ints, ``Fraction`` or sympy's ``QQ``
    elements); zero entries are left out. Signs are kept, so a vector that
    must stay positive on some places (a siphon's control) still does.
    """
    from sympy import QQ   # sympy takes most of a second to import: only when needed
    items = [(k, QQ.convert(v)) for k, v in vec.items() if v]
    scale = lcm(*(int(QQ.denom(v)) for _, v in items))
    ints = {k: int(QQ.numer(v)) * (scale // int(QQ.denom(v))) for k, v in items}
    g = gcd(*ints.values())
    return {k: v // g for k, v in ints.items()}


def _nullspace(rows: Sequence[Mapping[int, int]], ncols: int) -> list[dict[int, int]]:
    """A basis of {x : A x = 0} for a sparse integer A (row i of A = ``rows[i]``).

    Gauss-Jordan elimination on the sparse rows (:func:`_reduced_rows`), with the columns
    taken last first. The reduced row echelon form A' is unique, so the basis is too: one
    vector per free (non-pivot) column f, with x_f = 1, 0 at the other free columns, and
    -A'[r][f] at each pivot row r's pivot column, scaled to coprime integers. A row's
    pivot is its last column, so f is the vector's first nonzero entry, which no other
    vector has: the vectors are independent at a glance. They come in the order of those
    columns.

    Why last first: places are numbered as the nets were composed, so a
    compiled mission's first places are its outermost structure, through
    which every token passes. Eliminated first, they enter nearly every
    vector; eliminated last, they are the free columns, and each vector
    stays within a few neighbouring places. On a 275-call survey (4,982
    places) the basis has 4% of the nonzeros and comes fifty times faster;
    on the paper's task it reads like the paper's own equations
    (``MTX + EXE + E_OK + E_FAIL + W_OK + W_FAIL + W_A``).

    Where the elimination writes more than :data:`FILL_IN` times the dense matrix's entries
    (a dense or random net, whose rows no longer stay sparse), FLINT's dense elimination
    reads the same unique form (:func:`_nullspace_dense`).
    """
    dense = len(rows) * ncols
    budget = max(int(FILL_IN * dense), SMALL_WORK) if dense <= DENSE_ENTRIES else None
    reduced = _reduced_rows(rows, budget)
    if reduced is None:
        return _nullspace_dense(rows, ncols)
    pivots, holders = reduced
    vectors = []
    for f in sorted(set(range(ncols)) - pivots.keys()):
        vec = {f: 1, **{c: -pivots[c][f] for c in holders.get(f, ())}}
        # whole already where the pivots were 1 or -1, as a net's arcs mostly make them
        fractions = [q.denominator for q in vec.values() if type(q) is Fraction]
        if fractions:
            scale = lcm(*fractions)
            vec = {j: int(q * scale) for j, q in vec.items()}
        vectors.append(_coprime(vec))
    return vectors


def _coprime(vec: dict[int, int]) -> dict[int, int]:
    """A basis vector as the output gives it: coprime integers, its first (lowest) index
    positive, the indices in order. A basis vector's sign is arbitrary; fixing it makes
    the basis one function of the net, whatever the elimination did."""
    g = gcd(*vec.values())
    if vec[min(vec)] < 0:
        g = -g
    return {j: vec[j] // g for j in sorted(vec)}


#: What share of the dense matrix's entries the sparse elimination may write before FLINT's
#: dense one takes over. Measured on the examples and the contest's nets (rows ordered as
#: :func:`_reduced_rows` orders them): at most 0.17 on a matrix past :data:`SMALL_WORK`
#: entries, where a random one with a fifth of its entries nonzero writes twenty to eighty
#: times its size, in growing fractions.
FILL_IN = 0.5
#: Writes any matrix may take, however small: a few milliseconds, less than FLINT's import.
SMALL_WORK = 10_000
#: The largest matrix (rows times columns) FLINT may take dense: its elimination grows as
#: the cube, its memory as the square. Past it, the sparse elimination runs to the end
#: (under the budget's guard).
DENSE_ENTRIES = 1_000_000


def _reduced_rows(rows: Sequence[Mapping[int, int]], budget: int | None
                  ) -> tuple[dict[int, dict[int, Rational]], dict[int, set[int]]] | None:
    """The reduced row echelon form of A, columns last first: {pivot column: its row}, each
    row 1 at its pivot and zero at every other pivot column; and {column: the pivot
    columns whose rows hold it}. None once the entries written pass ``budget``.

    Row by row, the shorter first (after Markowitz: the pivots that fill in least): a row is
    reduced by the pivot rows it meets (each holds no other pivot column, so one pass
    clears them all), its last column becomes a pivot, and that column is cleared from
    the pivot rows holding it. Every update is in place and touches only the pivot row's
    nonzeros, so a long row (a place every transition uses) is not copied once per pivot;
    entries stay Python integers while the pivots are 1 or -1, as a net's arcs mostly are.
    """
    pivots: dict[int, dict[int, Rational]] = {}
    holders: dict[int, set[int]] = {}       # column -> the pivot columns whose rows hold it
    written = 0
    for given in sorted(rows, key=len):
        row: dict[int, Rational] = {j: v for j, v in given.items() if v}
        for c in [c for c in row if c in pivots]:
            written += _subtract(row, row[c], pivots[c])
        if not row:
            continue
        c = max(row)
        scale = row[c]
        if scale != 1:
            row = {j: _divided(v, scale) for j, v in row.items()}
        for k in holders.pop(c, ()):
            old = pivots[k]
            before = old.keys() - {c}
            written += _subtract(old, old[c], row)
            for j in before - old.keys():
                holders[j].discard(k)
            for j in old.keys() - before - {k}:
                holders.setdefault(j, set()).add(k)
        pivots[c] = row
        for j in row:
            if j != c:
                holders.setdefault(j, set()).add(c)
        if budget is not None and written > budget:
            return None
    return pivots, holders


#: An entry of the elimination: an int, or a Fraction once a pivot other than 1 or -1
#: divides.
Rational = int | Fraction


def _subtract(row: dict[int, Rational], factor: Rational, pivot_row: dict[int, Rational]) -> int:
    """row -= factor * pivot_row, in place, zeros dropped; how many entries it wrote."""
    for j, v in pivot_row.items():
        w = row.get(j, 0) - factor * v
        if w:
            row[j] = w
        else:
            del row[j]
    return len(pivot_row)


def _divided(v: Rational, d: Rational) -> Rational:
    if d == -1:
        return -v
    q = Fraction(v) / d
    return q.numerator if q.denominator == 1 else q


def _nullspace_dense(rows: Sequence[Mapping[int, int]], ncols: int) -> list[dict[int, int]]:
    """:func:`_nullspace` by FLINT's exact elimination (python-flint's ``fmpz_mat``). Its
    nullspace is read off the same unique RREF, columns taken last first: a non-pivot
    column's vector is the denominator there and minus the pivot rows' entries, so
    made coprime with its first entry positive, the basis is the sparse elimination's,
    vector for vector."""
    from flint import fmpz_mat   # python-flint, 20 ms to import: only for a dense net
    last = ncols - 1
    a = fmpz_mat(max(1, len(rows)), ncols)
    for i, row in enumerate(rows):
        for j, v in row.items():
            if v:
                a[i, last - j] = v
    basis, nullity = a.nullspace()
    vectors = [_coprime({last - j: int(basis[j, k]) for j in range(ncols) if basis[j, k] != 0})
               for k in range(nullity)]
    return sorted(vectors, key=min)


def p_invariant_basis(s: Structure) -> list[dict[str, int]]:
    """A basis of the P-invariants {y : y^T C = 0} (Murata 1989).

    Exact, over the rationals, by sparse elimination (:func:`_nullspace`):
    the dimension is |P| - rank(C). Each vector is {place: coefficient} with
    zero coefficients left out, coprime integers, the first nonzero one in
    place order positive; each vector's first place is in no other vector,
    and the vectors come in the order of those places (see
    :func:`_nullspace`), so the basis is a function of the net and its place
    order alone.
    """
    # y^T C = 0  <=>  C^T y = 0: the rows of C^T are the columns of C
    basis = _nullspace(s.incidence, len(s.places))
    return [{s.places[i]: c for i, c in v.items()} for v in basis]


def t_invariant_basis(s: Structure) -> list[dict[str, int]]:
    """A basis of the T-invariants {x : C x = 0} (Murata 1989).

    The same construction as :func:`p_invariant_basis`, on C itself;
    {transition: coefficient}, dimension |T| - rank(C).
    """
    basis = _nullspace(s.incidence_rows, len(s.transitions))
    return [{s.transitions[j]: c for j, c in v.items()} for v in basis]


def is_p_invariant(s: Structure, y: Mapping[str, int]) -> bool:
    """Whether ``y`` ({place: coefficient}) is a P-invariant: nonzero, y^T C = 0.

    Checked column by column on the sparse incidence matrix (Murata 1989).
    A name that is not a place of the net makes it False.
    """
    idx = s.place_index
    if any(p not in idx for p in y) or not any(y.values()):
        return False
    vec = {idx[p]: c for p, c in y.items()}
    return all(sum(vec.get(p, 0) * v for p, v in col.items()) == 0 for col in s.incidence)


def invariant_value(s: Structure, y: Mapping[str, int], marking: Mapping[str, int]) -> int:
    """y . M: the token count a P-invariant keeps constant (Murata 1989).

    ``marking`` maps place names to tokens (a :class:`~mcl2pnml.core.net.Marking`,
    or ``s.net.initial`` for M0); places it leaves out hold no token.
    """
    unknown = sorted(p for p in y if p not in s.place_index)
    if unknown:
        raise Mcl2PnmlError(f"not places of net '{s.net.name}': {', '.join(unknown)}")
    return sum(c * marking.get(p, 0) for p, c in y.items())


def format_invariant(y: Mapping[str, int], value: int | None = None) -> str:
    """``ON + OFF = 1``: an invariant as the paper writes it."""
    terms = []
    for p, c in y.items():
        mag = "" if abs(c) == 1 else f"{abs(c)} "
        terms.append(("-" if c < 0 else "+", mag + p))
    if not terms:
        text = "0"
    else:
        text = ("-" if terms[0][0] == "-" else "") + terms[0][1]
        text += "".join(f" {sign} {term}" for sign, term in terms[1:])
    return text if value is None else f"{text} = {value}"


# ---------------------------------------------------------------------------
# Farkas, with Martinez and Silva's minimal-support pruning


class _FarkasRows:
    """The working rows of :func:`_farkas` and, per column, the rows nonzero there and
    their signs, so that the cheapest column is found from a heap, not by a scan.

    A row is (A part, y, the support of y as a bit mask, so that a subset test is two
    integer operations)."""

    def __init__(self, ncols: int, limit: int | None, what: str):
        self.rows: dict[int, tuple[dict[int, int], dict[int, int], int]] = {}
        self.users: list[set[int]] = [set() for _ in range(ncols)]  # column -> rows nonzero
        self.positive, self.negative = [0] * ncols, [0] * ncols
        self.remaining = set(range(ncols))
        self.heap = [(0, j) for j in range(ncols)]  # (positive x negative, column), lazily
        self.next_id = 0
        self.limit, self.what = limit, what
        self.deadline: float | None = None

    def index(self, rid: int, a: Mapping[int, int], step: int) -> None:
        for k, v in a.items():
            if v > 0:
                self.positive[k] += step
            else:
                self.negative[k] += step
            (self.users[k].add if step > 0 else self.users[k].discard)(rid)
            if k in self.remaining:
                heapq.heappush(self.heap, (self.positive[k] * self.negative[k], k))

    def add(self, a: dict[int, int], y: dict[int, int], mask: int) -> None:
        self.rows[self.next_id] = (a, y, mask)
        self.index(self.next_id, a, 1)
        self.next_id += 1

    def remove(self, rid: int) -> tuple[dict[int, int], dict[int, int], int]:
        row = self.rows.pop(rid)
        self.index(rid, row[0], -1)
        return row

    def over_limit(self, size: int) -> None:
        if self.deadline is not None and time.monotonic() > self.deadline:
            raise AnalysisLimit(f"past its time computing the minimal semi-positive "
                                f"{self.what} (Farkas algorithm)")
        if self.limit is not None and size > self.limit:
            raise AnalysisLimit(f"more than {self.limit:,} intermediate rows computing the "
                                f"minimal semi-positive {self.what} (Farkas algorithm)")

    def cheapest(self) -> int | None:
        """The column to eliminate next (fewest new rows), taken out of those remaining;
        None when every column is done."""
        while self.remaining:
            cost, j = heapq.heappop(self.heap)
            if j not in self.remaining or cost != self.positive[j] * self.negative[j]:
                continue  # a stale entry: the column's counts changed since
            self.remaining.discard(j)
            return j
        return None

    def eliminate(self, j: int) -> None:
        """Column ``j`` cancelled: every positive row combined with every negative one,
        the new rows that are not minimal (Martinez and Silva's rule) dropped."""
        rows = self.rows
        pos = [self.remove(r) for r in sorted(self.users[j]) if rows[r][0][j] > 0]
        neg = [self.remove(r) for r in sorted(self.users[j])]  # what is left is negative
        # only the rows that stay with a support inside the places of pos and
        # neg can be inside a new row's support; small first: they rule out most
        zone = 0
        for _, _, m in (*pos, *neg):
            zone |= m
        supports = sorted((m for _, _, m in rows.values() if m | zone == zone),
                          key=int.bit_count)
        new: list[tuple[int, dict[int, int], dict[int, int]]] = []
        for a1, y1, m1 in pos:
            self.over_limit(len(rows) + len(new))   # a time bound is looked at here too
            for a2, y2, m2 in neg:
                union = m1 | m2
                if any(m & union == m for m in supports):
                    continue  # contains a row that stays: not minimal
                f1, f2 = -a2[j], a1[j]
                a = {k: f1 * a1.get(k, 0) + f2 * a2.get(k, 0) for k in a1.keys() | a2.keys()}
                a = {k: v for k, v in a.items() if v}
                y = {k: f1 * y1.get(k, 0) + f2 * y2.get(k, 0) for k in y1.keys() | y2.keys()}
                g = gcd(*a.values(), *y.values())
                new.append((union, {k: v // g for k, v in a.items()},
                            {k: v // g for k, v in y.items()}))
                self.over_limit(len(rows) + len(new))
        new.sort(key=lambda r: r[0].bit_count())  # stable: the pair order breaks ties
        for union, a, y in new:
            if not any(m & union == m for m in supports):
                self.add(a, y, union)
                supports.append(union)


def _farkas(a_rows: Sequence[Mapping[int, int]], ncols: int, limit: int | None,
            what: str, seconds: float | None = None) -> list[dict[int, int]]:
    """The minimal-support semi-positive solutions y >= 0 of y^T A = 0.

    Row i of A is ``a_rows[i]`` ({column: value}). The working rows are those
    of [A | I]: (what is left of a combination of A's rows, the combination
    y). Columns are eliminated one at a time; rows that are zero in the
    column stay, every positive row is combined with every negative one so
    that the column cancels, and each new row is divided by the gcd of its
    entries (Martinez and Silva 1982).

    After each column the rows are exactly the extreme rays of the cone
    {y >= 0 : y^T A = 0 on the columns done}, and an extreme ray is the
    unique (up to scale) element of its support, which no other element's
    support is inside of. So a new row whose support (the places of y)
    contains another row's support is not one of them, and is dropped:
    Martinez and Silva's rule. New rows are tried smallest support first,
    so that the extreme rays are in place before the rows they rule out.

    The column eliminated next is the one with the fewest pairs of a
    positive and a negative row, the usual heuristic to keep the rows few;
    ``limit`` bounds the rows held at any time, new ones included.
    """
    work = _FarkasRows(ncols, limit, what)
    if seconds is not None:     # a search's own bound: its answer must not wait on this
        work.deadline = time.monotonic() + seconds
    # before the rows are built: row i's support mask is i bits wide, so a
    # million rows would take 60 GB before the limit could say no
    work.over_limit(len(a_rows))
    for i, a_row in enumerate(a_rows):
        work.add({k: v for k, v in a_row.items() if v}, {i: 1}, 1 << i)
    # cheapest column first: it makes the fewest new rows
    while (j := work.cheapest()) is not None:
        work.eliminate(j)
    # every column is eliminated: each row's A part is zero, y is an invariant
    found = [y for _, y, _ in work.rows.values()]
    return sorted(({k: y[k] for k in sorted(y)} for y in found),
                  key=lambda y: (len(y), list(y)))


def minimal_semipositive_p_invariants(s: Structure, limit: int | None = None,
                                      seconds: float | None = None) -> list[dict[str, int]]:
    """The minimal-support semi-positive P-invariants (Martinez and Silva 1982).

    Every y >= 0, y != 0 with y^T C = 0 whose support contains no other such
    vector's support, as {place: coefficient} with coprime coefficients;
    every semi-positive P-invariant is a nonnegative combination of them.
    Sorted by support size, then by place order. The Farkas algorithm can
    need exponentially many rows: past ``limit`` intermediate rows, or past ``seconds``
    (a search's bound, where it may do without them), it raises :class:`AnalysisLimit`.
    """
    found = _farkas(s.incidence_rows, len(s.transitions), limit, "P-invariants", seconds)
    return [{s.places[i]: c for i, c in y.items()} for y in found]


def minimal_semipositive_t_invariants(s: Structure, limit: int | None = None
                                      ) -> list[dict[str, int]]:
    """The minimal-support semi-positive T-invariants (Martinez and Silva 1982).

    As :func:`minimal_semipositive_p_invariants`, for C x = 0:
    {transition: coefficient}, sorted by support size, then transition order.
    """
    found = _farkas(s.incidence, len(s.places), limit, "T-invariants")
    return [{s.transitions[j]: c for j, c in x.items()} for x in found]
