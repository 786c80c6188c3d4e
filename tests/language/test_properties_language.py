"""A mission's properties in MCL (docs/properties.md): syntax, checks, atoms on the net.

The invalid inputs' messages are golden files with the rest of MCL's
(tests/data/mcl/invalid/property_*.mcl, run by test_mcl_frontend.py).
"""
import itertools
from pathlib import Path

import pytest

from mcl2pnml import pipeline
from mcl2pnml.core import patterns as typed
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.language import ast
from mcl2pnml.language.semantics import check_program
from mcl2pnml.language.compiler import compile_checked
from mcl2pnml.language.parser import parse, parse_file
from mcl2pnml.language.declared_properties import ATOMS, compile_properties, text_of

from helpers import ROOT, run_cli as run

EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))
SAUCE = ROOT / "examples" / "sauce.mcl"

PATTERNS = {"never A": typed.Pattern.ABSENCE, "always A": typed.Pattern.UNIVERSALITY,
            "eventually A": typed.Pattern.EXISTENCE,
            "at most 3 times A": typed.Pattern.BOUNDED_EXISTENCE,
            "A only after B": typed.Pattern.PRECEDENCE, "A leads to B": typed.Pattern.RESPONSE}
SCOPES = {"": typed.ScopeKind.GLOBALLY, "globally": typed.ScopeKind.GLOBALLY,
          "before B": typed.ScopeKind.BEFORE, "after A": typed.ScopeKind.AFTER,
          "between A and B": typed.ScopeKind.BETWEEN,
          "after A until B": typed.ScopeKind.AFTER_UNTIL}
A, B = "enabled(KeepDepth)", "outcome(OK) or not running(Dive)"


def _mission(props: str) -> str:
    return ("primitive KeepDepth(d);\ntask Dive(d) = AchieveGoal(KeepDepth(d));\n"
            f"mission {{ Dive(2.0); }}\n{props}\n")


@pytest.mark.parametrize("pattern, scope", list(itertools.product(PATTERNS, SCOPES)))
def test_every_pattern_in_every_scope_parses_and_compiles(pattern, scope):
    written = f"{pattern} {scope}".replace("A", f"({A})").replace("B", f"({B})").strip()
    checked = check_program(parse(_mission(f"property P: {written};"), "m.mcl"))
    (decl,) = checked.program.of(ast.Property)
    net = compile_checked(checked)
    (prop,) = compile_properties(net, [checked.program])
    assert prop.pattern is PATTERNS[pattern] and prop.scope.kind is SCOPES[scope]
    assert prop.bound == (3 if "at most" in pattern else None)
    assert (prop.s is not None) == (prop.pattern in (typed.Pattern.PRECEDENCE,
                                                     typed.Pattern.RESPONSE))
    assert (prop.location.line, prop.location.column) == (4, 10)
    # written back, it parses to the same property
    again = parse(_mission(f"property P: {text_of(decl)};"), "m.mcl").of(ast.Property)
    assert again == [decl]


def test_precedence_of_not_and_or():
    (decl,) = parse(_mission("property P: never not enabled(KeepDepth) and outcome(OK) "
                             "or outcome(FAIL);"), "m.mcl").of(ast.Property)
    assert decl.p == ast.PropOr((ast.PropAnd((ast.PropNot(ast.PropAtom("enabled", ("KeepDepth",))),
                                              ast.PropAtom("outcome", ("OK",)))),
                                 ast.PropAtom("outcome", ("FAIL",))))


def test_property_words_stay_names_elsewhere():
    # no new keyword: a mission that names a primitive "before" or "never" still checks
    program = parse("primitive before();\ntask never() = AchieveGoal(before());\n"
                    "mission { never(); }\nproperty after: never enabled(before) "
                    "before running(never);\n", "m.mcl")
    net, (prop,) = _compiled(program)
    assert typed.places_of(prop.p) == {"before.ON"} and "never.GATE" in net.place_index


def _compiled(program, reduced=False):
    checked = check_program(program)
    net = compile_checked(checked, reduced=reduced)
    return net, compile_properties(net, [checked.program], reduced=reduced)


def test_the_atoms_name_the_places_of_the_table():
    _, props = _compiled(parse(_mission(
        "property P: always enabled(KeepDepth) or achieved(KeepDepth) or failed(KeepDepth) "
        "or running(Dive) or ended(Dive, ABORTED) or outcome(FAIL) or true or false;"),
        "m.mcl"))
    assert props[0].p == typed.Or((
        typed.Tokens(("KeepDepth.ON",)), typed.Tokens(("KeepDepth.S2",)),
        typed.Tokens(("KeepDepth.S1",)), typed.Not(typed.Tokens(("Dive.GATE",))),
        typed.Tokens(("Dive.ABORTED",)), typed.Tokens(("mission.FAIL",)),
        typed.Const(True), typed.Const(False)))
    assert typed.describe(props[0].p).startswith(
        "KeepDepth.ON >= 1 or KeepDepth.S2 >= 1 or KeepDepth.S1 >= 1 or "
        "(not (Dive.GATE >= 1)) or Dive.ABORTED >= 1 or mission.FAIL >= 1 or true")


