"""`mcl2pnml analyze` and `mcl2pnml template`: the contract of cli.md, on our nets and others'."""
import json
import subprocess
import sys

import pytest

from helpers import DATA, ROOT, run_cli as run

SPEC_KEYS = {"places", "transitions", "p_invariants", "siphons", "bounded", "safe",
             "terminal_markings", "reusable", "deadlock_free", "states"}


@pytest.fixture(scope="module")
def task_pnml(tmp_path_factory):
    path = tmp_path_factory.mktemp("t") / "task.pnml"
    out = run("template", "task", "-o", path)
    assert out.returncode == 0, out.stderr
    return path


def test_template_list_names_every_template():
    out = run("template", "--list")
    assert out.returncode == 0
    for name in ("primitive", "task", "task-reduced", "sequence", "parallel", "if-then-else",
                 "while", "monitor"):
        assert name in out.stdout


def test_analyze_json_has_the_keys_of_the_spec(task_pnml):
    out = run("analyze", task_pnml, "--json")
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout)
    assert SPEC_KEYS <= set(r)
    assert (r["places"], r["transitions"]) == (19, 19)
    assert len(r["p_invariants"]) == 6
    assert all(all(isinstance(c, int) and c for c in y.values()) for y in r["p_invariants"])
    assert ["MTX", "EXE", "E_OK", "E_FAIL", "W_OK", "W_FAIL", "W_A"] in [
        sorted(s, key=["MTX", "EXE", "E_OK", "E_FAIL", "W_OK", "W_FAIL", "W_A"].index)
        for s in r["siphons"] if set(s) == {"MTX", "EXE", "E_OK", "E_FAIL", "W_OK", "W_FAIL", "W_A"}]
    assert r["bounded"] and r["safe"] and r["reusable"] and r["deadlock_free"]
    assert r["siphons_controlled"]
    assert sorted(r["terminal_markings"]) == [
        ["A", "C", "FAIL", "MTX", "OFF"], ["A", "C", "MTX", "OFF", "OK"],
        ["ABORTED", "C", "MTX", "OFF"]]


def test_initial_replaces_the_marking(task_pnml):
    r = json.loads(run("analyze", task_pnml, "--json", "--initial", "B,MTX,OFF,C").stdout)
    assert sorted(r["terminal_markings"]) == [["C", "FAIL", "MTX", "OFF"],
                                              ["C", "MTX", "OFF", "OK"]]


def test_state_space_only(task_pnml):
    r = json.loads(run("analyze", task_pnml, "--state-space", "--json").stdout)
    # what the state space says, and nothing that needs the structure
    assert {"states", "bounded", "safe", "terminal_markings", "deadlock_free",
            "reusable", "places", "initial_marking"} <= set(r)
    assert not {"p_invariants", "siphons", "traps"} & set(r)
    assert r["states"] == 24 and r["safe"] and r["deadlock_free"] and r["reusable"]


def test_counts_above_one_and_omega_in_terminal_markings(tmp_path):
    from mcl2pnml import NetBuilder, save_pnml
    b = NetBuilder("two")
    b.place("p", 2)
    b.place("q")
    b.transition("t")
    b.arc("p", "t")
    b.arc("t", "q")
    path = save_pnml(b.build(), tmp_path / "two.pnml")
    r = json.loads(run("analyze", path, "--json").stdout)
    assert r["terminal_markings"] == [["q*2"]] and r["bounded"] and not r["safe"]


def test_text_report_is_tables(task_pnml):
    out = run("analyze", task_pnml)
    assert out.returncode == 0
    assert "P-invariants (a basis of 6)" in out.stdout
    assert "Minimal siphons" in out.stdout and "Terminal markings (3)" in out.stdout


