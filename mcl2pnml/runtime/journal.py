"""The run journal: a run written down as it happens, so that a killed run can be resumed.

``mcl2pnml run MISSION --journal FILE`` writes the JSON-lines log of
:mod:`mcl2pnml.runtime.runlog` (each action sent, each event received, each
transition fired, each event ignored, the safe stop, then the outcome) to
FILE, after one header line naming the mission, the engine and the
vehicle, with digests of the files they came from. The journal is
**append-only by design** (the one output not written through
:mod:`mcl2pnml.core.files`' atomic writers): a line is written whole with one
``write`` and flushed at once, so that a process killed at any point leaves
every line before the kill in the file, and at most a torn last line.
There is no ``fsync``: a flushed line is in the kernel's cache, which
outlives the process (SIGKILL, an uncaught error, the OOM killer), and an
``fsync`` per line would cost a disk round trip per event; a power cut of
the machine itself can lose the last lines, and resuming then replays less.

``mcl2pnml run MISSION --resume FILE`` runs the same mission again, from
the start, with a fresh engine and a fresh vehicle of the same kind (the
simulator and the scripted vehicle are deterministic), and :class:`Replay`
checks each line it would write against the journal, in order: the
journaled part is replayed, not redone, and a difference is one error
naming the journal's line. Past the journal's end the run goes on live and
its lines are appended to the same file. A torn last line is dropped (and
said so) before anything is appended.

For tests only: with ``MCL2PNML_JOURNAL_KILL_AFTER=N`` in the environment,
the process kills itself (SIGKILL) right after writing the journal's N-th
line (the header is line 1), as a crash at that point would.
"""
from __future__ import annotations

import hashlib
import json
import os
import signal
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mcl2pnml.core.errors import Location, Mcl2PnmlError

VERSION = 1
KILL_AFTER = "MCL2PNML_JOURNAL_KILL_AFTER"


def digest(path: str | Path) -> str:
    """The SHA-256 of a file the run depends on (the mission, the script, the world)."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError as e:
        raise Mcl2PnmlError(f"cannot read: {e.strerror or e}", Location(str(path))) from None


class _Appender:
    """Appends whole lines to the journal, flushing each (and the test hook's kill)."""

    def __init__(self, path: Path, lines_before: int, mode: str):
        self.path = path
        try:
            self.file = open(path, mode, encoding="utf-8")
        except FileExistsError:
            raise Mcl2PnmlError("the journal exists already: resume it with --resume, or give "
                                "another file", Location(str(path))) from None
        except OSError as e:
            raise Mcl2PnmlError(f"cannot write the journal: {e.strerror or e}",
                                Location(str(path))) from None
        self.count = lines_before
        kill = os.environ.get(KILL_AFTER)
        self.kill_after = int(kill) if kill and kill.isdigit() else None

    def write(self, line: str) -> None:
        self.file.write(line)
        self.file.flush()
        self.count += 1
        if self.count == self.kill_after:
            os.kill(os.getpid(), signal.SIGKILL)

    def flush(self) -> None:
        self.file.flush()

    def close(self) -> None:
        self.file.close()


def create(path: str | Path, header: dict[str, Any]) -> _Appender:
    """A new journal (refused if the file exists: a journal is never overwritten)."""
    out = _Appender(Path(path), 0, "x")
    out.write(json.dumps({"journal": VERSION, **header}) + "\n")
    return out


@dataclass
class Loaded:
    """A journal read back: its header, its lines after the header, and what was dropped."""

    path: Path
    header: dict[str, Any]
    lines: list[dict[str, Any]] = field(default_factory=list)
    torn: str | None = None       # the note on a torn last line, if there was one
    size: int = 0                 # bytes up to the end of the last whole line


def load(path: str | Path) -> Loaded:
    """Read a journal; a torn last line is dropped, any other bad line is an error."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as e:
        raise Mcl2PnmlError(f"cannot read the journal: {e.strerror or e}",
                            Location(str(path))) from None
    raw = data.split(b"\n")
    tail = raw.pop()               # after the last newline: empty, or a torn line
    torn = None
    if tail:
        torn = (f"{path}:{len(raw) + 1}: the last line was cut off (the run was killed "
                "while writing it): dropped")
    parsed = []
    for n, line in enumerate(raw, 1):
        try:
            obj = json.loads(line)
        except (json.JSONDecodeError, UnicodeDecodeError) as e:
            raise Mcl2PnmlError(f"not a journal line: {getattr(e, 'msg', e)}",
                                Location(str(path), n, 1,
                                         line.decode(errors="replace"))) from None
        if not isinstance(obj, dict):
            raise Mcl2PnmlError("not a journal line: a JSON object per line",
                                Location(str(path), n, 1))
        parsed.append(obj)
    if not parsed or parsed[0].get("journal") != VERSION:
        raise Mcl2PnmlError(f"not a run journal of mcl2pnml (its first line is a header "
                            f'{{"journal": {VERSION}, ...}})', Location(str(path), 1, 1))
    return Loaded(path, parsed[0], parsed[1:], torn, len(data) - len(tail))


class Replay:
    """The journal's writer on a resumed run: checks the replayed lines, then appends.

    Given to :class:`~mcl2pnml.runtime.runlog.RunLog` as its journal. The first
    lines the resumed run writes must be the journal's, one for one (as
    JSON objects); the rest are appended to the file.
    """

    def __init__(self, loaded: Loaded):
        self.loaded = loaded
        self.next = 0
        self.failed = False
        with open(loaded.path, "r+b") as f:      # drop the torn line before appending
            f.truncate(loaded.size)
        self.out = _Appender(loaded.path, 1 + len(loaded.lines), "a")

    @property
    def replaying(self) -> bool:
        return self.next < len(self.loaded.lines)

    def write(self, line: str) -> None:
        if self.failed:
            return        # the first difference is the error; the safe stop's lines are not
        if not self.replaying:
            return self.out.write(line)
        expected, obj = self.loaded.lines[self.next], json.loads(line)
        self.next += 1
        if obj != expected:
            self.failed = True
            raise Mcl2PnmlError(
                f"the resumed run differs from the journal here: the journal has "
                f"{json.dumps(expected)}, the run now gives {json.dumps(obj)} (another "
                "mission, vehicle or version?)", Location(str(self.loaded.path), self.next + 1))

    def finish(self) -> None:
        """After the run: the journal must not go on past where the run ended."""
        if self.replaying:
            raise Mcl2PnmlError(
                "the run ended before the journal does: the journal has "
                f"{json.dumps(self.loaded.lines[self.next])} here",
                Location(str(self.loaded.path), self.next + 2))
        self.out.close()

    def flush(self) -> None:
        self.out.flush()
