"""`mcl2pnml query`: the Model Checking Contest's own questions, answered as the contest's
tools agreed in 2021.

``../shared/external-nets/mcc-queries`` holds 19 contest models, each with its 2021
formula files (reachability, CTL and LTL over cardinality and fireability atoms, upper
bounds: 16 formulas each) and, in ``oracle/``, the consensus verdicts, with the
generic examinations' (a reachable deadlock, one-safety, a stable marking,
quasi-liveness, liveness). Every answer must equal the oracle's, and every question be
answered: a test suite nobody here wrote. ``make test`` takes all 19 (a few seconds in
all: the LTL products are searched on the fly, tests/analysis/test_graph_kernels.py).

And ours: a mission's properties written by ``compile --properties`` and read back give
``analyze --properties``'s verdicts; a malformed file is one message at its line and
column (tests/data/mcc/invalid, each with its ``.expected``).
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from mcl2pnml.analysis.contest import answers as mcc
from mcl2pnml.analysis.contest.generic import GENERIC, generic
from mcl2pnml.analysis.contest.reachability_queries import settled_by_state_equation
from mcl2pnml.analysis.checking.observers import Status
from mcl2pnml.analysis.statespace.explore import ExplorationLimit
from helpers import DATA, ROOT, assert_error_golden, one_error, run_cli
from mcl2pnml import pipeline
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.io.mccquery import parse_queries, read_queries

CORPUS = ROOT.parent / "shared" / "external-nets" / "mcc-queries"
FILES = ("ReachabilityCardinality", "ReachabilityFireability", "CTLCardinality",
         "CTLFireability", "LTLCardinality", "LTLFireability", "UpperBounds")
MODELS = sorted(p.name for p in CORPUS.iterdir() if p.is_dir() and p.name != "oracle") \
    if CORPUS.is_dir() else []


def _oracle(model: str) -> dict[str, str]:
    verdicts = {}
    for f in (CORPUS / "oracle").glob(f"{model}-*.out"):
        for line in f.read_text().splitlines():
            m = re.match(r"FORMULA (\S+) (\S+) TECHNIQUES", line)
            if m:
                verdicts[m.group(1)] = m.group(2)
    return verdicts


def _shown(value) -> str:
    return ("TRUE" if value else "FALSE") if isinstance(value, bool) else str(value)


def _agrees(model: str) -> None:
    folder = CORPUS / model
    net = pipeline.load_net(folder / "model.pnml")
    queries = [x for name in FILES for x in read_queries(folder / f"{name}.xml")]
    answers = mcc.answer(net, queries) + generic(net)
    oracle = _oracle(model)
    assert len(answers) == len(queries) + len(GENERIC) == len(oracle), model
    unanswered = [(a.id, a.reason) for a in answers if a.value is None]
    assert not unanswered, unanswered
    wrong = [(a.id, _shown(a.value), oracle[a.id]) for a in answers
             if oracle[a.id] != "?" and _shown(a.value) != oracle[a.id]]
    assert not wrong, f"{model}: ours, the oracle's: {wrong}"


def _corpus():
    if not MODELS:
        pytest.skip(f"{CORPUS} is not there (../shared beside the checkout)")


@pytest.mark.parametrize("model", MODELS or ["(none)"])
def test_every_answer_is_the_contests(model):
    _corpus()
    _agrees(model)


def test_the_command_prints_the_contests_answer_lines(tmp_path):
    _corpus()
    folder = CORPUS / "TokenRing-PT-005"
    out = run_cli("query", folder / "model.pnml", folder / "UpperBounds.xml",
                  "--examination", "ReachabilityDeadlock")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert len(lines) == 17 and all(line.startswith("FORMULA ") for line in lines)
    oracle = _oracle("TokenRing-PT-005")
    for line in lines:
        _, fid, value, *_ = line.split()
        assert oracle[fid] == value, line
    data = json.loads(run_cli("query", folder / "model.pnml", folder / "UpperBounds.xml",
                              "--json").stdout)
    assert [a["id"] for a in data["answers"]] == [line.split()[1] for line in lines[:16]]
    # past the limits: what needs the graph (CTL beyond E F and A G) has no answer, said,
    # and exit 3
    out = run_cli("query", folder / "model.pnml", folder / "CTLCardinality.xml",
                  "--max-states", "2")
    assert out.returncode == 3 and "CANNOT_COMPUTE" in out.stdout and "limit" in out.stdout


@pytest.mark.parametrize("mission", ["sauce", "docking"])
def test_a_missions_properties_read_back_give_analyzes_verdicts(mission, tmp_path):
    """``compile --properties`` writes them in the contest's categories; this command
    reads them back and answers as ``analyze --properties`` (on the untimed net)."""
    path = ROOT / "examples" / f"{mission}.mcl"
    net, props = pipeline.properties_of(path, extra=path.with_suffix(".false.props"))
    written = pipeline.save_property_queries(props, tmp_path / mission)
    verdicts = {v.property.name: v.status for v in pipeline.check_properties(net, props)}
    answered: dict[str, set] = {}
    for file, _ in written:
        for a in mcc.answer(net, read_queries(file)):
            answered.setdefault(a.id, set()).add(a.value)
    assert set(answered) <= set(verdicts) and answered, (answered, verdicts)
    for name, values in answered.items():
        assert values == {verdicts[name] is Status.HOLDS}, (name, values, verdicts[name])


INVALID = sorted((DATA / "mcc" / "invalid").glob("*.xml"))


@pytest.mark.parametrize("path", INVALID, ids=lambda p: p.stem)
def test_a_bad_file_is_one_message_at_its_line_and_column(path):
    with pytest.raises(Mcl2PnmlError) as e:
        parse_queries(path.read_bytes(), path.name)
    assert_error_golden(path.with_suffix(".expected"), e.value)


@pytest.mark.parametrize("large", [False, True], ids=["small", "past-the-graph"])
@pytest.mark.parametrize("formula, said", [
    ("<place-bound><place>Nowhere</place></place-bound>", "no place 'Nowhere'"),
    ("<exists-path><next><is-fireable><transition>never</transition></is-fireable></next>"
     "</exists-path>", "no transition 'never'")], ids=["place", "transition"])
def test_a_name_the_net_does_not_have_is_refused_at_its_line(tmp_path, formula, said, large):
    # refused before any answer whatever the net's size: a net past the first exploration
    # once had it left unanswered, its limits blamed
    from test_found_markings import _toggles
    bad = tmp_path / "q.xml"
    bad.write_text('<?xml version="1.0"?>\n<property-set xmlns="http://mcc.lip6.fr/">\n'
                   "  <property><id>ok</id><formula><place-bound><place>on0</place>"
                   "</place-bound></formula></property>\n"
                   f"  <property><id>p</id><formula>{formula}</formula></property>\n"
                   "</property-set>\n")
    net = tmp_path / "net.pnml"
    net.write_bytes(pipeline.to_pnml_bytes(_toggles(30 if large else 2)))
    out = run_cli("query", net, bad, "--max-states", "1000")
    one_error(out, "q.xml:4:3:", said)
    assert out.stdout == ""


#: The models whose questions without the graph ``make test`` asks (every model's behind
#: ``slow``): safe and not, each kind of answer given without the graph among them.
#: Referendum-PT-0010 (40 s, most of it CTL on the fly, which
#: tests/analysis/test_ctl_on_the_fly.py checks in the portfolio) is behind ``slow``.
WITHOUT_GRAPH = {"CircadianClock-PT-000001", "CSRepetitions-PT-02", "Eratosthenes-PT-010",
                 "FMS-PT-00002", "NeoElection-PT-2", "TokenRing-PT-005"}


def _some(models):
    """The models of ``models`` in ``make test``; every one behind ``slow``."""
    return [m if m in models else pytest.param(m, marks=pytest.mark.slow)
            for m in MODELS] or ["(none)"]


@pytest.mark.parametrize("model", _some(WITHOUT_GRAPH))
def test_past_the_graphs_limits_what_is_answered_is_the_contests(model, monkeypatch):
    """When the reachability graph cannot be built, the reachability questions are
    searched on the fly and what the initial marking and the P-invariants settle is
    answered: every answer given is the oracle's, the rest unanswered with the reason."""
    _corpus()
    folder = CORPUS / model
    net = pipeline.load_net(folder / "model.pnml")
    queries = [x for name in FILES for x in read_queries(folder / f"{name}.xml")]
    monkeypatch.setattr(mcc, "_space", lambda *a: (None, "the state space is past its limit",
                                                    ExplorationLimit("past it")))
    answers = mcc.answer(net, queries)
    oracle = _oracle(model)
    wrong = [(a.id, _shown(a.value), oracle[a.id]) for a in answers
             if a.value is not None and oracle[a.id] not in ("?", _shown(a.value))]
    assert not wrong, f"{model}: ours, the oracle's: {wrong}"
    assert all(a.reason for a in answers if a.value is None)
    assert any(a.value is not None for a in answers), "nothing settled without the graph"


