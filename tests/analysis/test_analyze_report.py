"""The analysis as typed data, ``analyze``'s output byte for byte, and what the command line
loads to start.

``mcl2pnml.analysis.report.analyze`` returns a frozen :class:`Analysis` whose ``as_json()``
is the object ``analyze --json`` prints; the golden files of ``tests/data/cli/analyze`` were
written by the command when it printed a dictionary, before the analysis was typed.
"""
from __future__ import annotations

import dataclasses
import io
import os
import subprocess
import sys

import pytest

from mcl2pnml import pipeline
from mcl2pnml.analysis.report import Analysis, CertifiedFacts, Partial, analyze
from mcl2pnml.commands import analyze as analyzing, fly as campaigning
from mcl2pnml.core.progress import Notes, ProgressMeter
from mcl2pnml.core.settings import SettingError

from helpers import DATA, ROOT, run_cli

EXAMPLES = ROOT / "examples"

GOLDEN = DATA / "cli" / "analyze"


@pytest.fixture(scope="module")
def task(tmp_path_factory):
    folder = tmp_path_factory.mktemp("task")
    out = run_cli("template", "task", "-o", folder / "task.pnml")
    assert out.returncode == 0, out.stderr
    return folder / "task.pnml"


@pytest.mark.parametrize("args, golden", [
    (["--json"], "task.json"),
    ([], "task.txt"),
    (["--state-space", "--json"], "task.state-space.json"),
])
def test_analyze_prints_as_it_did(task, args, golden):
    out = run_cli("analyze", task, *args)
    assert out.returncode == 0 and out.stderr == "", out.stderr
    assert out.stdout == (GOLDEN / golden).read_text(encoding="utf-8")


def test_the_analysis_is_frozen_typed_data():
    net = pipeline.template_net("task")
    result = analyze(net)
    assert isinstance(result, Analysis) and result.facts.safe and result.structural is not None
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.facts.states = 0
    only = analyze(net, state_space_only=True)
    assert only.structural is None and "p_invariants" not in only.as_json()
    assert only.as_json()["states"] == result.facts.states


def test_a_partial_answer_says_what_it_explored():
    stopped = analyze(pipeline.template_net("task"), max_states=3, explorer="general")
    assert stopped.facts.states is None and stopped.partial.stopped
    said = stopped.as_json()
    assert said["partial"] == {"markings_explored": stopped.partial.markings_explored,
                               "deadlock_found": stopped.partial.deadlock_found}
    assert "more than 3 markings" in said["limits"]["states"]
    assert Partial(left_out={"traps": "why"}).as_json() == {"left_out": {"traps": "why"}}


def test_a_certificate_proves_the_behaviour_without_exploring():
    net = pipeline.template_net("task")
    unexplored = analyze(net, explore_states=False)
    assert unexplored.facts.safe is None and unexplored.facts.states is None
    proven = unexplored.certified(CertifiedFacts("task.cert.json", ["OK"]))
    assert proven.facts.safe and proven.facts.reusable and proven.facts.states is None
    assert list(proven.as_json())[-1] == "certificate"
    assert proven.as_json()["certificate"] == {"file": "task.cert.json", "holds": True,
                                               "ends": ["OK"]}


def test_analyze_shows_its_progress_and_notes_on_the_streams_it_is_given(task):
    stream, said = io.StringIO(), io.StringIO()
    notes = Notes(said)
    outcome = analyzing.analyze(task, analyzing.AnalyzeOptions(state_space=True), notes=notes,
                                progress=ProgressMeter(stream))
    assert outcome.status == 0 and outcome.result.facts.states == 24
    shown = stream.getvalue()
    assert shown.endswith("\n") and all(line.startswith("  explored ")
                                        for line in shown.strip("\r\n").split("\r") if line)
    assert said.getvalue() == "".join(line + "\n" for line in outcome.messages)


def test_a_setting_error_names_the_setting_and_the_cli_the_option(tmp_path):
    options = campaigning.CampaignOptions(workers=2, scheduler="tcp://127.0.0.1:1")
    with pytest.raises(SettingError) as refused:
        campaigning.campaign(EXAMPLES / "sauce.mcl", options)
    assert refused.value.setting == "workers"
    out = run_cli("campaign", EXAMPLES / "sauce.mcl", "--workers", "2", "--scheduler",
                  "tcp://127.0.0.1:1")
    assert out.returncode == 2
    assert out.stderr == ("mcl2pnml campaign: error: Invalid value for --workers: the "
                          "scheduler's cluster has its own workers (see 'mcl2pnml campaign "
                          "--help')\n")


#: What ``--version`` must not load: each costs a start-up it does not need.
HEAVY = ("lxml", "numpy", "lark", "graphviz", "sympy", "numba", "tqdm", "dask")


def test_the_version_loads_no_heavy_module():
    """``python -X importtime -m mcl2pnml --version``: every module it imports is listed;
    none of the heavy ones (today's measure: no lxml, which the PNML reader alone needs,
    and no numpy, which the analysis alone needs)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPROFILEIMPORTTIME"}
    out = subprocess.run([sys.executable, "-X", "importtime", "-m", "mcl2pnml", "--version"],
                         capture_output=True, text=True, env=env, timeout=120)
    assert out.returncode == 0, out.stderr
    imported = {line.rsplit("|", 1)[-1].strip() for line in out.stderr.splitlines()
                if line.startswith("import time:")}
    assert "mcl2pnml.cli" in imported
    loaded = sorted(m for m in imported if m.split(".")[0] in HEAVY)
    assert not loaded, loaded
