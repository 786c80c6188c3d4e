"""Our PNML schema (``mcl2pnml/io/pnml/ptnet.rng``) against the official 2009 grammar.

The schema is ours so that ``mcl2pnml validate`` works with nothing beside
the package; it is meant to admit exactly the documents the standard's P/T
grammar admits. Held here to that, wherever the official files are found
(``../shared/pnml-grammar``, beside the checkout, given explicitly):

* every PNML we write: each template, each example mission, generated missions;
* a corpus: the hand-made files of ``data/pnml/schema`` (``valid/``, and
  ``invalid/`` with each message as a golden ``.expected``), the broken
  files of ``data/pnml/invalid`` and the other tools' files of
  ``data/pnml/foreign``;
* mutants of valid files: every element deleted, doubled, renamed, moved out
  of its namespace, given text or an unknown child, its children reversed;
  every attribute dropped or set to values of the wrong kind (other ids
  among them), every number label set to what xsd accepts and refuses;
  and hypothesis's compositions of several of these;
* every order of up to four children of a net, a page, a place, an arc and
  their labels, against what the standard says (any order, so many of each).

Both schemas must give the same verdict on each, but for the cases listed in
``SCHEMA_DIFFERENCES`` with the reason, and the list must be exactly those
cases: the pages whose children libxml2 refuses in some orders when it
checks the official grammar (a nested interleave), which the standard, and
our schema, admit. On top, the reader's rules (the strict reading of
``mcl2pnml/io/pnml/strict.py``) refuse what no schema can say, and what the
standard admits but tools read in different ways; ``RULES_CATCH`` lists the
corpus files the official grammar lets pass and ``validate`` refuses, each
with its reason, and the list must be exactly those files.
"""
from __future__ import annotations

import copy
import fnmatch
from functools import lru_cache
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from lxml import etree

from mcl2pnml import pipeline
from mcl2pnml.io.pnml import grammar
from mcl2pnml.io.pnml.grammar import (ENV, OFFICIAL, OURS, find_grammar, official_grammar,
                                      our_schema, validate_bytes)

from helpers import DATA, ROOT, assert_golden, official_grammar_dir, run_cli
from missions import missions
from strategies import nets
from sampling import sample

PNML = DATA / "pnml"
SCHEMA_VALID = sorted((PNML / "schema" / "valid").glob("*.pnml"))
SCHEMA_INVALID = sorted((PNML / "schema" / "invalid").glob("*.pnml"))
CORPUS = sorted(path for folder in ("foreign", "invalid") for path in
                (PNML / folder).glob("*.pnml")) + SCHEMA_VALID + SCHEMA_INVALID
NS = "http://www.pnml.org/version-2009/grammar/pnml"

#: Why libxml2's check of the official grammar refuses some valid pages: RELAX NG's
#: interleave admits every order, but the official grammar nests a page's name and tool
#: data (an interleave) in the page's own interleave, and libxml2 does not follow every
#: order of such a nesting. Our schema spells a page's content out as sequences.
NESTED_INTERLEAVE = ("valid by the standard (any order); refused only as libxml2 checks the "
                     "official grammar's nested interleave of a page")
#: Where our schema's verdict differs from the official grammar's as libxml2 checks it,
#: with the reason: corpus files by path, and (object, order of its children) for the
#: orders of up to four children (test_every_order_of_every_object_gets_the_standards_verdict).
SCHEMA_DIFFERENCES: dict[str | tuple, str] = {
    "schema/valid/page_children_interleaved.pnml": NESTED_INTERLEAVE,
    **{("page", order): NESTED_INTERLEAVE for order in [
        ("name", "place", "tools", "place"), ("name", "place", "tools", "page"),
        ("name", "page", "tools", "place"), ("name", "page", "tools", "page"),
        ("tools", "place", "name", "place"), ("tools", "place", "name", "page"),
        ("tools", "page", "name", "place"), ("tools", "page", "name", "page"),
        ("tools", "place", "tools", "place"), ("tools", "place", "tools", "page"),
        ("tools", "page", "tools", "place"), ("tools", "page", "tools", "page")]},
}

