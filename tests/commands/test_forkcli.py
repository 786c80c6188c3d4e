"""The tests' command runner (tests/support/forkcli.py) gives what a fresh interpreter
gives: the same standard output and error, the same exit status, the same end
by a signal, the same behaviour on a closed pipe; and a command past its
timeout is stopped. Most tests run ``mcl2pnml`` through it, so if it differed
from ``python -m mcl2pnml`` they would be testing something a user never runs.
"""
import os
import subprocess
import sys
import time

import pytest

import forkcli
from helpers import DATA, ROOT

SAUCE = ROOT / "examples" / "sauce.mcl"
CASES = {
    "ok": ("check", SAUCE),
    "version": ("--version",),
    "usage": ("compile",),
    "unknown option": ("compile", SAUCE, "--bogus"),
    "missing file": ("check", "no-such-mission.mcl"),
    "invalid mission": ("check", DATA / "mcl" / "invalid" / "const_as_task.mcl"),
    "help": ("analyze", "--help"),
    "a net on standard output": ("template", "task"),
    "json": ("analyze", DATA / "pnml" / "foreign" / "pm4py_order_process.pnml", "--json"),
}


def fresh(args, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mcl2pnml", *map(str, args)],
                          capture_output=True, text=True, timeout=120, **kw)


def _as_seen(out: subprocess.CompletedProcess) -> tuple:
    return out.returncode, out.stdout, out.stderr


@pytest.mark.parametrize("args", CASES.values(), ids=CASES.keys())
def test_a_forked_command_prints_and_ends_as_a_fresh_interpreter_does(args):
    assert forkcli.server() is not None, "MCL2PNML_TEST_FRESH=1: nothing to compare"
    assert _as_seen(forkcli.run(args, timeout=120)) == _as_seen(fresh(args))


def test_the_directory_and_environment_are_the_callers(tmp_path):
    mission = tmp_path / "m.mcl"
    mission.write_text(SAUCE.read_text())
    env = {**os.environ, "MCL2PNML_TEMPLATE_PATH": str(tmp_path / "no-such-folder")}
    forked = forkcli.run(("compile", "m.mcl"), cwd=tmp_path, env=env, timeout=120)
    assert _as_seen(forked) == _as_seen(fresh(("compile", "m.mcl"), cwd=tmp_path, env=env))
    assert forked.returncode == 2 and "no-such-folder" in forked.stderr


def test_a_command_that_kills_itself_ends_by_its_signal(tmp_path):
    env = {**os.environ, "MCL2PNML_JOURNAL_KILL_AFTER": "3"}
    args = ("run", SAUCE, "--journal", tmp_path / "journal")
    forked = forkcli.run(args, env=env, timeout=120)
    (tmp_path / "journal").unlink()
    assert forked.returncode == fresh(args, env=env).returncode == -9


def test_the_shell_client_passes_its_streams_and_a_closed_pipe_is_as_for_python(tmp_path):
    line = "mcl2pnml template --list | head -n 1; mcl2pnml check nope.mcl; echo status $?"
    client = (f'{forkcli.ENV}="{forkcli.server()}" exec "{sys.executable}" -S '
              f'"{forkcli.__file__}" run "$@"')
    direct = f'exec "{sys.executable}" -m mcl2pnml "$@"'
    seen = []
    for body in (client, direct):
        bin_ = tmp_path / str(len(seen))
        bin_.mkdir()
        (bin_ / "mcl2pnml").write_text(f"#!/bin/sh\n{body}\n")
        (bin_ / "mcl2pnml").chmod(0o755)
        env = {**os.environ, "PATH": f"{bin_}{os.pathsep}{os.environ['PATH']}"}
        out = subprocess.run(["bash", "-c", line], capture_output=True, text=True, env=env,
                             cwd=tmp_path, timeout=120)
        seen.append(_as_seen(out))
    assert seen[0] == seen[1]
    assert seen[0][1].endswith("status 2\n")


def test_a_command_past_its_timeout_is_stopped(tmp_path):
    log = tmp_path / "run.jsonl"
    log.write_text("")
    start = time.monotonic()
    with pytest.raises(subprocess.TimeoutExpired):    # `show --live` serves until stopped
        forkcli.run(("show", SAUCE, "--live", log), timeout=3)
    assert time.monotonic() - start < 60
