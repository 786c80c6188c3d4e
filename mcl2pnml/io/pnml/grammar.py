"""Validation against the official PNML grammar (ISO/IEC 15909-2, RELAX NG).

The grammar files are AFNOR's and are not shipped with mcl2pnml. They are
looked for, in order:

1. the directory given explicitly (``mcl2pnml validate --grammar DIR``);
2. the directory in the environment variable ``MCL2PNML_PNML_GRAMMAR``;
3. a ``shared/pnml-grammar`` directory beside or above the working directory
   or the installed package (where a checkout of this project keeps it).

The directory must hold ``ptnet.pntd`` and the files it includes
(``pnmlcoremodel.rng``, ``conventions.rng``, ``anyElement.rng``) with local
``include`` references, as pnml.org's ``grammar.zip`` unpacked and pointed at
its own files.

The grammar cannot check everything: an arc from a place to a place passes
it, so :func:`validate` also runs the reader's own checks, and a file is
valid only when both agree.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from lxml import etree

from mcl2pnml.core.errors import ErrorList, Mcl2PnmlError, PnmlError
from mcl2pnml.io.pnml.reader import XmlError, _parse_xml, _Source, parse_pnml, read_file

ENV = "MCL2PNML_PNML_GRAMMAR"
ENTRY = "ptnet.pntd"


def find_grammar(explicit: str | Path | None = None) -> Path:
    """The directory of the PNML grammar, or a :class:`PnmlError` saying how to get one."""
    if explicit is not None:
        candidates = [Path(explicit)]
    elif os.environ.get(ENV):
        candidates = [Path(os.environ[ENV])]
    else:
        candidates = []
        for start in (Path.cwd(), Path(__file__).resolve().parent):
            for d in (start, *start.parents):
                candidates.append(d / "shared" / "pnml-grammar")
    for c in candidates:
        if (c / ENTRY).is_file():
            return c
    where = candidates[0] if (explicit is not None or os.environ.get(ENV)) else None
    detail = f"no {ENTRY} in {where}" if where else "not found beside or above this directory"
    raise PnmlError(
        f"PNML grammar {detail}; unpack pnml.org's version-2009 grammar.zip (ptnet.pntd and "
        f"the .rng files it includes) and pass --grammar DIR or set {ENV}=DIR")


@lru_cache(maxsize=4)
def _relaxng(directory: str) -> etree.RelaxNG:
    parser = etree.XMLParser(no_network=True, resolve_entities=False)
    return etree.RelaxNG(etree.parse(os.path.join(directory, ENTRY), parser))


@dataclass(frozen=True)
class Verdict:
    """The outcome of :func:`validate`: valid, or the problems found."""

    file: str
    errors: tuple[Mcl2PnmlError, ...]

    @property
    def valid(self) -> bool:
        return not self.errors


def validate(path: str | Path, grammar: str | Path | None = None,
             net_id: str | None = None) -> Verdict:
    """Check a PNML file against the grammar and against the reader's rules.

    ``net_id``: the net the reader's rules are checked on, of a file that holds several.
    """
    return validate_bytes(read_file(path), str(path), grammar, net_id)


def validate_bytes(data: bytes, filename: str, grammar: str | Path | None = None,
                   net_id: str | None = None) -> Verdict:
    rng = _relaxng(str(find_grammar(grammar)))
    src = _Source(filename, data)
    try:
        doc = _parse_xml(data, src)
    except XmlError as e:
        return Verdict(filename, (e,))  # nothing more can be checked
    errors: list[Mcl2PnmlError] = []
    if not rng.validate(doc):
        for entry in rng.error_log:
            errors.append(PnmlError(f"grammar: {entry.message}",
                                    src.at(entry.line, entry.column or None)))
    try:
        parse_pnml(data, filename, net_id)
    except ErrorList as e:
        errors.extend(e.errors)
    except PnmlError as e:
        errors.append(e)
    return Verdict(filename, tuple(errors))
