"""The command line: one clear line and exit 2 on bad input, never a traceback."""
import pytest

from mcl2pnml import __version__, save_pnml

from helpers import DATA, run_cli as run
from examples.handbuilt_primitive import primitive


def test_version_and_help():
    out = run("--version")
    assert out.returncode == 0 and out.stdout.strip() == f"mcl2pnml {__version__}"
    out = run("--help")
    assert out.returncode == 0 and "validate" in out.stdout and "Examples:" in out.stdout
    assert run("validate", "--help").stdout.count("--grammar") >= 1


def test_validate_a_good_file(tmp_path):
    path = save_pnml(primitive(), tmp_path / "primitive.pnml")
    out = run("validate", path)   # our schema; the official grammar only where given
    assert out.returncode == 0, out.stderr
    assert "valid PNML P/T net" in out.stdout and "7 places, 8 transitions" in out.stdout


def test_validate_finds_what_the_grammar_lets_pass():
    out = run("validate", DATA / "pnml" / "invalid" / "place_to_place.pnml")
    assert out.returncode == 2
    assert "place_to_place.pnml:7:7: arc 'a' goes from place 'p' to place 'q'" in out.stderr
    assert "Traceback" not in out.stderr


@pytest.mark.parametrize("args, message", [
    (["validat", "x.pnml"], "No such command 'validat'"),
    (["validate"], "Missing argument 'FILE'"),
    (["validate", "/no/such/file.pnml"], "does not exist"),
    (["--bogus"], "No such option '--bogus'"),
])
def test_bad_arguments_are_one_line_and_exit_2(args, message):
    out = run(*args)
    assert out.returncode == 2
    assert message in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1, out.stderr
    assert "Traceback" not in out.stderr


@pytest.mark.parametrize("path", sorted(p for p in (DATA / "pnml" / "invalid").glob("*.pnml")
                                       # those the strict reading refuses (a golden message)
                                       if p.with_suffix(".expected").exists()),
                         ids=lambda p: p.name)
def test_bad_pnml_exits_2_with_positions(path):
    out = run("validate", path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert f"{path}:" in out.stderr and "^" in out.stderr


def test_runs_from_any_directory(tmp_path):
    out = run("--version", cwd=tmp_path)
    assert out.returncode == 0
