"""TINA's .net and LoLA's format: what we write, read back by readers written from
the formats' descriptions (tests/support/formats_readers.py) and by our own; bad files."""
from __future__ import annotations

import functools
import json
import re
from pathlib import Path

import pytest
from hypothesis import given, settings

from mcl2pnml.pipeline import compile_file
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.io.formats import read_net
from mcl2pnml.io.lola import parse_lola, to_lola
from mcl2pnml.io.tina import parse_tina, to_tina
from mcl2pnml.core.net import ArcKind, NetBuilder, Timing
from mcl2pnml.io import ids
from mcl2pnml.language.library import default_library

from helpers import DATA, ROOT, assert_error_golden, run_cli as run
from formats_readers import read_dot, read_lola, read_tina
from strategies import nets
from sampling import VARIANT, sample

EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))
TEMPLATES = ["primitive", "task", "KeepGoal", "sequence", "parallel", "monitor"]
INVALID = sorted(p for p in (DATA / "formats" / "invalid").iterdir() if p.suffix != ".expected")


# compiled once per process: three tests are parametrized by them at collection, in every
# worker, and each compiled every example again (nets are immutable, sharing is safe)
@functools.cache
def missions():
    return [(p.stem, compile_file(p)) for p in EXAMPLES]


@functools.cache
def templates():
    lib = default_library()
    return [(name, lib.composed(name)) for name in TEMPLATES]


def plain(net, *, read_as: str) -> dict:
    """The net in the readers' shape; read arcs as test arcs, or as a self-loop pair."""
    arcs: dict = {}
    for a in net.arcs:
        if a.kind is ArcKind.READ and read_as == "loop":
            for key in ((a.source, a.target, "normal"), (a.target, a.source, "normal")):
                arcs[key] = arcs.get(key, 0) + a.weight
        else:
            key = (a.source, a.target, "test" if a.kind is ArcKind.READ else "normal")
            arcs[key] = arcs.get(key, 0) + a.weight
    return {"places": {p.id: net.initial[p.id] for p in net.places},
            "transitions": {t.id for t in net.transitions}, "arcs": arcs}


def unit_of(text: str) -> int:
    """10^d where the file says its time unit is 10^-d s."""
    m = re.search(r"# time unit: (?:1/(\d+)|1) s", text)
    assert m, "a TINA file we write states its time unit"
    return int(m.group(1) or 1)


@pytest.mark.parametrize("name, net", missions() + templates(), ids=lambda x: x
                         if isinstance(x, str) else "")
def test_tina_as_tina_reads_it(name, net):
    text = to_tina(net, urgent=True)
    seen = read_tina(text)
    want = plain(net, read_as="test")
    assert seen["places"] == want["places"]
    assert set(seen["transitions"]) == want["transitions"]
    assert seen["arcs"] == want["arcs"]
    scale = unit_of(text)
    for t in net.transitions:
        payload = t.payload or {}
        if t.timing is not None:     # a time-out: its delay, as a static interval
            hi = None if t.timing.latest is None else round(t.timing.latest * scale)
            expected = (round(t.timing.earliest * scale), hi)
        elif "event" in payload:     # the vehicle fires it, whenever it reports
            expected = None
        else:                        # immediate: fires before time passes
            expected = (0, 0)
        assert seen["transitions"][t.id] == expected, t.id


@pytest.mark.parametrize("name, net", missions() + templates(), ids=lambda x: x
                         if isinstance(x, str) else "")
def test_lola_as_lola_reads_it(name, net):
    text = to_lola(net)
    decode = ids.decode if "{ ids: xml-name-escapes }" in text else (lambda s: s)
    seen = read_lola(text, decode)
    want = plain(net, read_as="loop")
    assert seen["places"] == want["places"]
    assert set(seen["transitions"]) == want["transitions"]
    assert seen["arcs"] == want["arcs"]


