"""Every command's ``--help``, byte for byte as ``tests/data/cli/help/*.txt`` holds it.

The help is what a user reads of the command line: a change to the code under
it (where an option's default or choices come from, which module a command
lives in) must leave it as it was. The golden files were written from the
command as it was before its code was divided into one module per command;
``python tests/commands/test_cli_help.py`` writes them again, for a change that is meant.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "support"))
from helpers import DATA, run_cli  # noqa: E402

HELP = DATA / "cli" / "help"
COMMANDS = ("", "analyze", "campaign", "certify", "check", "compile", "functional", "odds",
            "query", "run", "show", "template", "validate", "lsp")
#: click wraps the help to the terminal's width, capped at 80 columns: the width is fixed
ENV = {**os.environ, "COLUMNS": "80"}


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


if __name__ == "__main__":
    HELP.mkdir(parents=True, exist_ok=True)
    for name in COMMANDS:
        written = help_of(name)
        assert written.returncode == 0, written.stderr
        golden(name).write_text(written.stdout, encoding="utf-8")
