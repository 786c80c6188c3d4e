"""Warnings (mcl2pnml.language.lint, docs/warnings.md): valid MCL that does not do what it
seems to say, each at its line and column, with the fix; ``--strict`` makes them errors.

The golden inputs are tests/data/warnings/*.mcl, each with its ``.expected`` output
(``MCL2PNML_REGOLD=1`` rewrites them); the traps they warn of are run on both engines
here, so that a warning says what really happens.
"""
from pathlib import Path

import pytest

from mcl2pnml import pipeline
from mcl2pnml.language import lint as lint_module
from mcl2pnml.language.lint import CODES, Warning, lint

from helpers import DATA, ROOT, assert_golden, both, run_cli as run

CASES = DATA / "warnings"
EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))


def warnings_in(path: Path) -> list[Warning]:
    return lint(pipeline.check_source(path.read_text(), path.name))


def rendered(warnings) -> str:
    return "".join(str(w) + "\n" for w in warnings)


@pytest.mark.parametrize("case", sorted(CASES.glob("*.mcl")), ids=lambda p: p.stem)
def test_golden(case):
    assert_golden(case.with_suffix(".expected"), rendered(warnings_in(case)))


def test_the_monitor_trap():
    """Dive(10); monitor(parallel(Goto(WP1), Goto(WP2)), Watch(5)); Dive(0);"""
    found = warnings_in(CASES / "monitor_then_surface.mcl")
    assert [(w.code, w.location.line, w.location.column) for w in found] == [
        ("W001", 15, 5), ("W002", 15, 33)]
    assert "Dive(0) on line 16 never runs" in found[0].message
    assert "if (monitor(...)) then" in found[0].fix
    text = str(found[0])
    assert text.startswith("monitor_then_surface.mcl:15:5: warning: ")
    assert text.splitlines()[1:3] == [
        "        monitor(parallel(Goto(WP1), Goto(WP2)), Watch(5));", "        ^"]


def _trace(result) -> list[tuple]:
    return [(e["t"], e.get("action") or e.get("event"), e["primitive"], e.get("args"))
            for e in result["trace"]]


def test_the_monitor_trap_is_what_the_engines_do():
    # the watched part ends first, both ways OK: the monitor FAILs and Dive(0) never runs;
    # the two Gotos run one after the other (the second enabled when the first is off)
    checked = pipeline.check_file(CASES / "monitor_then_surface.mcl")
    script = {"KeepDepth": ["ok@1", "ok@1"], "GoToWayPoint": ["ok@5", "ok@5"]}
    petri, reference = both(checked, script)
    assert petri == reference and reference["outcome"] == "FAIL"
    trace = _trace(reference)
    assert [e for e in trace if e[1] == "enable" and e[2] == "KeepDepth"] == [
        (0, "enable", "KeepDepth", [10])]
    gotos = [e[0] for e in trace if e[2] == "GoToWayPoint" and e[1] in ("enable", "off")]
    assert gotos == [1, 6, 6, 11]          # on, off, on, off: never both on
    # the fix: tested by an if, the surfacing runs whatever the monitor's result
    fixed = pipeline.check_file(CASES / "monitor_tested.mcl")
    petri, reference = both(fixed, {"KeepDepth": ["ok@1", "ok@1"], "GoToWayPoint": ["ok@5"]})
    assert petri == reference and reference["outcome"] == "OK"
    assert (6, "enable", "KeepDepth", [0]) in _trace(reference)


def test_an_if_without_else_takes_a_failure_as_ok_on_both_engines():
    checked = pipeline.check_file(CASES / "if_without_else.mcl")
    script = {"GoToWayPoint": ["fail@5", "ok@1", "ok@1", "ok@1"],
              "KeepDepth": ["ok@1"] * 6}
    petri, reference = both(checked, script)
    assert petri == reference and reference["outcome"] == "OK"
    trace = _trace(reference)
    # the first Goto failed, its then-block never ran, and the mission went on
    assert (5, "failed", "GoToWayPoint", None) in trace
    assert (5, "enable", "GoToWayPoint", [[10.0, 0.0, 5.0]]) in trace


