"""Nets the size of compiled missions build, fuse and round-trip through PNML.

Only correctness is asserted here; how time grows with size is measured by
the benchmarks in bench/, never by timed assertions.
"""
from mcl2pnml import NetBuilder, compose, parse_pnml, to_pnml_bytes

N = 25_000  # per component: two components make 100,000 places and transitions


def ring(n: int, name: str):
    b = NetBuilder(name)
    for i in range(n):
        b.place(f"p{i}", 1 if i == 0 else 0, interface="B" if i == 0 else None)
        b.transition(f"t{i}")
    for i in range(n):
        b.arc(f"p{i}", f"t{i}")
        b.arc(f"t{i}", f"p{(i + 1) % n}")
    return b.build()


def test_100k_nodes_build_fuse_and_round_trip():
    net = compose({"a": ring(N, "a"), "b": ring(N, "b")}, [["a.p0", "b.p0"]], name="big")
    assert len(net.places) + len(net.transitions) == 4 * N - 1
    assert net.initial == {"a.p0": 1}
    back = parse_pnml(to_pnml_bytes(net))
    assert back == net
    assert all(p.position is not None for p in back.places)
