"""Real P/T nets written by other tools, with their published answers.

The table ``tests/data/external/corpus.json`` says, for each file, where it
comes from (repository, path, commit, the tool that wrote it), what was
published about it, what TAPAAL's verifypn and LoLA answered on it, and what
we must do: find its state count and whether it has a dead marking, or refuse
it with a located message naming the construct a P/T net cannot say
(inhibitor, transport and timed arcs, coloured content, guards).
PROVENANCE.md beside it tells the sources.

Files are read strictly by default (``mcl2pnml/io/pnml/strict.py``): the net
verifypn reads, or a refusal at a line and column. A row whose ``strict``
says ``refuse`` (a regular expression on one of the located messages) is a
file the strict reading refuses, another tool's dialect or a net of another
class; its ``expect`` is then what the forgiving reading (``lenient=True``)
finds or refuses. Every other row is read strictly, as the same net as the
forgiving reading makes of it.

The files themselves are other projects' data and are not kept in this
repository: the tests look for them in ``$MCL2PNML_EXTERNAL_NETS``, then in
``../shared/external-nets`` beside the repository, then in
``tests/data/external`` (a local copy), and skip, saying so, where they are not.
Each file found must be the one the table describes (its SHA-256).
"""
from __future__ import annotations

import hashlib
import json
import os
import re
from pathlib import Path

import pytest

import peers
from helpers import DATA, ROOT
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.pipeline import load_net
from mcl2pnml.analysis.statespace.explore import explore

TABLE_DIR = DATA / "external"
ROWS = json.loads((TABLE_DIR / "corpus.json").read_text())
LOCATED = re.compile(r":\d+:\d+")


def _corpus_dirs() -> list[Path]:
    dirs = []
    if os.environ.get("MCL2PNML_EXTERNAL_NETS"):
        dirs.append(Path(os.environ["MCL2PNML_EXTERNAL_NETS"]))
    dirs += [ROOT.parent / "shared" / "external-nets", TABLE_DIR]
    return dirs


def corpus_file(row: dict) -> Path:
    """The file the row describes, checked against its SHA-256; skips if absent."""
    for folder in _corpus_dirs():
        path = folder / row["file"]
        if path.is_file():
            digest = hashlib.sha256(path.read_bytes()).hexdigest()
            assert digest == row["sha256"], f"{path} is not the file the table describes"
            return path
    # one reason for every absent file, so that the summary says it in one line
    pytest.skip("a file of the external corpus is not here (looked in "
                "$MCL2PNML_EXTERNAL_NETS, ../shared/external-nets and tests/data/external); "
                "tests/data/external/PROVENANCE.md says where each comes from")


def _params(rows):
    return [pytest.param(r, id=r["file"], marks=[pytest.mark.slow] if r.get("slow") else [])
            for r in rows]


ACCEPTED = [r for r in ROWS if "refuse" not in r["expect"]]
REFUSED = [r for r in ROWS if "refuse" in r["expect"]]


def test_the_table_is_whole():
    """Every row says where its file comes from and what is expected of it."""
    assert len({r["file"] for r in ROWS}) == len(ROWS)
    for r in ROWS:
        for key in ("repo", "source", "writer", "sha256", "published", "expect"):
            assert r.get(key) is not None or key == "commit", (r["file"], key)
        assert r["repo"].startswith("PyPI") or re.fullmatch(r"[0-9a-f]{40}", r["commit"]), r["file"]


STRICT_REFUSED = [r for r in ROWS if "strict" in r]
STRICT_READ = [r for r in ROWS if "strict" not in r]


@pytest.mark.parametrize("row", _params(ACCEPTED))
def test_we_find_the_published_answer(row):
    """Strictly where the strict reading reads the file, else the forgiving way."""
    net = load_net(corpus_file(row), lenient="strict" in row)
    space = explore(net)
    want = row["expect"]
    if "bounded" in want:
        assert space.bounded == want["bounded"]
    if "states" in want:
        assert space.bounded, "a net with a published state count is bounded"
        assert space.states == want["states"], row["published"]
    if want.get("deadlock") is not None:
        assert (len(space.terminal) > 0) == want["deadlock"]


@pytest.mark.parametrize("row", _params(REFUSED))
def test_we_refuse_what_a_pt_net_cannot_say(row):
    """Even the forgiving reading refuses these (the strict one too: test_strict_reading)."""
    path = corpus_file(row)
    with pytest.raises(Mcl2PnmlError) as caught:
        load_net(path, lenient=True)
    message = str(caught.value)
    assert LOCATED.search(message), f"the refusal is not located (file:line:col): {message}"
    # the messages themselves, not the source lines shown under them
    said = " ".join(e.message for e in getattr(caught.value, "errors", [caught.value]))
    assert re.search(row["expect"]["refuse"], said, re.IGNORECASE), (
        f"the refusal does not name the construct /{row['expect']['refuse']}/: {message}")


def test_every_row_the_strict_reading_refuses_says_so():
    """Refused by either reading, refused by the strict one: its row says how."""
    assert all("strict" in r for r in REFUSED)
    assert all(set(r["strict"]) == {"refuse"} and re.compile(r["strict"]["refuse"])
               for r in STRICT_REFUSED)


@pytest.mark.parametrize("row", _params(STRICT_REFUSED))
def test_the_strict_reading_refuses_these_at_a_line(row):
    path = corpus_file(row)
    with pytest.raises(Mcl2PnmlError) as caught:
        load_net(path)
    errors = getattr(caught.value, "errors", [caught.value])
    named = [e for e in errors if re.search(row["strict"]["refuse"], e.message)]
    assert named, (f"the strict refusal does not name /{row['strict']['refuse']}/: "
                   f"{str(caught.value)[:3000]}")
    # located in this file, at a line and a column
    assert all(e.location.file == str(path) and e.location.line and e.location.column
               for e in named), str(caught.value)[:3000]


@pytest.mark.parametrize("row", _params(STRICT_READ))
def test_the_strict_reading_reads_the_others_as_the_forgiving_one(row):
    path = corpus_file(row)
    assert load_net(path) == load_net(path, lenient=True)


VERIFYPN_READS = [r for r in ACCEPTED if r["peers"]["verifypn"] is not None]
LOLA_READS = [r for r in ACCEPTED if r["peers"]["lola"] is not None]


@pytest.mark.parametrize("row", _params(VERIFYPN_READS))
def test_verifypn_agrees(row, tmp_path):
    path = corpus_file(row)
    assert peers.verifypn_states(path) == row["expect"]["states"]
    if row["expect"].get("deadlock") is not None:
        assert peers.verifypn_deadlock(path, tmp_path) == row["expect"]["deadlock"]


@pytest.mark.parametrize("row", _params(LOLA_READS))
def test_lola_agrees(row):
    assert peers.lola_states(corpus_file(row)) == row["expect"]["states"]


@pytest.mark.parametrize("row", _params([r for r in ACCEPTED if r.get("pm4py_reads")]))
def test_pm4py_agrees(row):
    pm4py = pytest.importorskip("pm4py")
    from pm4py.objects.petri_net.utils.reachability_graph import construct_reachability_graph

    net, initial, _ = pm4py.read_pnml(str(corpus_file(row)))
    graph = construct_reachability_graph(net, initial)
    assert len(graph.states) == row["expect"]["states"]
    assert any(not s.outgoing for s in graph.states) == row["expect"]["deadlock"]
