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

Each proof carries a results table: the subject checked again with each
child reduced to each signature (:data:`SIGNATURES`: the results it can
give, and whether it may run for ever instead), and what the subject then
does (its own signature), or the clause it breaks. The certificate derives
each node's signature from its children's through these rows: whether a
mission can always end depends on what its parts can give, which the
contract alone does not say. The package's tables are stored whole; a
user's template is proven row by row as certificates read it.

List the stored proofs, or rewrite them after a deliberate change to a template:

    python -m mcl2pnml.certify.templates --list
    python -m mcl2pnml.certify.templates --update
"""
from __future__ import annotations

import hashlib
import json
import sys
import weakref
from dataclasses import dataclass
from itertools import product
from pathlib import Path

from mcl2pnml.analysis.checking.contract import VERSION as CONTRACT_VERSION
from mcl2pnml.analysis.checking.contract import Clause, Own, check_contract, restricted
from mcl2pnml.core.compose import compose
from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import atomic_write_text
from mcl2pnml.core.net import Marking, Net, NetBuilder, Place
from mcl2pnml.core.payloads import read_transition
from mcl2pnml.language.compiler import call_site_net
from mcl2pnml.language.library import Library, at_rest, default_library, template_dirs
from mcl2pnml.language.template_parser import CONTROL, TemplateKind, slot_places

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
    """The digest of the composed net checked, and of the contract it was checked against:
    a proof of another version of the contract is no proof of this one."""
    return hashlib.sha256(f"contract {CONTRACT_VERSION}\n{canonical(net)}".encode()).hexdigest()


def shape(net: Net, slots: frozenset[str] = frozenset()) -> str:
    """The digest of one instance's own net, as the certificate's checker finds it in a
    compiled PNML: ids, arcs, and the marking of its own places (not of ``slots``, the
    places it shares with its children or primitives, whose marking is theirs); no labels,
    which fusion does not keep, and no timing: the proofs are of the untimed net, which
    allows every timing."""
    text = json.dumps({
        "places": sorted([p.id, None if p.id in slots else net.initial[p.id]]
                         for p in net.places),
        "transitions": sorted(t.id for t in net.transitions),
        "arcs": sorted([a.source, a.target, a.weight, a.kind.value] for a in net.arcs)},
        separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def local(lib: Library, subject: str) -> tuple[Net, frozenset[str]]:
    """The own net of an instance of ``subject`` in a compiled mission, with its slot places:
    a structure's template at rest; a task's pattern at rest with its gate (without its
    time-out transitions for "NAME without a time-out", timing left to the checker); a
    primitive with its lock; a call site taking ``k`` locks ("call site/k")."""
    if subject == "primitive":
        net = at_rest(lib.primitive.net)
        net = Net("primitive", (*net.places, Place("LOCK")), net.transitions, net.arcs,
                  Marking({**net.initial, "LOCK": 1}))
        return net, frozenset()
    if subject.startswith(CALL_SITE + "/"):
        k = int(subject.rsplit("/", 1)[1])
        net = call_site_net("T", [str(i) for i in range(1, k + 1)])
        slots = frozenset(p.id for p in net.places if p.id.startswith(("to.", "lock.")))
        return net, slots
    name = subject.removesuffix(" without a time-out")
    t = lib.get(name)
    net = at_rest(t.net)
    if t.kind is TemplateKind.PATTERN:
        if name != subject:
            net = without_timeouts(net)
        net = Net(name, (*net.places, Place("GATE")), net.transitions, net.arcs,
                  Marking({**net.initial, "GATE": 1}))
    return net, _slot_ids(lib, t)


def local_digest(lib: Library, subject: str) -> str:
    net, slots = local(lib, subject)
    return shape(net, slots)


#: What a child may be known to do, from B with no abort asked: the results it can give,
#: and whether it may also run for ever (until aborted); the reduced model restricted to
#: that (:func:`mcl2pnml.analysis.checking.contract.restricted`) stands for it. A child that gives no result
#: runs for ever (a loop whose condition never fails).
SIGNATURES = tuple((frozenset(r), stuck) for r, stuck in (
    ((), True), (("OK",), False), (("OK",), True), (("FAIL",), False), (("FAIL",), True),
    (("OK", "FAIL"), False), (("OK", "FAIL"), True)))
FULL = (frozenset({"OK", "FAIL"}), False)


def signature_text(results, stuck: bool) -> str:
    """``OK+FAIL``; ``OK~`` (OK, or runs for ever); ``~`` (runs for ever)."""
    return "+".join(r for r in ("OK", "FAIL") if r in results) + ("~" if stuck else "")


def results_key(children) -> str:
    """The key of a row of a proof's results table: each child's signature, ``OK+FAIL;OK~``."""
    return ";".join(signature_text(r, stuck) for r, stuck in children)


def classify(verdict) -> dict:
    """A row of a results table from the contract's verdict: the results the component
    gives (from B, no abort asked), and whether it may run for ever instead (the one
    clause broken: from rest + B, an end cannot always be reached; aborted, it always
    ends, in those results or ABORTED); else the breach that keeps any reduced model
    from standing for it."""
    ends = [r for r in ("OK", "FAIL") if r in verdict.results]
    if verdict.kept:
        return {"ends": ends, "stuck": False}
    if all(b.clause is Clause.ALWAYS_ENDS and b.start == "rest + B"
           for b in verdict.breaches) \
            and verdict.results_aborted == verdict.results | {"ABORTED"}:
        return {"ends": ends, "stuck": True}
    return {"breach": str(verdict.breaches[0])}


@dataclass(frozen=True)
class Proof:
    """A template checked against the contract: its composed net's digest and markings,
    and its results table: for each choice of the results its children can give (each one
    of :data:`SIGNATURES`), the results it then gives, or the clause it then breaks (a
    loop whose condition never fails never ends)."""

    template: str
    kind: str
    digest: str
    markings: int
    results: dict

    def as_json(self) -> dict:
        return {"kind": self.kind, "digest": self.digest, "markings": self.markings,
                "results": self.results}


class BrokenTemplate(Mcl2PnmlError):
    """A template whose composed net breaks the interface contract."""


def components(lib: Library) -> list:
    """The templates the contract is stated for: every one but the primitive."""
    return [t for t in lib.unique() if t.kind is not TemplateKind.PRIMITIVE]


#: The proofs of the compiler's own joints, beside the templates': a call site with its
#: callee behind the gate and a lock, and two call sites sharing one callee (a parallel
#: structure's two branches calling the same task).
CALL_SITE, SHARED_CALLEE = "call site", "call sites sharing a callee"
#: The most primitives a task uses (a pattern's slots), so the most locks a call site takes.
MAX_LOCKS = 2


def call_net(lib: Library, sites: int, results: tuple | None = None) -> Net:
    """``sites`` call sites (:func:`mcl2pnml.language.compiler.call_site_net`) of one
    callee, the reduced task (Fig. 3) with its gate, taking one primitive's lock; two
    sites are the branches of a parallel structure. Any callee that keeps the contract
    behaves toward its call sites as the reduced one does; ``results``: the callee's
    signature (:data:`SIGNATURES`)."""
    reduced = at_rest(lib.reduced.net if results is None
                      else restricted(lib.reduced.net, *results))
    # its places unlabelled: fused with the call sites', the interface labels are the
    # sites' (the joint's B is the first site's)
    callee = Net("T", (*(Place(p.id) for p in reduced.places), Place("GATE")),
                 reduced.transitions, reduced.arcs, Marking({**reduced.initial, "GATE": 1}))
    lock = NetBuilder("P")
    lock.place("LOCK", 1)
    names = ["site"] if sites == 1 else [f"site{k}" for k in range(1, sites + 1)]
    # the callee first: the places fused with it keep its ids (T.B, ...), which the
    # contract's caller clause reads the callee's state by
    parts = [("T", callee), *((n, call_site_net("T", ["P"])) for n in names),
             ("P", lock.build())]
    groups = [["T.GATE", *(f"{n}.to.GATE" for n in names)],
              ["P.LOCK", *(f"{n}.lock.P" for n in names)]]
    groups += [[f"T.{p}", *(f"{n}.to.{p}" for n in names)] for p in CONTROL if p != "MTX"]
    if sites > 1:
        parallel = lib.get("parallel")
        parts.insert(0, ("par", at_rest(parallel.net)))
        groups += [[f"{n}.{p}", f"par.{slot}_{p}"]
                   for n, slot in zip(names, parallel.children) for p in CONTROL]
    return compose(parts, groups, name=CALL_SITE if sites == 1 else SHARED_CALLEE)


def without_timeouts(net: Net) -> Net:
    """``net`` without its time-out transitions (and their arcs), as the compiler makes a
    task declared with no ``timeout``."""
    gone = {t.id for t in net.transitions if read_transition(t).timeout is not None}
    return Net(net.name, net.places, tuple(t for t in net.transitions if t.id not in gone),
               tuple(a for a in net.arcs if a.source not in gone and a.target not in gone),
               net.initial)


def subjects(lib: Library) -> list[tuple[str, str, Net, str]]:
    """(name, kind, net, where it comes from) of everything proven: each component
    template composed as the paper analyses it, then the compiler's call-site joints."""
    return [(name, kind, make(None), source) for name, kind, make, _, source in _subjects(lib)]


