"""Fuzzing the two readers of untrusted input: the MCL front end and the PNML reader.

Inputs are mutants of a corpus (the examples, the test data, PNML written
from compiled missions and from the templates): characters inserted, deleted,
duplicated and spliced in from another corpus file, random unicode, and
truncation; PNML also gets structural mutations (elements dropped,
duplicated, moved, nested; ids, arc ends, markings and weights rewritten).

The property is the one ``errors.py`` promises: nothing but
:class:`Mcl2PnmlError` ever escapes, and every error names the file and,
where the input has lines, the line and column.

``make test`` runs a few hundred of each; ``make test-slow`` runs the long
campaign (``FUZZ_EXAMPLES`` inputs each, 100,000 by default).
"""
from __future__ import annotations

import copy
import os
import re
import time
from functools import lru_cache

import pytest
from hypothesis import HealthCheck, Phase, given, settings, strategies as st
from lxml import etree

from mcl2pnml.pipeline import compile_source
from mcl2pnml.language.compiler import compile_checked
from mcl2pnml.core.errors import ErrorList, Mcl2PnmlError
from mcl2pnml.language.semantics import check_program
from mcl2pnml.language.parser import decode, parse
from mcl2pnml.io.pnml.reader import parse_pnml
from mcl2pnml.pipeline import to_pnml_bytes
from mcl2pnml.language.library import default_library

from helpers import DATA, ROOT
from sampling import sample

MCL_NAME = "fuzz.mcl"
PNML_NAME = "fuzz.pnml"
#: Inputs per target in the long campaign; the property holds for any count.
LONG = int(os.environ.get("FUZZ_EXAMPLES", "100000"))
#: Shrinking is of no use to a campaign that counts inputs; the database
#: keeps any failure found so that the next run starts from it.
CAMPAIGN = dict(deadline=None, phases=[Phase.reuse, Phase.generate],
                suppress_health_check=list(HealthCheck))


# -- the corpus ------------------------------------------------------------------

@lru_cache(maxsize=1)
def mcl_corpus() -> tuple[str, ...]:
    paths = sorted(ROOT.glob("examples/*.mcl")) + sorted((DATA / "mcl").rglob("*.mcl"))
    texts = []
    for p in paths:
        try:
            texts.append(p.read_bytes().decode("utf-8"))
        except UnicodeDecodeError:
            continue  # the deliberately binary files are not seeds for text mutation
    return tuple(texts)


@lru_cache(maxsize=1)
def pnml_corpus() -> tuple[bytes, ...]:
    files = [p.read_bytes() for p in sorted((DATA / "pnml").rglob("*.pnml"))]
    library = default_library()
    # small nets only: a seed is read once per input, and structure, not size, finds faults
    for t in library.unique():
        files.append(to_pnml_bytes(library.composed(t.name), "layers"))
    for p in (ROOT / "examples" / "sauce.mcl", DATA / "mcl" / "golden" / "if_else.mcl"):
        net = compile_source(p.read_text(), p.name)
        files.append(to_pnml_bytes(net, "layers"))
    return tuple(files)


def _tokens(texts) -> list[str]:
    found = set()
    for t in texts:
        found.update(re.findall(r"\w+|[^\w\s]", t))
    return sorted(found)


@lru_cache(maxsize=1)
def mcl_tokens() -> tuple[str, ...]:
    return tuple(_tokens(mcl_corpus()))


# -- character mutations ------------------------------------------------------------

#: The strategies of the mutations that do not depend on the input, built once: built
#: afresh at each draw, each was validated again (the draws are the same).
_MUTATIONS = st.integers(1, 8)
_TEXT_KINDS = st.sampled_from(["insert", "delete", "duplicate", "splice", "token", "unicode",
                               "truncate", "swap"])
_INSERTED = st.text(max_size=8)
_ANY_CHARACTER = st.characters(codec=None)
_ONE_IN_TEN = st.integers(0, 9)
_BYTES = st.binary(min_size=1, max_size=4)

