"""The library's templates proven once against the interface contract (mcl2pnml/certify/
templates.py): the stored proofs are current, and a user's template is proven when it is
used, a broken one refused with its run."""
from __future__ import annotations

import pytest

from mcl2pnml.certify.templates import (canonical, current, digest, local_digest, stored,
                                        subjects)
from mcl2pnml.language.library import default_library

from helpers import ROOT, run_cli

LIB = default_library()
ACHIEVE = (ROOT / "templates" / "achieve_goal.pnt").read_text()
MISSION = """primitive P(v);
task T(x) = {pattern}(P(x)) timeout 5;
mission {{ T(1); }}
"""


#: The subjects whose proofs take longest (if-then-else: a row for every combination of
#: its three children's signatures, half the time of all): proven again in the slow suite;
#: the default one holds each stored proof to the net it is of by its digest, so that
#: an edit of the template still fails it.
LONG_PROOFS = frozenset({"if-then-else"})


def _stored_proofs_are_current(kept: frozenset[str]) -> None:
    """Every subject proven now, but those in ``kept``, whose stored proofs are taken where
    their digest is their net's now (proven again if not)."""
    now = current(LIB, known={name: e for name, e in stored().items() if name in kept},
                  eager=True)
    assert stored() == now
    assert {name for name, *_ in subjects(LIB)} <= set(now)
    for name, entry in stored().items():     # the instances' own nets, as the checker reads
        if "local" in entry:
            assert entry["local"] == local_digest(LIB, name), name
    assert {"call site", "call sites sharing a callee", "sequence", "AchieveGoal"} <= set(now)


def test_the_stored_proofs_are_the_templates_proven_now():
    """Every component template's proof is stored, with the digest of the net it is proven
    on now (after a deliberate change: python -m mcl2pnml.certify.templates --update); all
    but the longest proven again here."""
    _stored_proofs_are_current(LONG_PROOFS)


@pytest.mark.slow
def test_the_stored_proofs_are_all_the_templates_proven_now():
    """The same, every subject proven again, the longest included."""
    _stored_proofs_are_current(frozenset())


def test_the_results_tables_say_what_each_structure_gives_with_its_children_s_results():
    """Each structure proven with each child reduced to what it may do (mcl2pnml.analysis.checking.contract.
    restricted): end only OK, only FAIL, or either, and perhaps run for ever instead; the
    rows are mcl.md's semantics, computed: a loop whose condition never fails never ends."""
    table = {name: {k: (tuple(v["ends"]), v["stuck"]) if "ends" in v else v["breach"]
                    for k, v in entry["results"].items()}
             for name, entry in current(LIB).items() if "results" in entry}
    assert table["null"] == {"": (("OK",), False)}
    assert table["KeepGoal without a time-out"] == {"": (("FAIL",), False)}
    assert table["AchieveGoal"] == {"": (("OK", "FAIL"), False)}
    assert table["sequence"]["OK;FAIL"] == (("FAIL",), False)
    assert table["sequence"]["FAIL;OK+FAIL~"] == (("FAIL",), False)  # T2 never runs
    assert table["sequence"]["OK+FAIL;~"] == (("FAIL",), True)
    assert table["parallel"]["OK;OK"] == (("OK",), False)
    assert table["parallel"]["FAIL;~"] == ((), True)         # it waits for both: for ever
    assert table["while"]["FAIL;OK"] == (("OK",), False)      # the condition fails: OK
    assert table["while"]["OK;FAIL"] == (("FAIL",), False)    # the body fails: FAIL
    assert table["while"]["OK;OK"] == ((), True)              # never ends
    assert table["if-then-else"]["OK;FAIL;OK"] == (("FAIL",), False)   # then taken
    assert table["call site"] == {"OK": (("OK",), False), "FAIL": (("FAIL",), False),
                                  "OK+FAIL": (("OK", "FAIL"), False), "~": ((), True),
                                  "OK~": (("OK",), True), "FAIL~": (("FAIL",), True),
                                  "OK+FAIL~": (("OK", "FAIL"), True)}
    # every row of every structure: 7 signatures a child
    assert len(table["if-then-else"]) == 7 ** 3 and len(table["monitor"]) == 7 ** 2


def test_a_template_not_stored_is_proven_row_by_row_as_missions_read_it():
    """A user's template (here: nothing taken as stored) is proven on its children reduced
    at once, and on each other row of its results table when a certificate first reads it,
    with the same answer as proving them all."""
    lazy = current(LIB, known={})["while"]["results"]
    assert list(lazy) == ["OK+FAIL;OK+FAIL"]
    eager = stored()["while"]["results"]
    assert {key: lazy[key] for key in eager} == eager and len(lazy) == 49
    assert lazy.get("OK;NOPE") is None and lazy.get("OK") is None


def test_the_digest_covers_the_behaviour_not_the_names():
    net = LIB.composed("sequence")
    assert digest(net.renamed("another name")) == digest(net)
    fewer = net.__class__(net.name, net.places, net.transitions, net.arcs[1:], net.initial)
    assert digest(fewer) != digest(net)
    assert '"arcs"' in canonical(net)


def _user(tmp_path, name: str, text: str):
    folder = tmp_path / "mine"
    folder.mkdir(exist_ok=True)
    (folder / f"{name.lower()}.pnt").write_text(text)
    mission = tmp_path / "m.mcl"
    mission.write_text(MISSION.format(pattern=name))
    import os
    env = {**os.environ, "MCL2PNML_TEMPLATE_PATH": str(folder)}
    return run_cli("compile", mission, "-o", tmp_path / "m.pnml", env=env), tmp_path / "m.pnml"


def test_a_user_s_pattern_that_keeps_the_contract_compiles(tmp_path):
    text = ACHIEVE.replace("pattern AchieveGoal alias task", "pattern AchieveOnce")
    out, pnml = _user(tmp_path, "AchieveOnce", text)
    assert out.returncode == 0, out.stderr
    assert pnml.is_file()


def test_a_user_s_pattern_that_breaks_the_contract_is_refused_with_its_run(tmp_path):
    """t08 ends OK without giving MTX back: the task could never be called again."""
    text = ACHIEVE.replace("pattern AchieveGoal alias task", "pattern AchieveLeaky").replace(
        "transition t08: W_OK, ?OFF -> OK, MTX", "transition t08: W_OK, ?OFF -> OK")
    out, pnml = _user(tmp_path, "AchieveLeaky", text)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "achieveleaky.pnt" in out.stderr
    assert "template 'AchieveLeaky' breaks the interface contract" in out.stderr
    assert "ended OK with MTX not back at rest" in out.stderr and "t08" in out.stderr
    assert not pnml.exists()
