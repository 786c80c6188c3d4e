"""The net TAPAAL's verifypn reads from a PNML file, beside the net we read from it.

verifypn writes the net it has read (``--write-unfolded-net OUT -r 0 --noverify``):
its places with their initial markings, its transitions, and its arcs with their
weights, parallel arcs already added up. :func:`verifypn_net` reads that file
back into a :class:`ReadNet`; :func:`read_net` puts one of our nets in the same
form (a read arc is the pair of arcs verifypn reads it as: the same behaviour);
:func:`differences` names what differs. A file that we accept must give no
difference (tests/test_pnml_differential.py, the mutation campaign).

verifypn's exit status says little (255 after writing the net, for want of a
query it does not need; 139 when its reader crashes on a file): what counts is
whether it wrote the net. Every call has a time limit.
"""
from __future__ import annotations

import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

import peers

#: The time one reading may take, however large the file (verifypn hangs on some).
TIMEOUT = 60.0
_QUERY = """<?xml version="1.0"?>
<property-set xmlns="http://mcc.lip6.fr/"><property><id>d</id><description>d</description>
<formula><exists-path><finally><deadlock/></finally></exists-path></formula></property>
</property-set>
"""
_NS = "{http://www.pnml.org/version-2009/grammar/pnml}"


@dataclass(frozen=True)
class ReadNet:
    """A P/T net as a reader understood it: what a comparison needs and nothing else."""

    places: dict = field(default_factory=dict)        # id -> initial tokens
    transitions: frozenset = frozenset()
    arcs: dict = field(default_factory=dict)          # (source, target, kind) -> weight


@dataclass(frozen=True)
class Refused:
    """The reader gave no net: why, in its own words."""

    why: str


def verifypn_net(path: Path, timeout: float = TIMEOUT) -> ReadNet | Refused:
    """The net verifypn reads from ``path`` (skips the calling test where verifypn is absent)."""
    tool = peers.need(peers.VERIFYPN)
    with tempfile.TemporaryDirectory(prefix="vp-read-") as tmp:
        out, query = Path(tmp) / "read.pnml", Path(tmp) / "q.xml"
        query.write_text(_QUERY)
        try:
            ran = subprocess.run([str(tool), "--write-unfolded-net", str(out), "-r", "0",
                                  "--noverify", str(Path(path).resolve()), "-x", "1", str(query)],
                                 capture_output=True, timeout=timeout, cwd=tmp)
        except subprocess.TimeoutExpired:
            return Refused(f"no net within {timeout:g} s")
        said = (ran.stdout + ran.stderr).decode("utf-8", "replace")
        if not out.is_file():
            lines = [line for line in said.splitlines()
                     if line.strip() and not line.startswith(("Parameters:", "RWSTATS"))]
            return Refused(f"exit {ran.returncode}: " + (lines[-1] if lines else "no message"))
        return _written(out)


def _written(path: Path) -> ReadNet:
    """The net verifypn wrote: its own plain PNML, one page."""
    tree = etree.parse(str(path), etree.XMLParser(resolve_entities=False, huge_tree=True))
    places = {p.get("id"): int(p.findtext(f"{_NS}initialMarking/{_NS}text") or 0)
              for p in tree.iter(f"{_NS}place")}
    transitions = frozenset(t.get("id") for t in tree.iter(f"{_NS}transition"))
    arcs: dict = {}
    for a in tree.iter(f"{_NS}arc"):
        key = (a.get("source"), a.get("target"), a.get("type") or "normal")
        arcs[key] = arcs.get(key, 0) + int(a.findtext(f"{_NS}inscription/{_NS}text") or 1)
    return ReadNet(places, transitions, arcs)


def read_net(net) -> ReadNet:
    """One of our nets (:class:`mcl2pnml.core.net.Net`) as a :class:`ReadNet`."""
    from mcl2pnml.core.net import ArcKind
    arcs: dict = {}

    def add(key, weight):
        arcs[key] = arcs.get(key, 0) + weight

    for a in net.arcs:
        add((a.source, a.target, "normal"), a.weight)
        if a.kind is ArcKind.READ:      # read arcs test their place: a loop that gives back
            add((a.target, a.source, "normal"), a.weight)
    return ReadNet({p.id: net.initial.get(p.id, 0) for p in net.places},
                   frozenset(t.id for t in net.transitions), arcs)


def differences(ours: ReadNet, theirs: ReadNet, limit: int = 5) -> list[str]:
    """What differs between two readings, at most ``limit`` lines; none if they are equal.

    Our ids may be the decoded form of the file's (our writer escapes ids that are not
    XML names, and our reader decodes them): the file's ids are tried decoded too.
    """
    found = _differences(ours, theirs, limit)
    if found:
        from mcl2pnml.io.ids import decode
        renamed = ReadNet({decode(p): m for p, m in theirs.places.items()},
                          frozenset(map(decode, theirs.transitions)),
                          {(decode(s), decode(t), k): w for (s, t, k), w in theirs.arcs.items()})
        if len(renamed.places) == len(theirs.places) and \
                len(renamed.transitions) == len(theirs.transitions) and \
                not _differences(ours, renamed, limit):
            return []
    return found


def _differences(ours: ReadNet, theirs: ReadNet, limit: int) -> list[str]:
    out = []
    for what, a, b in (("place", ours.places, theirs.places),
                       ("transition", dict.fromkeys(ours.transitions, 0),
                        dict.fromkeys(theirs.transitions, 0)),
                       ("arc", ours.arcs, theirs.arcs)):
        for key in sorted(set(a) | set(b), key=repr):
            if a.get(key) != b.get(key):
                mine = "absent" if key not in a else a[key]
                peer = "absent" if key not in b else b[key]
                out.append(f"{what} {key!r}: ours {mine}, verifypn's {peer}")
                if len(out) >= limit:
                    return out
    return out