def _subjects(lib: Library) -> list:
    """(name, kind, its net with the children giving given results, how many children,
    source) of everything proven."""
    def composed(name, timeouts=True):
        def make(results):
            children = None if results is None else tuple(
                restricted(lib.reduced.net, r, stuck) for r, stuck in results)
            net = lib.composed(name, children)
            return net if timeouts else without_timeouts(net)
        return make

    out = []
    for t in components(lib):
        slots = len(t.children) if t.kind is TemplateKind.STRUCTURE else 0
        # the template's own nodes: not its slots (a child's places, a primitive's)
        slot_ids = _slot_ids(lib, t)
        own = (frozenset(x.id for x in t.net.transitions),
               frozenset(p.id for p in t.net.places if p.id not in slot_ids))
        out.append((t.name, t.kind.value, _marked(
            composed(t.name), tuple(f"{c}_" for c in t.children[:slots]), own), slots,
            t.source))
        if t.kind is TemplateKind.PATTERN:
            # a task declared without a time-out has no t03 (the compiler removes it)
            out.append((f"{t.name} without a time-out", t.kind.value,
                        _marked(composed(t.name, timeouts=False), (), own), 0, t.source))
    compiler = "mcl2pnml/language/compiler.py"
    for name, sites in ((CALL_SITE, 1), (SHARED_CALLEE, 2)):
        make = (lambda k: lambda r: call_net(lib, k, r and r[0]))(sites)
        out.append((name, "joint", _marked(make, ("T.",), _JOINT), 1, compiler))
    return out


