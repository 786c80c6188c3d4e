"""PNML out and in: round trips, the official grammar, real tools' files, bad files."""

import pytest
from hypothesis import given, settings

from mcl2pnml import (ArcKind, NetBuilder, PnmlError, Timing, load_pnml, parse_pnml,
                      save_pnml, to_pnml_bytes)
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.io import ids

from helpers import DATA, assert_error_golden, everything
from strategies import nets
from examples.handbuilt_primitive import primitive

INVALID = sorted((DATA / "pnml" / "invalid").glob("*.pnml"))
FOREIGN = sorted((DATA / "pnml" / "foreign").glob("*.pnml"))


def test_round_trip_keeps_everything(assert_valid, tmp_path):
    net = everything()
    path = save_pnml(net, tmp_path / "everything.pnml")
    assert_valid(path.read_bytes())
    back = load_pnml(path)
    assert back == net
    assert back.transition_index["t03"].timing == Timing.delay(60)
    assert [a.kind for a in back.arcs if a.target == "t03" and a.source.endswith("MTX")] \
        == [ArcKind.READ]
    # every node has a drawing position, and positions survive a second trip
    assert all(n.position is not None for n in (*back.places, *back.transitions))
    again = parse_pnml(to_pnml_bytes(back))
    assert {p.id: p.position for p in again.places} == {p.id: p.position for p in back.places}


@settings(max_examples=60, deadline=None)
@given(nets())
def test_round_trip_of_random_nets_is_exact_and_valid(assert_valid, net):
    data = to_pnml_bytes(net, layout_engine="layers")
    assert_valid(data)
    assert parse_pnml(data) == net


def test_one_flat_page_and_a_position_for_every_node():
    from lxml import etree
    doc = etree.fromstring(to_pnml_bytes(primitive()))
    ns = {"p": "http://www.pnml.org/version-2009/grammar/pnml"}
    assert len(doc.findall(".//p:page", ns)) == 1
    assert not doc.findall(".//p:page/p:page", ns)
    nodes = doc.findall(".//p:place", ns) + doc.findall(".//p:transition", ns)
    positions = {(n.find("p:graphics/p:position", ns).get("x"),
                  n.find("p:graphics/p:position", ns).get("y")) for n in nodes}
    assert len(positions) == len(nodes), "two nodes drawn on the same spot"


def test_without_layout_the_file_is_still_valid_and_exact(assert_valid):
    data = to_pnml_bytes(everything(), layout_engine="none")
    assert_valid(data)
    assert b"<graphics>" not in data
    back = parse_pnml(data)
    assert back == everything() and all(p.position is None for p in back.places)


def test_arc_numbers_never_clash_with_node_ids(assert_valid):
    b = NetBuilder("clash")
    b.place("a1", 1)
    b.place("a_1")
    b.transition("a2")
    b.arc("a1", "a2")
    b.arc("a2", "a_1")
    data = to_pnml_bytes(b.build(), layout_engine="layers")
    assert_valid(data)   # ids are xsd:ID: a clash would make the file invalid
    assert parse_pnml(data) == b.build()


def test_one_node_per_line_so_grep_finds_a_node_whole():
    lines = to_pnml_bytes(everything(), layout_engine="layers").decode().splitlines()
    t03 = [line for line in lines if 'id="t03"' in line]
    assert len(t03) == 1 and 'latest="60"' in t03[0] and "</transition>" in t03[0]


def test_read_arc_is_a_self_loop_for_other_tools():
    from lxml import etree
    doc = etree.fromstring(to_pnml_bytes(everything()))
    arcs = {(a.get("source"), a.get("target")) for a in doc.iter("{*}arc")}
    assert ("AchieveDepth.MTX", "t03") in arcs and ("t03", "AchieveDepth.MTX") in arcs


@pytest.mark.parametrize("node_id", ["AchieveDepth.MTX", "({'a'}, {'b'})", "1st", "_x0041_",
                                     "é", "a b", "x" * 50])
def test_ids_that_are_not_xml_names_are_escaped_and_restored(node_id):
    encoded = ids.encode(node_id)
    assert ids.decode(encoded) == node_id
    from lxml import etree  # the encoded form is an XML name: it parses as an element name
    etree.fromstring(f"<{encoded}/>")


@pytest.mark.parametrize("path", FOREIGN, ids=lambda p: p.name)
def test_reads_what_other_tools_write(path):
    net = load_pnml(path)
    assert net.places and net.transitions and net.arcs and net.initial


def test_reader_flattens_pages_and_resolves_references():
    net = load_pnml(DATA / "pnml" / "foreign" / "nested_pages_with_references.pnml")
    assert {p.id for p in net.places} == {"ready", "busy", "log"}
    assert {(a.source, a.target, a.weight) for a in net.arcs} == {
        ("ready", "start", 1), ("start", "busy", 1), ("busy", "finish", 1),
        ("finish", "ready", 1), ("finish", "log", 3)}
    assert net.initial["ready"] == 2