#: The models whose generic examinations, the graph withheld, take a few seconds at most;
#: the others (up to minutes: each transition's ``A G E F`` searched on the fly) are slow.
GENERIC_WITHOUT_GRAPH = {"CSRepetitions-PT-02", "Eratosthenes-PT-010", "NeoElection-PT-2",
                         "Philosophers-PT-000005", "Philosophers-PT-000010", "Raft-PT-02",
                         "Railroad-PT-005", "Referendum-PT-0010", "ShieldIIPt-PT-001A"}


@pytest.mark.parametrize("model", _some(GENERIC_WITHOUT_GRAPH))
def test_past_the_graphs_limits_the_generic_examinations_are_the_contests(model,
                                                                          monkeypatch):
    """Without the graph, each generic examination is what its atoms say (a deadlock, a
    place's bound, a transition fired...), through the formula files' portfolio: every
    answer given is the oracle's, the rest unanswered with the reason."""
    _corpus()
    net = pipeline.load_net(CORPUS / model / "model.pnml")
    monkeypatch.setattr(mcc, "_space", lambda *a: (None, "the state space is past its limit",
                                                    ExplorationLimit("past it")))
    answers = generic(net)
    oracle = _oracle(model)
    wrong = [(a.id, _shown(a.value), oracle[a.id]) for a in answers
             if a.value is not None and oracle[a.id] not in ("?", _shown(a.value))]
    assert not wrong, f"{model}: ours, the oracle's: {wrong}"
    assert all(a.reason for a in answers if a.value is None)
    if model in GENERIC_WITHOUT_GRAPH:     # on these, every one is settled so
        assert all(a.value is not None for a in answers), answers


