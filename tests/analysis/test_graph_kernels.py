"""The reachability graph's searches that answer the contest's questions
(:mod:`mcl2pnml.analysis.contest.answers`), in C (``analysis/statespace/loops/_native.c``) and in Python
(``analysis/statespace/loops/python.py``, where C was not built), one suite for both, each held to
networkx on random graphs: Tarjan's components on a subset of the nodes, the backward
search of ``E(a U b)``, and Couvreur's on-the-fly emptiness check of a graph's product
with a generalised Büchi automaton, against the product built whole and its components
searched by networkx; and the counting sort that puts a graph's edges in compressed
rows, held to numpy's stable sort."""
from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from mcl2pnml.analysis.statespace.rows import compressed_rows as _csr
from mcl2pnml.analysis.statespace.loops import backends


@pytest.fixture(params=["c", "python"])
def native(request):
    """One backend of the searches."""
    loops = backends.named(request.param)
    if loops is None:
        pytest.skip("the loops in C are not built (mcl2pnml installed without a C compiler)")
    return loops


def _graph(rng, n: int, m: int):
    src, dst = rng.integers(0, n, m), rng.integers(0, n, m)
    g = nx.DiGraph()
    g.add_nodes_from(range(n))
    g.add_edges_from(zip(src.tolist(), dst.tolist()))
    return src.astype(np.int64), dst.astype(np.int64), g


@pytest.mark.parametrize("seed", range(4))
def test_the_edges_are_ordered_by_source_as_a_stable_sort_orders_them(seed, native):
    rng = np.random.default_rng(200 + seed)
    for _ in range(100):
        n = int(rng.integers(1, 40))
        src = rng.integers(0, n, int(rng.integers(0, 3 * n))).astype(np.int64)
        ptr = np.zeros(n + 1, dtype=np.int64)
        np.cumsum(np.bincount(src, minlength=n), out=ptr[1:])
        values = rng.integers(-5, 5, len(src)).astype(np.int64)
        cursor, out = ptr[:-1].copy(), np.empty(len(src), dtype=np.int64)
        native.scatter_by_source(src, values, cursor, out)
        assert out.tolist() == values[np.argsort(src, kind="stable")].tolist()
        assert cursor.tolist() == ptr[1:].tolist()      # each row's cursor at its end


@pytest.mark.parametrize("src, cursor", [([3], [0, 0]), ([-1], [0, 0]), ([0, 0], [1, 0]),
                                         ([1], [0, -5])])
def test_an_edge_out_of_its_rows_is_refused_not_written(src, cursor, native):
    # a source past the rows, or a row's slots past the edges: an error, never a write
    # outside ``order``
    out = np.full(len(src), -7, dtype=np.int64)
    with pytest.raises(ValueError):
        native.scatter_by_source(np.array(src, dtype=np.int64), np.zeros(len(src), np.int64),
                                 np.array(cursor, dtype=np.int64), out)


@pytest.mark.parametrize("seed", range(4))
def test_the_components_are_networkxs(seed, native):
    rng = np.random.default_rng(seed)
    for _ in range(100):
        n = int(rng.integers(1, 40))
        src, dst, g = _graph(rng, n, int(rng.integers(0, 3 * n)))
        keep = rng.random(n) < 0.8
        label = np.empty(n, dtype=np.int64)
        count = native.scc(*_csr(src, dst, n), keep.astype(np.uint8), label)
        theirs = list(nx.strongly_connected_components(g.subgraph(np.flatnonzero(keep).tolist())))
        assert count == len(theirs)
        assert {frozenset(np.flatnonzero(label == c).tolist()) for c in range(count)} \
            == {frozenset(c) for c in theirs}
        assert (label[~keep] == -1).all()
        # numbered as they complete: an edge between two components goes to a smaller one
        for a, b in zip(src, dst):
            if keep[a] and keep[b] and label[a] != label[b]:
                assert label[b] < label[a]


@pytest.mark.parametrize("seed", range(4))
def test_the_backward_search_is_until(seed, native):
    rng = np.random.default_rng(100 + seed)
    for _ in range(100):
        n = int(rng.integers(1, 40))
        src, dst, g = _graph(rng, n, int(rng.integers(0, 3 * n)))
        before, reach = rng.random(n) < 0.6, rng.random(n) < 0.15
        out = reach.astype(np.uint8)
        native.back_reach(*_csr(dst, src, n), before.astype(np.uint8), out)
        # E(before U reach), the least fixpoint: reach, or before with a successor in it
        expected = {v for v in range(n) if reach[v]}
        while True:
            more = {v for v in range(n) if before[v] and v not in expected
                    and any(w in expected for w in g.successors(v))}
            if not more:
                break
            expected |= more
        assert set(np.flatnonzero(out).tolist()) == expected


