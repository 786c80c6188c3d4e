"""The net TAPAAL's verifypn reads from a PNML file, beside the net we read from it.

verifypn writes the net it has read (``--write-unfolded-net OUT -r 0 --noverify``):
its places with their initial markings, its transitions, and its arcs with their
weights, parallel arcs already added up. :func:`verifypn_net` reads that file
back into a :class:`ReadNet`; :func:`read_net` puts one of our nets in the same
form (a read arc is the pair of arcs verifypn reads it as: the same behaviour);
:func:`differences` names what differs. A file that we accept must give no
difference (tests/peers/test_pnml_differential.py, the mutation campaign).
:func:`pm4py_net` and :func:`lola_net` are second opinions, in the same form:
the net pm4py's importer builds, and the net LoLA prints (``--printNet``).

verifypn's exit status says little (255 after writing the net, for want of a
query it does not need; 139 when its reader crashes on a file): what counts is
whether it wrote the net. Every call has a time limit.
"""
from __future__ import annotations

import os
import pty
import re
import select
import subprocess
import tempfile
import time
import tty
import warnings
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
    """The net verifypn wrote: its own plain PNML, one page.

    verifypn writes ids as it read them, unescaped: a tab in an id is written as a tab,
    which an XML parser reads back as a space (attribute values are normalised). Such
    characters are turned into character references first, so that the id read back is
    the one verifypn holds.
    """
    data = path.read_bytes()
    if re.search(rb'="[^"<]*[\t\n\r]', data):   # one scan in C; rewritten only then
        data = re.sub(rb'="[^"<]*"', lambda m: m.group(0).replace(b"\t", b"&#9;")
                      .replace(b"\n", b"&#10;").replace(b"\r", b"&#13;"), data)
    tree = etree.ElementTree(etree.fromstring(
        data, etree.XMLParser(resolve_entities=False, huge_tree=True)))
    places = {p.get("id"): int(p.findtext(f"{_NS}initialMarking/{_NS}text") or 0)
              for p in tree.iter(f"{_NS}place")}
    transitions = frozenset(t.get("id") for t in tree.iter(f"{_NS}transition"))
    arcs: dict = {}
    for a in tree.iter(f"{_NS}arc"):
        key = (a.get("source"), a.get("target"), a.get("type") or "normal")
        arcs[key] = arcs.get(key, 0) + int(a.findtext(f"{_NS}inscription/{_NS}text") or 1)
    return ReadNet(places, transitions, arcs)


def pm4py_net(path: Path) -> ReadNet | Refused:
    """The net pm4py's importer (``pm4py.read_pnml``) builds from ``path``.

    pm4py names nodes by their XML id, as verifypn does. It keeps an arc of a type it
    knows (inhibitor, reset) as such, and reads any other type as an ordinary arc; its
    parallel arcs are kept apart, and added up here.
    """
    import pm4py  # installed by `make test` (the `test` extra): its absence is a failure
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # no final marking, deprecated options
        try:
            net, initial, _ = pm4py.read_pnml(str(path))
        except Exception as e:   # its importer fails with whatever its code meets
            return Refused(f"{type(e).__name__}: {e}"[:300])
    arcs: dict = {}
    for a in net.arcs:
        key = (a.source.name, a.target.name, a.properties.get("arctype") or "normal")
        arcs[key] = arcs.get(key, 0) + a.weight
    return ReadNet({p.name: initial.get(p, 0) for p in net.places},
                   frozenset(t.name for t in net.transitions), arcs)