def test_a_net_written_by_pm4py():
    """Its final marking is refused by the strict reading, at its line; --lenient reads it."""
    path = DATA / "pnml" / "foreign" / "pm4py_order_process.pnml"
    out = run("analyze", path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert out.stderr.startswith(f"{path}:80:5: <finalmarkings> is a final marking"), out.stderr
    r = json.loads(run("analyze", path, "--lenient", "--json").stdout)
    assert r["places"] == 6 and r["safe"]
    assert r["terminal_markings"] == [["sink"]]
    # no mission interface: its dead marking is a deadlock, as other tools count it,
    # and it is also the workflow's proper end
    assert r["interface"] == "none" and not r["deadlock_free"] and r["deadlocks"] == [["sink"]]
    assert r["ends_properly"] and r["reusable"]


def test_every_explorer_gives_the_same_answer(task_pnml):
    answers = {e: json.loads(run("analyze", task_pnml, "--state-space", "--json", "--initial",
                                 "B,MTX,OFF,C", "--explorer", e).stdout)
               for e in ("auto", "counters", "packed", "general")}
    assert answers["general"]["states"] > 1
    assert all(a == answers["general"] for a in answers.values())


@pytest.mark.parametrize("args, message", [
    (["--initial", "B,NOPE"], "no place NOPE"),
    (["--initial", "B*x"], "a count is a natural number"),
    (["--max-states", "0"], "0"),
    (["--explorer", "fast"], "'fast' is not one of 'auto', 'native', 'packed', 'counters', 'general'"),
])
def test_bad_options_are_one_line(task_pnml, args, message):
    out = run("analyze", task_pnml, *args)
    assert out.returncode == 2 and message in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1 and "Traceback" not in out.stderr


def test_unknown_template_lists_the_valid_ones():
    out = run("template", "sequense", "-o", "x.pnml")
    assert out.returncode == 2
    assert "did you mean 'sequence'" in out.stderr and "Traceback" not in out.stderr


def test_a_state_space_too_large_still_gives_the_structure(task_pnml):
    r = json.loads(run("analyze", task_pnml, "--json", "--max-states", "5").stdout)
    assert r["states"] is None and r["reusable"] is None and "states" in r["limits"]
    assert len(r["p_invariants"]) == 6 and r["siphons"]
    out = run("analyze", task_pnml, "--state-space", "--max-states", "5")
    assert out.returncode == 2 and "more than 5 markings" in out.stderr


def test_one_net_of_several_is_chosen_with_net():
    """The forgiving reading chooses one net of a file of several; the strict one refuses
    the file at its second net, whichever is asked for."""
    two = DATA / "pnml" / "invalid" / "two_nets.pnml"
    r = json.loads(run("analyze", two, "--lenient", "--net", "second", "--state-space",
                       "--json").stdout)
    assert r["net"] == "second" and r["states"] == 1
    out = run("analyze", two, "--lenient")
    assert out.returncode == 2 and "choose one with --net ID" in out.stderr
    out = run("show", two, "-o", "/dev/null", "--lenient", "--net", "third")
    assert out.returncode == 2 and "no net with id 'third'" in out.stderr
    for command in (["analyze", two], ["analyze", two, "--net", "second"],
                    ["validate", two, "--net", "third"],
                    ["show", two, "-o", "/dev/null", "--net", "second"]):
        out = run(*command)
        assert out.returncode == 2 and "Traceback" not in out.stderr, command
        assert f"{two}:4:3: a second <net> in this file" in out.stderr, command


def test_net_is_refused_where_a_file_holds_one_net(tmp_path):
    path = tmp_path / "one.net"
    path.write_text("pl p (1)\ntr t p -> \n")
    out = run("analyze", path, "--net", "x")
    assert out.returncode == 2 and "--net" in out.stderr and "holds one net" in out.stderr


def test_a_memory_budget_ends_in_a_partial_answer_with_exit_status_3(task_pnml):
    """The structural results are computed before the exploration and kept."""
    out = run("analyze", task_pnml, "--json", "--max-memory", "1K")
    r = json.loads(out.stdout)
    assert out.returncode == 3 and r["states"] is None and "memory budget" in r["limits"]["states"]
    assert r["partial"]["markings_explored"] > 0 and r["p_invariants"] and r["siphons"]
    out = run("analyze", task_pnml, "--state-space", "--max-memory", "1K")
    assert out.returncode == 3 and "Partial answer:" in out.stdout and "markings explored" in out.stdout
    assert run("analyze", task_pnml, "--state-space", "--max-memory", "1G").returncode == 0


@pytest.mark.parametrize("size, message", [("lots", "'lots': a size is a number"),
                                           ("0", "at least one byte")])
def test_a_bad_memory_budget_is_one_line(task_pnml, size, message):
    out = run("analyze", task_pnml, "--max-memory", size)
    assert out.returncode == 2 and message in out.stderr and "--max-memory" in out.stderr


def test_a_wide_net_ends_with_what_fits_in_its_limits(tmp_path):
    """Enumerations whose items span every place are bounded by their width too,
    and the exploration by the memory budget: a partial answer, not a run that never ends."""
    from mcl2pnml import save_pnml
    from mcl2pnml.analysis import zoo
    path = save_pnml(zoo.cycles(2500), tmp_path / "wide.pnml", "none")   # 10,000 places
    out = run("analyze", path, "--json", "--max-memory", "256M")   # a few hundred markings
    r = json.loads(out.stdout)
    assert out.returncode == 3 and r["partial"]["markings_explored"] > 0
    assert {"semipositive_p_invariants", "siphons", "states"} <= set(r["limits"])
    assert len(r["p_invariants"]) == 2500   # the exact basis still comes: one per cycle


def test_where_the_state_space_decides_the_enumerations_are_left_to_it(task_pnml, monkeypatch):
    # a net as small as the task is enumerated whatever decides its properties; a larger
    # one whose graph was built whole is not (shrunk here so that the task counts as
    # larger): the report says why and how to ask, and --structure computes them
    from mcl2pnml import pipeline
    import mcl2pnml.analysis.report as report
    net = pipeline.load_net(task_pnml)
    full = pipeline.analyze(net)
    assert full.structural.siphons and "siphons" not in full.limits
    monkeypatch.setattr(report, "QUICK_PLACES", 0)
    quick = pipeline.analyze(net)
    assert quick.structural.siphons is None and quick.structural.traps is None
    assert quick.structural.semipositive_p_invariants is None
    assert quick.limits["siphons"].endswith("; --structure computes them")
    assert quick.structural.p_invariants == full.structural.p_invariants   # the bases stay
    assert quick.facts == full.facts            # the verdicts are the state space's
    assert quick.partial is None                # nothing was cut short
    asked = pipeline.analyze(net, enumerate_all=True)
    assert asked.structural.siphons == full.structural.siphons
    # a state space past its limit does not decide: the enumerations run
    stopped = pipeline.analyze(net, max_states=2)
    assert stopped.structural.siphons == full.structural.siphons


def test_the_structure_option_reaches_the_enumerations(task_pnml):
    out = run("analyze", task_pnml, "--structure", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["siphons"]


def test_plain_analyze_of_an_example_loads_neither_flint_nor_sympy():
    # the bases of a mission's net stay sparse (invariants.FILL_IN): plain analyze waits
    # on neither library's import, which took longer than the whole elimination
    code = ("import runpy, sys\n"
            "sys.argv = ['mcl2pnml', 'analyze', sys.argv[1], '--untimed']\n"
            "try:\n"
            "    runpy.run_module('mcl2pnml', run_name='__main__')\n"
            "finally:\n"
            "    print(sorted(m for m in ('flint', 'sympy') if m in sys.modules),\n"
            "          file=sys.stderr)\n")
    out = subprocess.run([sys.executable, "-c", code, str(ROOT / "examples" / "docking.mcl")],
                         capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert out.returncode == 0 and "P-invariants" in out.stdout, out.stderr[-2000:]
    assert out.stderr.strip() == "[]"
