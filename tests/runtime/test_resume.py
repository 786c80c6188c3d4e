"""Crash-safe runs: a run killed at any point and resumed from its journal is the run uninterrupted.

The runs are real processes (``python -m mcl2pnml run``), killed with
SIGKILL by the journal's test hook (``MCL2PNML_JOURNAL_KILL_AFTER=N``: the
process kills itself right after the journal's N-th line), then resumed
with ``--resume``. The resumed run must print the same result (outcome,
time, trace) and leave the same journal, line for line, as a run never
killed: no step missing, none repeated.
"""
from __future__ import annotations

import json
import os
import random
import signal

import pytest

from helpers import ROOT, run_cli

SAUCE = ROOT / "examples" / "sauce.mcl"
FOUND = {"GoToWayPoint": ["ok@30", "ok@40"], "DetectCross": ["ok@50"],
         "KeepDepth": ["ok@5", "ok@6"], "ReleaseMarker": ["ok@1"]}


def mcl2pnml(*args, kill_after: int | None = None, cwd=None):
    env = dict(os.environ)
    env.pop("MCL2PNML_JOURNAL_KILL_AFTER", None)
    if kill_after is not None:
        env["MCL2PNML_JOURNAL_KILL_AFTER"] = str(kill_after)
    return run_cli(*args, env=env, cwd=cwd)


@pytest.fixture
def script(tmp_path):
    path = tmp_path / "vehicle.json"
    path.write_text(json.dumps(FOUND))
    return path


def uninterrupted(tmp_path, vehicle, engine):
    journal = tmp_path / f"whole-{engine}.journal"
    out = mcl2pnml("run", SAUCE, "--engine", engine, "--vehicle", vehicle, "--json",
                   "--journal", journal)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout), journal.read_text()


def killed_and_resumed(tmp_path, vehicle, engine, kills: list[int]):
    """Kill the run after each of ``kills`` journal lines in turn (resuming in between)."""
    journal = tmp_path / f"killed-{engine}-{'-'.join(map(str, kills))}.journal"
    out = mcl2pnml("run", SAUCE, "--engine", engine, "--vehicle", vehicle, "--json",
                   "--journal", journal, kill_after=kills[0])
    assert out.returncode == -signal.SIGKILL, out.stderr
    for k in kills[1:]:
        out = mcl2pnml("run", SAUCE, "--resume", journal, "--json", kill_after=k)
        assert out.returncode == -signal.SIGKILL, out.stderr
    lines_at_kill = len(journal.read_text().splitlines())
    assert lines_at_kill == kills[-1]
    out = mcl2pnml("run", SAUCE, "--resume", journal, "--json")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout), journal.read_text()


@pytest.mark.parametrize("engine, kills", [("petri", [2]), ("petri", [37]),
                                           ("petri", [20, 70]), ("reference", [9])])
def test_a_killed_run_resumes_to_the_uninterrupted_result(tmp_path, script, engine, kills):
    whole, whole_journal = uninterrupted(tmp_path, script, engine)
    result, journal = killed_and_resumed(tmp_path, script, engine, kills)
    assert result == whole and result["outcome"] == "OK"
    assert journal.splitlines()[1:] == whole_journal.splitlines()[1:]   # no step lost or doubled
    assert json.loads(journal.splitlines()[-1]) == {"t": whole["time"], "outcome": "OK"}


def test_a_torn_last_line_is_dropped_and_said_so(tmp_path, script):
    whole, whole_journal = uninterrupted(tmp_path, script, "petri")
    journal = tmp_path / "torn.journal"
    out = mcl2pnml("run", SAUCE, "--vehicle", script, "--journal", journal, kill_after=30)
    assert out.returncode == -signal.SIGKILL
    with open(journal, "a") as f:       # killed half-way through writing line 31
        f.write('{"t": 0, "fi')
    out = mcl2pnml("run", SAUCE, "--resume", journal, "--json")
    assert out.returncode == 0, out.stderr
    assert f"{journal}:31: the last line was cut off" in out.stderr
    assert json.loads(out.stdout) == whole
    assert journal.read_text().splitlines()[1:] == whole_journal.splitlines()[1:]