def _accepting_cycle_by_networkx(src, dst, n, a_edges, k, label, acc, sets, start) -> bool:
    product = nx.DiGraph()
    initial = [a for a in start]
    for s, t in zip(src.tolist(), dst.tolist()):
        for a, b in a_edges:
            if label[b, t]:
                product.add_edge((s, a), (t, b))
    reached = set()
    for a in initial:
        reached |= {(0, a)} | (nx.descendants(product, (0, a)) if (0, a) in product else set())
    sub = product.subgraph(reached)
    for comp in nx.strongly_connected_components(sub):
        node = next(iter(comp))
        if len(comp) == 1 and not sub.has_edge(node, node):
            continue
        if all(any(acc[b] >> bit & 1 for _, b in comp) for bit in range(sets)):
            return True
    return False


@pytest.mark.parametrize("seed", range(4))
def test_the_on_the_fly_emptiness_check_is_the_whole_products(seed, native):
    rng = np.random.default_rng(200 + seed)
    found_both = set()
    for _ in range(150):
        n, k = int(rng.integers(1, 12)), int(rng.integers(1, 5))
        src, dst, _ = _graph(rng, n, int(rng.integers(0, 3 * n)))
        dead = np.setdiff1d(np.arange(n), src)          # a dead node repeats for ever
        src, dst = np.concatenate([src, dead]), np.concatenate([dst, dead])
        a_edges = sorted({(int(a), int(b)) for a, b in rng.integers(0, k, (2 * k, 2))})
        label = rng.random((k, n)) < 0.7
        sets = int(rng.integers(0, 3))
        acc = np.zeros(k, dtype=np.uint64)
        for bit in range(sets):
            acc[rng.random(k) < 0.5] |= np.uint64(1 << bit)
        start = [a for a in range(k) if rng.random() < 0.6 and label[a, 0]]
        if not start:
            continue
        a_src = np.array([a for a, _ in a_edges], dtype=np.int64)
        a_dst = np.array([b for _, b in a_edges], dtype=np.int64)
        found, states = native.ltl_product(
            *_csr(src, dst, n), *_csr(a_src, a_dst, k), label.view(np.uint8).ravel(), acc,
            (1 << sets) - 1, np.array(start, dtype=np.int64), np.zeros(n * k, dtype=np.int32),
            10 ** 6)
        expected = _accepting_cycle_by_networkx(src, dst, n, a_edges, k, label,
                                                [int(x) for x in acc], sets, start)
        assert bool(found) == expected
        assert 1 <= states <= n * k
        found_both.add(expected)
    assert found_both == {True, False}


def test_the_product_search_stops_at_its_limit(native):
    n = 50                                   # a ring: one product state per node
    src = np.arange(n, dtype=np.int64)
    dst = (src + 1) % n
    one = np.zeros(1, dtype=np.int64)
    args = (*_csr(src, dst, n), *_csr(one, one, 1), np.ones(n, dtype=np.uint8),
            np.zeros(1, dtype=np.uint64), 1, one)
    assert native.ltl_product(*args, np.zeros(n, dtype=np.int32), 10)[0] == -1
    # with room, the ring's one cycle misses the acceptance set: empty
    assert native.ltl_product(*args, np.zeros(n, dtype=np.int32), 100) == (0, n)


def _packed_spaces():
    from mcl2pnml.analysis.statespace.explore import explore
    from mcl2pnml import pipeline
    from helpers import ROOT
    nets = [pipeline.compile_file(ROOT / "examples" / "sauce.mcl")]
    corpus = ROOT.parent / "shared" / "external-nets" / "mcc-queries"
    nets += [pipeline.load_net(corpus / m / "model.pnml")
             for m in ("Dekker-PT-010", "Philosophers-PT-000010", "Raft-PT-02")
             if (corpus / m).is_dir()]
    return [explore(net) for net in nets]


def test_the_edges_of_packed_markings_listed_in_c_are_numpys():
    """The edges of a safe net's packed markings, listed by the loop in C, are those the
    numpy path finds, in the same order (node, then transition) and types."""
    from mcl2pnml.analysis.statespace.packedmarkings import PackedStateSpace
    spaces = [s for s in _packed_spaces() if isinstance(s, PackedStateSpace)]
    assert spaces, "no safe net explored with packed markings"
    for space in spaces:
        in_c = space._edges
        del space.__dict__["_edges"]
        space._kernels = lambda: None                 # the numpy path
        for a, b in zip(in_c, space._edges):
            assert a.dtype == b.dtype and np.array_equal(a, b)