def _every_atom(checked) -> str:
    """One property with every atom kind on every name of a checked mission."""
    atoms = [f"outcome({r})" for r in ("OK", "FAIL", "ABORTED")]
    for prim in checked.primitives:
        atoms += [f"{kind}({prim})" for kind in ("enabled", "achieved", "failed")]
    for name in (*checked.tasks, *checked.functions):
        atoms += [f"running({name})"] + [f"ended({name}, {r})" for r in ("OK", "FAIL", "ABORTED")]
    assert {a.split("(")[0] for a in atoms} == set(ATOMS)
    return " or ".join(atoms)


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_atom_of_every_example_names_places_of_its_net(path):
    checked = check_program(parse_file(path))
    source = path.read_text() + f"\nproperty Every: eventually {_every_atom(checked)};\n"
    net, (prop,) = _compiled(parse(source, path.name))
    assert typed.places_of(prop.p) <= set(net.place_index)   # compile_properties checks too
    assert len(typed.places_of(prop.p)) == 3 + 3 * len(checked.primitives) + 4 * (
        len(checked.tasks) + len(checked.functions))


def test_the_reduced_model_has_no_primitive_atoms():
    program = parse(_mission("property P: never enabled(KeepDepth) and running(Dive);"), "m.mcl")
    with pytest.raises(Mcl2PnmlError) as info:
        _compiled(program, reduced=True)
    assert str(info.value).startswith("m.mcl:4:19: 'enabled(KeepDepth)' reads a primitive's "
                                      "net, and the reduced model (Fig. 3) has none")
    program = parse(_mission("property P: never running(Dive) before outcome(OK);"), "m.mcl")
    _, (prop,) = _compiled(program, reduced=True)
    assert prop.p == typed.Not(typed.Tokens(("Dive.GATE",)))


def test_properties_do_not_change_the_net():
    plain = pipeline.compile_file(SAUCE)
    net, props = pipeline.properties_of(SAUCE, extra=SAUCE.with_suffix(".props"))
    with_decl = pipeline.compile_source(SAUCE.read_text() + "\nproperty P: eventually true;\n",
                                         "sauce.mcl")
    assert net == plain == with_decl
    assert len(props) >= 3 and all(p.location.file.endswith("sauce.props") for p in props)


def test_a_side_file_holds_properties_only_and_shares_their_names(tmp_path: Path):
    mission = tmp_path / "m.mcl"
    mission.write_text(_mission("property P: eventually outcome(OK);"))
    side = tmp_path / "m.props"
    side.write_text("const X = 1;\nproperty Q: never failed(Keep);\n")
    with pytest.raises(Mcl2PnmlError) as info:
        pipeline.properties_of(mission, extra=side)
    assert str(info.value).splitlines()[::3] == [
        f"{side}:1:7: a properties file holds only 'property' declarations; declare the rest "
        "in the mission",
        f"{side}:2:26: undeclared primitive 'Keep'; did you mean 'KeepDepth'? declared "
        "primitives: KeepDepth"]
    side.write_text("property P: never failed(KeepDepth);\n")
    with pytest.raises(Mcl2PnmlError, match=r"m.props:1:10: duplicate property 'P': already "
                                            r"declared in .*m.mcl"):
        pipeline.properties_of(mission, extra=side)


def test_nesting_is_bounded():
    with pytest.raises(Mcl2PnmlError, match="nested too deeply"):
        parse(_mission("property P: never " + "not (" * 150 + "true" + ")" * 150 + ";"), "m.mcl")


def test_check_prints_each_property_as_place_formulas():
    out = run("check", SAUCE, "--properties")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    at = lines.index("property MarkerOnlyOverCross (" + str(SAUCE.with_suffix(".props"))
                     + ":7:10): enabled(ReleaseMarker) only after achieved(DetectCross) globally")
    assert lines[at + 1:at + 3] == [
        "  precedence: P = ReleaseMarker.ON >= 1; S = DetectCross.S2 >= 1", "  globally"]
    assert "  after: Q = mission.OK >= 1 or mission.FAIL >= 1 or mission.ABORTED >= 1" in lines
    missing = run("check", SAUCE, "--properties", "nowhere.props")
    assert missing.returncode == 2 and "no file 'nowhere.props'" in missing.stderr


def test_the_fast_and_the_slow_parser_agree_on_properties():
    from mcl2pnml.language.parser import _parse_tree
    source = SAUCE.read_text() + SAUCE.with_suffix(".props").read_text()
    fast = parse(source, "sauce.mcl").declarations
    assert fast == _parse_tree(source, "sauce.mcl") and len(fast) > 15
    assert [d.pos for d in fast if isinstance(d, ast.Property)] == \
        [d.pos for d in _parse_tree(source, "sauce.mcl") if isinstance(d, ast.Property)]