def lola_net(path: Path, timeout: float = TIMEOUT) -> ReadNet | Refused:
    """The net LoLA reads from ``path``, as it prints it (``--printNet``).

    Asked no question (``--check=none``), LoLA prints the net it has read, ending in a
    line ``done``, and then idles for seconds before it exits. Its output goes through a
    pseudo-terminal, which it writes line by line (it is linked statically: ``stdbuf``
    cannot change its buffering), and it is stopped once the net is there.
    """
    tool = peers.need(peers.LOLA)
    master, slave = pty.openpty()
    tty.setraw(slave)   # bytes as written: no line ending or tab translated
    with tempfile.TemporaryFile() as said:
        lola = subprocess.Popen([str(tool), "--pnmlnet", str(Path(path).resolve()),
                                 "--check=none", "--netreduction=off", "--printNet"],
                                stdin=subprocess.DEVNULL, stdout=slave, stderr=said)
        os.close(slave)
        out, deadline = b"", time.monotonic() + timeout
        try:
            while b"\ndone" not in out:
                left = deadline - time.monotonic()
                if left <= 0 or not select.select([master], [], [], left)[0]:
                    return Refused(f"no net within {timeout:g} s")
                try:
                    chunk = os.read(master, 1 << 16)
                except OSError:   # LoLA has exited: the terminal is closed
                    chunk = b""
                if not chunk:
                    break
                out += chunk
        finally:
            lola.kill()
            lola.wait(timeout=timeout)
            os.close(master)
        if b"\ndone" not in out:
            said.seek(0)
            lines = [line.removeprefix("lola:").strip()
                     for line in said.read().decode("utf-8", "replace").splitlines()]
            # "syntax error -- aborting [#01]" after the line that says what is wrong
            end = next((i for i, line in enumerate(lines) if "aborting" in line), None)
            last = next((line for line in reversed(lines) if line), "no message")
            if end is not None:
                return Refused(f"exit {lola.returncode}: "
                               + "; ".join(lines[max(0, end - 1):end + 1]))
            if lola.returncode is not None and lola.returncode < 0:
                return Refused(f"crashed (signal {-lola.returncode}) after '{last}'")
            return Refused(f"exit {lola.returncode}: {last}")
    return _printed(out.decode("utf-8", "replace"))


def _printed(text: str) -> ReadNet:
    """The net of LoLA's ``--printNet``: ``PLACE i NAME sy NAME: n tokens ...``, then each
    ``TRANSITION i :NAME sy NAME`` with the lines after ``CONSUME:`` and ``PRODUCE:``,
    ``NAME:weight`` apart by spaces (parallel arcs listed apart: added up here)."""
    places, transitions, arcs = {}, set(), {}
    current, side = None, None
    for line in text.split("\n"):
        if m := re.match(r"PLACE \d+ (.*) sy \1: (\d+) tokens ", line):
            places[m.group(1)] = int(m.group(2))
        elif m := re.match(r"TRANSITION \d+ :(.*) sy \1$", line):
            current, side = m.group(1), None
            transitions.add(current)
        elif line in ("CONSUME:", "PRODUCE:"):
            side = line
        elif side is not None and current is not None:
            for item in line.split(" "):
                if item:
                    node, weight = item.rsplit(":", 1)
                    key = (node, current, "normal") if side == "CONSUME:" else \
                        (current, node, "normal")
                    arcs[key] = arcs.get(key, 0) + int(weight)
            side = None
    return ReadNet(places, frozenset(transitions), arcs)


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


def differences(ours: ReadNet, theirs: ReadNet, limit: int = 5,
                peer: str = "verifypn") -> list[str]:
    """What differs between two readings, at most ``limit`` lines; none if they are equal.

    Our ids may be the decoded form of the file's (our writer escapes ids that are not
    XML names, and our reader decodes them): the file's ids are tried decoded too.
    """
    found = _differences(ours, theirs, limit, peer)
    if found:
        from mcl2pnml.io.ids import decode
        renamed = ReadNet({decode(p): m for p, m in theirs.places.items()},
                          frozenset(map(decode, theirs.transitions)),
                          {(decode(s), decode(t), k): w for (s, t, k), w in theirs.arcs.items()})
        if len(renamed.places) == len(theirs.places) and \
                len(renamed.transitions) == len(theirs.transitions) and \
                not _differences(ours, renamed, limit, peer):
            return []
    return found


def _differences(ours: ReadNet, theirs: ReadNet, limit: int, peer: str) -> list[str]:
    out = []
    for what, a, b in (("place", ours.places, theirs.places),
                       ("transition", dict.fromkeys(ours.transitions, 0),
                        dict.fromkeys(theirs.transitions, 0)),
                       ("arc", ours.arcs, theirs.arcs)):
        for key in sorted(set(a) | set(b), key=repr):
            if a.get(key) != b.get(key):
                mine = "absent" if key not in a else a[key]
                other = "absent" if key not in b else b[key]
                out.append(f"{what} {key!r}: ours {mine}, {peer}'s {other}")
                if len(out) >= limit:
                    return out
    return out
