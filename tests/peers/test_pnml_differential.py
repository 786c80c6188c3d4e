"""Every PNML file we have, read by us and by TAPAAL's verifypn: a refusal, or one net.

A proof is about the net read from a file. PNML is read in different ways by
different tools: a prefixed element, a node inside ``<toolspecific>``, a
marking split by a comment, two ``<text>`` in one label, ``weight=`` as an
attribute each give one net to one tool and another net to the next. So our
reader either refuses a file, with a message at its file:line:col, or reads
exactly the net verifypn reads from it (``--write-unfolded-net``: places with
their initial markings, transitions, arcs with their weights;
tests/support/pnml_peer.py). A file we read and verifypn does not (it refuses it or
crashes on it) fails too: its net is one no peer can check.

The files: the external corpus (tests/data/external/corpus.json, with the
contest's larger models of ``bench-models/`` and the models of
``mcc-queries/``; skipped where the corpus is not here); every example mission
compiled by the pipeline, the net with every feature of the core and every
template, each written by our writer (which we must read); and the
hand-written hostile files of tests/data/pnml/hostile, each the net of
``plain.pnml`` with one construct that tools read differently. :data:`HOSTILE`
says of each what we must do with it, :data:`FAULTS` what we still do wrong.

Second opinions, where they read the file: pm4py's importer and LoLA (its
``--printNet``). A file we read is one with a single meaning, so every tool
that reads it must read the same net; a tool that reads another one has found
a second meaning, which our reader should have refused.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import pytest

import pnml_peer
from helpers import DATA, ROOT, everything
from mcl2pnml import pipeline
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.io.pnml.reader import read_pnml
from test_external import ROWS, _corpus_dirs, corpus_file

HOSTILE_DIR = DATA / "pnml" / "hostile"

#: Must be read, as verifypn reads it.
READ = "read"

#: Each hostile file, and what our reader must do with it: :data:`READ`, or refuse it with
#: a message that matches the pattern (the comment says what verifypn reads from it).
HOSTILE: dict[str, str] = {
    # verifypn: the net as written
    "plain.pnml": READ,
    # verifypn: no arc finish -> done (it matches names with their prefix)
    "prefixed_arc.pnml": r"<p:arc> .*without a prefix",
    # verifypn: the nodes and the arc inside are part of the net
    "node_in_page_toolspecific.pnml": r"<place> in <toolspecific>",
    "node_in_page_graphics.pnml": r"<place> in <graphics>",
    # verifypn: both nets, as one
    "net_in_unknown_element.pnml": r"<net> in <wrapper>",
    "two_nets_one_id.pnml": r"a second <net>",
    # verifypn: markings of 0 (it reads the characters before the comment, or none)
    "marking_cdata.pnml": r"<initialMarking> holds a CDATA section",
    "marking_comment.pnml": r"<initialMarking> holds a comment",
    "marking_pi.pnml": r"<initialMarking> holds a processing instruction",
    "marking_nbsp.pnml": r"initialMarking must be a natural number in ASCII digits",
    # verifypn: refused (a weight of 0, or not digits)
    "inscription_cdata.pnml": r"<inscription> holds a CDATA section",
    "inscription_comment.pnml": r"<inscription> holds a comment",
    "inscription_pi.pnml": r"<inscription> holds a processing instruction",
    "inscription_nbsp.pnml": r"inscription must be a positive integer in ASCII digits",
    # verifypn: weight 2, marking 1 (TAPAAL's attributes, in any file)
    "weight_attribute.pnml": r"<arc> has the attribute weight",
    "marking_attribute.pnml": r"<place> has the attribute initialMarking",
    # verifypn: marking 0 (the number of "Default,1")
    "pipe_value_marking.pnml": r"<value> in <initialMarking>",
    # verifypn: no arc idle -> start (the reference is no node to it)
    "reference_place_arc.pnml": r"<referencePlace> is a reference place",
    # verifypn: the subprocess's nodes beside finish, not instead of it
    "woped_subprocess_page.pnml": r"<net> inside <page> 'finish'",
    # verifypn: the last label, the last text: 3
    "two_initial_markings.pnml": r"a second <initialMarking>",
    "two_texts_in_label.pnml": r"a second <text> in <initialMarking>",
    # verifypn: an ordinary arc, which consumes (it knows no read arcs)
    "arc_type_test.pnml": r"type='test'",
    "arc_type_read.pnml": r"type='read'",
    "arctype_test.pnml": r"type 'test'",
    # verifypn: 3, the last text it finds, at any depth of the label
    "marking_text_in_toolspecific.pnml": r"<text> inside <toolspecific>",
    "marking_text_in_graphics.pnml": r"<text> inside <graphics>",
    # verifypn: marking 1; the weight refused (a sign is not a digit)
    "marking_sign.pnml": r"natural number in ASCII digits.*'\+1'",
    "inscription_sign.pnml": r"positive integer in ASCII digits.*'\+2'",
    # verifypn: 1 and 2
    "marking_leading_zero.pnml": READ,
    "inscription_leading_zero.pnml": READ,
    # verifypn: marking 1; the weight refused (a line break is not a blank)
    "marking_newline.pnml": READ,
    "inscription_newline.pnml": r"has a line break around it, which verifypn refuses",
    # verifypn: marking refused (over 2^32 - 1); weight 2 (2^32 + 2 cut to 32 bits)
    "marking_over_2_32.pnml": r"initialMarking 4294967297 is too large",
    "inscription_over_2_32.pnml": r"inscription 4294967298 is too large",
    # verifypn: the id with its tab, where an XML parser reads a space
    "id_with_tab.pnml": r"white space|tab",
    # verifypn: two places, go.on and go_x002E_on, where our ids marker makes them one
    "ids_marker.pnml": r"reads as 'go\.on' once its escapes are decoded",
}

#: Hostile files the reader still gets wrong, and how: each test of them is expected to
#: fail (strictly: once the reader is right, the entry must go).
FAULTS: dict[str, str] = {}

#: Files this large are read in `make test-slow` only: three readers take a second on them.
SLOW_BYTES = 500_000


@dataclass(frozen=True)
class Source:
    """One file to read: where it comes from, and its name there."""

    kind: str          # external, example, core (tests/support/helpers.py), template or hostile
    name: str
    row: dict | None = None   # an external file's row of corpus.json

    def __str__(self) -> str:
        return f"{self.kind}/{self.name}"


def _found(relative: str) -> Path | None:
    """An external file that corpus.json does not describe, where the corpus is."""
    return next((d / relative for d in _corpus_dirs() if (d / relative).is_file()), None)


def _listed(folder: str, pattern: str) -> list[str]:
    for d in _corpus_dirs():
        if (d / folder).is_dir():
            return sorted(str(p.relative_to(d)) for p in (d / folder).glob(pattern))
    return []


def _external() -> list[Source]:
    rows = [Source("external", r["file"], r) for r in ROWS]
    found = _listed("bench-models", "*.pnml") + _listed("mcc-queries", "*/model.pnml")
    # without the corpus there is none of them: one test says so, instead of none at all
    return rows + [Source("external", name) for name in found or ["bench-models"]]


def _param(source: Source, faults: dict[str, str] | None = None):
    """The test's parameter: slow for a large file; with ``faults``, expected to fail for a
    hostile file named there."""
    marks = []
    if source.kind == "external":
        path = _found(source.name)
        if path is not None and path.stat().st_size > SLOW_BYTES:
            marks.append(pytest.mark.slow)
    elif source.kind == "hostile" and source.name in (faults or {}):
        marks.append(pytest.mark.xfail(strict=True, reason=faults[source.name]))
    return pytest.param(source, id=str(source), marks=marks)


EXTERNAL = _external()
EXAMPLES = [Source("example", p.name) for p in sorted((ROOT / "examples").glob("*.mcl"))]
EXAMPLES.append(Source("core", "everything"))   # every feature of the core, odd ids too
TEMPLATES = [Source("template", names.split(",")[0]) for names, _, _ in pipeline.templates()]
HOSTILES = [Source("hostile", name) for name in HOSTILE]
ALL = EXTERNAL + EXAMPLES + TEMPLATES + HOSTILES


@pytest.fixture(scope="module")
def file_of(tmp_path_factory):
    """The file of a source: found, or written by our writer once per module."""
    folder = tmp_path_factory.mktemp("differential")
    written: dict[str, Path] = {}

    def path(source: Source) -> Path:
        if source.kind == "external":
            if source.row is not None:
                return corpus_file(source.row)
            found = _found(source.name)
            if found is None:
                pytest.skip("the external corpus is not here (looked in "
                            "$MCL2PNML_EXTERNAL_NETS, ../shared/external-nets and "
                            "tests/data/external)")
            return found
        if source.kind == "hostile":
            return HOSTILE_DIR / source.name
        key = str(source)
        if key not in written:
            if source.kind == "template":
                net = pipeline.template_net(source.name)
            elif source.kind == "core":
                net = everything()
            else:
                net = pipeline.compile_file(ROOT / "examples" / source.name)
            # without a layout: positions change no reading (the hostile files hold graphics
            # of their own), and laying out costs more than the three readings together
            written[key] = pipeline.save_pnml(net, folder / f"{source.kind}-{source.name}.pnml",
                                              "none")
        return written[key]

    return path


def assert_located(error: Mcl2PnmlError, path: Path) -> None:
    """Every message of a refusal names the file, the line and the column."""
    for e in getattr(error, "errors", [error]):
        where = e.location
        assert where is not None and where.line is not None and where.column is not None, (
            f"a refusal of {path.name} without its line and column: {e}")
        assert str(e).startswith(f"{path}:{where.line}:{where.column}: "), str(e)


@lru_cache(maxsize=None)
def _our_reading(path: Path):
    """``read_pnml(path)``: the net, or the refusal. Computed once per file: the files do not
    change during a run, and each was read again by the verifypn, pm4py and LoLA tests."""
    try:
        return read_pnml(path)
    except Mcl2PnmlError as e:
        return e


def _read(path: Path):
    """Our reading of ``path``, as ``read_pnml`` gives it (a refusal raised)."""
    reading = _our_reading(path)
    if isinstance(reading, Mcl2PnmlError):
        raise reading
    return reading


def read_as_verifypn(path: Path) -> Mcl2PnmlError | None:
    """Our reading of ``path`` against verifypn's: the refusal, located, or None after
    asserting that we read verifypn's net."""
    theirs = pnml_peer.verifypn_net(path)
    try:
        ours = _read(path)
    except Mcl2PnmlError as e:
        assert_located(e, path)
        return e
    assert not isinstance(theirs, pnml_peer.Refused), (
        f"we read {path.name}, but verifypn reads no net from it ({theirs.why}): "
        "refuse it, or find why verifypn does not read it")
    found = pnml_peer.differences(pnml_peer.read_net(ours), theirs)
    assert not found, f"we read {path.name} otherwise than verifypn:\n  " + "\n  ".join(found)
    return None


