"""Every input has a bound, checked before the work it would cost: a mission's size and a
properties file's before they are read, the atoms before they are checked, the
counterexamples explained before they are searched for; and no counterexample is written
over an input. What a mission's size lets through is read and checked in linear work.

Each case is the command line and its one message, exit status 2, no traceback, nothing
written or overwritten. Nothing is timed: each refusal is shown to come before the stage
it spares (a file of NUL bytes refused for its size was not read, properties refused for
their atoms were not checked, the witnesses searched for are counted).
"""
from __future__ import annotations

import cProfile
import os
import tracemalloc

import pytest

from helpers import ROOT, cli, one_error, run_cli
from mcl2pnml import pipeline
from mcl2pnml.commands import analyze as analyzing, query as querying
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.files import read_bytes, read_text
from mcl2pnml.core.bounds import MAX_MISSION_SIZE, MAX_PROPERTY_ATOMS

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


# -- a mission's size, checked before it is read, by every command that reads one ------------

#: Each command that reads a mission (MISSION.mcl, or FILE given as one), with what else it
#: needs to reach the reading.
READ_A_MISSION = {
    "check": (), "functional": (), "compile": (), "run": (), "analyze": (), "certify": (),
    "show": (), "query": ("--examination", "OneSafe"), "campaign": ("--runs", "1"),
    "odds": ("--vehicle-model", str(ROOT / "examples" / "sauce.model.json")),
}
TOO_LARGE = ("m.mcl: cannot read: it is 17.0 MiB, over the limit of 16.0 MiB "
             "(--max-mission-size to raise it)")


def test_every_command_that_reads_a_mission_has_the_bound():
    from mcl2pnml.cli import main
    bounded = {name for name, command in main.commands.items()
               if any(p.name == "max_mission_size" for p in command.params)}
    assert bounded == set(READ_A_MISSION)
    # one default, in core/bounds.py: the option's is the same number of bytes
    from mcl2pnml.cli_options import MISSION_SIZE
    assert pipeline.parse_size(MISSION_SIZE) == pipeline.mission_limit() == MAX_MISSION_SIZE