#: The joints' own nodes: the call sites' (and a parallel's), not the callee's or the lock's.
_JOINT = ("T.", "P.")


def _slot_ids(lib: Library, t) -> frozenset[str]:
    """The places of template ``t`` that fill its slots: its children's interface places,
    its primitives'."""
    if t.kind is TemplateKind.PATTERN:
        interface = tuple(p.id for p in lib.primitive.net.places if p.interface is not None)
        return frozenset(p for slot in t.primitives for p in slot_places(slot, interface))
    return frozenset(p.id for p in t.net.places
                     if any(p.id.startswith(f"{c}_") for c in t.children))


def _marked(make, children: tuple[str, ...], own):
    """``make`` marked with what the contract's ``caller`` and ``asleep`` clauses hold its
    nets to (:func:`_checked`): the prefixes of its reduced children's places, and its own
    nodes (the template's transitions and places; for a joint, the prefixes of the parts
    that are not its own)."""
    make.children, make.own = children, own
    return make


def _checked(make, net: Net):
    """The contract checked on ``net``, made by ``make``: with its reduced children held
    to the ``caller`` clause, and its own transitions to the ``asleep`` clause."""
    own = getattr(make, "own", None)
    if own is _JOINT:
        mine = Own(frozenset(t.id for t in net.transitions if not t.id.startswith(_JOINT)),
                   frozenset(p.id for p in net.places if p.id.startswith(_JOINT)))
    elif own is not None:
        transitions, places = own
        mine = Own(transitions & {t.id for t in net.transitions},
                   frozenset(p.id for p in net.places if p.id not in places))
    else:
        mine = None
    return check_contract(net, children=getattr(make, "children", ()), own=mine)


class Rows(dict):
    """A results table whose rows are proven when first read: a user's template is proven
    on the rows a mission needs, not on all of them (a structure of three slots has 343)."""

    def __init__(self, make, children: int, rows: dict):
        super().__init__(rows)
        self._make, self._children = make, children

    def __missing__(self, key: str) -> dict:
        parts = key.split(";") if self._children else [""]
        row = [_signature(p) for p in parts] if len(parts) == self._children else None
        if row is None or None in row:
            raise KeyError(key)
        self[key] = classify(_checked(self._make, self._make(tuple(row))))
        return self[key]

    def get(self, key, default=None):
        try:
            return self[key]
        except KeyError:
            return default


def _signature(text: str):
    """The signature a row's key names for one child (``OK+FAIL~``), None if no such."""
    sig = (frozenset(r for r in text.rstrip("~").split("+") if r), text.endswith("~"))
    return sig if sig in SIGNATURES and signature_text(*sig) == text else None