def same_structure(a, b, *, read_as_loop: bool = False) -> None:
    """Same places, transitions, arcs and marking; names and timings compared apart."""
    mode = "loop" if read_as_loop else "test"
    assert plain(a, read_as=mode) == plain(b, read_as=mode)


@settings(max_examples=sample(150, 50), deadline=None)
@given(nets())
def test_any_net_survives_tina_and_lola_through_our_readers(net):
    back = parse_tina(to_tina(net), "random.net")
    same_structure(net, back)
    assert back.name == net.name
    for t in net.transitions:
        mine = back.transition_index[t.id].timing
        untimed = t.timing is None or (t.timing.earliest == 0 and t.timing.latest is None)
        assert (mine is None) if untimed else (mine == t.timing)
    for p in net.places:
        assert back.place_index[p.id].name == p.name
    same_structure(net, parse_lola(to_lola(net), "random.lola"), read_as_loop=True)
    # and the test readers agree on the odd ids (spaces, braces, keywords, unicode)
    assert set(read_tina(to_tina(net))["places"]) == {p.id for p in net.places}


def test_delays_that_are_not_whole_seconds_take_a_finer_unit():
    b = NetBuilder("fine")
    b.place("p", 1)
    b.transition("t", timing=Timing.delay(2.5))
    b.transition("u", timing=Timing(0.25, None))
    b.arc("p", "t")
    b.arc("p", "u")
    text = to_tina(b.build())
    assert "# time unit: 1/100 s" in text
    assert read_tina(text)["transitions"] == {"t": (250, 250), "u": (25, None)}
    back = parse_tina(text, "fine.net")
    assert back.transition_index["t"].timing == Timing(2.5, 2.5)
    assert back.transition_index["u"].timing == Timing(0.25, None)


def test_a_net_written_by_hand_for_tina():
    """What TINA's users write: K and M counts, labels, notes, place-side arcs, [0,w[."""
    net = read_net(DATA / "formats" / "foreign" / "buffer.net")
    assert net.name == "buffer"
    assert net.initial == {"idle": 2, "slots": 2000, "power": 1}
    assert net.place_index["idle"].name == "waiting"                # from 'lb'

    assert net.transition_index["put"].name == "put an item"
    assert net.transition_index["put"].timing is None          # [0,w[ is untimed
    assert net.transition_index["get"].timing == Timing(1, 3)
    arcs = {(a.source, a.target): (a.weight, a.kind) for a in net.arcs}
    assert arcs[("slots", "put")] == (1, ArcKind.NORMAL)
    assert arcs[("put", "items")] == (1, ArcKind.NORMAL)       # declared on the place
    assert arcs[("items", "get")] == (2, ArcKind.NORMAL)
    assert arcs[("power", "get")] == (1, ArcKind.READ)


def test_a_net_written_by_hand_for_lola():
    net = read_net(DATA / "formats" / "foreign" / "mutex.lola")
    assert net.initial == {"idle1": 1, "idle2": 1, "free": 1}
    assert len(net.transitions) == 4 and len(net.arcs) == 12


@pytest.mark.parametrize("path", INVALID, ids=lambda p: p.name)
def test_bad_files_give_the_expected_message(path):
    """Golden messages: file:line:col, the line, a caret."""
    with pytest.raises(Mcl2PnmlError) as info:
        read_net(path.relative_to(ROOT))
    assert_error_golden(path, info.value)


@pytest.mark.parametrize("fmt, suffix", [("tina", ".net"), ("lola", ".lola")])
def test_compile_then_analyze_through_the_format(tmp_path, fmt, suffix):
    mission = tmp_path / "sauce.mcl"
    mission.write_text((ROOT / "examples" / "sauce.mcl").read_text())
    out = run("compile", mission, "--format", fmt)
    assert out.returncode == 0, out.stderr
    written = mission.with_suffix(suffix)
    assert written.exists()
    via = json.loads(run("analyze", written, "--state-space", "--json").stdout)
    direct = _analyzed_directly(mission)
    for key in ("states", "safe", "deadlock_free", "reusable", "terminal_markings"):
        assert via[key] == direct[key], key