#: Corpus files the official grammar accepts and ``validate`` refuses: what the
#: reader's rules catch on top of the schemas, with the reason.
#: A reference node: the standard's, but verifypn ignores it and drops its arcs.
REFERENCE = "reference nodes, which tools read in different ways (verifypn drops their arcs)"
#: Several nets in a file: the standard's, but tools read the first, all, or one chosen.
SEVERAL_NETS = "two nets in one file, which tools read in different ways: one net per file"
RULES_CATCH = {
    "invalid/place_to_place.pnml":
        "an arc from a place to a place: an IDREF says nothing of what it names",
    "invalid/reference_loop.pnml": REFERENCE + " (these two refer to each other, which "
                                   "the standard forbids in prose only)",
    "foreign/nested_pages_with_references.pnml": REFERENCE,
    "schema/valid/everything.pnml": REFERENCE,
    "invalid/two_nets.pnml": SEVERAL_NETS,
    "schema/valid/two_nets_unique_ids.pnml": SEVERAL_NETS,
    "schema/valid/numbers_as_xsd_writes_them.pnml":
        "a marking with a sign ('+3'), which xsd admits and 32-bit readers (verifypn) refuse",
    "invalid/huge_marking.pnml":
        "a marking of 5,000 digits: the grammar's nonNegativeInteger has no bound; a "
        "32-bit reader (verifypn) holds at most 2^32-1",
    "invalid/huge_weight.pnml": "a weight past 2^31-1, what a 32-bit reader holds",
    "invalid/timing_too_long.pnml":
        "a time bound past 10^9 s in our tool data, which no grammar reads",
    "invalid/payload_too_deep.pnml":
        "our tool data's JSON nested 5,000 deep, which no grammar reads",
    "schema/valid/type_uri_with_spaces.pnml":
        "the reader takes the net type URI as written, white space included, where the "
        "grammar compares it as a token: a URI with spaces around it is refused on purpose",
}

#: Values an attribute of any kind is set to: empty, signs, fractions, exponents, too
#: many digits, a space inside, a value of a closed list, an id of nothing.
BAD_VALUES = ("", "-1", "0", "2.55", "1e3", "10000", "a b", "curve", "nowhere")
#: Values a number label's text is set to, the ones xsd admits among them.
NUMBERS = ("", "0", "1", "+3", " 7 ", "007", "-1", "two", "1.0", "99999999999999999999")
#: Names an element is renamed to: the vocabulary of PNML, and one it does not have.
VOCABULARY = ("pnml", "net", "page", "place", "transition", "arc", "referencePlace",
              "referenceTransition", "name", "text", "initialMarking", "inscription",
              "graphics", "position", "offset", "dimension", "fill", "line", "font",
              "toolspecific", "capacity")


# -- the judges ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def official(grammar_dir):
    """The official grammar, compiled; the tests that compare with it skip without it."""
    return official_grammar(str(grammar_dir))


@lru_cache(maxsize=1)
def _official_or_none():
    found = official_grammar_dir()
    return official_grammar(str(found)) if found is not None else None


def schema_verdicts(data: bytes) -> tuple[bool, bool | None]:
    """Our schema's verdict and the official grammar's (``None`` where it is not here)."""
    doc = etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True))
    official = _official_or_none()
    return our_schema().validate(doc), (official.validate(doc) if official else None)


def ours_alone(data: bytes, name: str, net_id: str | None = None):
    """``validate``'s verdict with our schema and the rules only: the same on any machine."""
    with pytest.MonkeyPatch.context() as m:
        m.setenv(ENV, "none")
        return validate_bytes(data, name, net_id=net_id)


def rules_verdict(data: bytes, name: str) -> bool:
    """Our schema and the reader's rules, on every net of the document."""
    root = etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True))
    net_ids = [n.get("id") for n in root
               if isinstance(n.tag, str) and etree.QName(n).localname == "net"]
    return all(ours_alone(data, name, n if len(net_ids) > 1 else None).valid
               for n in net_ids or [None])


