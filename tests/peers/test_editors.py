"""Our nets open in the editors lecturers use, read by the editors' own readers.

WoPeD reads our PNML; PIPE reads only its own dialect, which ``compile
--format pipe`` and ``template --format pipe`` write (:mod:`mcl2pnml.io.pipe`).
Each reader runs headless on every template, every example and a hundred
generated missions (tests/support/editors.py), and what it read is held to the net,
element by element: each place with its tokens and position, each transition
with its position, each arc with its ends, its weight and its bend points;
and neither reader may complain (WoPeD's warnings, PIPE's skipped elements).

A JVM takes a second to start and WoPeD's reader takes time quadratic in a
file's size, so ``make test`` reads several nets per file, as their disjoint
union (each net's ids prefixed, each laid out as the command writing it alone
lays it out, side by side): the templates in one file, the examples in
two, ten generated missions in another. The ``slow`` variants
read all hundred generated missions, and every template, example and
generated mission alone, as ``compile`` and ``template`` write them.
"""
from __future__ import annotations

import re
from collections import Counter
from functools import lru_cache
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, seed, settings

import editors
from helpers import ROOT, run_cli
from mcl2pnml import pipeline
from mcl2pnml.core.compose import union
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.io.pipe import write_pipe
from mcl2pnml.io.pnml.writer import pt_arcs, write_pnml
from mcl2pnml.view.layout import Drawn
from missions import missions
from sampling import variants

TEMPLATES = sorted({names.split(", ")[0] for names, _, _ in pipeline.templates()})
EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))
SAUCE = ROOT / "examples" / "sauce.mcl"
GENERATED = 100
#: Generated missions per file: WoPeD's reader takes time quadratic in a file's size
#: (1.5 s for 10 missions, 870 places; 5.7 s for 25)
BATCH = 10
#: The batches ``make test`` reads (the first 10 missions); the rest are ``slow``.
FAST_BATCHES = 1


def _expected(net, drawn):
    """What a reader must find: places (tokens, x, y), transitions (x, y), and the arcs
    by their ends: (weight, points), the points being its ends and its bend points."""
    pos = drawn.positions if drawn else {}
    bends = drawn.bends if drawn else {}

    def at(node):
        xy = pos.get(node)
        return (None, None) if xy is None else (round(xy[0]), round(xy[1]))
    tokens = dict(net.initial.items())
    places = {p.id: (tokens.get(p.id, 0), *at(p.id)) for p in net.places}
    transitions = {t.id: at(t.id) for t in net.transitions}
    arcs = {}
    for s, d, w, _ in pt_arcs(net):
        assert (s, d) not in arcs, f"two arcs from {s} to {d} in one file"
        bent = bends.get((s, d)) or bends.get((d, s)) or []
        arcs[(s, d)] = (w, len(bent) + 2 if pos else None)
    return places, transitions, arcs


def _holds(editor: str, path: Path, net, drawn) -> None:
    got = editors.read(editor, path)
    assert not got.complaints, f"{editor} on {path.name}: {got.complaints[:5]}"
    places, transitions, arcs = _expected(net, drawn)
    assert got.places == places, _diff(editor, "places", got.places, places)
    assert got.transitions == transitions, \
        _diff(editor, "transitions", got.transitions, transitions)
    read = Counter((s, d) for s, d, _, _ in got.arcs.values())
    assert all(k == 1 for k in read.values()), f"{editor}: arcs read twice"
    found = {(s, d): (w, n if drawn else None) for s, d, w, n in got.arcs.values()}
    assert found == arcs, _diff(editor, "arcs", found, arcs)
    assert got.counts["initial_marking_sum"] == sum(dict(net.initial.items()).values())


def _diff(editor: str, what: str, got: dict, want: dict) -> str:
    wrong = [k for k in want if got.get(k) != want[k]][:5]
    extra = [k for k in got if k not in want][:5]
    return (f"{editor} read the {what} differently: "
            + "; ".join(f"{k}: read {got.get(k)}, wrote {want[k]}" for k in wrong)
            + (f"; not ours: {extra}" if extra else ""))


def _both(net, folder: Path, stem: str, layout: str = "auto") -> None:
    """Write ``net`` as our PNML and in PIPE's dialect, as the commands do, and hold both
    editors' readings to it."""
    editors.need("woped"), editors.need("pipe")
    _written(net, folder, stem, pipeline._drawn(net, layout))


def _written(net, folder: Path, stem: str, drawn) -> None:
    pnml, xml = folder / f"{stem}.pnml", folder / f"{stem}.xml"
    write_pnml(net, pnml, drawn and drawn.positions, drawn and drawn.bends)
    write_pipe(net, xml, drawn and drawn.positions, drawn and drawn.bends)
    _holds("woped", pnml, net, drawn)
    _holds("pipe", xml, net, drawn)


def _side_by_side(nets: list, folder: Path, stem: str) -> None:
    """The nets' disjoint union, each laid out as the command that writes it alone lays it
    out, side by side, held to both editors' readings: one file per editor."""
    editors.need("woped"), editors.need("pipe")
    whole = union(nets, name=stem)
    positions, bends, left = {}, {}, 0.0
    for name, net in nets:
        drawn = pipeline._drawn(net, "auto")
        xs = [x for x, _ in drawn.positions.values()]
        shift = left - min(xs)
        positions.update({f"{name}.{k}": (x + shift, y) for k, (x, y) in drawn.positions.items()})
        bends.update({(f"{name}.{a}", f"{name}.{b}"): [(x + shift, y) for x, y in points]
                      for (a, b), points in drawn.bends.items()})
        left += max(xs) - min(xs) + 100
    _written(whole, folder, stem, Drawn(positions, bends))