@st.composite
def mutated_text(draw, corpus: tuple[str, ...], tokens: tuple[str, ...]) -> str:
    """A corpus text after one to eight character-level mutations."""
    text = draw(st.sampled_from(corpus))
    for _ in range(draw(_MUTATIONS)):
        n = len(text)
        i = draw(st.integers(0, n))
        j = draw(st.integers(i, min(n, i + 40)))
        kind = draw(_TEXT_KINDS)
        if kind == "insert":
            text = text[:i] + draw(_INSERTED) + text[i:]
        elif kind == "delete":
            text = text[:i] + text[j:]
        elif kind == "duplicate":
            text = text[:j] + text[i:j] + text[j:]
        elif kind == "splice":  # a piece of another corpus file
            other = draw(st.sampled_from(corpus))
            a = draw(st.integers(0, len(other)))
            b = draw(st.integers(a, min(len(other), a + 200)))
            text = text[:i] + other[a:b] + text[j:]
        elif kind == "token":
            text = text[:i] + draw(st.sampled_from(tokens)) + text[j:]
        elif kind == "unicode":
            text = text[:i] + draw(_ANY_CHARACTER) + text[j:]
        elif kind == "truncate":
            text = text[:i]
        else:  # two pieces trade places
            text = text[:i] + text[j:] + text[i:j]
    return text


@st.composite
def mutated_mcl(draw) -> bytes:
    text = draw(mutated_text(mcl_corpus(), mcl_tokens()))
    if draw(_ONE_IN_TEN) == 0:  # now and then, bytes that are not UTF-8
        data = bytearray(text.encode("utf-8", "surrogatepass"))
        i = draw(st.integers(0, len(data)))
        data[i:i] = draw(_BYTES)
        return bytes(data)
    return text.encode("utf-8", "surrogatepass")


# -- structural PNML mutations ----------------------------------------------------

_NUMBERS = ["-1", "-0", "0", "1", "99999999999999999999999999", "1e3", "1.5", "", " ",
            "x", "NaN", "inf", "٣", "0x10", "+2", "१२"]
_TREE_KINDS = st.sampled_from(["drop", "duplicate", "move", "nest", "id", "arc end",
                               "marking", "attribute", "text", "wrap"])
_NEW_IDS = st.text(max_size=6).filter(lambda s: "\x00" not in s and s.isprintable())
_ENDS = st.sampled_from(["source", "target", "ref"])
_NUMBER_TEXTS = st.sampled_from(_NUMBERS)
_ATTRIBUTES = st.sampled_from(["type", "tool", "x", "y", "earliest", "latest", "id"])
_TEXTS = st.sampled_from(_NUMBERS + ["{", "[1,", "null", '{"a": 1}'])
_WRAPPERS = st.sampled_from(["{http://www.pnml.org/version-2009/grammar/pnml}page", "page",
                             "unknown"])
_COIN = st.booleans()
_TREE_MUTATIONS = st.integers(1, 6)


def _mutate_tree(draw, root) -> None:
    elements = [e for e in root.iter() if isinstance(e.tag, str)]
    ids = [e.get("id") for e in elements if e.get("id") is not None] or ["x"]
    el = draw(st.sampled_from(elements))
    kind = draw(_TREE_KINDS)
    parent = el.getparent()
    if kind == "drop" and parent is not None:
        parent.remove(el)
    elif kind == "duplicate" and parent is not None:
        parent.insert(parent.index(el), copy.deepcopy(el))
    elif kind == "move" and parent is not None:
        target = draw(st.sampled_from(elements))
        if el not in target.iterancestors() and el is not target:
            parent.remove(el)
            target.append(el)
    elif kind == "nest":  # an element inside a copy of itself
        el.append(copy.deepcopy(el))
    elif kind == "id":
        el.set("id", draw(st.sampled_from(ids) | _NEW_IDS))
    elif kind == "arc end":
        el.set(draw(_ENDS), draw(st.sampled_from(ids)))
    elif kind == "marking":
        for label in el.iter("{*}initialMarking", "{*}inscription", "initialMarking",
                             "inscription"):
            for text in label.iter("{*}text", "text"):
                text.text = draw(_NUMBER_TEXTS)
    elif kind == "attribute":
        name = draw(_ATTRIBUTES)
        el.set(name, draw(st.sampled_from(_NUMBERS + ids)))
    elif kind == "text":
        el.text = draw(_TEXTS)
    elif parent is not None:  # wrap in a page, or in an element nobody knows
        wrapper = etree.Element(draw(_WRAPPERS),
            id=draw(st.sampled_from(ids)))
        parent.replace(el, wrapper)
        wrapper.append(el)


@st.composite
def mutated_pnml(draw) -> bytes:
    data = draw(st.sampled_from(pnml_corpus()))
    if draw(_COIN):
        try:
            root = etree.fromstring(data, etree.XMLParser(resolve_entities=False))
        except etree.XMLSyntaxError:
            root = None  # a corpus file that is not XML on purpose
        if root is not None:
            for _ in range(draw(_TREE_MUTATIONS)):
                _mutate_tree(draw, root)
            data = etree.tostring(root, xml_declaration=draw(_COIN), encoding="utf-8")
    if draw(_COIN):
        text = data.decode("utf-8", "replace")
        text = draw(mutated_text((text,), ("<", ">", "/>", "</net>", "<page>", '"', "&amp;",
                                          "&#0;", "<!--", "]]>", "<![CDATA[", "&x;")))
        data = text.encode("utf-8", "surrogatepass")
    return data