@pytest.mark.parametrize("source", [_param(s) for s in EXTERNAL + EXAMPLES + TEMPLATES])
def test_refused_or_read_as_verifypn(source, file_of):
    refused = read_as_verifypn(file_of(source))
    if source.kind != "external":
        # our writer's files are the ones our tools exchange: refusing one is a fault
        assert refused is None, f"we refuse the file our writer wrote: {refused}"


@pytest.mark.parametrize("source", [_param(s, FAULTS) for s in HOSTILES])
def test_a_hostile_file_is_refused_or_read_as_verifypn(source, file_of):
    path = file_of(source)
    refused = read_as_verifypn(path)
    expected = HOSTILE[source.name]
    if expected == READ:
        assert refused is None, f"{source.name} must be read: {refused}"
    else:
        assert refused is not None, f"{source.name} must be refused (/{expected}/)"
        said = " ".join(e.message for e in getattr(refused, "errors", [refused]))
        assert re.search(expected, said), f"the refusal does not say /{expected}/: {refused}"


def test_the_hostile_table_names_every_file():
    assert sorted(HOSTILE) == sorted(p.name for p in HOSTILE_DIR.glob("*.pnml"))


def _ours_or_skip(path: Path):
    try:
        return pnml_peer.read_net(_read(path))
    except Mcl2PnmlError:
        pytest.skip("we refuse the file: no net of ours to compare")


