"""Nets the size of compiled missions build, fuse and round-trip through PNML.

Only correctness is asserted here; how time grows with size is measured by
the benchmarks in bench/, never by timed assertions.
"""
import pytest

from mcl2pnml.analysis.zoo import cycle
from mcl2pnml import compose, parse_pnml, to_pnml_bytes


def _build_fuse_and_round_trip(n: int) -> None:
    """Two cycles of ``n`` places and ``n`` transitions, fused at one place."""
    net = compose({"a": cycle(n, "a", interface="B"), "b": cycle(n, "b", interface="B")},
                  [["a.p0", "b.p0"]], name="big")
    assert len(net.places) + len(net.transitions) == 4 * n - 1
    assert net.initial == {"a.p0": 1}
    back = parse_pnml(to_pnml_bytes(net))
    assert back == net
    assert all(p.position is not None for p in back.places)


def test_20k_nodes_build_fuse_and_round_trip():
    _build_fuse_and_round_trip(5_000)


@pytest.mark.slow
def test_100k_nodes_build_fuse_and_round_trip():
    _build_fuse_and_round_trip(25_000)