@pytest.mark.parametrize("model", _some(WITHOUT_GRAPH))
def test_what_the_state_equation_proves_is_the_contests(model):
    """Every reachability question of every file the state equation settles (``E F φ``
    false, ``A G φ`` true) is settled as the oracle has it; on these models it settles
    some (on the 19: 247 answers)."""
    _corpus()
    folder = CORPUS / model
    net = pipeline.load_net(folder / "model.pnml")
    queries = [x for name in FILES for x in read_queries(folder / f"{name}.xml")]
    settled = settled_by_state_equation(net, queries)
    oracle = _oracle(model)
    wrong = [(k, _shown(v), oracle[k]) for k, (v, _) in settled.items()
             if oracle[k] not in ("?", _shown(v))]
    assert not wrong, f"{model}: ours, the oracle's: {wrong}"
    assert settled, "the state equation settled nothing"


@pytest.mark.parametrize("model", _some(WITHOUT_GRAPH - {"FMS-PT-00002"} | {"Raft-PT-02"}))
def test_the_reduced_search_answers_as_the_contest(model):
    """``--stubborn``: the reachability questions of a net proven 1-safe searched on the fly
    under stubborn sets; the answers stay the oracle's, and on a net not proven safe the
    search runs unreduced."""
    _corpus()
    folder = CORPUS / model
    net = pipeline.load_net(folder / "model.pnml")
    queries = [x for name in FILES[:2] for x in read_queries(folder / f"{name}.xml")]
    answers = mcc.answer(net, queries, stubborn=True)
    oracle = _oracle(model)
    wrong = [(a.id, _shown(a.value), oracle[a.id]) for a in answers
             if oracle[a.id] not in ("?", _shown(a.value))]
    assert not wrong, f"{model}: ours, the oracle's: {wrong}"
    assert all(a.value is not None for a in answers)


@pytest.mark.parametrize("tool", ["ours", "verifypn", "lola"])
def test_the_benchmark_reads_each_tools_answers(tool):
    """bench/mcc_queries.py's commands, on one model's LTL file: every tool's answer lines
    are read (LoLA pads them with two spaces) and are the oracle's."""
    _corpus()
    from bench import mcc_queries
    model = CORPUS / "TokenRing-PT-005"
    command = mcc_queries.commands(model, "LTLCardinality")[tool]
    if tool != "ours" and not Path(command[0]).is_file():
        pytest.skip(f"{command[0]} is not there (the benchmark runs the peers of ../shared)")
    seconds, _, out = mcc_queries.run(command)
    assert seconds is not None, f"{tool} past {mcc_queries.TIMEOUT} s"
    got = mcc_queries.answers(out)
    oracle = _oracle("TokenRing-PT-005")
    assert len(got) == 16 and all(oracle[k] in (v, "?") for k, v in got.items()), (got, out)


@pytest.mark.parametrize("model", ["TokenRing-PT-005", "CircadianClock-PT-000001", "Eratosthenes-PT-010"])
def test_without_the_loops_in_c_the_answers_are_the_same(model, monkeypatch):
    """The searches in Python (a machine where C was not built) give the contest's
    answers too, on three models."""
    _corpus()
    from mcl2pnml.analysis.statespace.loops import python as _graph_loops
    monkeypatch.setattr(mcc, "_loops", _graph_loops)
    _agrees(model)


def test_the_command_offers_every_generic_examination_the_library_answers():
    """``query --examination`` takes its choices from a list kept apart (the command line
    must not import the analysis to parse its options): it is the library's."""
    from mcl2pnml.commands.query import EXAMINATIONS
    assert EXAMINATIONS == GENERIC