@pytest.mark.parametrize("source", [_param(s) for s in ALL])
def test_pm4py_reads_the_net_we_read(source, file_of):
    _assert_read_alike(file_of(source), pnml_peer.pm4py_net, "pm4py", "pm4py")


@pytest.mark.parametrize("source", [_param(s, FAULTS) for s in ALL])
def test_lola_reads_the_net_we_read(source, file_of):
    """LoLA reads only the 2009 P/T net type: a file of the core model's type (pm4py's,
    WoPeD's) is no net to it, and is skipped."""
    _assert_read_alike(file_of(source), pnml_peer.lola_net, "lola", "LoLA")


def _assert_read_alike(path: Path, read, peer: str, name: str) -> None:
    """The peer (``read``, ``peer`` as :func:`pnml_peer.differences` names it) reads the net
    we read from ``path``; skipped where either of us reads none."""
    ours = _ours_or_skip(path)
    theirs = read(path)
    if isinstance(theirs, pnml_peer.Refused):
        pytest.skip(f"{name} reads no net from the file")
    found = pnml_peer.differences(ours, theirs, peer=peer)
    assert not found, f"{name} reads {path.name} otherwise than we do:\n  " + "\n  ".join(found)


def _outcome(path: Path):
    """The strict reading of ``path``: the net, or every message of its refusal."""
    try:
        return read_pnml(path)
    except Mcl2PnmlError as e:
        return [str(x) for x in getattr(e, "errors", [e])]


INVALID_DIRS = ("invalid", "foreign", "schema/invalid", "schema/valid", "hostile")
LOCAL = sorted(p for d in INVALID_DIRS for p in (DATA / "pnml" / d).glob("*.pnml"))


@pytest.mark.parametrize("source", [_param(s) for s in EXTERNAL + EXAMPLES + TEMPLATES]
                         + [pytest.param(p, id=str(p.relative_to(DATA))) for p in LOCAL])
def test_the_fast_paths_read_as_the_careful_one(source, file_of, monkeypatch):
    """The shapes writers use are read in few steps, anything else the careful way
    (mcl2pnml/io/pnml/strict.py): both give the same net, or the same messages."""
    from mcl2pnml.io.pnml import strict
    path = source if isinstance(source, Path) else file_of(source)
    fast = _outcome(path)
    monkeypatch.setattr(strict, "FAST", False)
    assert _outcome(path) == fast