def test_a_journal_that_the_run_does_not_match_is_one_error_naming_its_line(tmp_path, script):
    journal = tmp_path / "run.journal"
    assert mcl2pnml("run", SAUCE, "--vehicle", script, "--journal", journal,
                    kill_after=40).returncode == -signal.SIGKILL
    lines = journal.read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if '"event"' in line)
    lines[k] = lines[k].replace('"on"', '"failed"')
    journal.write_text("\n".join(lines) + "\n")
    out = mcl2pnml("run", SAUCE, "--resume", journal)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert out.stderr.startswith(f"{journal}:{k + 1}:1: the resumed run differs from the "
                                 "journal here"), out.stderr


def test_resume_refuses_what_it_cannot_replay(tmp_path, script):
    journal = tmp_path / "run.journal"
    assert mcl2pnml("run", SAUCE, "--vehicle", script, "--journal", journal,
                    kill_after=10).returncode == -signal.SIGKILL
    out = mcl2pnml("run", SAUCE, "--vehicle", script, "--journal", journal)
    assert out.returncode == 2 and "the journal exists already" in out.stderr
    out = mcl2pnml("run", SAUCE, "--resume", journal, "--engine", "reference")
    assert out.returncode == 2 and f"{journal}:1:1: the journal's run has --engine petri" \
        in out.stderr
    script.write_text(json.dumps({**FOUND, "DetectCross": ["ok@51"]}))
    out = mcl2pnml("run", SAUCE, "--resume", journal)
    assert out.returncode == 2 and "has changed since this journal was written" in out.stderr
    assert len(journal.read_text().splitlines()) == 10     # nothing appended


@pytest.mark.slow
@pytest.mark.parametrize("vehicle", ["script", "sim"])
def test_many_random_kill_points(tmp_path, script, engine, vehicle):
    """Random kill points, single and chained, over the whole journal."""
    engine = engine.name
    vehicle = script if vehicle == "script" else "sim"
    whole, whole_journal = uninterrupted(tmp_path, vehicle, engine)
    n = len(whole_journal.splitlines())
    rng = random.Random(f"{engine}-{vehicle}")
    plans = [[k] for k in rng.sample(range(1, n), min(12, n - 1))]
    plans += [sorted(rng.sample(range(1, n), 3)) for _ in range(4)]
    for kills in plans:
        result, journal = killed_and_resumed(tmp_path, vehicle, engine, kills)
        assert result == whole, kills
        assert journal.splitlines()[1:] == whole_journal.splitlines()[1:], kills


# -- every other output is written whole or not at all ----------------------------------
# (the journal is the one file appended to, by design: see mcl2pnml/journal.py)

def _cli_in_process(args):
    from click.testing import CliRunner

    from mcl2pnml.cli import main
    return CliRunner().invoke(main, [str(a) for a in args])


OUTPUTS = [
    ("compile", ["compile", SAUCE, "--layout", "none", "-o"]),
    ("compile-dot", ["compile", SAUCE, "--format", "dot", "-o"]),
    ("template", ["template", "task", "-o"]),
    ("run-log", ["run", SAUCE, "--json", "--log"]),
]


@pytest.mark.parametrize("name, args", OUTPUTS, ids=[n for n, _ in OUTPUTS])
def test_a_full_disk_leaves_no_partial_file_and_keeps_the_old_one(tmp_path, monkeypatch,
                                                                 name, args):
    """The disk fills up at the last moment (the fsync): the old file stays, no temp is left."""
    import errno

    import mcl2pnml.core.files

    target = tmp_path / f"{name}.out"
    target.write_text("the previous version\n")

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    monkeypatch.setattr(mcl2pnml.core.files.os, "fsync", full)
    out = _cli_in_process(args + [target])
    assert out.exit_code == 2, out.output
    assert f"{target}: cannot write: No space left on device" in out.output
    assert target.read_text() == "the previous version\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == [target.name]


def test_a_write_that_fails_half_way_leaves_no_file(tmp_path, monkeypatch):
    """A PNML streamed out fails after its first bytes: nothing appears at the target."""
    import mcl2pnml.io.pnml.writer as writer

    def half(net, out, *drawing):
        out.write(b"<?xml version='1.0'?>\n<pnml")
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(writer, "stream_pnml", half)
    target = tmp_path / "sauce.pnml"
    out = _cli_in_process(["compile", SAUCE, "--layout", "none", "-o", target])
    assert out.exit_code == 2 and "cannot write: No space left on device" in out.output
    assert list(tmp_path.iterdir()) == []
