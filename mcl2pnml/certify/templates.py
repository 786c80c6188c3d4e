"""The library's templates proven once: each against the interface contract, children reduced.

A task pattern is checked with its primitive (Fig. 2), a control structure
with a reduced task in each slot (Fig. 4), the reduced task alone (Fig. 3):
:meth:`mcl2pnml.language.library.Library.composed`, the nets the paper
analyses, each a few hundred markings at most. The result is stored in
``templates/proofs.json`` with the SHA-256 digest of the composed net's
canonical form (its places with their marking and interface labels, its
transitions with their timing, its arcs; names, positions and comments left
out, which change nothing of its behaviour). A template whose composed net
has the digest stored is taken as proven; any other (a user's file on
``$MCL2PNML_TEMPLATE_PATH``, an edited one) is checked when the library is
used, and a template that breaks the contract is refused with the run that
shows it.

Rewrite the stored proofs after a deliberate change to a template:

    python -m mcl2pnml.certify.templates --update
"""
from __future__ import annotations

import hashlib
import json
import sys
from dataclasses import dataclass
from pathlib import Path

from analysis.contract import check
from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import atomic_write_text
from mcl2pnml.core.net import Net
from mcl2pnml.language.library import Library, default_library, template_dirs
from mcl2pnml.language.template_parser import TemplateKind

#: The stored proofs, beside the package's own templates.
PROOFS = "proofs.json"


def canonical(net: Net) -> str:
    """The composed net as the contract sees it, one JSON text: what the digest covers."""
    return json.dumps({
        "places": sorted([p.id, net.initial[p.id], p.interface] for p in net.places),
        "transitions": sorted([t.id, None if t.timing is None else
                               [t.timing.earliest, t.timing.latest]] for t in net.transitions),
        "arcs": sorted([a.source, a.target, a.weight, a.kind.value] for a in net.arcs),
    }, separators=(",", ":"))


def digest(net: Net) -> str:
    return hashlib.sha256(canonical(net).encode()).hexdigest()


@dataclass(frozen=True)
class Proof:
    """A template checked against the contract: its composed net's digest and markings."""

    template: str
    kind: str
    digest: str
    markings: int

    def as_json(self) -> dict:
        return {"kind": self.kind, "digest": self.digest, "markings": self.markings}


class BrokenTemplate(Mcl2PnmlError):
    """A template whose composed net breaks the interface contract."""


def components(lib: Library) -> list:
    """The templates the contract is stated for: every one but the primitive."""
    return [t for t in lib.unique() if t.kind is not TemplateKind.PRIMITIVE]


def prove(lib: Library, name: str) -> Proof:
    """Template ``name`` checked against the contract now; :class:`BrokenTemplate` with the
    first breach's run if it breaks it."""
    t = lib.get(name)
    net = lib.composed(name)
    verdict = check(net)
    if not verdict.kept:
        breaches = "; ".join(str(b) for b in verdict.breaches[:3])
        more = len(verdict.breaches) - 3
        raise BrokenTemplate(
            f"template '{t.name}' breaks the interface contract (docs/ARCHITECTURE.md, "
            f"analysis.contract) with its children reduced: {breaches}"
            + (f"; and {more} more" if more > 0 else ""), Location(t.source))
    return Proof(t.name, t.kind.value, digest(net), verdict.markings)


def stored(folder: Path | None = None) -> dict[str, dict]:
    """The proofs stored beside the package's templates (none if the file is missing)."""
    path = (folder or template_dirs()[0]) / PROOFS
    try:
        return json.loads(path.read_text(encoding="utf-8"))["templates"]
    except (OSError, ValueError, KeyError, TypeError):
        return {}


def proven(lib: Library | None = None) -> dict[str, Proof]:
    """Every component template's proof: the stored one where the digest matches, else
    checked now (a template that breaks the contract is refused)."""
    lib = lib or default_library()
    known = stored()
    out = {}
    for t in components(lib):
        net = lib.composed(t.name)
        d = digest(net)
        entry = known.get(t.name)
        if entry is not None and entry.get("digest") == d:
            out[t.name] = Proof(t.name, t.kind.value, d, entry.get("markings", 0))
        else:
            out[t.name] = prove(lib, t.name)
    return out


def update(folder: Path | None = None) -> Path:
    """Prove every template of the package's library now and store the proofs."""
    lib = Library.load([folder or template_dirs()[0]])
    proofs = {t.name: prove(lib, t.name).as_json() for t in components(lib)}
    path = (folder or template_dirs()[0]) / PROOFS
    atomic_write_text(path, json.dumps({
        "about": "each template checked against the interface contract with its children "
                 "reduced; the digest is of the composed net (mcl2pnml/certify/templates.py)",
        "templates": proofs}, indent=2, sort_keys=True) + "\n")
    return path


if __name__ == "__main__":
    if sys.argv[1:] != ["--update"]:
        print(__doc__.strip().splitlines()[-1].strip(), file=sys.stderr)
        sys.exit(2)
    print(f"wrote {update()}")