def prove(name: str, kind: str, make, children: int, source: str,
          eager: bool = True, net: Net | None = None) -> Proof:
    """The subject checked against the contract now, its children reduced (``make(None)``),
    then with its children giving each choice of results (``make(row)``): every row now, or
    (not ``eager``) each when first read (:class:`Rows`); :class:`BrokenTemplate` with the
    first breaches' runs if it breaks the contract. ``net``: ``make(None)``, if made."""
    net = net if net is not None else make(None)
    verdict = _checked(make, net)
    # one that may run for ever until aborted (a loop with no way out, a goal kept with
    # no time-out) keeps the rest of the contract: its signature says so, and a mission
    # that waits on it is refused where it matters (unless an abort is pending)
    if "breach" in classify(verdict):
        breaches = "; ".join(str(b) for b in verdict.breaches[:3])
        more = len(verdict.breaches) - 3
        raise BrokenTemplate(
            f"template '{name}' breaks the interface contract (docs/ARCHITECTURE.md, "
            f"mcl2pnml.analysis.checking.contract) with its children reduced: {breaches}"
            + (f"; and {more} more" if more > 0 else ""), Location(source))
    markings, table = verdict.markings, {results_key((FULL,) * children): classify(verdict)}
    for row in product(SIGNATURES, repeat=children) if eager else ():
        if results_key(row) not in table:
            v = _checked(make, make(row))
            markings += v.markings
            table[results_key(row)] = classify(v)
    return Proof(name, kind, digest(net), markings,
                 table if eager else Rows(make, children, table))


def stored(folder: Path | None = None) -> dict[str, dict]:
    """The proofs stored beside the package's templates (none if the file is missing)."""
    path = (folder or template_dirs()[0]) / PROOFS
    try:
        return json.loads(path.read_text(encoding="utf-8"))["templates"]
    except (OSError, ValueError, KeyError, TypeError):
        return {}


#: The stored proofs as :func:`current` and :func:`untrusted_reduced` read them, with the
#: file's path, size and time they were read at: the checker asks for them once per
#: certificate, and parsing the file each time was a large part of checking a small one.
_STORED: dict[Path, tuple[tuple[int, int], dict[str, dict]]] = {}


def _stored_now() -> dict[str, dict]:
    """:func:`stored`, read again only when the file changed (never written to: callers
    copy what they hand on)."""
    path = template_dirs()[0] / PROOFS
    try:
        info = path.stat()
        stamp = (info.st_mtime_ns, info.st_size)
    except OSError:
        return {}
    if _STORED.get(path, (None,))[0] != stamp:
        _STORED[path] = (stamp, stored())
    return _STORED[path][1]


@dataclass(frozen=True)
class _Parts:
    """What :func:`current` computes from a library alone: each subject with its composed
    net and that net's digest, each instance's own net with its slots and their shape, and
    the digest of the reduced task composed (:func:`untrusted_reduced`)."""

    subjects: tuple
    own: dict
    shapes: dict
    reduced: str


#: :class:`_Parts` per library, by identity (a library is not hashable), each dropped with
#: its library: composing every template again for each certificate checked was most of the
#: checker's time on a small mission.
_PARTS: dict[int, tuple[weakref.ref, _Parts]] = {}


#: A subject's composed net, its digest and its own net (None for a joint), by the
#: templates they are made of: a library that differs from another in a template or two
#: (a user's pattern, a mutant's) composes only those again.
_MADE: dict[tuple, tuple] = {}


def _made_of(lib: Library, name: str, kind: str) -> tuple:
    """The templates subject ``name`` of ``lib`` is composed from (its own, the primitive's,
    the reduced task's; a joint's: the reduced task's, and the parallel's for two sites)."""
    if kind == "joint":
        return (name, lib.reduced, lib.get("parallel") if name == SHARED_CALLEE else None)
    return (name, lib.get(name.removesuffix(" without a time-out")), lib.primitive,
            lib.reduced)


def _parts(lib: Library) -> _Parts:
    known = _PARTS.get(id(lib))
    if known is not None and known[0]() is lib:
        return known[1]
    subjects, own = [], {}
    if len(_MADE) > 1_000:      # a long run of generated templates: keep memory flat
        _MADE.clear()
    for name, kind, make, children, source in _subjects(lib):
        key = _made_of(lib, name, kind)
        if key not in _MADE:
            net = make(None)
            _MADE[key] = (net, digest(net), None if kind == "joint" else local(lib, name))
        net, net_digest, own_net = _MADE[key]
        subjects.append((name, kind, make, children, source, net, net_digest))
        if own_net is not None:
            own[name] = own_net
    for name in ("primitive", *(f"{CALL_SITE}/{k}" for k in range(MAX_LOCKS + 1))):
        own[name] = local(lib, name)
    parts = _Parts(tuple(subjects), own, {name: shape(*o) for name, o in own.items()},
                   digest(lib.composed(lib.reduced.name)))
    key = id(lib)
    # the dict bound now: at exit the module's names may be gone when a library goes
    _PARTS[key] = (weakref.ref(lib, lambda _, key=key, held=_PARTS: held.pop(key, None)),
                   parts)
    return parts