def assert_written_is_valid(data: bytes, name: str) -> None:
    ours, official = schema_verdicts(data)
    assert ours, f"{name}: our schema refuses what we write"
    assert official in (True, None), f"{name}: the official grammar refuses what we write"
    verdict = ours_alone(data, name)
    assert verdict.valid, "\n".join(map(str, verdict.errors))


# -- the schema itself --------------------------------------------------------------------


def test_the_schema_ships_with_the_package_and_stands_alone():
    import tomllib
    from importlib import resources

    shipped = resources.files("mcl2pnml.io.pnml").joinpath(grammar.SCHEMA)
    assert shipped.is_file()
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    patterns = config["tool"]["setuptools"]["package-data"]["mcl2pnml.io.pnml"]
    assert any(fnmatch.fnmatch(grammar.SCHEMA, p) for p in patterns)
    # one file: an installed copy needs nothing beside it, and nothing is fetched
    rng = etree.fromstring(shipped.read_bytes())
    relaxng = "{http://relaxng.org/ns/structure/1.0}"
    assert not list(rng.iter(f"{relaxng}include", f"{relaxng}externalRef"))
    assert our_schema().validate(etree.fromstring(pipeline.to_pnml_bytes(
        pipeline.template_net("task"), "none")))


def test_without_the_official_grammar_given_our_schema_judges_alone(monkeypatch):
    # never looked for: not in the checkout's ../shared/pnml-grammar, wherever it is run
    monkeypatch.delenv(ENV, raising=False)
    monkeypatch.chdir(ROOT)
    assert find_grammar() is None
    good = validate_bytes((PNML / "schema" / "valid" / "labels_in_any_order.pnml").read_bytes(),
                          "e.pnml")
    assert good.valid and good.judges() == OURS
    bad = validate_bytes((PNML / "schema" / "invalid" / "two_positions.pnml").read_bytes(),
                         "t.pnml")
    assert not bad.valid and bad.judges() == f"{OURS}: invalid"
    assert str(bad.errors[0]).startswith("t.pnml:5:33: schema: ")


# -- what we write ------------------------------------------------------------------------


@pytest.mark.parametrize("name", [names.split(", ")[0] for names, _, _ in pipeline.templates()])
def test_every_template_is_valid_by_both(name):
    net = pipeline.template_net(name)
    for layout in ("none", "layers"):
        assert_written_is_valid(pipeline.to_pnml_bytes(net, layout), f"{name} ({layout})")


@pytest.mark.parametrize("path", sorted((ROOT / "examples").glob("*.mcl")), ids=lambda p: p.name)
def test_every_example_mission_is_valid_by_both(path, examples):
    net = examples.net(path.name)   # compiled once per process, shared with other tests
    assert_written_is_valid(pipeline.to_pnml_bytes(net, "layers"), path.name)


