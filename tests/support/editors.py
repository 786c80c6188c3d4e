"""The Petri-net editors' own readers, headless: WoPeD's PNML import and PIPE's reader.

``../shared/peers/woped/woped-pnml-import.jar`` and
``../shared/peers/pipe/pipe-pnml-import.jar`` (their READMEs say how they were
built) call the readers behind each editor's File > Open and print what they
read: counts, warnings, and with ``--list`` one line per place, transition and
arc. They need Java 17 (``make setup`` installs ``openjdk-17-jre-headless``
where ``java`` is missing). A test that needs one calls :func:`need`, which
skips with the reason when Java or the jar is absent.

A JVM takes about a second to start; a class-data archive of each reader
(``-XX:ArchiveClassesAtExit``) takes a third of that off. Writing one costs a
reader's run twice over, more than the few runs of one test process saved
(each process wrote its own: 3 s of CPU for WoPeD, then 1.2 s a run instead of
1.5), so one archive per reader, jar and JVM is kept in the temporary folder
and shared by every test process and run of the suite; the JVM checks it
against the jars and itself, and starts without it where they differ. Every
run has a time bound.
"""
from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import tempfile
import uuid
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import pytest

from helpers import ROOT

PEERS = ROOT.parent / "shared" / "peers"
JARS = {"woped": PEERS / "woped" / "woped-pnml-import.jar",
        "pipe": PEERS / "pipe" / "pipe-pnml-import.jar"}
TIMEOUT = 120.0
#: Flags that shorten a short-lived JVM: the client compiler only, the serial collector.
FAST = ("-XX:TieredStopAtLevel=1", "-XX:+UseSerialGC")


@lru_cache(maxsize=None)
def find(editor: str) -> tuple[list[str] | None, str]:
    """The command that runs ``editor``'s reader (``woped`` or ``pipe``), or None and why."""
    jar = JARS[editor]
    java = shutil.which("java")
    if java is None:
        return None, "no java on PATH (make setup installs openjdk-17-jre-headless)"
    if not jar.is_file():
        return None, f"{jar} is not there (../shared/peers beside the checkout)"
    return [java, *FAST, "-jar", str(jar)], ""


def archived(editor: str) -> list[str] | None:
    """The command of :func:`find`, started from the shared class-data archive of the reader
    where one is there (as a document's ``$`` line runs it: tests/support/tutorial.py)."""
    command, _ = find(editor)
    if command is None:
        return None
    archive = _archive(editor, command[0])
    if not archive.is_file():
        return command
    return [command[0], *QUIET, f"-XX:SharedArchiveFile={archive}", *command[1:]]


def need(editor: str) -> list[str]:
    command, why = find(editor)
    if command is None:
        pytest.skip(why)
    return command


#: The readers' class-data archives, one per reader, jar and JVM (the module's documentation).
_ARCHIVES = Path(tempfile.gettempdir()) / f"mcl2pnml-jsa-{os.getuid()}"
#: JVM options: no log lines on standard output (a JVM that cannot use an archive says so
#: there, among the reader's lines).
QUIET = ("-Xlog:disable",)


@lru_cache(maxsize=None)
def _archive(editor: str, java: str) -> Path:
    """Where the class-data archive of ``editor``'s reader run by ``java`` is kept: named by
    a digest of the jar, of the jars beside it, and of the JVM."""
    jar = JARS[editor]
    digest = hashlib.sha256(jar.read_bytes())
    home = Path(java).resolve().parent.parent
    for path in sorted([*jar.parent.glob("lib/*.jar"), Path(java).resolve(),
                        *home.glob("lib/server/libjvm.so")]):
        stat = path.stat()
        digest.update(f"{path}:{stat.st_size}:{stat.st_mtime_ns}\n".encode())
    return _ARCHIVES / f"{editor}-{digest.hexdigest()[:20]}.jsa"


@dataclass
class Read:
    """What an editor's reader read of a file."""

    counts: dict[str, int] = field(default_factory=dict)
    #: id -> (tokens, x, y)
    places: dict[str, tuple[int, int | None, int | None]] = field(default_factory=dict)
    #: id -> (x, y)
    transitions: dict[str, tuple[int | None, int | None]] = field(default_factory=dict)
    #: id -> (source, target, weight, points: its ends and bend points)
    arcs: dict[str, tuple[str, str, int, int]] = field(default_factory=dict)
    #: what the reader complained of (WoPeD's warnings, PIPE's unexpected elements)
    complaints: list[str] = field(default_factory=list)
    output: str = ""


_PAIRS = re.compile(r"(\w+)=(\S*)")


def _number(text: str | None) -> int | None:
    return None if text is None else round(float(text))


def read(editor: str, path: Path) -> Read:
    """Run ``editor``'s reader on ``path`` with ``--list`` (and PIPE's ``--verbose``, which
    shows the elements it skipped); fails the test on an error."""
    command = need(editor)
    archive = _archive(editor, command[0])
    written = None
    if archive.is_file():
        share = f"-XX:SharedArchiveFile={archive}"
    else:   # written under a name of its own, then put in place whole
        _ARCHIVES.mkdir(exist_ok=True)
        written = archive.with_name(f"{archive.name}.{uuid.uuid4().hex}.tmp")
        share = f"-XX:ArchiveClassesAtExit={written}"
    args = [command[0], *QUIET, share, *command[1:], "--list",
            *(["--verbose"] if editor == "pipe" else []), str(path)]
    try:
        out = subprocess.run(args, capture_output=True, text=True, timeout=TIMEOUT)
    finally:
        if written is not None and written.is_file():
            if "out" in locals() and out.returncode == 0:    # a whole archive
                os.replace(written, archive)
            else:
                written.unlink()
    assert out.returncode == 0, f"{editor} could not read {path.name}:\n{out.stdout}{out.stderr}"
    got = Read(output=out.stdout)
    for line in out.stdout.splitlines():
        words = line.split()
        if not words:
            continue
        kv = dict(_PAIRS.findall(line))
        if words[0] == "place" and len(words) > 2:
            got.places[words[1]] = (int(kv["tokens"]), _number(kv.get("x")),
                                    _number(kv.get("y")))
        elif words[0] == "transition" and len(words) > 2:
            got.transitions[words[1]] = (_number(kv.get("x")), _number(kv.get("y")))
        elif words[0] == "arc" and len(words) > 2:
            source, target = words[2].split("->")
            weight = kv.get("weight")
            if weight is None:      # PIPE: weights={Default=2}
                weight = sum(map(int, re.findall(r"=(\d+)", kv.get("weights", ""))))
            got.arcs[words[1]] = (source, target, int(weight), int(kv.get("points", 0)))
        elif words[0] == "warning":
            got.complaints.append(line)
        elif len(words) == 2 and words[1].lstrip("-").isdigit():
            got.counts[words[0]] = int(words[1])
        elif "unexpected element" in line or "ValidationEvent" in line:
            got.complaints.append(line.strip())
    if got.counts.get("warnings"):
        got.complaints.append(f"warnings {got.counts['warnings']}")
    return got