def test_reader_takes_pipe_value_labels():
    net = load_pnml(DATA / "pnml" / "foreign" / "pipe_value_labels.pnml")
    assert net.initial["P0"] == 3
    assert {(a.source, a.target, a.weight) for a in net.arcs} == {("P0", "T0", 2), ("T0", "P1", 1)}


def test_tapaal_native_files_keep_their_markings_and_weights():
    """TAPAAL's own format says markings and weights in attributes: read, not dropped."""
    net = load_pnml(DATA / "pnml" / "foreign" / "tapaal_native.pnml")
    assert dict(net.initial.items()) == {"P0": 2}
    assert {(a.source, a.target, a.weight) for a in net.arcs} == {("P0", "T0", 2),
                                                                 ("T0", "P1", 3)}


def test_read_arcs_of_other_tools_are_read_arcs():
    net = load_pnml(DATA / "pnml" / "foreign" / "read_arcs_prom.pnml")
    assert {(a.source, a.target, a.kind) for a in net.arcs} == {
        ("todo", "work", ArcKind.NORMAL), ("work", "done", ArcKind.NORMAL),
        ("lights_on", "work", ArcKind.READ)}


def test_a_woped_subprocess_stands_in_for_its_transition():
    """The subprocess page refines its transition: the net read is the flattened one."""
    net = load_pnml(DATA / "pnml" / "foreign" / "woped_subprocess.pnml")
    assert {t.id for t in net.transitions} == {"sub1_t1", "sub1_t2", "sub1_t3"}
    assert {p.id for p in net.places} == {"p1", "p2", "sub1_p1"}
    assert {(a.source, a.target) for a in net.arcs} == {
        ("p1", "sub1_t1"), ("sub1_t1", "sub1_p1"), ("sub1_p1", "sub1_t2"),
        ("sub1_p1", "sub1_t3"), ("sub1_t2", "p2"), ("sub1_t3", "p2")}


def test_errors_in_one_line_files_point_at_the_faulty_element():
    """ProM and pm4py write a net on one line: the caret goes under this arc's label."""
    line = ('<pnml><net id="n"><page id="g"><place id="p"/><transition id="t"/>'
            '<arc id="a1" source="p" target="t"><inscription><text>1</text></inscription></arc>'
            '<arc id="a2" source="p" target="t"><inscription><text>0</text></inscription></arc>'
            '</page></net></pnml>')
    with pytest.raises(PnmlError) as info:
        parse_pnml(line.encode(), "one_line.pnml")
    column = info.value.location.column
    assert line[column - 1:].startswith("<inscription><text>0"), column


def test_foreign_nets_round_trip_through_our_writer(assert_valid):
    for path in FOREIGN:
        net = load_pnml(path)
        data = to_pnml_bytes(net)
        assert_valid(data, path.name)
        assert parse_pnml(data) == net, path.name


@pytest.mark.parametrize("path", INVALID, ids=lambda p: p.name)
def test_bad_files_give_the_expected_message(path):
    """Golden messages: file:line:col, the line, a caret; one error type only."""
    with pytest.raises(Mcl2PnmlError) as info:
        parse_pnml(path.read_bytes(), path.name)
    assert isinstance(info.value, PnmlError) or all(
        isinstance(e, PnmlError) for e in getattr(info.value, "errors", ()))
    assert_error_golden(path, info.value)


def test_entities_are_never_expanded_or_fetched():
    for name in ("entity_bomb.pnml", "external_entity.pnml"):
        with pytest.raises(PnmlError, match="document type declarations are refused"):
            parse_pnml((DATA / "pnml" / "invalid" / name).read_bytes(), name)


def test_choosing_one_of_several_nets():
    data = (DATA / "pnml" / "invalid" / "two_nets.pnml").read_bytes()
    assert parse_pnml(data, net_id="second").name == "second"
    with pytest.raises(PnmlError, match="no net with id 'third'; nets in this file: first, second"):
        parse_pnml(data, net_id="third")


def test_save_is_atomic(tmp_path, monkeypatch):
    target = tmp_path / "net.pnml"
    target.write_text("old")
    import mcl2pnml.core.files as files

    def broken(*_a, **_k):
        raise OSError("disk full")
    monkeypatch.setattr(files.os, "fsync", broken)
    with pytest.raises(Mcl2PnmlError, match="net.pnml: cannot write: disk full"):
        save_pnml(everything(), target)
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["net.pnml"]


def test_grammar_rejects_what_it_should(grammar_dir):
    from mcl2pnml.io.pnml.grammar import validate_bytes
    data = to_pnml_bytes(everything()).replace(b'type="http://www.pnml.org/version-2009/grammar/ptnet"',
                                               b'type="urn:not-a-type"')
    verdict = validate_bytes(data, "x.pnml", grammar_dir)
    assert not verdict.valid
    assert any("grammar:" in str(e) for e in verdict.errors)


def test_missing_grammar_says_how_to_get_it(tmp_path, monkeypatch):
    from mcl2pnml.io.pnml.grammar import ENV, find_grammar
    monkeypatch.setenv(ENV, str(tmp_path))
    with pytest.raises(PnmlError, match=f"no ptnet.pntd in {tmp_path}.*{ENV}"):
        find_grammar()
