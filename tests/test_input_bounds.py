"""Every input has a bound, checked before the work it would cost: a properties file's
size before it is read, its atoms before they are checked, the counterexamples explained
before they are searched for; and no counterexample is written over an input.

Each case is the command line and its one message, exit status 2, no traceback, nothing
written or overwritten. Nothing is timed: each refusal is shown to come before the stage
it spares (a file of NUL bytes refused for its size was not read, properties refused for
their atoms were not checked, the witnesses searched for are counted).
"""
from __future__ import annotations

import os

import pytest

from helpers import ROOT, cli, one_error, run_cli
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.files import read_bytes, read_text
from mcl2pnml.core.bounds import MAX_PROPERTY_ATOMS

SAUCE = ROOT / "examples" / "sauce.mcl"


@pytest.fixture
def mission(tmp_path, monkeypatch):
    """The paper's mission in a directory of its own, the current one (as a user types)."""
    path = tmp_path / "m.mcl"
    path.write_bytes(SAUCE.read_bytes())
    monkeypatch.chdir(tmp_path)
    return path


def first_line(out) -> str:
    return out.output.strip().splitlines()[0]


def contents(folder) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


# -- a properties file's size, checked before it is read ------------------------------------

def sparse(path, size: int):
    """A file of ``size`` NUL bytes that takes no room on disk: read and parsed, it would be
    refused as binary, so that a refusal for its size shows it was not read."""
    with open(path, "wb") as f:
        f.truncate(size)
    return path


@pytest.mark.timeout(60)
def test_a_properties_file_too_large_is_refused_before_it_is_read(mission):
    sparse(mission.parent / "big.props", 200 << 20)
    out = cli("analyze", "m.mcl", "--properties", "big.props")
    one_error(out)
    assert first_line(out) == ("big.props: cannot read the properties file: it is 200.0 MiB, "
                               "over the limit of 4.0 MiB (--max-properties-size to raise it)")


@pytest.mark.timeout(60)
@pytest.mark.parametrize("command", ["check", "compile", "analyze"])
def test_the_side_file_is_bounded_too_and_the_option_sets_the_limit(mission, command):
    sparse(mission.with_suffix(".props"), (1 << 20) + 1)
    out = cli(command, "m.mcl", "--properties", "--max-properties-size", "1M")
    one_error(out)
    assert out.output.strip().splitlines()[-1] == (
        "m.props: cannot read the properties file: it is 1.0 MiB, over the limit of 1.0 MiB "
        "(--max-properties-size to raise it)")
    assert not (mission.parent / "m.pnml").exists()
    # raised, the file is read, and refused for what it holds
    out = cli(command, "m.mcl", "--properties", "--max-properties-size", "2M")
    assert "this is not an MCL text file (a NUL byte: binary?)" in one_error(out)


def test_a_bounded_read_reads_no_more_than_its_limit(tmp_path):
    # /proc's files say they are empty: only the bytes read can tell
    with pytest.raises(Mcl2PnmlError) as info:
        read_bytes("/proc/self/status", "status", limit=10, option="--max-status")
    assert str(info.value) == ("/proc/self/status: cannot read the status: it is over the "
                               "limit of 0.0 MiB (--max-status to raise it)")
    small = tmp_path / "small.txt"
    small.write_text("1234567890")
    assert read_text(small, "note", limit=10) == "1234567890"
    with pytest.raises(Mcl2PnmlError, match="it is 0.0 MiB, over the limit of 0.0 MiB$"):
        read_text(small, "note", limit=9)


# -- the atoms of the properties, counted before they are checked -----------------------------

def chain(operands: int, atom: str = "outcome(FAIL)") -> str:
    return f"property Long: never {' or '.join([atom] * operands)};\n"


@pytest.mark.timeout(60)
def test_properties_of_too_many_atoms_are_refused_before_they_are_checked(mission):
    # the undeclared primitive after the limit is never reached: checking would name it
    text = chain(MAX_PROPERTY_ATOMS - 1) + "property Bad: never enabled(Nope) or enabled(Nope);\n"
    (mission.parent / "long.props").write_text(text)
    out = cli("analyze", "m.mcl", "--properties", "long.props")
    one_error(out)
    assert first_line(out) == ("long.props:2:38: the properties have 10,001 atoms in all, "
                               "over the limit of 10,000 (--max-atoms to raise it); this is "
                               "atom 10,001")
    out = cli("analyze", "m.mcl", "--properties", "long.props", "--max-atoms", "10001")
    assert "undeclared primitive 'Nope'" in first_line(out)


@pytest.mark.timeout(60)
def test_the_missions_own_properties_count_with_the_files(mission):
    mission.write_text(mission.read_text() + "property Own: never outcome(OK) or outcome(FAIL);\n")
    (mission.parent / "m.props").write_text("property Side: never outcome(OK);\n")
    out = cli("compile", "m.mcl", "--properties", "--max-atoms", "2")
    one_error(out)
    assert first_line(out) == ("m.props:1:22: the properties have 3 atoms in all, over the "
                               "limit of 2 (--max-atoms to raise it); this is atom 3")
    assert not (mission.parent / "m.pnml").exists()


# -- long chains and deep nesting: parsed, or refused with one message -----------------------

@pytest.mark.timeout(60)
def test_a_chain_of_100000_operands_is_refused_by_its_atoms_not_by_a_recursion(mission):
    (mission.parent / "long.props").write_text(chain(100_000))
    out = cli("check", "m.mcl", "--properties", "long.props")
    assert out.exit_code == 2 and "Traceback" not in out.output
    assert out.output.splitlines()[1].startswith(
        "long.props:1:170022: the properties have 100,000 atoms in all, over the limit of "
        "10,000 (--max-atoms to raise it)")