class Proofs(dict):
    """The proofs of one library's parts: subject -> its proof, as ``templates/proofs.json``
    stores it, its ``local`` digest that of the own net an instance of it has in a compiled
    mission. Knows the library, so that the checker can write those own nets out
    (:meth:`own`)."""

    def __init__(self, entries: dict[str, dict], lib: Library,
                 own: dict[str, tuple[Net, frozenset[str]]] | None = None) -> None:
        super().__init__(entries)
        self.lib = lib
        self._own = dict(own or {})

    def own(self, subject: str) -> tuple[Net, frozenset[str]]:
        """The own net of an instance of ``subject``, and its slot places (:func:`local`)."""
        if subject not in self._own:
            self._own[subject] = local(self.lib, subject)
        return self._own[subject]


def current(lib: Library | None = None, known: dict[str, dict] | None = None,
            eager: bool = False) -> Proofs:
    """The proofs of the library in use, as the certificate and its checker read them: the
    ``known`` ones (default: the stored ones) where the digest matches, every other subject
    (a user's template, an edited one) proven now (its results table row by row as it is
    read, unless ``eager``), and every instance's own digest computed from the library
    (:class:`BrokenTemplate` for a subject that breaks the contract)."""
    lib = lib or default_library()
    known = _stored_now() if known is None else known
    parts = _parts(lib)
    out: dict[str, dict] = {}
    for name, kind, make, children, source, net, net_digest in parts.subjects:
        entry = known.get(name)
        if entry is None or entry.get("digest") != net_digest or "results" not in entry:
            entry = prove(name, kind, make, children, source, eager, net).as_json()
        # a copy: the stored entries are read by every call
        entry = {**entry, "local": parts.shapes[name]} if kind != "joint" else dict(entry)
        out[name] = entry
    # the instances a compiled mission is made of, besides the proven components
    for name, kind in (("primitive", "primitive"),
                       *((f"{CALL_SITE}/{k}", "joint") for k in range(MAX_LOCKS + 1))):
        out[name] = {"kind": kind, "local": parts.shapes[name]}
    return Proofs(out, lib, parts.own)


def untrusted_reduced(lib: Library) -> Mcl2PnmlError | None:
    """Why certificates cannot rest on ``lib``, if they cannot: its reduced task is not the
    package's (a user's file replaced it). Every proof stands a child by the reduced model
    restricted to the child's signature, and that it may is an argument about the
    package's Fig. 3 (docs/certificate.md), not about any net a user names so."""
    package = next((e for e in _stored_now().values() if e.get("kind") == "reduced"), None)
    if package is None or package.get("digest") == _parts(lib).reduced:
        return None
    return Mcl2PnmlError(
        f"the reduced task '{lib.reduced.name}' is not the package's: certificates rest on "
        "the package's reduced model (Fig. 3), which stands for any child that keeps the "
        "contract (docs/certificate.md); remove this file from $MCL2PNML_TEMPLATE_PATH to "
        "certify", Location(str(lib.reduced.source)))


def update(folder: Path | None = None) -> Path:
    """Prove every subject of the package's library now and store the proofs."""
    lib = Library.load([folder or template_dirs()[0]])
    proofs = current(lib, known={}, eager=True)   # nothing taken as known: all proven now
    path = (folder or template_dirs()[0]) / PROOFS
    atomic_write_text(path, json.dumps({
        "about": "each template checked against the interface contract with its children "
                 "reduced, and the compiler's call-site joints; the digest is of the net "
                 "checked (mcl2pnml/certify/templates.py)",
        "templates": proofs}, indent=2, sort_keys=True) + "\n")
    return path


def listing() -> list[str]:
    """One line per stored proof: what was proven, on how many markings."""
    out = []
    for name, entry in sorted(stored().items()):
        if "digest" in entry:
            out.append(f"{name:<32} {entry['kind']:<10} {entry['markings']:>6,} markings  "
                       f"{entry['digest'][:12]}")
    return out


if __name__ == "__main__":
    if sys.argv[1:] == ["--list"]:
        print("\n".join(listing()))
    elif sys.argv[1:] == ["--update"]:
        print(f"wrote {update()}")
    else:
        print("python -m mcl2pnml.certify.templates --list | --update", file=sys.stderr)
        sys.exit(2)