_DIRECT: dict = {}


def _analyzed_directly(mission: Path) -> dict:
    """``analyze --state-space --json`` of the paper's mission itself, run once per process:
    both formats are compared with the same answer (a copy of one file, the same command)."""
    if not _DIRECT:
        out = run("analyze", mission, "--state-space", "--json")
        assert out.returncode == 0, out.stderr
        _DIRECT.update(json.loads(out.stdout))
    return _DIRECT


def test_an_unknown_suffix_lists_the_known_formats(tmp_path):
    path = tmp_path / "net.txt"
    path.write_text("PLACE a; MARKING a: 1;")
    out = run("analyze", path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert ".net (TINA)" in out.stderr and ".lola (LoLA)" in out.stderr


# -- DOT: the drawing, read back as a net ------------------------------------------------

def net_from_dot(text: str) -> tuple[dict, dict]:
    """The net a DOT drawing of ours shows, in the readers' shape, and its clusters."""
    from mcl2pnml.view.drawing import TOKEN

    dot = read_dot(text)
    kinds = {n: a.get("class") for n, a in dot["nodes"].items()}
    original = {n: (n.rpartition("~")[0] if kinds[n] == "copy" else n) for n in kinds}
    places, transitions, arcs = {}, {}, {}
    for n, a in dot["nodes"].items():
        if kinds[n] == "place":
            last = a.get("label", "").split("\n")[-1]
            places[n] = (last.count(TOKEN) if set(last) == {TOKEN}
                         else int(last[:-1]) if last.endswith(TOKEN) else 0)
        elif kinds[n] == "transition":
            # a delay is drawn "◷ 300 s", an interval "◷ [2, 5] s"
            m = re.search(r"\u25f7 (?:([\d.]+)|\[([\d.]+), ([\d.]+|inf)\]) s$",
                          a.get("label", ""))
            transitions[n] = m and ((float(m.group(1)), float(m.group(1))) if m.group(1) else
                                    (float(m.group(2)),
                                     None if m.group(3) == "inf" else float(m.group(3))))
    for a, b, attrs in dot["edges"]:
        if "legend" in (kinds[a], kinds[b]):
            continue
        read = attrs.get("style") == "dashed" and attrs.get("arrowhead") == "none"
        key = (original[a], original[b], "test" if read else "normal")
        arcs[key] = arcs.get(key, 0) + int(attrs.get("label", 1))
    boxes = {b: m for b, m in dot["clusters"].items() if b != "legend"}
    return {"places": places, "transitions": transitions, "arcs": arcs}, boxes


# every template, and the paper's mission for the missions' boxes; the other examples reach
# no line or branch of ours that these do not (``make test-slow`` runs them)
@pytest.mark.parametrize("name, net", [
    pytest.param(name, net, id=name, marks=VARIANT if name != "sauce" else ())
    for name, net in missions()] + [pytest.param(name, net, id=name) for name, net in templates()])
def test_dot_shows_the_net_and_its_instances(name, net):
    from mcl2pnml.view.drawing import dot_graph, instance_clusters

    boxes = instance_clusters(net)
    source = dot_graph(net, clusters=boxes).source
    seen, clusters = net_from_dot(source)
    # the transition a copy of a place is drawn beside: the one it marks or is read by
    beside = {**{b: a for a, b, _ in read_dot(source)["edges"]},
              **{a: b for a, b, _ in read_dot(source)["edges"] if "~" in a}}
    want = plain(net, read_as="test")
    assert seen["places"] == want["places"]
    assert set(seen["transitions"]) == want["transitions"]
    assert seen["arcs"] == want["arcs"]
    for t in net.transitions:
        if t.timing is not None:
            assert seen["transitions"][t.id] == (t.timing.earliest, t.timing.latest)
    # one box per instance, each node in its own instance's box, and the places
    # where boxes meet (fused) on no box
    assert set(clusters) == {b for b in boxes if any(m in clusters.get(b, ()) for m in
                                                     boxes[b])}
    box_of = {m: b for b, members in clusters.items() for m in members}
    for box, members in clusters.items():
        for m in members:
            if "~" in m and m.rpartition("~")[0] in net.place_index:
                # a copy of a place is drawn beside the transition that marks or reads it
                assert box_of[beside[m]] == box, m
            else:
                assert m.startswith(box + "."), (box, m)
    assert not boxes or clusters, "a net drawn in boxes has nodes inside them"


def test_fusion_places_sit_between_the_boxes_they_join():
    from mcl2pnml.view.drawing import dot_graph, instance_clusters

    net = dict(missions())["sauce"]
    _, clusters = net_from_dot(dot_graph(net, clusters=instance_clusters(net)).source)
    inside = {m for members in clusters.values() for m in members}
    box_of = {m: b for b, members in clusters.items() for m in members}
    for p in net.places:
        neighbours = {a.target if a.source == p.id else a.source
                      for a in net.arcs if p.id in (a.source, a.target)}
        boxes = {box_of.get(t) for t in neighbours}
        assert (p.id in inside) == (len(boxes) == 1), (p.id, boxes)


def test_templates_in_every_format(tmp_path):
    """A template is a plain net: in TINA, no interval it does not have; a mission's
    immediate transitions are [0,0] (checked above on compiled missions)."""
    for fmt, suffix in (("tina", ".net"), ("lola", ".lola"), ("dot", ".dot"), ("png", ".png")):
        out = run("template", "sequence", "--format", fmt, "-o", tmp_path / f"seq{suffix}")
        assert out.returncode == 0, out.stderr
    seen = read_tina((tmp_path / "seq.net").read_text())
    assert set(seen["transitions"].values()) == {None}
    assert (tmp_path / "seq.png").read_bytes().startswith(b"\x89PNG")
    assert read_net(tmp_path / "seq.lola").initial == default_library().composed(
        "sequence").initial


def test_every_format_is_read_and_written_by_functions_of_one_pattern():
    """Each module of io reads a file with read_X, text or bytes with parse_X, writes a file
    with write_X and makes its text with to_X; the format table names them so."""
    import importlib
    import inspect

    from mcl2pnml.io.formats import FORMATS
    for form in FORMATS.values():
        module = importlib.import_module(form.module)
        assert form.writer.startswith("write_") and callable(getattr(module, form.writer))
        if form.reader is not None:
            assert form.reader.startswith("read_") and callable(getattr(module, form.reader))
    for name in ("pnml", "tina", "lola", "pipe", "tapn", "mccquery", "text", "dot"):
        module = importlib.import_module(f"mcl2pnml.io.{name}")
        public = [n for n, f in vars(module).items() if inspect.isfunction(f)
                  and f.__module__.startswith("mcl2pnml.io") and not n.startswith("_")]
        assert not [n for n in public if n.startswith(("load_", "save_"))], name


def test_a_drawing_is_made_by_the_view_and_written_by_io(tmp_path):
    """io writes the DOT text the view draws, byte for byte, and never draws: a writer of a
    drawing format is handed the drawing (SaveOptions.drawing), as PNML's is the positions."""
    from mcl2pnml.io.dot import write_dot
    from mcl2pnml.io.formats import FORMATS
    from mcl2pnml.pipeline import save_net
    from mcl2pnml.view.drawing import drawing
    net = default_library().composed("sequence")
    slots = default_library().slots("sequence")
    save_net(net, tmp_path / "seq.dot", "dot", title="Fig. 4", clusters=slots, expand=None)
    drawn = drawing(net, "Fig. 4", clusters=slots, expand=None).source
    assert (tmp_path / "seq.dot").read_text() == drawn
    write_dot(net, tmp_path / "again.dot", drawing=drawn)
    assert (tmp_path / "again.dot").read_text() == drawn
    assert {f.name for f in FORMATS.values() if "drawing" in f.options} == {"dot", "svg", "png"}
