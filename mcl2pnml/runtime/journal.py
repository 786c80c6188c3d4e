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

A journal is locked (``flock``, exclusive) by the run that writes it, from
its creation or the start of its resume to the end of the run: a second
``--resume`` of it meanwhile is refused, not run beside the first. Its
header is checked field by field before anything is run (a header edited
by hand is one message naming the field, not a crash), and a journal whose
run has ended (its last line is the outcome) is not resumed: there is
nothing left to run.

For tests only: with ``MCL2PNML_JOURNAL_KILL_AFTER=N`` in the environment,
the process kills itself (SIGKILL) right after writing the journal's N-th
line (the header is line 1), as a crash at that point would.
"""
from __future__ import annotations

import fcntl
import hashlib
import json
import math
import os
import re
import signal
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import json_fault, open_regular, read_bytes
from mcl2pnml.core.settings import SettingError
from mcl2pnml.core.timing import seconds_setting
from mcl2pnml.runtime.vehicles import is_simulator

VERSION = 1
KILL_AFTER = "MCL2PNML_JOURNAL_KILL_AFTER"
#: The engines a journal may name: those of ``run --engine``.
ENGINES = ("petri", "reference")
#: The header's digests, by the file each is of.
DIGESTS = ("mission_sha256", "vehicle_sha256", "world_sha256")
_SHA256 = re.compile(r"[0-9a-f]{64}")


def digest(path: str | Path) -> str:
    """The SHA-256 of a file the run depends on (the mission, the script, the world)."""
    return hashlib.sha256(read_bytes(path)).hexdigest()


def _lock(fd: int, path: Path) -> None:
    """Take the journal for this run, or refuse: one run writes a journal at a time."""
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        raise Mcl2PnmlError("the journal is in use by another run (resuming or writing "
                            "it): one run at a time", Location(str(path))) from None
    except OSError as e:   # a file system without locks: say so rather than risk two writers
        raise Mcl2PnmlError(f"cannot lock the journal: {e.strerror or e}",
                            Location(str(path))) from None


class _Appender:
    """Appends whole lines to the journal, flushing each (and the test hook's kill).

    Made on a new file (``create``), it locks it; made on the descriptor of a
    journal being resumed (``fd``, locked by :func:`load`), it keeps that lock.
    """

    def __init__(self, path: Path, lines_before: int, fd: int | None = None):
        self.path = path
        if fd is None:
            try:
                self.file: IO[str] = open(path, "x", encoding="utf-8")
            except FileExistsError:
                raise Mcl2PnmlError("the journal exists already: resume it with --resume, or "
                                    "give another file", Location(str(path))) from None
            except OSError as e:
                raise Mcl2PnmlError(f"cannot write the journal: {e.strerror or e}",
                                    Location(str(path))) from None
            try:
                _lock(self.file.fileno(), path)
            except Mcl2PnmlError:
                self.file.close()
                raise
        else:
            # appending from now on, blocking as a plain file does
            flags = fcntl.fcntl(fd, fcntl.F_GETFL)
            fcntl.fcntl(fd, fcntl.F_SETFL, (flags | os.O_APPEND) & ~os.O_NONBLOCK)
            self.file = open(fd, "a", encoding="utf-8")
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
    """A new journal, locked for this run (refused if the file exists: a journal is
    never overwritten)."""
    out = _Appender(Path(path), 0)
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
    fd: int | None = None         # the journal, open and locked for this run


def load(path: str | Path) -> Loaded:
    """Read a journal to resume it, and lock it for this run.

    A torn last line is dropped, any other bad line is an error; so are a
    header that is not one :func:`create` writes (:func:`check_header`), a
    journal another run holds, and a run that has ended.
    """
    path = Path(path)
    try:
        fd = open_regular(path, "journal", os.O_RDWR)
    except Mcl2PnmlError:
        if os.path.isfile(path) and os.access(path, os.R_OK) and not os.access(path, os.W_OK):
            raise Mcl2PnmlError("cannot resume the journal: it is read-only, and a resumed "
                                "run appends to it", Location(str(path))) from None
        raise
    try:
        _lock(fd, path)
        with os.fdopen(os.dup(fd), "rb") as f:
            data = f.read()
        loaded = _parse(path, data)
    except BaseException:
        os.close(fd)
        raise
    loaded.fd = fd
    return loaded


def _parse(path: Path, data: bytes) -> Loaded:
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
        except (ValueError, RecursionError) as e:
            # ValueError: not JSON, not UTF-8, or an integer past Python's digit limit;
            # RecursionError: arrays nested thousands deep
            raise Mcl2PnmlError(f"not a journal line: {json_fault(e)}",
                                Location(str(path), n, 1,
                                         line[:200].decode(errors="replace"))) from None
        if not isinstance(obj, dict):
            raise Mcl2PnmlError("not a journal line: a JSON object per line",
                                Location(str(path), n, 1))
        parsed.append(obj)
    version = parsed[0].get("journal") if parsed else None
    if type(version) is not int or version != VERSION:
        raise Mcl2PnmlError(f"not a run journal of mcl2pnml (its first line is a header "
                            f'{{"journal": {VERSION}, ...}})', Location(str(path), 1, 1))
    check_header(parsed[0], str(path), raw[0].decode(errors="replace"))
    for n, line in enumerate(parsed[1:], 2):
        if "outcome" in line:
            t = line.get("t")
            when = f"{t:g}" if isinstance(t, (int, float)) and not isinstance(t, bool) \
                else json.dumps(t)
            outcome = line["outcome"]
            said = outcome if isinstance(outcome, str) else json.dumps(outcome)
            raise Mcl2PnmlError(f"this run has ended ({said} at t={when} s, line {n}); "
                                "nothing to resume", Location(str(path)))
    return Loaded(path, parsed[0], parsed[1:], torn, len(data) - len(tail))


def check_header(header: dict[str, Any], filename: str, line: str = "") -> None:
    """Every field of a journal's header, as :func:`create` writes them; one located
    error for the first that is not (``line``: the header's text, to point at it)."""
    def fault(key: str, message: str) -> Mcl2PnmlError:
        at = line.find(f'"{key}"')
        shown = line if len(line) <= 10_000 else None
        return Mcl2PnmlError(f"the journal's header: {message}",
                             Location(filename, 1, at + 1 if at >= 0 else 1, shown))

    def text(key: str, what: str) -> str:
        if key not in header:
            raise fault(key, f'no "{key}" ({what}); the header is not one mcl2pnml wrote')
        value = header[key]
        if not isinstance(value, str) or not value:
            raise fault(key, f'"{key}" is {what}, not {json.dumps(value)[:80]}')
        return value

    text("mission", "the mission's file name")
    engine = text("engine", "the engine's name")
    if engine not in ENGINES:
        raise fault("engine", f"unknown engine '{engine[:80]}'; valid: {', '.join(ENGINES)}")
    vehicle = text("vehicle", "the vehicle: sim or a vehicle script's file name")
    if vehicle.startswith("bridge:"):
        raise fault("vehicle", f"the vehicle '{vehicle[:80]}' is a real one, whose run cannot "
                               "be replayed; valid: sim, or a vehicle script")
    world = header.get("world")
    if world is not None:
        if not isinstance(world, str) or not world:
            raise fault("world", '"world" is the world file\'s name, or null, not '
                                 f"{json.dumps(world)[:80]}")
        if not is_simulator(vehicle):
            raise fault("world", "a world is for the simulator (vehicle sim), not for "
                                 f"'{vehicle[:80]}'")
    if "max_time" not in header:
        raise fault("max_time", 'no "max_time" (the run\'s time limit, in seconds)')
    max_time = header["max_time"]
    if not isinstance(max_time, (int, float)) or isinstance(max_time, bool) \
            or not math.isfinite(max_time) or max_time < 0:
        raise fault("max_time", '"max_time" is the time limit, a finite number of seconds '
                                f">= 0, not {json.dumps(max_time)[:80]}")
    for key in ("ack_within", "report_gap"):    # left out by an older journal: the default
        value = header.get(key, "0")
        try:
            if not isinstance(value, str):
                raise SettingError(key, "not a string")
            seconds_setting(value, key)
        except SettingError:
            raise fault(key, f'"{key}" is an assumption of the timed verdicts, a number of '
                             f"seconds in a string, not {json.dumps(value)[:80]}") from None
    if not isinstance(header.get("stop_on_breach", False), bool):
        raise fault("stop_on_breach", '"stop_on_breach" is true or false, not '
                                      f'{json.dumps(header["stop_on_breach"])[:80]}')
    needed = {"mission_sha256": True, "vehicle_sha256": not is_simulator(vehicle),
              "world_sha256": world is not None}
    for key in DIGESTS:
        value = header.get(key)
        if value is None:
            if needed[key]:
                raise fault(key, f'no "{key}" (the digest of the {key[:-7]} file)')
            continue
        if not needed[key]:
            raise fault(key, f'"{key}" is the digest of a file this run does not have')
        if not isinstance(value, str) or not _SHA256.fullmatch(value):
            raise fault(key, f'"{key}" is a SHA-256 digest (64 hexadecimal digits), not '
                             f"{json.dumps(value)[:80]}")


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
        if loaded.fd is None:     # loaded without its lock (a test): take it now
            loaded.fd = open_regular(loaded.path, "journal", os.O_RDWR)
            _lock(loaded.fd, loaded.path)
        try:
            os.ftruncate(loaded.fd, loaded.size)     # drop the torn line before appending
        except OSError as e:
            raise Mcl2PnmlError(f"cannot write the journal: {e.strerror or e}",
                                Location(str(loaded.path))) from None
        self.out = _Appender(loaded.path, 1 + len(loaded.lines), loaded.fd)

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