@settings(max_examples=12, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(missions(depth=2, width=2))
def test_generated_missions_are_valid_by_both(source):
    net = pipeline.compile_source(source)
    assert_written_is_valid(pipeline.to_pnml_bytes(net, "layers"), "<generated>")


# -- the corpus ---------------------------------------------------------------------------


def _key(path: Path) -> str:
    return path.relative_to(PNML).as_posix()


def test_hand_made_valid_files_are_valid_by_our_schema():
    for path in SCHEMA_VALID:
        ours, official = schema_verdicts(path.read_bytes())
        assert ours and (official in (True, None) or _key(path) in SCHEMA_DIFFERENCES), path.name


@pytest.mark.parametrize("path", SCHEMA_INVALID, ids=lambda p: p.name)
def test_hand_made_invalid_files_give_their_expected_messages(path):
    """Each is refused by our schema itself (not only by the rules), located, as its golden says."""
    verdict = ours_alone(path.read_bytes(), path.name)
    assert not verdict.valid
    assert any(e.message.startswith("schema: ") and e.location.line for e in verdict.errors)
    assert_golden(path.with_suffix(".expected"), "\n".join(map(str, verdict.errors)) + "\n")


def test_the_corpus_gets_one_verdict_from_both(official):
    differences, caught = {}, set()
    for path in CORPUS:
        data = path.read_bytes()
        try:
            ours, theirs = schema_verdicts(data)
        except etree.XMLSyntaxError:
            continue   # not XML: no schema judges it, validate says why (test_cli.py)
        if ours != theirs:
            differences[_key(path)] = (ours, theirs)
        if theirs and not rules_verdict(data, path.name):
            caught.add(_key(path))
    listed = {k for k in SCHEMA_DIFFERENCES if isinstance(k, str)}
    assert set(differences) == listed, f"the schemas differ on {differences}, not on {listed}"
    assert all(ours for ours, _ in differences.values())   # we refuse nothing the standard admits
    assert caught == set(RULES_CATCH), "RULES_CATCH is not what the rules catch"


def test_an_arc_between_places_passes_both_schemas_and_not_the_rules(official):
    data = (PNML / "invalid" / "place_to_place.pnml").read_bytes()
    assert schema_verdicts(data) == (True, True)
    verdict = validate_bytes(data, "place_to_place.pnml", official_grammar_dir())
    assert [s.valid for s in verdict.schemas] == [True, True]
    assert [(e.message, e.location.line, e.location.column) for e in verdict.errors] == [
        ("arc 'a' goes from place 'p' to place 'q'; an arc joins a place and a transition", 7, 7)]


# -- the orders the standard's interleaves allow ---------------------------------------------

TOOL = '<toolspecific tool="x" version="1"/>'
NODE_GRAPHICS = '<graphics><position x="0" y="0"/></graphics>'
LABEL_GRAPHICS = '<graphics><offset x="0" y="0"/></graphics>'
#: What each object may hold, in any order: (its text, at most how many, at least how
#: many), the standard's interleaves read as RELAX NG defines them.
HOLDS = {
    "net": {"name": ("<name/>", 1, 0), "tools": (TOOL, 9, 0), "page": ('<page id="g{i}"/>', 9, 1)},
    "page": {"name": ("<name/>", 1, 0), "tools": (TOOL, 9, 0), "graphics": (NODE_GRAPHICS, 1, 0),
             "place": ('<place id="p{i}"/>', 9, 0), "page": ('<page id="g{i}"/>', 9, 0)},
    "place": {"name": ("<name/>", 1, 0), "tools": (TOOL, 9, 0), "graphics": (NODE_GRAPHICS, 1, 0),
              "marking": ("<initialMarking><text>1</text></initialMarking>", 1, 0)},
    "arc": {"name": ("<name/>", 1, 0), "tools": (TOOL, 9, 0), "graphics": ("<graphics/>", 1, 0),
            "weight": ("<inscription><text>1</text></inscription>", 1, 0)},
    "name": {"text": ("<text>x</text>", 1, 0), "tools": (TOOL, 9, 0),
             "graphics": (LABEL_GRAPHICS, 1, 0)},
    "initialMarking": {"text": ("<text>1</text>", 1, 1), "tools": (TOOL, 9, 0),
                       "graphics": (LABEL_GRAPHICS, 1, 0)},
}

def _holding(parent: str, order: tuple[str, ...]) -> bytes:
    """A document whose one ``parent`` holds ``order`` (with what else it needs to be valid)."""
    body = "".join(HOLDS[parent][c][0].format(i=i) for i, c in enumerate(order))
    inner = {"net": body,
             "page": f'<page id="top">{body}</page>',
             "place": f'<page id="top"><place id="p">{body}</place></page>',
             "arc": f'<page id="top"><place id="p"/><transition id="t"/>'
                    f'<arc id="a" source="p" target="t">{body}</arc></page>',
             "name": f'<page id="top"><place id="p"><name>{body}</name></place></page>',
             "initialMarking": f'<page id="top"><place id="p"><initialMarking>{body}'
                               f'</initialMarking></place></page>'}[parent]
    return (f'<pnml xmlns="{NS}"><net id="n" type="http://www.pnml.org/version-2009/grammar/'
            f'ptnet">{inner}</net></pnml>').encode()


@pytest.mark.parametrize("parent", HOLDS)
def test_every_order_of_every_object_gets_the_standards_verdict(parent):
    """Every sequence of up to four children: our schema says what the standard says (any
    order, so many of each); the official grammar too, but for the orders listed."""
    import itertools
    official = _official_or_none()
    kinds = HOLDS[parent]
    refused_by_libxml2 = set()
    for length in range(5):
        for order in itertools.product(kinds, repeat=length):
            standard = all(low <= order.count(k) <= high for k, (_, high, low) in kinds.items())
            ours, theirs = schema_verdicts(_holding(parent, order))
            assert ours == standard, (parent, order)
            if official is not None and theirs != standard:
                refused_by_libxml2.add((parent, order))
                assert standard and not theirs, (parent, order)
    if official is not None:   # without it, our schema is held to the standard alone
        assert refused_by_libxml2 == {d for d in SCHEMA_DIFFERENCES
                                      if isinstance(d, tuple) and d[0] == parent}


# -- mutants ------------------------------------------------------------------------------


def mutations(root) -> list[tuple]:
    """Every mutation of the document ``root`` as (operation, element number, argument),
    the element numbered in document order; cheap to list, applied by :func:`mutate`."""
    ids = sorted({el.get("id") for el in root.iter() if el.get("id")})
    out: list[tuple] = []
    for i, el in enumerate(root.iter()):
        local = etree.QName(el).localname
        out += [("delete", i, None), ("double", i, None), ("reverse", i, None),
                ("text", i, "loose"), ("child", i, f"{{{NS}}}unknown"),
                ("child", i, "{urn:example:other}unknown"), ("unqualify", i, None)]
        out += [("rename", i, name) for name in VOCABULARY if name != local]
        out += [("set", i, (a, v)) for a in el.attrib for v in (*BAD_VALUES, *ids[:6])]
        out += [("drop", i, a) for a in el.attrib]
        out.append(("set", i, ("bogus", "1")))
        if local == "text":
            out += [("text", i, v) for v in NUMBERS]
    return out


def mutate(root, mutation: tuple):
    """A copy of ``root`` with ``mutation`` (from :func:`mutations`) applied."""
    root = copy.deepcopy(root)
    op, i, arg = mutation
    el = list(root.iter())[i % sum(1 for _ in root.iter())]
    parent = el.getparent()
    if op == "delete" and parent is not None:
        parent.remove(el)
    elif op == "double" and parent is not None:
        el.addnext(copy.deepcopy(el))
    elif op == "reverse":
        el[:] = list(reversed(el))
    elif op == "text":
        el.text = arg
    elif op == "child":
        etree.SubElement(el, arg)
    elif op == "unqualify":
        el.tag = etree.QName(el).localname
    elif op == "rename":
        el.tag = etree.QName(etree.QName(el).namespace, arg).text
    elif op == "set":
        el.set(*arg)
    elif op == "drop":
        del el.attrib[arg]
    return root


def _verdicts(root) -> tuple[bool, bool | None]:
    # serialised and parsed again, so that libxml2 sees ids as a parser registers them
    return schema_verdicts(etree.tostring(root))


def _base(path: Path):
    return etree.fromstring(path.read_bytes(), etree.XMLParser(remove_comments=True))


BASES = [PNML / "schema" / "valid" / "everything.pnml",
         PNML / "schema" / "valid" / "numbers_as_xsd_writes_them.pnml"]


@pytest.mark.parametrize("base", BASES, ids=lambda p: p.name)
def test_every_mutant_gets_one_verdict_from_both(base, official):
    root = _base(base)
    counts = {(True, True): 0, (False, False): 0}
    differ, caught = [], []
    for m in mutations(root):
        mutant = mutate(root, m)
        verdict = _verdicts(mutant)
        if verdict[0] != verdict[1]:
            differ.append((m, verdict))
            continue
        counts[verdict] += 1
        if verdict == (True, True) and not rules_verdict(etree.tostring(mutant), base.name):
            caught.append(m)
    assert not differ, f"our schema and the official grammar differ on {differ[:5]}"
    # both outcomes are exercised, and the rules catch some mutants the grammar passes
    # (an arc turned to join two places, a reference turned to loop)
    assert counts[(True, True)] > 50 and counts[(False, False)] > 500, counts
    assert caught, "no mutant that the official grammar passes was caught by the rules"


@st.composite
def mutants(draw):
    """A valid document, ours or one we wrote of a random net, with one to three mutations."""
    if draw(st.booleans()):
        root = _base(draw(st.sampled_from(BASES)))
    else:
        root = etree.fromstring(pipeline.to_pnml_bytes(draw(nets(max_places=4,
                                                                 max_transitions=3)), "none"))
    for _ in range(draw(st.integers(1, 3))):
        root = mutate(root, draw(st.sampled_from(mutations(root))))
    return root


@settings(max_examples=sample(150, 50), deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(mutants())
def test_composed_mutants_get_one_verdict_from_both(official, root):
    ours, theirs = _verdicts(root)
    assert ours == theirs, etree.tostring(root).decode()


@pytest.mark.slow
@settings(max_examples=5_000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutants())
def test_composed_mutants_get_one_verdict_from_both_at_length(official, root):
    ours, theirs = _verdicts(root)
    assert ours == theirs, etree.tostring(root).decode()


# -- the command --------------------------------------------------------------------------


def test_validate_names_the_schemas_it_applied(tmp_path, grammar_dir):
    path = tmp_path / "task.pnml"
    path.write_bytes(pipeline.to_pnml_bytes(pipeline.template_net("task"), "none"))
    alone = run_cli("validate", path, env=_env(**{ENV: "none"}))
    assert alone.returncode == 0, alone.stderr
    assert alone.stdout == (f"{path}: valid PNML P/T net ({OURS}): 19 places, "
                            "19 transitions, 69 arcs\n")
    both = run_cli("validate", path, "--grammar", grammar_dir, env=_env(**{ENV: "none"}))
    assert both.returncode == 0, both.stderr
    assert f"({OURS}; {OFFICIAL}: valid)" in both.stdout


def test_validate_refuses_with_located_schema_messages():
    path = PNML / "schema" / "invalid" / "marking_not_a_number.pnml"
    out = run_cli("validate", path, env=_env(**{ENV: "none"}))
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert f"{path}:5:33: schema: " in out.stderr
    assert f"{path}:5:33: place 'p': initialMarking must be a natural number" in out.stderr
    assert out.stderr.splitlines()[-1] == f"{path}: invalid PNML (2 problems; {OURS}: invalid)"


def test_a_grammar_given_that_is_missing_or_broken_is_an_error(tmp_path):
    good = PNML / "schema" / "valid" / "everything.pnml"
    (tmp_path / "ptnet.pntd").write_text("<grammar xmlns='http://relaxng.org/ns/structure/1.0'>"
                                         "<include href='conventions.rng'/></grammar>\n")
    out = run_cli("validate", good, "--grammar", tmp_path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert out.stderr.startswith(f"{tmp_path / 'ptnet.pntd'}:1:")
    assert f"the PNML grammar in {tmp_path} cannot be used" in out.stderr
    empty = tmp_path / "empty"
    empty.mkdir()
    for args, env in ((["--grammar", empty], {}), ([], {ENV: str(empty)})):
        out = run_cli("validate", good, *args, env=_env(**env))
        assert out.returncode == 2 and "Traceback" not in out.stderr
        assert f"no ptnet.pntd in {empty}" in out.stderr and len(out.stderr.splitlines()) == 1


def _env(**extra: str) -> dict[str, str]:
    import os
    return {**os.environ, **extra}