@pytest.mark.timeout(60)
def test_a_long_chain_within_the_limit_is_checked_and_judged(mission):
    (mission.parent / "long.props").write_text(
        "property Long: always " + " and ".join(["not outcome(FAIL)"] * 5_000)
        + " or outcome(FAIL);\n")
    out = cli("analyze", "m.mcl", "--state-space", "--properties", "long.props")
    assert out.exit_code == 0, out.output
    assert "property Long (long.props:1:10): holds" in out.output


@pytest.mark.timeout(60)
def test_parentheses_100000_deep_parse(mission):
    depth = 100_000
    (mission.parent / "deep.props").write_text(
        f"property Deep: never {'(' * depth}outcome(FAIL){')' * depth};\n")
    out = cli("check", "m.mcl", "--properties", "deep.props")
    assert out.exit_code == 0, out.output
    assert "property Deep (deep.props:1:10): never outcome(FAIL) globally" in out.output


@pytest.mark.timeout(60)
@pytest.mark.parametrize("expression", [
    "not " * 1_000 + "outcome(FAIL)",
    "(outcome(FAIL) and (outcome(OK) or " * 500 + "true" + "))" * 500,
], ids=["negations", "operators"])
def test_operators_nested_too_deeply_are_one_message(mission, expression):
    (mission.parent / "deep.props").write_text(f"property Deep: never {expression};\n")
    out = cli("analyze", "m.mcl", "--properties", "deep.props")
    one_error(out, "deep.props:1:", ": nested too deeply: more than 100 levels of operators "
                   "in a property; write it more simply, or as several properties")


# -- counterexamples: at most so many explained, never written over an input -----------------

def failing(count: int) -> str:
    return "".join(f"property P{k}: never outcome(OK);\n" for k in range(count))


@pytest.mark.timeout(120)
def test_only_the_counterexamples_written_are_searched_for(mission, monkeypatch):
    import mcl2pnml.counterexample as counterexample
    searched = []
    real = counterexample.witness
    monkeypatch.setattr(counterexample, "witness",
                        lambda *a, **k: searched.append(a[2].name) or real(*a, **k))
    (mission.parent / "many.props").write_text(failing(60))
    out = cli("analyze", "m.mcl", "--state-space", "--properties", "many.props",
              "--counterexamples", "out", "--max-counterexamples", "2")
    assert out.exit_code == 1 and "Traceback" not in out.output, out.output
    assert searched == ["P0", "P1"]
    assert sorted(p.name for p in (mission.parent / "out").iterdir()) == [
        f"P{k}.{suffix}" for k in (0, 1) for suffix in ("html", "log", "txt", "vehicle.json")]
    assert ("counterexamples of 58 of the 60 failing properties left out: the first 2 are "
            "explained (--max-counterexamples to raise the limit)") in out.output.splitlines()
    # every verdict is still given, with its firing sequence; the first two explained
    assert out.output.count(": fails\n") == 60
    assert out.output.count("in the mission's terms") == 2


@pytest.mark.timeout(60)
def test_a_counterexample_named_as_the_properties_file_is_refused_before_anything(mission):
    (mission.parent / "Never.txt").write_text("property Never: never outcome(OK);\n")
    kept = contents(mission.parent)
    out = run_cli("analyze", "m.mcl", "--properties", "Never.txt", "--counterexamples", ".",
                  cwd=mission.parent)
    one_error(out)
    assert out.stderr.splitlines() == [
        "mcl2pnml analyze: error: Invalid value for --counterexamples: 'Never.txt' is the "
        "properties file (--properties), which this command reads: writing there would "
        "destroy it; give another folder, or rename the property (see 'mcl2pnml analyze "
        "--help')"]
    assert contents(mission.parent) == kept


@pytest.mark.timeout(60)
@pytest.mark.parametrize("link", [os.link, os.symlink], ids=["hard", "symbolic"])
def test_no_counterexample_is_written_through_a_link_to_an_input(mission, link):
    side = mission.with_suffix(".props")
    side.write_text("property Never: never outcome(OK);\n")
    out_dir = mission.parent / "out"
    out_dir.mkdir()
    link(mission, out_dir / "Never.log")
    link(side, out_dir / "Never.html")
    kept = contents(mission.parent)
    out = cli("analyze", "m.mcl", "--properties", "--counterexamples", "out")
    one_error(out, "--counterexamples: 'out/Never.log' is the mission, which this command "
                   "reads")
    os.unlink(out_dir / "Never.log")
    out = cli("analyze", "m.mcl", "--properties", "--counterexamples", "out")
    one_error(out, "--counterexamples: 'out/Never.html' is the properties file "
                   "(--properties), which this command reads")
    assert mission.read_bytes() == kept["m.mcl"] and side.read_bytes() == kept["m.props"]
    assert [p.name for p in out_dir.iterdir()] == ["Never.html"]     # nothing written


@pytest.mark.timeout(60)
def test_a_query_file_of_compile_is_not_written_over_the_properties_file(mission):
    (mission.parent / "x.LTLCardinality.xml").write_text("property P: never outcome(OK);\n")
    kept = contents(mission.parent)
    out = cli("compile", "m.mcl", "-o", "x.pnml", "--properties", "x.LTLCardinality.xml")
    one_error(out, "--properties: 'x.LTLCardinality.xml' is the properties file "
                   "(--properties), which this command reads")
    assert contents(mission.parent) == kept
