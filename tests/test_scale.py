"""Nets the size of compiled missions build, fuse and round-trip through PNML.

Only correctness is asserted here; how time grows with size is measured by
the benchmarks in bench/, never by timed assertions.
"""
from analysis.zoo import cycle
from mcl2pnml import compose, parse_pnml, to_pnml_bytes

N = 25_000  # per component: two components make 100,000 places and transitions


def test_100k_nodes_build_fuse_and_round_trip():
    net = compose({"a": cycle(N, "a", interface="B"), "b": cycle(N, "b", interface="B")},
                  [["a.p0", "b.p0"]], name="big")
    assert len(net.places) + len(net.transitions) == 4 * N - 1
    assert net.initial == {"a.p0": 1}
    back = parse_pnml(to_pnml_bytes(net))
    assert back == net
    assert all(p.position is not None for p in back.places)
