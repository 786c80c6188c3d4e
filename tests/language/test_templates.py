"""The paper's nets as templates: each one proven, as the paper asks of every net.

Proven for every template, composed as the paper analyses it (a pattern with
its primitive, a structure with reduced tasks), from M0 with and without the
abort place A: every place 1-bounded; from every reachable marking a final
marking can still be reached; every final marking is the rest marking plus
exactly one of OK, FAIL, ABORTED, with no abort token left inside.
"""

import pytest

from mcl2pnml.analysis.behaviour import behaviour
from mcl2pnml.analysis.statespace.explore import explore
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.io.pnml import parse_pnml, to_pnml
from mcl2pnml.language.library import Library, default_library, source_places
from mcl2pnml.language.template_parser import CONTROL, TemplateKind, parse_template

from helpers import DATA, assert_error_golden
from paper_repro import nets

LIB = default_library()
ALL = [t.name for t in LIB.unique()]
RESULTS = {"OK", "FAIL", "ABORTED"}
INVALID = sorted((DATA / "templates" / "invalid").glob("*.pnt"))


def test_the_library_has_the_paper_nets_and_the_cli_names():
    for name in ("primitive", "task", "task-reduced", "sequence", "parallel", "if-then-else",
                 "while", "monitor", "null", "AchieveGoal", "KeepGoal", "KeepTwoGoals"):
        LIB.get(name)
    with pytest.raises(Mcl2PnmlError, match="unknown template 'sequense'; did you mean 'sequence'"):
        LIB.get("sequense")


def test_places_carry_the_papers_names():
    task = LIB.composed("task")
    assert {p.id for p in task.places} == set(
        "ON OFF E D C S1 S2 B A MTX OK FAIL ABORTED EXE E_OK E_FAIL W_OK W_FAIL W_A".split())
    seq = LIB.composed("sequence")
    assert {f"T{i}_{p}" for i in (1, 2) for p in CONTROL} <= {p.id for p in seq.places}


@pytest.mark.parametrize("name", [n for n in ALL if LIB.get(n).kind is not TemplateKind.PRIMITIVE])
@pytest.mark.parametrize("with_abort", [True, False], ids=["with-A", "without-A"])
def test_every_template_is_safe_terminating_and_reusable(name, with_abort):
    net = LIB.composed(name)
    start = dict(net.initial) if with_abort else {p: n for p, n in net.initial.items() if p != "A"}
    space = explore(net, start)
    b = behaviour(space)
    assert space.safe, f"{name} is not 1-bounded"
    assert b.final_always_reachable, f"{name} can get stuck"
    assert b.deadlock_free and b.reusable
    rest = {p for p in start if p not in ("B", "A")}
    for final in b.terminal:
        marked = set(final)
        results = marked & RESULTS
        assert len(results) == 1, final
        leftover = marked - results - rest
        # only the top-level abort place may remain (the paper's abort problem)
        assert leftover <= {"A"} and (not leftover or results != {"ABORTED"}), final
        assert not any(p.endswith("_A") for p in marked), "an abort token was left inside"


def test_the_primitive_is_reusable_after_enable_and_disable():
    space = explore(LIB.composed("primitive"), {"OFF": 1, "C": 1, "E": 1, "D": 1})
    assert [space.format(n) for n in space.terminal] == [["C", "OFF"]]
    assert behaviour(space).reusable


def test_a_task_called_again_at_once_stays_safe():
    """The composition that shows the mutex is never freed with a request pending."""
    space = explore(nets.called_again(LIB.composed("task")))
    assert space.safe
    assert nets.mutex_free_while_pending(space) == []


def test_the_task_as_the_paper_describes_it_is_not():
    space = explore(nets.called_again(nets.literal_task(LIB)))
    assert not space.safe
    bad = nets.mutex_free_while_pending(space)
    assert bad and space.path_to(bad[0])[:2] == ["t01", "t03"]


def test_template_pnml_starts_from_the_papers_m0(assert_valid):
    expected = {"primitive": {"OFF", "C"}, "task": {"B", "A", "MTX", "OFF", "C"},
                "task-reduced": {"B", "A", "MTX"},
                "sequence": {"B", "A", "MTX", "T1_MTX", "T2_MTX"}}
    for name, m0 in expected.items():
        data = to_pnml(LIB.composed(name))
        assert_valid(data, name)
        net = parse_pnml(data)
        assert set(net.initial) == m0 and set(net.initial.values()) == {1}


def test_adding_a_template_file_adds_a_structure(tmp_path, monkeypatch):
    (tmp_path / "race.pnt").write_text('''\
structure race "T1 and T2 at once; the first to end OK wins, the other is aborted"
uses structure T1, T2
place B = 1 interface
place A = 1 interface
place MTX = 1 interface
place OK interface
place FAIL interface
place ABORTED interface
place RUN
place STOP2
place STOP1
place LOST
transition s: B, MTX -> T1_B, T2_B, RUN
transition w1: RUN, T1_OK -> T2_A, STOP2
transition w2: RUN, T2_OK -> T1_A, STOP1
transition l1: RUN, T1_FAIL -> T2_A, LOST
transition l2: RUN, T2_FAIL -> T1_A, LOST
transition e1: STOP2, T2_ABORTED -> OK, MTX
transition e2: STOP2, T2_OK, T2_A -> OK, MTX
transition e3: STOP2, T2_FAIL, T2_A -> OK, MTX
transition e4: STOP1, T1_ABORTED -> OK, MTX
transition e5: STOP1, T1_OK, T1_A -> OK, MTX
transition e6: STOP1, T1_FAIL, T1_A -> OK, MTX
transition f1: LOST, T1_ABORTED -> FAIL, MTX
transition f2: LOST, T2_ABORTED -> FAIL, MTX
transition f3: LOST, T1_OK, T1_A -> FAIL, MTX
transition f4: LOST, T1_FAIL, T1_A -> FAIL, MTX
transition f5: LOST, T2_OK, T2_A -> FAIL, MTX
transition f6: LOST, T2_FAIL, T2_A -> FAIL, MTX
transition t0: B, A -> ABORTED
''')
    monkeypatch.setenv("MCL2PNML_TEMPLATE_PATH", str(tmp_path))
    lib = Library.load()
    assert lib.get("race").kind is TemplateKind.STRUCTURE
    space = explore(lib.composed("race"), {"B": 1, "MTX": 1, "T1_MTX": 1, "T2_MTX": 1})
    assert space.safe
    assert {tuple(space.format(n)) for n in space.terminal} == {
        ("MTX", "OK", "T1_MTX", "T2_MTX"), ("FAIL", "MTX", "T1_MTX", "T2_MTX")}


def test_source_places_are_the_inputs():
    assert source_places(LIB.get("primitive").net) == {"E", "D"}
    assert source_places(LIB.composed("task")) == {"B", "A"}


@pytest.mark.parametrize("path", INVALID, ids=lambda p: p.name)
def test_bad_templates_give_the_expected_message(path):
    with pytest.raises(Mcl2PnmlError) as info:
        parse_template(path.read_text(), path.name, ("E", "D", "OFF", "S1", "S2", "ON"))
    assert_error_golden(path, info.value)


def test_docs_and_tags_reach_the_payload():
    task = LIB.get("task").net
    t03 = task.transition_index["t03"]
    assert t03.payload["timeout"] is True and "time-out" in t03.payload["doc"]
    assert LIB.get("primitive").net.transition_index["achieved"].payload["event"] == "achieved"
