"""Each example's properties: those of ``NAME.props`` hold, those of ``NAME.false.props`` fail.

``examples/NAME.props`` states what the mission's engineer guarantees, each
property with why it holds; ``examples/NAME.false.props`` states mistakes
easily made about the same mission, each with why it is false
(docs/properties.md). Both are checked here through the facade, as
``mcl2pnml analyze --properties`` checks them: in the time the mission runs in
(``pipeline.check_properties_timed``, docs/time.md). On the untimed net
(``--untimed``, ``pipeline.check_properties``) the false ones fail too, and the
true ones hold, but for those whose comment says they fail on the untimed net,
and why: the comment is held to the verdict both ways.

The counterexample of each false property is kept as the command prints
it, in ``tests/data/counterexamples/NAME.PROPNAME.txt``: the lines of that
property in the output of
``mcl2pnml analyze examples/NAME.mcl --state-space --properties examples/NAME.false.props
--explain`` run from the repository's root (without ``--explain`` the command gives the
firing sequence only). After a deliberate change to how a verdict
is printed, rewrite every one of them (dam_inspection's included) with one
command, then review the diff:

    MCL2PNML_REGOLD=1 .venv/bin/python -m pytest tests/analysis/test_example_properties.py -m 'slow or not slow'

dam_inspection's state space (197,331 markings; some 15 s for both its
files) and sampling's zones in time (490,000, some 35 s a file) put their
cases behind the ``slow`` marker; the others take a few seconds together.
"""
from __future__ import annotations

import functools
import os
from pathlib import Path

import pytest

from mcl2pnml.analysis.checking.on_graph import Status
from mcl2pnml import pipeline

from helpers import DATA, ROOT, assert_golden, untimed_only
from sampling import variants

EXAMPLES = ROOT / "examples"
COUNTEREXAMPLES = DATA / "counterexamples"
#: The examples whose properties take more than a few seconds to check (sampling: its
#: sampling loop beside a 600 s leg gives 490,000 zones in time, some 35 s a file).
SLOW = {"dam_inspection", "sampling"}


def _examples(quick=None) -> list:
    """Every example, the ``SLOW`` ones and those not in ``quick`` (where it is given) marked
    slow."""
    stems = [m.stem for m in sorted(EXAMPLES.glob("*.mcl"))]
    kept = [s for s in stems if s not in SLOW and (quick is None or s in quick)]
    return variants(stems, kept, ids=stems, slow=[s for s in stems if s in SLOW])


@functools.lru_cache(maxsize=None)
def _verdicts(name: str, suffix: str, timed: bool = True) -> tuple:
    """The verdicts of ``examples/NAME.SUFFIX``'s properties (the mission declares none)."""
    mission = EXAMPLES / f"{name}.mcl"
    _, properties = pipeline.properties_of(mission, extra=EXAMPLES / f"{name}{suffix}")
    assert properties and all(p.location.file.endswith(suffix) for p in properties)
    net = pipeline.compile_file(mission)
    check = pipeline.check_properties_timed if timed else pipeline.check_properties
    return tuple(check(net, properties))





@functools.lru_cache(maxsize=None)
def _printed(name: str) -> str:
    """What ``mcl2pnml analyze --properties NAME.false.props --explain`` prints, run from
    the root."""
    from click.testing import CliRunner

    from mcl2pnml.cli import main
    here = Path.cwd()
    os.chdir(ROOT)   # the locations printed are then examples/NAME.false.props:L:C
    try:
        out = CliRunner().invoke(main, ["analyze", f"examples/{name}.mcl", "--state-space",
                                        "--no-progress", "--properties",
                                        f"examples/{name}.false.props", "--explain"])
    finally:
        os.chdir(here)
    assert out.exit_code == 1, out.output   # a property fails
    return out.stdout


def _block(printed: str, prop: str) -> str:
    """The lines the command prints for property ``prop``: its verdict, then its indented
    counterexample."""
    lines = printed.splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith(f"property {prop} ("))
    end = start + 1
    while end < len(lines) and lines[end].startswith(" "):
        end += 1
    return "\n".join(lines[start:end]) + "\n"


def test_every_example_has_both_files():
    for mission in sorted(EXAMPLES.glob("*.mcl")):
        assert mission.with_suffix(".props").is_file(), mission.name
        assert mission.with_name(mission.stem + ".false.props").is_file(), mission.name


@pytest.mark.parametrize("name", _examples())
def test_every_property_of_the_props_file_holds(name):
    verdicts = _verdicts(name, ".props")
    assert len(verdicts) >= 3
    assert {v.property.name: v.status for v in verdicts} == \
        {v.property.name: Status.HOLDS for v in verdicts}


@pytest.mark.parametrize("name", _examples())
def test_on_the_untimed_net_exactly_the_ones_said_to_fail_there_do(name):
    said = untimed_only(EXAMPLES / f"{name}.props")
    assert {v.property.name: v.status for v in _verdicts(name, ".props", False)} == \
        {v.property.name: Status.FAILS if v.property.name in said else Status.HOLDS
         for v in _verdicts(name, ".props", False)}
    assert all(v.status is Status.FAILS for v in _verdicts(name, ".false.props", False))


# multi_leg and lawnmower reach no line or branch of ours that the others do not: make test-slow
@pytest.mark.parametrize("name", _examples(quick={"sauce", "docking"}))
def test_every_property_of_the_false_file_fails_as_printed(name):
    verdicts = _verdicts(name, ".false.props")
    assert {v.property.name: v.status for v in verdicts} == \
        {v.property.name: Status.FAILS for v in verdicts}
    for v in verdicts:
        assert v.transitions, v.property.name
        block = _block(_printed(name), v.property.name)
        assert block.splitlines()[0].endswith(": fails")
        assert_golden(COUNTEREXAMPLES / f"{name}.{v.property.name}.txt", block)


def test_every_pattern_and_every_scope_holds_in_some_example():
    from mcl2pnml.core.patterns import Pattern, ScopeKind
    stated = []
    for mission in sorted(EXAMPLES.glob("*.mcl")):
        stated += pipeline.properties_of(mission, extra=mission.with_suffix(".props"))[1]
    assert {p.pattern for p in stated} == set(Pattern)
    assert {p.scope.kind for p in stated} == set(ScopeKind)
