"""The interface contract of tasks and structures (analysis/checking/contract.py): every template of
the library keeps it, with its children reduced (Fig. 3), and each clause is broken, and
said so with the run that shows it, by a net made to break it."""
from __future__ import annotations

import pytest

from mcl2pnml.analysis.checking.contract import Clause, NoInterface, check_contract, restricted, roles
from mcl2pnml.core.net import Net, NetBuilder
from mcl2pnml.language.library import default_library
from mcl2pnml.language.template_parser import TemplateKind

LIBRARY = default_library()
COMPONENTS = [t.name for t in LIBRARY.unique() if t.kind is not TemplateKind.PRIMITIVE]


@pytest.mark.parametrize("name", COMPONENTS)
def test_every_template_keeps_the_contract_with_its_children_reduced(name):
    verdict = check_contract(LIBRARY.composed(name))
    assert verdict.kept, [str(b) for b in verdict.breaches]
    assert verdict.markings >= 4    # rest, rest + A, and two starts, each explored


def reduced(*drop: str, extra=(), places=(), transitions=()) -> Net:
    """The reduced task (Fig. 3) without the arcs ``drop`` names ("t2:OK" is t2 -> OK),
    with ``extra`` arcs and the new ``places`` and ``transitions`` they join added: a
    component made to break a clause."""
    net = LIBRARY.reduced.net
    kept = tuple(a for a in net.arcs if f"{a.source}:{a.target}" not in drop
                 and f"{a.target}:{a.source}" not in drop)
    b = NetBuilder("broken")
    for p in net.places:
        b.place(p.id, net.initial[p.id], interface=p.interface)
    for p in places:
        b.place(p)
    for t in (*(t.id for t in net.transitions), *transitions):
        b.transition(t)
    for a in kept:
        b.arc(a.source, a.target)
    for source, target in extra:
        b.arc(source, target)
    return b.build()


@pytest.mark.parametrize("net,clause,start,why", [
    # t2 gives MTX back twice: two tokens in MTX
    (lambda: reduced(extra=[("t2", "MTX")]), Clause.SAFE, "rest + B", "MTX holds two tokens"),
    # t3 marks nothing: the run stops with no result
    (lambda: reduced("t3:FAIL"), Clause.ENDS, "rest + B", "no result"),
    # t2 forgets to give MTX back
    (lambda: reduced("t2:MTX"), Clause.ENDS, "rest + B", "MTX not back at rest"),
    # t4 leaves A marked when it ends ABORTED
    (lambda: reduced("A:t4"), Clause.ABORT, "rest + B", "ended ABORTED with no abort asked"),
    # t5 fires on A alone: an abort after the end restarts nothing, it must stay inert
    (lambda: reduced("B:t5"), Clause.IDLE, "rest + A", "t5 can fire"),
])
def test_each_clause_broken_is_said_with_its_run(net, clause, start, why):
    verdict = check_contract(net())
    assert not verdict.kept
    found = [b for b in verdict.breaches if b.clause is clause and b.start == start]
    assert found, [str(b) for b in verdict.breaches]
    assert why in str(found[0])


def test_a_component_that_can_run_for_ever_breaks_always_ends():
    """The reduced task with a way into a loop it never leaves (EXE -> trap -> LOOP, and
    spin: LOOP -> LOOP): no dead marking there, and no end either."""
    verdict = check_contract(reduced(extra=[("EXE", "trap"), ("trap", "LOOP"), ("LOOP", "spin"),
                                   ("spin", "LOOP")], places=["LOOP"],
                            transitions=["trap", "spin"]))
    [breach] = [br for br in verdict.breaches if br.start == "rest + B"]
    assert breach.clause is Clause.ALWAYS_ENDS and breach.path == ("t1", "trap")


def test_a_net_without_the_control_interface_is_refused_naming_what_lacks():
    b = NetBuilder("plain")
    b.place("B", 1, interface="B")
    b.place("OK", interface="OK")
    with pytest.raises(NoInterface, match="no place labelled A, FAIL, ABORTED"):
        roles(b.build())


def test_a_result_given_before_the_rest_is_restored_breaks_result_last():
    """t2 marks OK, and only a later step gives MTX back: a caller taking OK at once could
    start the component while it still holds its mutex (the dead markings are all fine)."""
    verdict = check_contract(reduced("t2:MTX", extra=[("t2", "HOLD"), ("HOLD", "t2b"), ("t2b", "MTX")],
                            places=["HOLD"], transitions=["t2b"]))
    [breach] = [br for br in verdict.breaches if br.start == "rest + B"
                and br.clause is Clause.RESULT_LAST]
    assert breach.path == ("t1", "t2")
    assert "MTX, HOLD is not back at rest" in breach.why


def test_a_result_taken_back_breaks_result_final():
    """The reduced task that may take its own OK back and end FAIL (regret: OK -> FAIL):
    every dead marking is a proper end, the rest is at rest whenever a result is marked,
    and its ends are only FAIL; but a caller takes the OK first, so "only FAIL" would be a
    lie to it. Version 2 of the contract refuses it, with the run to the OK."""
    verdict = check_contract(reduced(extra=[("OK", "regret"), ("regret", "FAIL")],
                            transitions=["regret"]))
    clauses = {b.clause for b in verdict.breaches}
    assert clauses == {Clause.INTERFACE, Clause.ASLEEP, Clause.RESULT_FINAL}, [
        str(b) for b in verdict.breaches]
    breach = next(b for b in verdict.breaches if b.start == "rest + B")
    assert breach.path == ("t1", "t2") and "regret can still fire" in breach.why


