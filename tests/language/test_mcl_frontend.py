"""The MCL front end: parser, checker, functional form (golden files, sqlglot style)."""
import pytest
from hypothesis import given, settings, strategies as st

from mcl2pnml.language import ast
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.language.functional import format_node, mission_expression
from mcl2pnml.language.semantics import check_program
from mcl2pnml.language.parser import decode, parse, parse_file

from helpers import DATA, ROOT, assert_error_golden, assert_golden, run_cli as run

INVALID = sorted((DATA / "mcl" / "invalid").glob("*.mcl"))
NOT_ON_SIM = sorted((DATA / "mcl" / "not_on_sim").glob("*.mcl"))
EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))
ALGORITHM_2 = ("sequence(if-then-else(monitor(Survey(), FindCross()), sequence("
               "AchieveDepth(CrossDepth), DropMarker()), NULL), AchieveDepth(SurfaceDepth))")


def test_the_papers_algorithm_1_gives_its_algorithm_2():
    checked = check_program(parse_file(ROOT / "examples" / "sauce.mcl"))
    assert format_node(mission_expression(checked.mission)) == ALGORITHM_2


def test_the_ast_keeps_positions_and_is_immutable():
    program = parse("primitive P();\ntask T() = AchieveGoal(P());\nmission {\n  T();\n}\n", "m.mcl")
    call = program.of(ast.Mission)[0].body.body[0]
    assert call == ast.Call("T", ()) and (call.pos.line, call.pos.column) == (4, 3)
    with pytest.raises(AttributeError):
        call.name = "U"  # type: ignore[misc]


@pytest.mark.parametrize("source, expected", [
    ("mission { }", "NULL"),
    ("mission { T(); }", "T()"),
    ("mission { T(); T(); T(); }", "sequence(T(), sequence(T(), T()))"),
    ("mission { parallel(T(), T(), {T(); T();}); }",
     "parallel(T(), parallel(T(), sequence(T(), T())))"),
    ("mission { while (T()) do { T(); } }", "while(T(), T())"),
    ("mission { while (T()) { } }", "while(T(), NULL)"),
    ("mission { if (T()) { T(); } else { } }", "if-then-else(T(), T(), NULL)"),
    ("mission { if ({T(); T();}) then { T(); } }",
     "if-then-else(sequence(T(), T()), T(), NULL)"),
    ("mission { monitor(parallel(T(), T()), T()); }", "monitor(parallel(T(), T()), T())"),
])
def test_functional_form(source, expected):
    program = parse("primitive P();\ntask T() = AchieveGoal(P());\n" + source)
    assert format_node(mission_expression(check_program(program).mission)) == expected


def test_literals_and_comments():
    program = parse('''
        /* a block
           comment */
        const Name = "dock \\"A\\"";   // a string with quotes
        const Neg = -1.5e2;
        const Point = (1, -2.0, Name);
        primitive P(x);
        task T(x) = KeepGoal(P(x)) timeout 2.5;
        mission { T(Point); T(+3); }
    ''')
    checked = check_program(program)
    assert checked.consts == {"Name": 'dock "A"', "Neg": -150.0, "Point": (1, -2.0, 'dock "A"')}
    assert checked.tasks["T"].timeout.value == 2.5


@pytest.mark.parametrize("path", INVALID, ids=lambda p: p.name)
def test_invalid_files_give_the_expected_messages(path):
    with pytest.raises(Mcl2PnmlError) as info:
        check_program(parse(decode(path.read_bytes(), path.name), path.name))
    assert_error_golden(path, info.value)


@pytest.mark.parametrize("path", NOT_ON_SIM, ids=lambda p: p.name)
def test_check_vehicle_sim_names_every_primitive_the_simulator_cannot_fly(path):
    out = run("check", path.name, "--vehicle", "sim", cwd=path.parent)
    assert out.returncode == (0 if path.stem.startswith("every") else 2), out.stderr
    assert_golden(path.with_suffix(".expected"), out.stdout + out.stderr)


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_example_checks(path):
    check_program(parse_file(path))


def test_cli_check_and_functional():
    out = run("functional", ROOT / "examples" / "sauce.mcl")
    assert out.returncode == 0 and out.stdout.strip() == ALGORITHM_2
    out = run("check", DATA / "mcl" / "invalid" / "several_errors.mcl")
    assert out.returncode == 2 and out.stderr.count("several_errors.mcl:") == 3
    assert "Traceback" not in out.stderr


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=200) | st.text(max_size=200).map(str.encode))
def test_garbage_gives_our_error_and_nothing_else(data):
    try:
        check_program(parse(decode(data, "fuzz.mcl"), "fuzz.mcl"))
    except Mcl2PnmlError as e:
        assert e.location is not None and e.location.file == "fuzz.mcl"


def test_long_lines_and_long_listings_are_cut_to_what_helps():
    from mcl2pnml.core.errors import EXCERPT_WIDTH, LISTED, Location, did_you_mean

    line = "x" * 500 + "FAULT" + "y" * 500
    shown = Location("m.mcl", 1, 501, line).excerpt().splitlines()
    assert len(shown[0]) <= EXCERPT_WIDTH + 4 + 6          # indent and two "..."
    assert shown[0].strip().startswith("...") and shown[0].endswith("...")
    assert shown[0][shown[1].index("^"):].startswith("FAULT")  # the caret still lands on it
    names = [f"Task{i}" for i in range(100)]
    hint = did_you_mean("Task", names, "declared tasks")
    assert hint.count(", ") == LISTED and f"({100 - LISTED} more)" in hint


@pytest.mark.parametrize("nesting", ["{ " * 150 + "T();" + " }" * 150,
                                     "T(" + "(" * 150 + "1" + ")" * 150 + ");",
                                     "if (T()) { " * 80 + "T();" + " }" * 80])
def test_deep_nesting_is_an_error_not_a_crash(nesting):
    with pytest.raises(Mcl2PnmlError, match="nested too deeply") as info:
        parse("primitive P(x);\ntask T(x) = AchieveGoal(P(x));\nmission { " + nesting + " }",
              "deep.mcl")
    assert info.value.location.line == 3