# -- the property -----------------------------------------------------------------

def assert_located(error: Mcl2PnmlError, filename: str, data: bytes) -> None:
    """Every error (each of a list) names the file and, where there are lines, a line
    and column; its excerpt is that line of the input (parsers count lines at ``\\n``)."""
    try:
        # a "\r" ending a line is left out of excerpts: it would return the cursor
        lines = [line[:-1] if line.endswith("\r") else line
                 for line in data.decode("utf-8").split("\n")]
    except UnicodeDecodeError:
        lines = None  # the excerpt shows what can be shown of undecodable bytes
    if b"\x00" in data:
        lines = None  # binary: control bytes are shown as '?' 
    for e in error.errors if isinstance(error, ErrorList) else (error,):
        loc = e.location
        assert loc is not None, f"no location: {e}"
        assert loc.file == filename, f"wrong file: {e}"
        if data.strip():
            assert loc.line is not None and loc.column is not None, f"no line and column: {e}"
        if lines is not None and loc.source_line is not None:
            assert loc.source_line == lines[loc.line - 1], f"excerpt of another line: {e}"
        str(e)  # rendering the excerpt must not fail either


def mcl_front_end(data: bytes) -> None:
    try:
        checked = check_program(parse(decode(data, MCL_NAME), MCL_NAME))
        compile_checked(checked)
    except Mcl2PnmlError as e:
        assert_located(e, MCL_NAME, data)


def pnml_reader(data: bytes) -> None:
    try:
        parse_pnml(data, PNML_NAME)
    except Mcl2PnmlError as e:
        assert_located(e, PNML_NAME, data)


# -- the short runs (make test) and the campaign (make test-slow) ---------------------

@settings(max_examples=sample(300, 100), **CAMPAIGN)
@given(mutated_mcl())
def test_mcl_front_end_mutants(data):
    mcl_front_end(data)


@settings(max_examples=sample(300, 100), **CAMPAIGN)
@given(mutated_pnml())
def test_pnml_reader_mutants(data):
    pnml_reader(data)


def campaign(target, inputs) -> None:
    """``LONG`` inputs through ``target``; prints the count and the rate (``pytest -s``)."""
    count = 0

    @settings(max_examples=LONG, **CAMPAIGN)
    @given(inputs)
    def run(data):
        nonlocal count
        count += 1
        target(data)

    start = time.perf_counter()
    run()
    seconds = time.perf_counter() - start
    print(f"\n{target.__name__}: {count:,} inputs in {seconds:.0f} s "
          f"({count / seconds:,.0f} inputs/s)")
    assert count >= LONG  # hypothesis did not stop early


@pytest.mark.slow
def test_mcl_front_end_campaign():
    campaign(mcl_front_end, mutated_mcl())


@pytest.mark.slow
def test_pnml_reader_campaign():
    campaign(pnml_reader, mutated_pnml())


def test_parsing_many_bad_files_does_not_accumulate_garbage():
    """A long-lived process (this campaign, an editor's checker) must not keep what
    each failed parse left: an exception and its traceback are a reference cycle,
    which the collector must still be allowed to find (the campaign once grew to
    24 GB)."""
    import gc

    bad = [p.read_bytes() for p in sorted((DATA / "pnml" / "invalid").glob("*.pnml"))]
    bad_mcl = [p.read_bytes() for p in sorted((DATA / "mcl" / "invalid").glob("*.mcl"))]

    def rounds(n: int) -> None:
        for k in range(n):
            try:
                parse_pnml(bad[k % len(bad)], PNML_NAME)
            except Mcl2PnmlError:
                pass
            try:
                parse(decode(bad_mcl[k % len(bad_mcl)], MCL_NAME), MCL_NAME)
            except Mcl2PnmlError:
                pass

    rounds(100)         # the caches filled once
    gc.collect()
    before = len(gc.get_objects())
    # a failed parse that left its traceback's cycle behind would leave its frames and
    # their locals, tens of objects each time: thousands here
    rounds(500)
    grown = len(gc.get_objects()) - before
    assert grown < 1_000, f"{grown:,} objects left behind by 500 failed parses"