def test_removing_an_arc_of_a_template_breaks_the_contract_but_for_five_guards():
    """Each arc of each template removed in turn: the contract is broken, except by the
    guards that matter only when tasks share a primitive (a task starts only if its
    primitive is off: the locks of the call sites keep two tasks apart) and NULL's read of
    its mutex (it is free whenever NULL starts)."""
    kept = []
    for name in COMPONENTS:
        t, net = LIBRARY.get(name), LIBRARY.composed(name)
        for a in t.net.arcs:
            mutant = Net(net.name, net.places, net.transitions,
                         tuple(x for x in net.arcs if x != a), net.initial)
            if check_contract(mutant).kept:
                kept.append(f"{t.name}: {a.source} -> {a.target}")
    assert kept == ["AchieveGoal: OFF -> t01", "KeepGoal: OFF -> t01",
                    "KeepTwoGoals: P_OFF -> t01", "KeepTwoGoals: Q_OFF -> t01",
                    "null: MTX -> t1"]


def test_a_component_that_ignores_aborts_breaks_abortable():
    """The reduced task without its two aborts (t4, t5): with an abort pending it still
    ends OK or FAIL, leaving A, but never ABORTED; a structure above could wait for ever."""
    net = LIBRARY.reduced.net
    net = Net("deaf", net.places, tuple(t for t in net.transitions if t.id not in ("t4", "t5")),
              tuple(a for a in net.arcs if "t4" not in (a.source, a.target)
                    and "t5" not in (a.source, a.target)), net.initial)
    verdict = check_contract(net)
    assert [b.clause for b in verdict.breaches] == [Clause.ABORTABLE]
    assert "with an abort pending it ends OK or FAIL, without one OK or FAIL" in \
        verdict.breaches[0].why


@pytest.mark.parametrize("results,stuck", [(r, s) for r in ((), ("OK",), ("FAIL",),
                                                            ("OK", "FAIL"))
                                           for s in (False, True) if r or s])
def test_the_restricted_reduced_model_has_exactly_its_signature(results, stuck):
    """The reduced task cut down to a signature (mcl2pnml.analysis.checking.contract.restricted) gives those
    results, may run for ever exactly when asked to, and keeps the rest of the contract:
    what the certificate's results tables rest on."""
    from mcl2pnml.certify.templates import classify
    verdict = check_contract(restricted(LIBRARY.reduced.net, frozenset(results), stuck))
    assert classify(verdict) == {"ends": list(results), "stuck": stuck}
    assert verdict.results_aborted == {*results, "ABORTED"}


def test_a_structure_that_starts_a_running_child_again_breaks_caller():
    """The sequence with a transition that marks its first child's B again while that
    child runs: the child's contract was checked from rest only, so a parent must start a
    child only at rest, and the ``caller`` clause says where it does not."""
    from mcl2pnml.core.net import Arc, Transition
    net = LIBRARY.composed("sequence")
    net = Net(net.name, net.places, (*net.transitions, Transition("again")),
              (*net.arcs, Arc("T1_EXE", "again"), Arc("again", "T1_EXE"),
               Arc("again", "T1_B")), net.initial)
    verdict = check_contract(net, children=("T1_", "T2_"))
    [breach] = [b for b in verdict.breaches if b.clause is Clause.CALLER
                and b.start == "rest + B"]
    assert breach.path == ("t1", "T1_t1", "again")
    assert "T1_B is marked while the child is running" in breach.why
    assert check_contract(LIBRARY.composed("sequence"), children=("T1_", "T2_")).kept


def test_a_component_that_marks_its_own_abort_breaks_interface():
    """t2 ends OK and marks A too: every clause read on the markings holds (A is the
    caller's place, left for it to drain), but the next start would be aborted with no
    abort asked; the interface clause refuses the arc itself."""
    verdict = check_contract(reduced(extra=[("t2", "A")]))
    assert [str(b) for b in verdict.breaches if b.clause is Clause.INTERFACE] == [
        "interface: from the net, after (no firing): t2 marks A, the caller's to mark "
        "(marked: nothing)"]


def test_a_structure_that_reads_its_child_s_mutex_breaks_caller():
    """A parent touches a child only through B, A and the results: the sequence's start
    made to read its first child's MTX sees the child in a state that a real child need not
    show where its reduced model does; the caller clause refuses the arc itself."""
    from mcl2pnml.core.net import Arc, ArcKind
    net = LIBRARY.composed("sequence")
    net = Net(net.name, net.places, net.transitions,
              (*net.arcs, Arc("T1_MTX", "t1", kind=ArcKind.READ)), net.initial)
    said = [b.why for b in check_contract(net, children=("T1_", "T2_")).breaches
            if b.clause is Clause.CALLER]
    assert said == ["t1 takes T1_MTX (read): a parent only marks a child's B and A, and "
                    "takes its results and a left A"]