def test_every_template_opens_in_both_editors(tmp_path):
    _side_by_side([(name, pipeline.template_net(name)) for name in TEMPLATES], tmp_path,
                  "templates")


# the half with the paper's mission in the quick suite, the other (which reaches no line or
# branch of ours that it and the generated missions do not) in ``make test-slow``
@pytest.mark.parametrize("half", variants([0, 1], [EXAMPLES.index(SAUCE) % 2]))
def test_every_example_opens_in_both_editors(half, tmp_path):
    """In two files (WoPeD's reader is quadratic in a file's size)."""
    chosen = EXAMPLES[half::2]
    _side_by_side([(m.stem, _mission(m)) for m in chosen], tmp_path, f"examples{half}")


def _mission(path: Path):
    return pipeline.compile_checked(pipeline.check_file(path))


@pytest.mark.slow
@pytest.mark.parametrize("name", TEMPLATES)
def test_each_template_opens_in_both_editors_alone(name, tmp_path):
    _both(pipeline.template_net(name), tmp_path, name)


@pytest.mark.slow
@pytest.mark.parametrize("mission", EXAMPLES, ids=lambda p: p.stem)
def test_each_example_opens_in_both_editors_alone(mission, tmp_path):
    _both(_mission(mission), tmp_path, mission.stem)


@lru_cache(maxsize=None)
def _sources(count: int) -> tuple:
    """The ``count`` missions drawn, as MCL: compiled where a test reads them (``make test``
    reads ten of the hundred; compiling the others took a second for nothing)."""
    sources = []

    @settings(max_examples=count, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(missions(depth=1, width=2))
    def collect(source):
        sources.append(source)

    seed(20261127)(collect)()
    assert len(sources) == count
    return tuple(sources)


def _compiled(source: str):
    return pipeline.compile_checked(pipeline.check_source(source, "generated.mcl"))


def _generated(count: int, chosen: slice = slice(None)) -> list:
    """The nets of the ``chosen`` ones of the ``count`` missions drawn."""
    return [_compiled(source) for source in _sources(count)[chosen]]


def _batch(batch: int, tmp_path: Path) -> None:
    """Ten missions at a time, as their disjoint union (the module's documentation)."""
    nets = _generated(GENERATED, slice(batch * BATCH, (batch + 1) * BATCH))
    whole = union([(f"g{batch * BATCH + k}", net) for k, net in enumerate(nets)],
                  name=f"generated{batch}")
    _both(whole, tmp_path, f"generated{batch}", layout="layers")


@pytest.mark.parametrize("batch", range(FAST_BATCHES))
def test_generated_missions_open_in_both_editors(batch, tmp_path):
    _batch(batch, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("batch", range(FAST_BATCHES, GENERATED // BATCH))
def test_a_hundred_generated_missions_open_in_both_editors(batch, tmp_path):
    _batch(batch, tmp_path)


@pytest.mark.slow
def test_each_generated_mission_opens_in_both_editors_alone(tmp_path):
    for k, net in enumerate(_generated(GENERATED)):
        _both(net, tmp_path, f"g{k}")


def test_compile_says_what_pipe_cannot(tmp_path):
    """A mission's time-outs are written immediate, their delays said on the canvas and
    in the command's message; the file reads back, the forgiving way (PIPE's labels are
    refused by the strict reading), as the same untimed net."""
    out = run_cli("compile", ROOT / "examples" / "sauce.mcl", "--format", "pipe", "-o",
                  tmp_path / "sauce.xml")
    assert out.returncode == 0, out.stderr
    assert "3 time-outs written as immediate transitions" in out.stderr
    text = (tmp_path / "sauce.xml").read_text()
    assert "AchieveDepth.t03: after 60 s" in text and "toolspecific" not in text
    with pytest.raises(Mcl2PnmlError) as refused:
        pipeline.load_net(tmp_path / "sauce.xml")
    assert re.search(rf"^{re.escape(str(tmp_path / 'sauce.xml'))}:\d+:\d+: this is PIPE's "
                     r"own dialect of PNML \(net type 'P/T net', labels in <value>",
                     str(refused.value), re.MULTILINE), str(refused.value)[:2000]
    back = pipeline.load_net(tmp_path / "sauce.xml", lenient=True)
    net = pipeline.compile_checked(pipeline.check_file(ROOT / "examples" / "sauce.mcl"))
    assert {p.id for p in back.places} == {p.id for p in net.places}
    assert {t.id for t in back.transitions} == {t.id for t in net.transitions}
    assert dict(back.initial.items()) == dict(net.initial.items())
    # the untimed P/T net: a read arc is its self-loop, as PIPE draws it
    assert sorted((a.source, a.target, a.weight) for a in back.arcs) == \
        sorted((s, d, w) for s, d, w, _ in pt_arcs(net))
    assert all(t.timing is None for t in back.transitions)
    # a template too, which has no time-outs: only its payloads are left out
    out = run_cli("template", "task", "--format", "pipe", "-o", tmp_path / "task.xml")
    assert out.returncode == 0, out.stderr
    assert "payloads" in out.stderr and "time-out" not in out.stderr
    assert pipeline.load_net(tmp_path / "task.xml", lenient=True).summary().startswith(
        "task: 19 places")
