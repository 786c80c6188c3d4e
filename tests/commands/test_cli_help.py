"""Every command's ``--help``, byte for byte as ``tests/data/cli/help/*.txt`` holds it.

The help is what a user reads of the command line: a change to the code under
it (where an option's default or choices come from, which module a command
lives in) must leave it as it was. The golden files were written from the
command as it was before its code was divided into one module per command;
``python tests/commands/test_cli_help.py`` writes them again, for a change that is meant.
"""
from __future__ import annotations

import os
import re
import shlex
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "support"))
from helpers import DATA, ROOT, run_cli  # noqa: E402

HELP = DATA / "cli" / "help"
COMMANDS = ("", "analyze", "campaign", "certify", "check", "compile", "functional", "odds",
            "query", "run", "show", "template", "validate", "lsp")
#: click wraps the help to the terminal's width, capped at 80 columns: the width is fixed
ENV = {**os.environ, "COLUMNS": "80"}
#: An example's environment setting before the command (NAME=VALUE).
ENV_SETTING = re.compile(r"[A-Z_][A-Z0-9_]*=.*")
#: A file of the repository an example names, alone or in a vehicle's specification
#: (model:FILE@SEED): a path with a folder in it.
IN_SPEC = re.compile(r"(?:[a-z]+:)?([\w.-]+/[\w./-]+?)(?:@[0-9]+)?")


def golden(command: str) -> Path:
    return HELP / f"{command or 'mcl2pnml'}.txt"


def help_of(command: str):
    return run_cli(*([command] if command else []), "--help", env=ENV)


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: c or "mcl2pnml")
def test_the_help_is_as_it_was(command: str):
    out = help_of(command)
    assert out.returncode == 0 and out.stderr == "", out.stderr
    assert out.stdout == golden(command).read_text(encoding="utf-8")


def test_every_command_has_its_golden_help():
    from mcl2pnml.cli import main
    assert set(main.commands) == set(COMMANDS) - {""}


def test_every_example_is_of_its_command_and_parses_on_files_that_exist(monkeypatch):
    """Each command's --help shows its own examples; each one's command line parses from
    the repository's root (click refuses an unknown option, a bad value, an input that is
    not there), and every file it names in a folder of the repository is there."""
    from mcl2pnml.cli import main
    from mcl2pnml.cli_options import EXAMPLES
    monkeypatch.chdir(ROOT)
    assert set(EXAMPLES) == set(main.commands)
    for command, lines in EXAMPLES.items():
        assert lines, command
        for line in lines:
            words = [w for w in shlex.split(line) if not ENV_SETTING.fullmatch(w)]
            assert words[:2] == ["mcl2pnml", command], line
            main.commands[command].make_context(command, words[2:])
            for word in words[2:]:
                path = IN_SPEC.fullmatch(word)
                assert path is None or (ROOT / path.group(1)).is_file(), (line, word)


if __name__ == "__main__":
    HELP.mkdir(parents=True, exist_ok=True)
    for name in COMMANDS:
        written = help_of(name)
        assert written.returncode == 0, written.stderr
        golden(name).write_text(written.stdout, encoding="utf-8")
