"""The paper's equations 1-26, computed from the templates and compared with the paper."""
import json
import subprocess
import sys

import pytest

from mcl2pnml.core.net import Net
from mcl2pnml.language.library import Library, default_library
from paper_repro import checks

from helpers import ROOT


@pytest.fixture(scope="module")
def rows():
    return checks.check_equations(default_library())


def test_all_26_equations_match(rows):
    assert [r.number for r in rows] == list(range(1, 27))
    failing = [(r.number, r.paper, r.computed) for r in rows if not r.match]
    assert not failing


def test_the_further_checks_hold():
    lib = default_library()
    for group in (checks.invariant_space(lib), [checks.siphon_16_control(lib)],
                  checks.other_siphons(lib), checks.reduced_model(lib),
                  [checks.sequence_fusion(lib)], checks.structures(lib), checks.recall(lib)):
        assert group and all(r.match for r in group), [r.computed for r in group if not r.match]


def _broken(lib: Library, name: str, drop: tuple[str, str]) -> Library:
    """The library with one arc of one template removed."""
    t = lib.templates[name]
    net = t.net
    arcs = tuple(a for a in net.arcs if (a.source, a.target) != drop)
    assert len(arcs) == len(net.arcs) - 1
    changed = type(t)(t.kind, t.name, t.aliases, t.doc,
                      Net(net.name, net.places, net.transitions, arcs, net.initial),
                      t.primitives, t.children, t.source)
    templates = {k: (changed if v is t else v) for k, v in lib.templates.items()}
    return Library(templates, changed if lib.primitive is t else lib.primitive,
                   changed if lib.reduced is t else lib.reduced)


@pytest.mark.parametrize("name, drop, breaks", [
    ("primitive", ("on", "ON"), {1, 8}),            # enabling no longer turns ON
    ("AchieveGoal", ("t11", "ABORTED"), {19}),      # an abort before the start: stuck
    ("task-reduced", ("t4", "MTX"), {24}),          # aborted without freeing the mutex
])
def test_a_broken_template_is_caught(name, drop, breaks):
    """The comparison is not vacuous: break a net and the equations say so."""
    rows = checks.check_equations(_broken(default_library(), name, drop))
    failing = {r.number for r in rows if not r.match}
    assert breaks <= failing


def test_python_m_paper_repro_writes_the_report_and_exits_0():
    out = subprocess.run([sys.executable, "-m", "paper_repro"], cwd=ROOT, capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "26/26" in out.stdout
    report = json.loads((ROOT / "paper_repro" / "out" / "report.json").read_text())
    assert set(report["equations"]) == {str(n) for n in range(1, 27)}
    assert all(e["match"] is True and "paper" in e and "computed" in e
               for e in report["equations"].values())
    md = (ROOT / "paper_repro" / "out" / "report.md").read_text()
    assert "26/26 equations match" in md and "reading:" in md
    # the headline says what the match rests on: templates we rebuilt from the text
    headline = next(line for line in md.splitlines() if "equations match" in line)
    assert "templates rebuilt from the paper's text" in headline
    # a row's claim is what is checked: the literal task is expected not to be 1-safe
    literal = [r for r in report["checks"]["Called again (the mutex and the abort problem)"]
               if r["net"] != "task"]
    assert literal and all(r["claim"].startswith("the literal task") and "not 1-safe"
                           in r["claim"] and r["holds"] for r in literal)
    for n in range(1, 5):
        for fmt in ("svg", "png"):
            assert (ROOT / "paper_repro" / "out" / f"fig{n}.{fmt}").stat().st_size > 1000
    # the experiment of section 3 and its Fig. 5
    assert (ROOT / "paper_repro" / "out" / "fig5.png").stat().st_size > 10_000
    experiment = report["checks"]["The experiment (section 3, Fig. 5), on the simulated AUV"]
    assert len(experiment) == 2 and all(r["holds"] for r in experiment)


def test_the_experiment_behaves_as_the_paper_says():
    from paper_repro import experiment
    found, missed = experiment.trials()
    rows = experiment.checks([found, missed])
    assert all(r.match for r in rows), [r.computed for r in rows]
    # the survey was cut short by the cross: the second waypoint was never reached
    assert found.time < missed.time + 10 and found.markers and not missed.markers