@pytest.mark.timeout(60)
@pytest.mark.parametrize("command", sorted(READ_A_MISSION))
def test_a_mission_too_large_is_refused_before_it_is_read(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    sparse(tmp_path / "m.mcl", 17 << 20)
    kept = contents(tmp_path)
    out = cli(command, "m.mcl", *READ_A_MISSION[command])
    one_error(out)
    assert first_line(out) == TOO_LARGE
    assert contents(tmp_path) == kept                 # nothing written
    # raised to its size, it is read, and refused for what it holds: NUL bytes
    out = cli(command, "m.mcl", *READ_A_MISSION[command], "--max-mission-size", "17M")
    one_error(out, "m.mcl:1:1: this is not an MCL text file (a NUL byte: binary?)")
    assert contents(tmp_path) == kept


@pytest.mark.timeout(60)
@pytest.mark.parametrize("command", sorted(READ_A_MISSION))
def test_a_mission_that_is_a_fifo_is_refused_not_waited_on(tmp_path, command):
    fifo = tmp_path / "m.mcl"
    os.mkfifo(fifo)
    out = run_cli(command, "m.mcl", *READ_A_MISSION[command], "--max-mission-size", "1G",
                  cwd=tmp_path, timeout=30)
    # show takes a template's name too: a mission is a regular file, or no file of its
    one_error(out, "no file 'm.mcl'" if command == "show" else
              "m.mcl: cannot read: this is a FIFO (named pipe), not a regular file")


def test_a_bad_size_is_the_options_error(mission):
    out = run_cli("check", "m.mcl", "--max-mission-size", "lots", cwd=mission.parent)
    one_error(out)
    assert out.stderr.splitlines() == ["mcl2pnml check: error: Invalid value for --max-mission-size: "
                               "'lots': a size is a number with K, M, G or T (4G, 500M) (see "
                               "'mcl2pnml check --help')"]


@pytest.mark.timeout(120)
def test_the_facade_bounds_every_mission_it_reads(tmp_path):
    big = sparse(tmp_path / "m.mcl", 17 << 20)
    reads = {
        "check_file": lambda **size: pipeline.check_file(big, *size.values()),
        "compile_file": lambda **size: pipeline.compile_file(big, **size),
        "load_net": lambda **size: pipeline.load_net(big, **size),
        "properties_of": lambda **size: pipeline.properties_of(big, **size),
        "certify_file": lambda **size: pipeline.certify_file(big, **size),
        "show_nets": lambda **size: pipeline.show_nets(str(big), **size),
        "run_mission": lambda **size: pipeline.run_mission(big, **size),
        "analyze": lambda **size: analyzing.analyze(big, analyzing.AnalyzeOptions(**size)),
        "query": lambda **size: querying.query(big, (), querying.QueryOptions(("OneSafe",),
                                                                            **size)),
    }
    for name, read in reads.items():
        with pytest.raises(Mcl2PnmlError) as refused:
            read()
        assert str(refused.value) == TOO_LARGE.replace("m.mcl", str(big)), name
        # raised, in bytes or as the option writes it, the file is read
        for size in (17 << 20, "17M"):
            with pytest.raises(Mcl2PnmlError, match="a NUL byte"):
                read(max_mission_size=size) if name != "check_file" else read(max_size=size)


# -- what the bound lets through is read in linear work ----------------------------------------

HEAD = """primitive GoToWayPoint(wp);
primitive KeepDepth(d);
task Goto(wp) = AchieveGoal(GoToWayPoint(wp)) timeout 100;
task Depth(d) = AchieveGoal(KeepDepth(d)) timeout 60;
"""


def _consts(n: int) -> str:        # each const named by the one before: a chain n long
    return (HEAD + "".join(f"const C{i} = C{i + 1};\n" for i in range(n))
            + f"const C{n} = 1;\nmission {{ Depth(C0); }}\n")


def _relay(n: int) -> str:         # each function running the next in parallel (W002's walk)
    from bench.missions import relay
    return relay(n)


def _watched(n: int) -> str:       # each function watching the next (W005's walk)
    return (HEAD + "".join(f"function F{i}() {{ if (monitor(F{i + 1}(), Depth({i}))) then "
                           f"{{ Goto({i}); }} }}\n" for i in range(n))
            + f"function F{n}() {{ Goto(0); }}\nmission {{ F0(); }}\n")


def _undeclared(n: int) -> str:    # n errors, each of which could search n names
    return ("".join(f"primitive P{i}(x);\ntask T{i}(x) = AchieveGoal(P{i}(x)) timeout 5;\n"
                    for i in range(n))
            + "mission {\n" + "".join(f"U{i}({i});\nP{i}({i});\n" for i in range(n)) + "}\n")


def _recursive(n: int) -> str:     # n cycles, each through the whole chain
    return (HEAD + "".join(f"function F{i}() {{ F{i + 1}(); F0(); }}\n" for i in range(n))
            + f"function F{n}() {{ Depth(2); }}\nmission {{ F0(); }}\n")


def _survey(n: int) -> str:
    from bench.missions import survey
    return survey(n)


def work(text: str) -> tuple[int, int]:
    """What ``check`` does with ``text`` (parse, check, the warnings, the message of every
    error), counted: the Python and C functions called, and the peak of the memory
    allocated (tracemalloc). Both are the same on every run: no clock is read."""
    from mcl2pnml.language.semantics import check_program
    from mcl2pnml.language.lint import lint
    from mcl2pnml.language.parser import parse
    parse("mission { }", "warm.mcl")             # the parser is built once, not counted
    # the calls are counted by the C profiler: the same count as a Python hook on every
    # call (what this counted before), which made checking thirteen times as costly
    counter = cProfile.Profile(builtins=True)
    tracemalloc.start()
    counter.enable()
    try:
        lint(check_program(parse(text, "m.mcl")))
    except Mcl2PnmlError as e:
        str(e)
    finally:
        counter.disable()
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return sum(entry.callcount for entry in counter.getstats()), peak


@pytest.mark.timeout(300)
@pytest.mark.parametrize("shape", [_survey, _consts, _relay, _watched, _undeclared, _recursive],
                         ids=lambda f: f.__name__[1:])
def test_reading_and_checking_a_mission_is_linear_in_its_size(shape):
    # four times the mission, four times the work: a quadratic step gives sixteen (the
    # warnings' walk through the functions below each parallel or monitor, "did you
    # mean" searching every name for every error, every cycle spelled out in full). What
    # a shape's first reading builds once (the survey's: a quarter of its calls at 200)
    # is built before, or it would count in the smaller size only and hide a square.
    # (At 100 and 400, a square step of one call per pair of lines is missed in relay's
    # and watched's: 200 and 800 catch it.)
    work(shape(4))
    (calls, peak), (calls4, peak4) = work(shape(200)), work(shape(800))
    assert calls4 / calls < 5, (calls, calls4)
    assert peak4 / peak < 5, (peak, peak4)
