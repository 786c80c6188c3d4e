"""Independent readers judge our PNML: pm4py and SNAKES must see the same net."""
import warnings

import pytest

from mcl2pnml import Net, save_pnml
from mcl2pnml.core.net import ArcKind
from mcl2pnml.io import ids

from examples.handbuilt_primitive import primitive
from helpers import everything
from sampling import VARIANT


def _expected_arcs(net: Net, xml_ids: bool = False) -> set:
    """Arcs as a P/T tool sees them: a read arc is a self-loop.

    With ``xml_ids``, nodes are named by their XML id, as pm4py names them.
    """
    name = ids.encode if xml_ids else (lambda i: i)
    out = set()
    for a in net.arcs:
        out.add((name(a.source), name(a.target), a.weight))
        if a.kind is ArcKind.READ:
            out.add((name(a.target), name(a.source), a.weight))
    return out


NETS = [primitive(), everything()]


# the net with every kind of node and arc in the quick suite; the primitive reaches no line or
# branch of ours that it does not (make test-slow)
@pytest.mark.parametrize("net", [pytest.param(n, id=n.name, marks=VARIANT if n is NETS[0] else ())
                                 for n in NETS])
def test_pm4py_reads_the_same_net(net, tmp_path):
    import pm4py  # installed by `make test` (the `test` extra): its absence is a failure
    path = save_pnml(net, tmp_path / f"{net.name}.pnml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pm4py warns that there is no final marking
        pn, im, _ = pm4py.read_pnml(str(path))
    # pm4py names nodes by their XML id, and keeps a transition's name as its label
    assert {p.name for p in pn.places} == {ids.encode(p.id) for p in net.places}
    assert {t.name for t in pn.transitions} == {ids.encode(t.id) for t in net.transitions}
    assert {t.label for t in pn.transitions} == {t.label for t in net.transitions}
    assert {(a.source.name, a.target.name, a.weight) for a in pn.arcs} \
        == _expected_arcs(net, xml_ids=True)
    assert {p.name: n for p, n in im.items()} == {ids.encode(p): n for p, n in net.initial.items()}


@pytest.mark.parametrize("net", NETS, ids=lambda n: n.name)
def test_snakes_reads_the_same_net(net, tmp_path):
    """SNAKES reads standard P/T PNML as a net of black tokens.

    What it cannot read, documented: it has no notion of our toolspecific
    data (timing, payloads, read arcs), which it skips; a read arc therefore
    reaches it as the equivalent self-loop, with the same firing rule.
    """
    import snakes.pnml
    path = save_pnml(net, tmp_path / f"{net.name}.pnml")
    sn = snakes.pnml.loads(path.read_text())
    # like pm4py, SNAKES names nodes by their XML id
    assert {p.name for p in sn.place()} == {ids.encode(p.id) for p in net.places}
    assert {t.name for t in sn.transition()} == {ids.encode(t.id) for t in net.transitions}
    arcs = set()
    for t in sn.transition():
        for place, label in t.input():
            arcs.add((place.name, t.name, len(list(_tokens(label)))))
        for place, label in t.output():
            arcs.add((t.name, place.name, len(list(_tokens(label)))))
    assert arcs == _expected_arcs(net, xml_ids=True)
    marking = {p: len(list(ms)) for p, ms in sn.get_marking().items()}
    assert marking == {ids.encode(p): n for p, n in net.initial.items()}


def _tokens(label):
    """The tokens an arc label of SNAKES stands for (Value(dot) or a MultiArc)."""
    from snakes.nets import MultiArc
    return list(label) if isinstance(label, MultiArc) else [label]