def test_the_watcher_that_shares_a_primitive_never_starts():
    checked = pipeline.check_file(CASES / "monitor_shared.mcl")
    petri, reference = both(checked, {"GoToWayPoint": ["ok@5", "ok@1"], "KeepDepth": []})
    assert petri == reference and reference["outcome"] == "OK"
    enables = [e for e in _trace(reference) if e[1] == "enable"]
    assert enables == [(0, "enable", "GoToWayPoint", [[10.0, 0.0, 5.0]])]   # Arrived: never


def test_sauce_style_and_every_example_is_warning_free():
    # sauce.mcl's `if (monitor(...)) then {...}` with no else, and its watcher without
    # timeout stopped by the survey, are the idiom, not a trap
    assert warnings_in(CASES / "monitor_tested.mcl") == []
    for example in EXAMPLES:
        assert warnings_in(example) == [], example.name


def test_an_acknowledgement_needs_its_code_and_a_reason():
    text = (CASES / "if_without_else.mcl").read_text()
    assert "// mcl: allow W004 because" in text
    without = text.replace("because a missed way point is retried at the end", "")
    assert len(lint(pipeline.check_source(without, "x.mcl"))) == 2
    other = text.replace("allow W004", "allow W001")
    assert len(lint(pipeline.check_source(other, "x.mcl"))) == 2
    same_line = text.replace("    // mcl: allow W004 because a missed way point is retried "
                             "at the end\n    if (Goto(A)) then {",
                             "    if (Goto(A)) then { // mcl: allow W002, W004 because retried")
    assert same_line != text
    assert len(lint(pipeline.check_source(same_line, "x.mcl"))) == 1


def test_every_code_is_documented():
    doc = (ROOT / "docs" / "warnings.md").read_text()
    for code in CODES:
        assert f"``{code}``" in lint_module.__doc__, code
        assert f"## {code}" in doc, code
    assert {w.code for case in CASES.glob("*.mcl") for w in warnings_in(case)} == set(CODES)


def test_check_prints_them_and_strict_makes_them_errors(tmp_path):
    mission = CASES / "monitor_then_surface.mcl"
    out = run("check", mission)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith(f"{mission}: ok (")
    assert out.stderr == rendered(warnings_in(mission)).replace(
        "monitor_then_surface.mcl:", f"{mission}:")
    out = run("check", "--strict", mission)
    assert out.returncode == 2 and out.stdout == ""
    assert "warning: " in out.stderr and "Traceback" not in out.stderr
    assert out.stderr.rstrip().endswith("2 warnings, which --strict makes errors (fix them, or "
                                        "acknowledge one that is meant with // mcl: allow "
                                        "CODE because ... on the line before it)")
    out = run("check", "--strict", CASES / "monitor_tested.mcl")
    assert out.returncode == 0 and out.stderr == ""


def test_compile_prints_them_and_strict_writes_nothing(tmp_path):
    mission = CASES / "monitor_then_surface.mcl"
    net = tmp_path / "trap.pnml"
    out = run("compile", mission, "-o", net, "--strict")
    assert out.returncode == 2 and not net.exists()
    assert "[W001]" in out.stderr and "which --strict makes errors" in out.stderr
    out = run("compile", mission, "-o", net, "--layout", "none")
    assert out.returncode == 0 and net.exists()
    assert "[W001]" in out.stderr and "[W002]" in out.stderr and f"wrote {net}" in out.stderr
    out = run("compile", ROOT / "examples" / "sauce.mcl", "-o", tmp_path / "sauce.pnml",
              "--layout", "none", "--strict")
    assert out.returncode == 0 and "warning" not in out.stderr
