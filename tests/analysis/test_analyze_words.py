"""The words of `mcl2pnml analyze`'s report that a reader could take the wrong way."""
import json

import pytest

from helpers import DATA, run_cli as run

from mcl2pnml.analysis.report import _change


@pytest.fixture(scope="module")
def nets(tmp_path_factory):
    folder = tmp_path_factory.mktemp("nets")
    for name in ("primitive", "task"):
        out = run("template", name, "-o", folder / f"{name}.pnml")
        assert out.returncode == 0, out.stderr
    return folder


def _row(text: str, name: str) -> str:
    """The value of the property table's row ``name``."""
    (line,) = [line for line in text.splitlines() if line.startswith(name + "  ")]
    return line[len(name):].strip()


def test_both_deadlock_freedoms_are_named(nets):
    """The primitive alone: its only marking is dead, and a proper end."""
    text = run("analyze", nets / "primitive.pnml").stdout
    assert _row(text, "deadlock-free (textbook: no dead marking reachable)") == \
        "no (1 dead marking)"
    assert _row(text, "no deadlock (ours: every dead marking is a proper end)") == "yes"
    r = json.loads(run("analyze", nets / "primitive.pnml", "--json").stdout)
    assert r["deadlock_free"] is True and r["deadlock_free_textbook"] is False


def test_a_net_without_our_interface_has_the_textbook_one_alone():
    path = DATA / "pnml" / "foreign" / "pm4py_order_process.pnml"   # read the forgiving way
    assert run("analyze", path).returncode == 2   # refused strictly for its final marking
    text = run("analyze", path, "--lenient").stdout
    assert _row(text, "deadlock-free (textbook: no dead marking reachable)") == \
        "no (1 dead marking)"
    assert "ours:" not in text
    r = json.loads(run("analyze", path, "--lenient", "--json").stdout)
    assert r["deadlock_free"] is False and r["deadlock_free_textbook"] is False


def test_semipositive_t_invariants_are_printed_beside_the_basis(nets):
    text = run("analyze", nets / "primitive.pnml").stdout
    assert "T-invariants (a basis of 4; its entries may be negative):" in text
    semi = text.split("Minimal semi-positive T-invariants (1;", 1)[1].splitlines()
    assert semi[1] == "  lost + regained"


def test_terminal_markings_are_changes_from_m0_and_whole_in_json(nets):
    text = run("analyze", nets / "task.pnml").stdout
    block = text.split("Terminal markings (3)", 1)[1].splitlines()[1:4]
    assert block == ["  -B +FAIL", "  -B +OK", "  -A -B +ABORTED"]
    r = json.loads(run("analyze", nets / "task.pnml", "--json").stdout)
    assert ["A", "C", "FAIL", "MTX", "OFF"] in r["terminal_markings"]
    primitive = run("analyze", nets / "primitive.pnml").stdout
    assert "  M0 (no change)" in primitive.splitlines()


def test_a_change_counts_tokens():
    assert _change({"p": 2}, ["q*2"]) == "-p*2 +q*2"
    assert _change({"p": 1}, ["p*3", "r*w"]) == "+p*2 +r*w"
    assert _change({"p": 1}, ["p"]) == "M0 (no change)"


def test_the_terms_point_to_the_glossary_once(nets):
    text = run("analyze", nets / "task.pnml").stdout
    assert text.count("docs/glossary.md") == 1
    assert text.rstrip().splitlines()[-1].endswith("see docs/glossary.md")
